#pragma once
/** @file noise.h
 *  Stochastic error models shared by the simulated sensors.
 *
 *  InertialAxisError: one gyro or accelerometer axis = white noise with
 *  density `random_walk` (ARW or VRW, per √s; sampled as N/√dt) + a constant
 *  turn-on bias + a first-order Gauss–Markov bias whose stationary σ is chosen
 *  so that the Allan-deviation floor (its minimum over cluster times up to the
 *  correlation time) equals the datasheet "bias instability". Beyond the floor
 *  the curve rises like rate random walk, as real gyros' do. The GM is
 *  discretised exactly for any dt.
 */
#include <mrpt/random/RandomGenerators.h>

namespace auvnav::sim
{
/** Allan variance of a first-order Gauss–Markov process of stationary σ
 *  `sigma` and correlation time `tau_c` at cluster time `T` (all SI). */
double gaussMarkovAllanVariance(double sigma, double tau_c, double T);

/** Stationary σ of a Gauss–Markov process with correlation time `tau_c` that,
 *  added to white noise of density `random_walk`, gives an Allan-deviation
 *  minimum (over cluster times up to `tau_c`) of `bias_instability`. Returns 0
 *  if the white noise alone already reaches that floor before `tau_c`. */
double gaussMarkovSigmaForAllanFloor(double random_walk, double bias_instability, double tau_c);

struct InertialAxisErrorParams
{
	double random_walk = 0;       //!< white-noise density [unit·√s], e.g. rad/√s
	double bias_instability = 0;  //!< Allan-deviation floor [unit]
	double bias_tau_s = 600;      //!< correlation time of the bias wander
	double turn_on_sigma = 0;     //!< σ of the constant turn-on bias [unit]
};

class InertialAxisError
{
 public:
	InertialAxisError(const InertialAxisErrorParams& p, mrpt::random::CRandomGenerator& rng);
	/** Error to add to the true value for a sample after `dt_s`; also
	 *  advances the bias. */
	double sample(double dt_s, mrpt::random::CRandomGenerator& rng);
	/** Current total bias (turn-on + wander), without white noise. */
	double bias() const { return turn_on_ + wander_; }
	double gaussMarkovSigma() const { return gm_sigma_; }

 private:
	InertialAxisErrorParams p_;
	double gm_sigma_ = 0;
	double turn_on_ = 0;
	double wander_ = 0;
};

/** A scalar first-order Gauss–Markov process, exact for any dt. */
class GaussMarkov
{
 public:
	GaussMarkov() = default;
	GaussMarkov(double sigma, double tau_s, mrpt::random::CRandomGenerator& rng);
	double advance(double dt_s, mrpt::random::CRandomGenerator& rng);
	double value() const { return x_; }

 private:
	double sigma_ = 0, tau_s_ = 1, x_ = 0;
};

}  // namespace auvnav::sim
