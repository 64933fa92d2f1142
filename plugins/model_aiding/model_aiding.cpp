#include "model_aiding.h"

#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/so3.h>

#include "plugin_common.h"

#include <cmath>

namespace auvnav::plugins
{
namespace
{
Matrix6d diagonal6(const config::Node& n, const std::string& key)
{
	const auto v = n.numbers(key);
	if (v.size() != 6) n.fail(key, "expected 6 diagonal values");
	Matrix6d D = Matrix6d::Zero();
	for (int i = 0; i < 6; ++i)
	{
		if (!(v[i] >= 0)) n.fail(key, "entries must be >= 0");
		D(i, i) = v[i];
	}
	return D;
}

/** Writes the 2x3 sub-matrix (rows x, y; columns x, y, ψ) into M. */
void place(Matrix6d& M, const Eigen::Matrix<double, 2, 3>& sub)
{
	for (int r = 0; r < 2; ++r)
	{
		M(r, 0) = sub(r, 0);
		M(r, 1) = sub(r, 1);
		M(r, 5) = sub(r, 2);
	}
}
/** physicalSub of the three parameter sub-matrices, their six logarithms
 *  taken out as one Eigen exp (two lanes a step, against six calls
 *  of the C library's exp: this runs once per sigma point, 87 of them an
 *  update). The two differ by 2 ulps at most (12 M values over [−20, 20]
 *  against std::exp). */
struct PhysicalSubs
{
	Eigen::Matrix<double, 2, 3> M, D_l, D_q;
	explicit PhysicalSubs(const NavState& x) : M(x.M_sub), D_l(x.Dl_sub), D_q(x.Dq_sub)
	{
		Eigen::Array<double, 6, 1> e;
		e << M(0, 0), M(1, 1), D_l(0, 0), D_l(1, 1), D_q(0, 0), D_q(1, 1);
		e = e.exp();
		M(0, 0) = e[0], M(1, 1) = e[1], D_l(0, 0) = e[2], D_l(1, 1) = e[3], D_q(0, 0) = e[4],
		     D_q(1, 1) = e[5];
	}
};

/** ν (velocity relative to the water, turn rate) and ν̇ at the body origin. */
void bodyMotion(const NavState& x, const Eigen::Vector3d& omega_b, const Eigen::Vector3d& alpha_b,
                const Eigen::Vector3d& r_imu_b, Vector6d& nu, Vector6d& nu_dot)
{
	const Eigen::Matrix3d Rt = x.R_nb.transpose();
	const Eigen::Vector3d c_n(x.current_vehicle_ne.x(), x.current_vehicle_ne.y(), 0.0);
	nu << Rt * (x.v_n - c_n) - omega_b.cross(r_imu_b), omega_b;
	nu_dot << Rt * x.a_n - alpha_b.cross(r_imu_b) - omega_b.cross(omega_b.cross(r_imu_b)), alpha_b;
}
}  // namespace

Vector6d restoringWrench(const VehicleModel& vm, const Eigen::Matrix3d& R_nb)
{
	const Eigen::Vector3d k_b = R_nb.transpose() * Eigen::Vector3d::UnitZ();  // down, body axes
	Vector6d g;
	g << -(vm.weight_n - vm.buoyancy_n) * k_b,
	    -(vm.r_g_b.cross(vm.weight_n * k_b) - vm.r_b_b.cross(vm.buoyancy_n * k_b));
	return g;
}

Vector6d coriolisWrench(const Matrix6d& M, const Vector6d& nu)
{
	const Matrix6d Ms = 0.5 * (M + M.transpose());
	const Vector6d p = Ms * nu;
	const Eigen::Vector3d v = nu.head<3>(), w = nu.tail<3>(), p1 = p.head<3>(), p2 = p.tail<3>();
	Vector6d c;
	c << w.cross(p1), v.cross(p1) + w.cross(p2);
	return c;
}

Vector6d predictedWrench(const VehicleModel& vm, const NavState& x, const Eigen::Vector3d& omega_b,
                         const Eigen::Vector3d& alpha_b, const Eigen::Vector3d& r_imu_b)
{
	Vector6d nu, nu_dot;
	bodyMotion(x, omega_b, alpha_b, r_imu_b, nu, nu_dot);
	Matrix6d M = vm.M, D_l = vm.D_l, D_q = vm.D_q;
	const PhysicalSubs subs(x);
	place(M, subs.M);
	place(D_l, subs.D_l);
	place(D_q, subs.D_q);
	Vector6d inertial = M * nu_dot;
	if (vm.coriolis)
	{
		// ν̇_r = a_b − ω × v_r (a current constant in n turns in body axes).
		nu_dot.head<3>() -= omega_b.cross(nu.head<3>());
		inertial = M * nu_dot + coriolisWrench(M, nu);
	}
	return inertial + D_l * nu + D_q * nu.cwiseAbs().cwiseProduct(nu) + restoringWrench(vm, x.R_nb);
}

namespace
{
/** A v for A = diag(base) with rows x, y replaced by `sub` in columns x, y, ψ
 *  (what place() makes of a diagonal matrix). */
Vector6d applyPlaced(const Matrix6d& base, const Eigen::Matrix<double, 2, 3>& sub, const Vector6d& v)
{
	Vector6d y;
	for (int r = 0; r < 2; ++r) y[r] = sub(r, 0) * v[0] + sub(r, 1) * v[1] + sub(r, 2) * v[5];
	for (int i = 2; i < 6; ++i) y[i] = base(i, i) * v[i];
	return y;
}
}  // namespace

Vector6d predictedWrenchDiagonal(const VehicleModel& vm, const NavState& x, const Eigen::Vector3d& omega_b,
                                 const Eigen::Vector3d& alpha_b, const Eigen::Vector3d& r_imu_b)
{
	Vector6d nu, nu_dot;
	bodyMotion(x, omega_b, alpha_b, r_imu_b, nu, nu_dot);
	const PhysicalSubs subs(x);
	const Eigen::Matrix<double, 2, 3>& M_sub = subs.M;
	Vector6d inertial;
	if (vm.coriolis)
	{
		nu_dot.head<3>() -= omega_b.cross(nu.head<3>());
		// C(ν)ν with Ms = ½ (M + Mᵀ): the diagonal, and the sub-block's
		// off-diagonal pairs (x, y), (x, ψ), (y, ψ) averaged with zeros or
		// with each other.
		const double m_xy = 0.5 * (M_sub(0, 1) + M_sub(1, 0)), m_xpsi = 0.5 * M_sub(0, 2),
		             m_ypsi = 0.5 * M_sub(1, 2);
		Vector6d p;
		p[0] = M_sub(0, 0) * nu[0] + m_xy * nu[1] + m_xpsi * nu[5];
		p[1] = m_xy * nu[0] + M_sub(1, 1) * nu[1] + m_ypsi * nu[5];
		for (int i = 2; i < 5; ++i) p[i] = vm.M(i, i) * nu[i];
		p[5] = m_xpsi * nu[0] + m_ypsi * nu[1] + vm.M(5, 5) * nu[5];
		const Eigen::Vector3d v = nu.head<3>(), w = nu.tail<3>(), p1 = p.head<3>(), p2 = p.tail<3>();
		Vector6d c;
		c << w.cross(p1), v.cross(p1) + w.cross(p2);
		inertial = applyPlaced(vm.M, M_sub, nu_dot) + c;
	}
	else
		inertial = applyPlaced(vm.M, M_sub, nu_dot);
	return inertial + applyPlaced(vm.D_l, subs.D_l, nu) +
	       applyPlaced(vm.D_q, subs.D_q, nu.cwiseAbs().cwiseProduct(nu)) + restoringWrench(vm, x.R_nb);
}

ModelAidingModel::ModelAidingModel(const config::Node& cfg, const std::string& /*label*/) : GatedModel(cfg)
{
	vm_.M = diagonal6(cfg, "inertia_diag");
	vm_.D_l = diagonal6(cfg, "linear_damping_diag");
	vm_.D_q = diagonal6(cfg, "quadratic_damping_diag");
	vm_.weight_n = cfg.positive("weight_n");
	vm_.buoyancy_n = cfg.positive("buoyancy_n");
	vm_.r_g_b = cfg.vector3("center_of_gravity_m");
	vm_.r_b_b = cfg.vector3("center_of_buoyancy_m");
	vm_.coriolis = cfg.boolean("coriolis", true);
	const std::string unit = cfg.string("effort_unit", "force");
	if (unit == "rpm")
	{
		rpm_ = true;
		rpm_coefficient_ = cfg.positive("rpm_coefficient");
	}
	else if (unit != "force")
		cfg.fail("effort_unit", "expected 'force' or 'rpm', got '" + unit + "'");
	const auto thrusters = cfg.sequence("thrusters");
	std::vector<double> time_constants_s;
	T_.resize(6, static_cast<Eigen::Index>(thrusters.size()));
	for (std::size_t i = 0; i < thrusters.size(); ++i)
	{
		const auto& t = thrusters[i];
		const Eigen::Vector3d d = t.vector3("direction");
		if (d.norm() < 1e-9) t.fail("direction", "must be non-zero");
		const Eigen::Vector3d r = t.vector3("position_m");
		T_.col(static_cast<Eigen::Index>(i)) << d.normalized(), r.cross(d.normalized());
		gain_forward_.push_back(t.positive("gain_forward", 1.0));
		gain_reverse_.push_back(t.positive("gain_reverse", 1.0));
		thrust_lag_ = thrust_lag_ || t.has("time_constant_s");
		time_constants_s.push_back(t.inRange("time_constant_s", 0.0, 10.0, 0.0));
	}
	response_ = ThrustResponse(time_constants_s);
	time_constant_sigma_s_ = cfg.inRange("time_constant_sigma_s", 0.0, 10.0, 0.0);
	if (thrusters.empty()) cfg.fail("thrusters", "at least one thruster");
	const auto s = cfg.numbers("sigma");
	if (s.size() != 6) cfg.fail("sigma", "expected 6 values: forces [N] x, y, z and torques [N m] x, y, z");
	for (int i = 0; i < 6; ++i)
	{
		if (!(s[i] > 0)) cfg.fail("sigma", "all entries must be positive");
		sigma_[i] = s[i];
	}
	surface_depth_m_ = cfg.nonNegative("surface_depth_m", surface_depth_m_);
	surface_factor_ = cfg.inRange("surface_noise_factor", 1.0, 1e6, surface_factor_);
	if (cfg.has("dofs"))
	{
		for (double d : cfg.numbers("dofs"))
		{
			if (d < 0 || d > 5 || std::floor(d) != d) cfg.fail("dofs", "expected indices 0..5");
			dofs_.push_back(static_cast<int>(d));
		}
	}
	else
		dofs_ = {0, 1, 2, 3, 4, 5};
	auto diagonal = [](const Matrix6d& A) { return (A - Matrix6d(A.diagonal().asDiagonal())).isZero(0); };
	diagonal_base_ = diagonal(vm_.M) && diagonal(vm_.D_l) && diagonal(vm_.D_q);
}

Eigen::VectorXd ModelAidingModel::thrusterForces(const std::vector<double>& effort) const
{
	Eigen::VectorXd f(static_cast<Eigen::Index>(effort.size()));
	for (std::size_t i = 0; i < effort.size(); ++i)
	{
		const double u = effort[i];
		const double force = rpm_ ? rpm_coefficient_ * u * std::abs(u) : u;
		f[static_cast<Eigen::Index>(i)] = force * (force >= 0 ? gain_forward_[i] : gain_reverse_[i]);
	}
	return f;
}

Vector6d ModelAidingModel::thrustWrench(const std::vector<double>& effort) const
{
	return T_ * thrusterForces(effort);
}

bool ModelAidingModel::laggedWrench(const std::vector<double>& effort, const FilterContext& ctx,
                                    Vector6d& wrench, Vector6d& rate, std::string& why)
{
	const Eigen::VectorXd command = thrusterForces(effort);
	const double t_obs = ctx.t_measurement_s;
	if (!response_.started() || t_obs < response_.time_s() || t_obs - response_.time_s() > kMaxCommandGap_s)
	{
		response_.restart(t_obs, command);
		why = "thrust response (re)started: no earlier command within " + std::to_string(kMaxCommandGap_s) +
		      " s";
		return false;
	}
	// The filter's angular acceleration lags the motion: the thrust it is
	// compared with is taken as much earlier.
	const double t_eval = std::min(ctx.t_s, t_obs) - ctx.alpha_delay_s;
	wrench = T_ * response_.forceAt(t_eval);
	rate = T_ * response_.rateAt(t_eval);
	response_.hold(t_obs, command);
	return true;
}

PrepareStatus ModelAidingModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                          std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	const auto* thr = observationAs<auvnav::obs::CObservationThrusters>(obs, why);
	if (!thr) return PrepareStatus::Invalid;
	if (static_cast<Eigen::Index>(thr->effort.size()) != T_.cols())
	{
		why = "observation has " + std::to_string(thr->effort.size()) + " thrusters, the configuration " +
		      std::to_string(T_.cols());
		return PrepareStatus::Invalid;
	}
	const bool rpm_obs = thr->unit == auvnav::obs::EffortUnit::Speed_rpm;
	if (rpm_obs != rpm_)
	{
		why = "effort unit of the observation differs from effort_unit";
		return PrepareStatus::Invalid;
	}
	for (double e : thr->effort)
		if (!std::isfinite(e))
		{
			why = "non-finite thruster effort";
			return PrepareStatus::Invalid;
		}
	Vector6d tau, tau_rate = Vector6d::Zero();
	if (!thrust_lag_)
		tau = thrustWrench(thr->effort);
	else if (!laggedWrench(thr->effort, ctx, tau, tau_rate, why))
		return PrepareStatus::Skip;
	// Near the surface waves and the breaching hull make the model poor.
	const bool shallow = ctx.mean && ctx.mean->p_n.z() < surface_depth_m_;
	const double factor = shallow ? surface_factor_ : 1.0;
	Measurement m;
	const int k = static_cast<int>(dofs_.size());
	m.z.resize(k);
	m.R = Eigen::MatrixXd::Zero(k, k);
	for (int i = 0; i < k; ++i)
	{
		m.z[i] = tau[dofs_[i]];
		m.R(i, i) = std::pow(factor * sigma_[dofs_[i]], 2);
	}
	// A time constant off by δτ shifts the response by about δτ: the wrench
	// is then off by its rate times δτ, in every row together.
	for (int i = 0; i < k; ++i)
		for (int j = 0; j < k; ++j)
			m.R(i, j) += std::pow(time_constant_sigma_s_, 2) * tau_rate[dofs_[i]] * tau_rate[dofs_[j]];
	m.label = "wrench";
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

bool ModelAidingModel::doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
                                 Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (z_pred.size() != static_cast<Eigen::Index>(dofs_.size())) return false;
	const Eigen::Vector3d omega_b = ctx.omega_ib_b - x.b_w - x.R_nb.transpose() * ctx.omega_ie_n;
	const Vector6d w = diagonal_base_
	                       ? predictedWrenchDiagonal(vm_, x, omega_b, ctx.alpha_b, ctx.imu_position_b)
	                       : predictedWrench(vm_, x, omega_b, ctx.alpha_b, ctx.imu_position_b);
	for (std::size_t i = 0; i < dofs_.size(); ++i) z_pred[static_cast<Eigen::Index>(i)] = w[dofs_[i]];
	(void)m;
	return true;
}

}  // namespace auvnav::plugins
