#include "noise.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace auvnav::sim
{
double gaussMarkovAllanVariance(double sigma, double tau_c, double T)
{
	// AVAR of a GM with driving PSD q = 2σ²/τc, from integrating its
	// autocorrelation σ² e^{−|t|/τc} over the Allan kernel:
	//   q τc² / T · [1 − τc/(2T) (3 − 4 e^{−T/τc} + e^{−2T/τc})]
	// Limits: q T/3 (rate random walk) for T ≪ τc, 2σ²τc/T (white) for T ≫ τc.
	const double q = 2 * sigma * sigma / tau_c;
	const double x = T / tau_c;
	if (x < 1e-4) return q * T / 3;  // small-T limit, avoids cancellation
	return q * tau_c * tau_c / T * (1 - (3 - 4 * std::exp(-x) + std::exp(-2 * x)) / (2 * x));
}

namespace
{
// The floor is the Allan-deviation minimum between the white-noise slope and
// the rise of the bias wander, i.e. over cluster times up to τc (beyond, a GM
// turns white again and the curve falls for ever).
double allanFloor(double n, double sigma, double tau_c)
{
	double best = INFINITY;
	for (double T = 0.01; T <= tau_c; T *= 1.02)
		best = std::min(best, n * n / T + gaussMarkovAllanVariance(sigma, tau_c, T));
	return std::sqrt(best);
}
}  // namespace

double gaussMarkovSigmaForAllanFloor(double random_walk, double bias_instability, double tau_c)
{
	if (bias_instability <= 0) return 0;
	if (allanFloor(random_walk, 0, tau_c) >= bias_instability) return 0;
	// The floor grows with σ; bracket it first. With little white noise the
	// σ needed can be many times the floor (about B²√(1.5τc)/(2N)): a fixed
	// bracket of 10·B once gave a silently wrong 5 °/h for ARW 0.012 °/√h,
	// B 0.5 °/h, τc 3000 s (11.6 °/h is right).
	double lo = 0, hi = bias_instability;
	while (allanFloor(random_walk, hi, tau_c) < bias_instability)
	{
		lo = hi;
		hi *= 2;
		if (hi > 1e6 * bias_instability)
			throw std::invalid_argument(
			    "bias instability unattainable with this random walk and correlation time");
	}
	for (int i = 0; i < 60; ++i)
	{
		const double mid = 0.5 * (lo + hi);
		(allanFloor(random_walk, mid, tau_c) < bias_instability ? lo : hi) = mid;
	}
	return 0.5 * (lo + hi);
}

InertialAxisError::InertialAxisError(const InertialAxisErrorParams& p, mrpt::random::CRandomGenerator& rng)
    : p_(p)
{
	gm_sigma_ = gaussMarkovSigmaForAllanFloor(p.random_walk, p.bias_instability, p.bias_tau_s);
	turn_on_ = p.turn_on_sigma * rng.drawGaussian1D_normalized();
	wander_ = gm_sigma_ * rng.drawGaussian1D_normalized();  // stationary start
}

double InertialAxisError::sample(double dt_s, mrpt::random::CRandomGenerator& rng)
{
	const double phi = std::exp(-dt_s / p_.bias_tau_s);
	wander_ = phi * wander_ + gm_sigma_ * std::sqrt(1 - phi * phi) * rng.drawGaussian1D_normalized();
	return bias() + p_.random_walk / std::sqrt(dt_s) * rng.drawGaussian1D_normalized();
}

GaussMarkov::GaussMarkov(double sigma, double tau_s, mrpt::random::CRandomGenerator& rng)
    : sigma_(sigma), tau_s_(tau_s), x_(sigma * rng.drawGaussian1D_normalized())
{
}

double GaussMarkov::advance(double dt_s, mrpt::random::CRandomGenerator& rng)
{
	const double phi = std::exp(-dt_s / tau_s_);
	x_ = phi * x_ + sigma_ * std::sqrt(1 - phi * phi) * rng.drawGaussian1D_normalized();
	return x_;
}

}  // namespace auvnav::sim
