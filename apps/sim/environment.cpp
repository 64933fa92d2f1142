#include "environment.h"

#include <algorithm>
#include <cmath>

namespace auvnav::sim
{
Environment::Environment(const CurrentParams& c, const SeabedParams& s, const WaterParams& w, uint32_t seed)
    : cur_(c), bed_(s), water_(w)
{
	rng_.randomize(seed);
	// Start the wander in its stationary distribution.
	wander_ne_ = {cur_.wander_sigma_mps * rng_.drawGaussian1D_normalized(),
	              cur_.wander_sigma_mps * rng_.drawGaussian1D_normalized()};
}

namespace
{
Eigen::Vector2d vector2(const config::Node& n, const std::string& key)
{
	const auto v = n.numbers(key);
	if (v.size() != 2) n.fail(key, "expected [north, east]");
	return {v[0], v[1]};
}
}  // namespace

Environment Environment::fromConfig(const config::Node& n, uint32_t seed)
{
	CurrentParams c;
	const auto nc = n.child("current");
	c.surface_ne_mps = vector2(nc, "surface_ne_mps");
	c.deep_ne_mps = vector2(nc, "deep_ne_mps");
	c.shear_depth_m = nc.positive("shear_depth_m");
	c.tidal_amplitude_ne_mps = vector2(nc, "tidal_amplitude_ne_mps");
	c.tidal_period_s = nc.positive("tidal_period_s");
	c.tidal_phase_rad = nc.number("tidal_phase_deg") * M_PI / 180;
	c.wander_sigma_mps = nc.nonNegative("wander_sigma_mps");
	c.wander_tau_s = nc.positive("wander_tau_s");
	SeabedParams s;
	const auto ns = n.child("seabed");
	s.depth_m = ns.positive("depth_at_origin_m");
	s.slope_ne = vector2(ns, "slope_ne");
	s.undulation_m = ns.nonNegative("undulation_m");
	s.wavelength_m = ns.positive("wavelength_m");
	WaterParams w;
	const auto nw = n.child("water");
	w.density_kg_m3 = nw.inRange("density_kg_m3", 990, 1050);
	w.atmospheric_pressure_pa = nw.inRange("atmospheric_pressure_pa", 80000, 110000);
	w.surface_temperature_c = nw.inRange("surface_temperature_c", -2, 40);
	w.temperature_gradient_c_per_m = nw.number("temperature_gradient_c_per_m");
	return Environment(c, s, w, seed);
}

void Environment::advanceTo(double t_s)
{
	const double dt = t_s - t_s_;
	if (dt <= 0) return;
	// Exact Gauss–Markov discretisation for any dt.
	const double phi = std::exp(-dt / cur_.wander_tau_s);
	const double q = cur_.wander_sigma_mps * std::sqrt(1 - phi * phi);
	wander_ne_ = phi * wander_ne_ +
	             q * Eigen::Vector2d(rng_.drawGaussian1D_normalized(), rng_.drawGaussian1D_normalized());
	t_s_ = t_s;
}

Eigen::Vector3d Environment::current(double depth_m) const
{
	const double w_surface = std::exp(-std::max(0.0, depth_m) / cur_.shear_depth_m);
	const Eigen::Vector2d tide =
	    cur_.tidal_amplitude_ne_mps * std::sin(2 * M_PI * t_s_ / cur_.tidal_period_s + cur_.tidal_phase_rad);
	const Eigen::Vector2d c =
	    w_surface * cur_.surface_ne_mps + (1 - w_surface) * cur_.deep_ne_mps + tide + wander_ne_;
	return {c.x(), c.y(), 0.0};
}

double Environment::seabedDepth(double north_m, double east_m) const
{
	const double k = 2 * M_PI / bed_.wavelength_m;
	return bed_.depth_m + bed_.slope_ne.x() * north_m + bed_.slope_ne.y() * east_m +
	       bed_.undulation_m * std::sin(k * north_m) * std::cos(k * 0.7 * east_m);
}

double Environment::rayToSeabed(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_range_m) const
{
	// Height above the seabed along the ray; march to the first sign change,
	// then bisect. Steps are small against the relief wavelength.
	auto clearance = [&](double s)
	{
		const Eigen::Vector3d p = o + s * d;
		return seabedDepth(p.x(), p.y()) - p.z();
	};
	if (clearance(0) <= 0) return 0;
	const double step = std::max(0.05, std::min(0.5, bed_.wavelength_m / 50));
	double s0 = 0;
	for (double s1 = step;; s1 += step)
	{
		s1 = std::min(s1, max_range_m);
		if (clearance(s1) <= 0)
		{
			double lo = s0, hi = s1;
			for (int i = 0; i < 40; ++i)
			{
				const double mid = 0.5 * (lo + hi);
				(clearance(mid) > 0 ? lo : hi) = mid;
			}
			return 0.5 * (lo + hi);
		}
		if (s1 >= max_range_m) return -1;
		s0 = s1;
	}
}

double Environment::temperature(double depth_m) const
{
	return water_.surface_temperature_c + water_.temperature_gradient_c_per_m * std::max(0.0, depth_m);
}

}  // namespace auvnav::sim
