#include <auvnav/process_model.h>
#include <auvnav/so3.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace auvnav
{
double GaussMarkov::phi(double dt_s) const
{
	return std::exp(-dt_s / tau_s);
}
double GaussMarkov::variance(double dt_s) const
{
	const double p = phi(dt_s);
	return sigma * sigma * (1 - p * p);
}

double ExtraStateProcess::variance(double dt_s, double distance_m) const
{
	switch (kind)
	{
		case StateProcess::RandomConstant:
			return 0;
		case StateProcess::RandomWalk:
			return sigma * sigma * dt_s;
		case StateProcess::RandomWalkPerMetre:
			return sigma * sigma * distance_m;
		case StateProcess::GaussMarkov:
		{
			const double p = phi(dt_s);
			return sigma * sigma * (1 - p * p);
		}
	}
	return 0;
}

void ProcessModel::appendBlock(const StateBlockSpec& b)
{
	const std::string why = b.problem();
	if (!why.empty()) throw std::invalid_argument(why);
	const int d = b.dimension();
	if (dim() + d > idx::max_dim)
		throw std::invalid_argument(
		    "state block '" + b.name + "': no room (" + std::to_string(dim() - idx::core_dim) +
		    " plugin states already, at most " + std::to_string(idx::max_extra) + ")");
	const int at = dim();
	TangentVector mean = prior_mean;
	mean.conservativeResize(at + d);
	for (int i = 0; i < d; ++i)
	{
		extra.push_back({b.process, b.process_sigma, b.tau_s});
		mean[at + i] = b.mean.empty() ? 0.0 : b.mean[i];
	}
	prior_mean = mean;
}

NavState ProcessModel::propagate(const NavState& x, const Eigen::Vector3d& omega_ib_b,
                                 const Eigen::Vector3d& omega_ie_n, double dt) const
{
	return propagateTurned(x, omega_ib_b, so3::Exp(-omega_ie_n * dt), decay(dt));
}

NavState ProcessModel::propagateTurned(const NavState& x, const Eigen::Vector3d& omega_ib_b,
                                       const Eigen::Matrix3d& R_earth_turn, const StepDecay& step) const
{
	return propagateTurned(x, R_earth_turn, so3::Exp((omega_ib_b - x.b_w) * step.dt_s), step);
}

StepDecay ProcessModel::decay(double dt) const
{
	StepDecay d;
	d.dt_s = dt;
	d.gyro_bias = noise.gyro_bias.phi(dt);
	d.accel_bias = noise.accel_bias.phi(dt);
	d.current = noise.current.phi(dt);
	d.adcp_bias = noise.adcp_bias.phi(dt);
	d.parameters = std::exp(-dt / noise.parameter_tau_s);
	for (std::size_t i = 0; i < extra.size() && i < d.extra.size(); ++i) d.extra[i] = extra[i].phi(dt);
	return d;
}

TangentVector ProcessModel::diagonalTailFactors(const StepDecay& step) const
{
	TangentVector a(dim() - idx::adcp_bias);
	a.head<idx::inertia - idx::adcp_bias>().setConstant(step.adcp_bias);
	a.segment<idx::core_dim - idx::inertia>(idx::inertia - idx::adcp_bias).setConstant(step.parameters);
	for (std::size_t i = 0; i < extra.size(); ++i)
		a[idx::core_dim - idx::adcp_bias + static_cast<int>(i)] =
		    extra[i].kind == StateProcess::GaussMarkov ? step.extra[i] : 1.0;
	return a;
}

namespace
{
/** A Gauss–Markov state relaxed to its prior mean over a step: φx + (1 − φ)μ.
 *  (Always inlined: it runs per member and sigma point, where a call's
 *  overhead outweighs these few multiply-adds.) */
template <typename V, typename M>
[[gnu::always_inline]] inline auto relaxToPriorMean(const V& v, double phi, const M& mu)
{
	return (v * phi + (1 - phi) * mu).eval();
}
}  // namespace

NavState ProcessModel::propagateTurned(const NavState& x, const Eigen::Matrix3d& R_earth_turn,
                                       const Eigen::Matrix3d& R_body_turn, const StepDecay& step) const
{
	if (x.dim() != dim())
		throw std::invalid_argument("ProcessModel::propagate: a " + std::to_string(x.dim()) +
		                            "-state, the model has " + std::to_string(dim()) + " coordinates");
	NavState y;
	y.extra.resize(x.extra.size());
	propagateInertialInto(x, R_earth_turn, R_body_turn, step, y);
	// Member by member (this runs per sigma point), the same sums as
	// applyLinearRows on the flat state followed by the prior-mean terms.
	y.b_adcp = relaxToPriorMean(x.b_adcp, step.adcp_bias, prior_mean.segment<2>(idx::adcp_bias));
	const auto relax23 = [&](const Eigen::Matrix<double, 2, 3>& m, int at)
	{
		Eigen::Matrix<double, 2, 3> out;
		for (int r = 0; r < 2; ++r)
			for (int c = 0; c < 3; ++c)
				out(r, c) = m(r, c) * step.parameters + (1 - step.parameters) * prior_mean[at + 3 * r + c];
		return out;
	};
	y.M_sub = relax23(x.M_sub, idx::inertia);
	y.Dl_sub = relax23(x.Dl_sub, idx::damping_lin);
	y.Dq_sub = relax23(x.Dq_sub, idx::damping_quad);
	for (int i = 0; i < static_cast<int>(x.extra.size()); ++i)
	{
		const double decayed =
		    extra[i].kind == StateProcess::GaussMarkov ? x.extra[i] * step.extra[i] : x.extra[i];
		y.extra[i] = decayed + (1 - step.extra[i]) * prior_mean[idx::extra + i];
	}
	return y;
}

void ProcessModel::propagateInertialInto(const NavState& x, const Eigen::Matrix3d& R_earth_turn,
                                         const Eigen::Matrix3d& R_body_turn, const StepDecay& step,
                                         NavState& y) const
{
	// Body rotation relative to inertial space, then undo the turn of the
	// Earth-fixed navigation frame.
	y.R_nb = R_earth_turn * x.R_nb * R_body_turn;
	const double dt = step.dt_s;
	// p += v dt + ½ a dt² (old v), then v += a dt; a and g are constant.
	y.p_n = x.p_n + (dt * x.v_n + (0.5 * dt * dt) * x.a_n);
	y.v_n = x.v_n + dt * x.a_n;
	y.a_n = x.a_n;
	y.g = x.g;
	y.b_a = relaxToPriorMean(x.b_a, step.accel_bias, prior_mean.segment<3>(idx::acc_bias));
	y.current_vehicle_ne =
	    relaxToPriorMean(x.current_vehicle_ne, step.current, prior_mean.segment<2>(idx::current_vehicle));
	y.current_far_ne =
	    relaxToPriorMean(x.current_far_ne, step.current, prior_mean.segment<2>(idx::current_far));
	if (current_far_distance_m > 0)
	{
		// The vehicle (and the far point D below it) moved Δz along the linear
		// profile the ADCP observes: both currents shift by Δz times its
		// gradient, which stays; exact for any step.
		const double dz_m = y.p_n.z() - x.p_n.z();
		const Eigen::Vector2d shift =
		    (dz_m / current_far_distance_m) * (y.current_far_ne - y.current_vehicle_ne);
		y.current_vehicle_ne += shift;
		y.current_far_ne += shift;
	}
	const double phi_g = step.gyro_bias;
	y.b_w = phi_g * x.b_w + (1 - phi_g) * prior_mean.segment<3>(idx::gyro_bias);
}

template <typename AddEntry>
void ProcessModel::forEachNoiseEntry(double dt, double speed_through_water_mps, double vertical_speed_mps,
                                     AddEntry&& add) const
{
	const double arw_var = noise.gyro_arw * noise.gyro_arw * dt, gyro_bias_var = noise.gyro_bias.variance(dt);
	for (int k = 0; k < 3; ++k)
	{
		add(idx::att + k, idx::att + k, arw_var);
		add(idx::gyro_bias + k, idx::gyro_bias + k, gyro_bias_var);
	}
	// White jerk integrated exactly into (p, v, a), per axis.
	const double q = noise.jerk_psd;
	const double dt2 = dt * dt, dt3 = dt2 * dt, dt4 = dt3 * dt, dt5 = dt4 * dt;
	for (int k = 0; k < 3; ++k)
	{
		const int p = idx::pos + k, v = idx::vel + k, a = idx::acc + k;
		const double pv = q * dt4 / 8 + noise.velocity_psd * dt2 / 2, pa = q * dt3 / 6, va = q * dt2 / 2;
		add(p, p, q * dt5 / 20 + noise.velocity_psd * dt3 / 3);
		add(p, v, pv);
		add(v, p, pv);
		add(p, a, pa);
		add(a, p, pa);
		add(v, v, q * dt3 / 3 + noise.velocity_psd * dt);
		add(v, a, va);
		add(a, v, va);
		add(a, a, q * dt);
	}
	add(idx::gravity, idx::gravity, noise.gravity_psd * dt);
	const double accel_bias_var = noise.accel_bias.variance(dt);
	for (int k = 0; k < 3; ++k) add(idx::acc_bias + k, idx::acc_bias + k, accel_bias_var);
	double current_var =
	    noise.current.variance(dt) + noise.current_spatial_var_per_m * speed_through_water_mps * dt;
	current_var += noise.current_vertical_var_per_m * std::abs(vertical_speed_mps) * dt;
	for (int k = 0; k < 4; ++k) add(idx::current_vehicle + k, idx::current_vehicle + k, current_var);
	const double adcp_bias_var = noise.adcp_bias.variance(dt);
	for (int k = 0; k < 2; ++k) add(idx::adcp_bias + k, idx::adcp_bias + k, adcp_bias_var);
	const double phi_p = std::exp(-dt / noise.parameter_tau_s);
	for (int i = 0; i < 18; ++i)
		add(idx::inertia + i, idx::inertia + i,
		    noise.parameter_sigma[i] * noise.parameter_sigma[i] * (1 - phi_p * phi_p));
	// The distance moved through the water over the step, for per-metre
	// plugin states (the currents' spatial noise above uses its horizontal part).
	const double distance_m = std::hypot(speed_through_water_mps, vertical_speed_mps) * dt;
	for (std::size_t i = 0; i < extra.size(); ++i)
		add(idx::extra + static_cast<int>(i), idx::extra + static_cast<int>(i),
		    extra[i].variance(dt, distance_m));
}

Covariance ProcessModel::noiseCovariance(double dt, double speed_through_water_mps,
                                         double vertical_speed_mps) const
{
	Covariance Q = Covariance::Zero(dim(), dim());
	forEachNoiseEntry(dt, speed_through_water_mps, vertical_speed_mps,
	                  [&](int i, int j, double q) { Q(i, j) = q; });
	return Q;
}

void ProcessModel::addNoiseCovariance(Covariance& P, double dt, double speed_through_water_mps,
                                      double vertical_speed_mps) const
{
	forEachNoiseEntry(dt, speed_through_water_mps, vertical_speed_mps,
	                  [&](int i, int j, double q) { P(i, j) += q; });
}

}  // namespace auvnav
