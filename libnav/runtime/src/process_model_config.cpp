#include <auvnav/process_model_config.h>

#include <cmath>
#include <string>

namespace auvnav
{
ProcessModel processModelFromConfig(const config::Node& process_noise, const TangentVector& prior_mean)
{
	ProcessModel m;
	m.prior_mean = prior_mean;
	auto gm = [&](const std::string& key, double unit)
	{
		const auto c = process_noise.child(key);
		GaussMarkov g;
		g.sigma = c.nonNegative("sigma") * unit;
		g.tau_s = c.positive("tau_s");
		return g;
	};
	constexpr double kDeg = M_PI / 180;
	m.noise.gyro_arw = process_noise.nonNegative("gyro_arw_deg_per_sqrt_h") * kDeg / 60;
	m.noise.gyro_bias = gm("gyro_bias_deg_per_h", kDeg / 3600);
	m.noise.accel_bias = gm("accel_bias_mg", 1e-3 * 9.80665);
	m.noise.jerk_psd = process_noise.positive("jerk_psd");
	m.noise.velocity_psd = process_noise.nonNegative("velocity_psd", m.noise.velocity_psd);
	m.noise.gravity_psd = process_noise.nonNegative("gravity_psd", m.noise.gravity_psd);
	m.noise.current = gm("current_mps", 1.0);
	m.noise.current_spatial_var_per_m = process_noise.nonNegative("current_spatial_var_per_m", 0.0);
	m.noise.current_vertical_var_per_m = process_noise.nonNegative("current_vertical_var_per_m", 0.0);
	m.current_far_distance_m = process_noise.nonNegative("current_far_distance_m", 0.0);
	m.noise.adcp_bias = gm("adcp_bias_mps", 1.0);
	m.noise.parameter_tau_s = process_noise.positive("parameter_tau_s");
	// Diagonal entries are logarithms: a relative σ is an absolute σ there. The
	// off-diagonal couplings get σ = relative σ × `parameter_coupling_fraction`
	// × the geometric mean of the sub-matrix's surge and sway entries.
	const double rel = process_noise.nonNegative("parameter_relative_sigma");
	const double coupling = process_noise.nonNegative("parameter_coupling_fraction", 0.05);
	for (int b = 0; b < 3; ++b)
	{
		const int at = idx::inertia + 6 * b;
		const double dx = std::exp(prior_mean[at + 0]), dy = std::exp(prior_mean[at + 4]);
		const double sigma_off = rel * coupling * std::sqrt(dx * dy);
		for (int i = 0; i < 6; ++i) m.noise.parameter_sigma[6 * b + i] = (i == 0 || i == 4) ? rel : sigma_off;
	}
	return m;
}

}  // namespace auvnav
