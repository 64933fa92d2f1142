#pragma once
/** @file environment.h
 *  The simulated ocean: a horizontal water-current field that varies with
 *  depth (exponential shear between a surface and a deep value) and slowly in
 *  time (a tidal oscillation plus a seeded Gauss–Markov wander), a seabed
 *  depth profile (plane + undulations), and water properties. Frames: NED
 *  tangent frame (frames.h); currents [m/s], depths [m, positive down].
 */
#include <auvnav/config.h>
#include <mrpt/random/RandomGenerators.h>

#include <Eigen/Core>

namespace auvnav::sim
{
struct CurrentParams
{
	Eigen::Vector2d surface_ne_mps{0, 0};  //!< current at the surface
	Eigen::Vector2d deep_ne_mps{0, 0};     //!< current far below the shear layer
	double shear_depth_m = 10;             //!< e-folding depth of the surface part
	Eigen::Vector2d tidal_amplitude_ne_mps{0, 0};
	double tidal_period_s = 44712;  //!< M2 tide, 12.42 h
	double tidal_phase_rad = 0;
	double wander_sigma_mps = 0;  //!< stationary σ of the Gauss–Markov wander (per axis)
	double wander_tau_s = 3600;
};

struct SeabedParams
{
	double depth_m = 30;             //!< depth at the origin
	Eigen::Vector2d slope_ne{0, 0};  //!< depth gradient along N and E [m/m]
	double undulation_m = 0;         //!< amplitude of the sinusoidal relief
	double wavelength_m = 100;
};

struct WaterParams
{
	double density_kg_m3 = 1025;
	double atmospheric_pressure_pa = 101325;
	double surface_temperature_c = 27;
	double temperature_gradient_c_per_m = -0.05;
};

class Environment
{
 public:
	Environment(const CurrentParams& c, const SeabedParams& s, const WaterParams& w, uint32_t seed);
	static Environment fromConfig(const config::Node& node, uint32_t seed);

	/** Advances the time-varying part of the current to `t_s` (monotonic). */
	void advanceTo(double t_s);
	/** Water current at depth `depth_m` now [m/s], NED (vertical part 0). */
	Eigen::Vector3d current(double depth_m) const;
	/** Seabed depth under the horizontal position (north, east). */
	double seabedDepth(double north_m, double east_m) const;
	/** Distance along a ray from `origin_n` in unit direction `dir_n` to the
	 *  seabed, or a negative number if it is not hit within `max_range_m`. */
	double rayToSeabed(const Eigen::Vector3d& origin_n, const Eigen::Vector3d& dir_n,
	                   double max_range_m) const;
	double temperature(double depth_m) const;
	const WaterParams& water() const { return water_; }

 private:
	CurrentParams cur_;
	SeabedParams bed_;
	WaterParams water_;
	mrpt::random::CRandomGenerator rng_;
	double t_s_ = 0;
	Eigen::Vector2d wander_ne_{0, 0};
};

}  // namespace auvnav::sim
