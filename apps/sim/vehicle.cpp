#include "vehicle.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace auvnav::sim
{
Eigen::Matrix3d skew(const Eigen::Vector3d& v)
{
	Eigen::Matrix3d S;
	S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
	return S;
}

Matrix6d coriolisMatrix(const Matrix6d& M, const Vector6d& nu)
{
	const Eigen::Vector3d a =
	    M.topLeftCorner<3, 3>() * nu.head<3>() + M.topRightCorner<3, 3>() * nu.tail<3>();
	const Eigen::Vector3d b =
	    M.bottomLeftCorner<3, 3>() * nu.head<3>() + M.bottomRightCorner<3, 3>() * nu.tail<3>();
	Matrix6d C = Matrix6d::Zero();
	C.topRightCorner<3, 3>() = -skew(a);
	C.bottomLeftCorner<3, 3>() = -skew(a);
	C.bottomRightCorner<3, 3>() = -skew(b);
	return C;
}

Eigen::Matrix<double, 6, Eigen::Dynamic> VehicleParams::configurationMatrix() const
{
	Eigen::Matrix<double, 6, Eigen::Dynamic> T(6, thrusters.size());
	for (std::size_t i = 0; i < thrusters.size(); ++i)
	{
		const Eigen::Vector3d d = thrusters[i].direction_b.normalized();
		T.col(i) << d, thrusters[i].position_b.cross(d);
	}
	return T;
}

namespace
{
Matrix6d diagonal6(const config::Node& n, const std::string& key)
{
	const auto v = n.numbers(key);
	if (v.size() != 6) n.fail(key, "expected 6 diagonal values");
	Matrix6d D = Matrix6d::Zero();
	for (int i = 0; i < 6; ++i) D(i, i) = v[i];
	return D;
}
}  // namespace

VehicleParams VehicleParams::fromConfig(const config::Node& n)
{
	VehicleParams p;
	p.M = diagonal6(n, "inertia_diag");
	p.D_l = diagonal6(n, "linear_damping_diag");
	p.D_q = diagonal6(n, "quadratic_damping_diag");
	for (int i = 0; i < 6; ++i)
	{
		if (!(p.M(i, i) > 0)) n.fail("inertia_diag", "all entries must be positive");
		if (p.D_l(i, i) < 0 || p.D_q(i, i) < 0) n.fail("linear_damping_diag", "damping must be >= 0");
	}
	p.weight_n = n.positive("weight_n");
	p.buoyancy_n = n.positive("buoyancy_n");
	p.mass_kg = p.weight_n / 9.80665;
	p.r_g_b = n.vector3("center_of_gravity_m");
	p.r_b_b = n.vector3("center_of_buoyancy_m");
	p.hull_height_m = n.positive("hull_height_m");
	p.surface_damping = n.vector3("surface_damping", Eigen::Vector3d::Zero());
	if ((p.surface_damping.array() < 0).any()) n.fail("surface_damping", "must be >= 0");
	for (int i = 0; i < 3; ++i)
		if (p.M(i, i) < p.mass_kg)
			n.fail("inertia_diag", "translational inertia must include the rigid-body mass weight_n/g");
	for (const auto& t : n.sequence("thrusters"))
	{
		t.markFreeForm("name");  // a label for people only
		Thruster th;
		th.position_b = t.vector3("position_m");
		th.direction_b = t.vector3("direction");
		if (th.direction_b.norm() < 1e-9) t.fail("direction", "must be a non-zero vector");
		th.max_force_n = t.positive("max_force_n");
		th.time_constant_s = t.positive("time_constant_s");
		th.efficiency_forward = t.positive("efficiency_forward", 1.0);
		th.efficiency_reverse = t.positive("efficiency_reverse", 1.0);
		p.thrusters.push_back(th);
	}
	if (p.thrusters.empty()) n.fail("thrusters", "at least one thruster is needed");
	if (n.has("tether"))
	{
		const auto t = n.child("tether");
		p.tether_enabled = t.boolean("enabled", false);
		p.tether_drag_n_per_m = t.nonNegative("drag_n_per_m_per_mps2");
		p.tether_extra_length_m = t.nonNegative("extra_length_m");
		p.tether_attach_b = t.vector3("attach_point_m");
	}
	return p;
}

Vehicle::Vehicle(VehicleParams p) : p_(std::move(p))
{
	M_inv_ = p_.M.inverse();  // constant, diagonal-dominant: computed once
	Matrix6d M_RB = Matrix6d::Zero();
	M_RB.topLeftCorner<3, 3>() = p_.mass_kg * Eigen::Matrix3d::Identity();
	M_RB.bottomRightCorner<3, 3>() = p_.M.bottomRightCorner<3, 3>();  // rotational inertia all rigid-body
	M_A_ = p_.M - M_RB;
	tcm_ = p_.configurationMatrix();
}

Vector6d Vehicle::restoring(const Eigen::Matrix3d& R_nb, double depth_m) const
{
	// Fraction of the hull under water: the hull spans depth ± h/2.
	const double h = p_.hull_height_m;
	const double wet = std::clamp((depth_m + 0.5 * h) / h, 0.0, 1.0);
	const double B = p_.buoyancy_n * wet;
	const Eigen::Vector3d k_b = R_nb.transpose() * Eigen::Vector3d::UnitZ();  // down, in body
	const Eigen::Vector3d f_w = p_.weight_n * k_b;
	const Eigen::Vector3d f_b = -B * k_b;
	Vector6d g;
	// g is what the equation subtracts: −(gravity + buoyancy forces/moments)
	g << -(f_w + f_b), -(p_.r_g_b.cross(f_w) + p_.r_b_b.cross(f_b));
	return g;
}

Eigen::VectorXd Vehicle::steadyThrust(const Eigen::VectorXd& cmd_n) const
{
	Eigen::VectorXd f(cmd_n.size());
	for (Eigen::Index i = 0; i < cmd_n.size(); ++i)
	{
		const auto& t = p_.thrusters[i];
		const double c = std::clamp(cmd_n[i], -t.max_force_n, t.max_force_n);
		f[i] = c * (c >= 0 ? t.efficiency_forward : t.efficiency_reverse);
	}
	return f;
}

VehicleRates Vehicle::rates(const VehicleState& x, const Eigen::VectorXd& cmd_n,
                            const Eigen::Vector3d& current_n) const
{
	const Eigen::Matrix3d R_nb = x.R_nb();
	const Eigen::Vector3d v_b = x.nu_b.head<3>();
	const Eigen::Vector3d w_b = x.nu_b.tail<3>();
	const Eigen::Vector3d vc_b = R_nb.transpose() * current_n;
	Vector6d nu_r = x.nu_b;
	nu_r.head<3>() -= vc_b;

	Vector6d tau = tcm_ * x.thrust_n;
	if (p_.tether_enabled)
	{
		// Horizontal drag on the wetted tether, proportional to its length.
		Eigen::Vector3d vr_n = R_nb * nu_r.head<3>();
		vr_n.z() = 0;
		const double length = std::max(0.0, x.p_n.z()) + p_.tether_extra_length_m;
		const Eigen::Vector3d f_n = -p_.tether_drag_n_per_m * length * vr_n.norm() * vr_n;
		const Eigen::Vector3d f_b = R_nb.transpose() * f_n;
		tau.head<3>() += f_b;
		tau.tail<3>() += p_.tether_attach_b.cross(f_b);
	}

	Matrix6d M_RB = p_.M - M_A_;
	Vector6d damping = p_.D_l * nu_r + p_.D_q * (nu_r.cwiseAbs().cwiseProduct(nu_r));
	// Wave-radiation damping near the surface: full while the hull top is out of
	// the water, fading over the next 0.2 m of submergence.
	const double hull_top_depth = x.p_n.z() - 0.5 * p_.hull_height_m;
	const double at_surface = std::clamp(1.0 - hull_top_depth / 0.2, 0.0, 1.0);
	if (at_surface > 0)
	{
		damping[2] += at_surface * p_.surface_damping[0] * nu_r[2];
		damping[3] += at_surface * p_.surface_damping[1] * nu_r[3];
		damping[4] += at_surface * p_.surface_damping[2] * nu_r[4];
	}
	// Current constant in n: its body-frame rate is −ω × v_c,b, which the added
	// mass must also accelerate (Fossen 2011, ch. 10).
	Vector6d current_accel = Vector6d::Zero();
	current_accel.head<3>() = -w_b.cross(vc_b);
	const Vector6d rhs = tau - coriolisMatrix(M_RB, x.nu_b) * x.nu_b - coriolisMatrix(M_A_, nu_r) * nu_r -
	                     damping - restoring(R_nb, x.p_n.z()) + M_A_ * current_accel;

	VehicleRates r;
	r.nu_dot_b = M_inv_ * rhs;
	r.p_dot_n = R_nb * v_b;
	const Eigen::Quaterniond w_q(0, w_b.x(), w_b.y(), w_b.z());
	const Eigen::Quaterniond qd = x.q_nb * w_q;
	r.q_dot << 0.5 * qd.w(), 0.5 * qd.x(), 0.5 * qd.y(), 0.5 * qd.z();
	const Eigen::VectorXd target = steadyThrust(cmd_n);
	r.thrust_dot.resize(target.size());
	for (Eigen::Index i = 0; i < target.size(); ++i)
		r.thrust_dot[i] = (target[i] - x.thrust_n[i]) / p_.thrusters[i].time_constant_s;
	return r;
}

namespace
{
VehicleState advance(const VehicleState& x, const VehicleRates& k, double h)
{
	VehicleState y = x;
	y.p_n += h * k.p_dot_n;
	y.q_nb.coeffs() += h * Eigen::Vector4d(k.q_dot[1], k.q_dot[2], k.q_dot[3], k.q_dot[0]);
	y.nu_b += h * k.nu_dot_b;
	y.thrust_n += h * k.thrust_dot;
	return y;
}
}  // namespace

void Vehicle::step(VehicleState& x, const Eigen::VectorXd& cmd_n, const Eigen::Vector3d& current_n,
                   double dt_s) const
{
	const VehicleRates k1 = rates(x, cmd_n, current_n);
	const VehicleRates k2 = rates(advance(x, k1, 0.5 * dt_s), cmd_n, current_n);
	const VehicleRates k3 = rates(advance(x, k2, 0.5 * dt_s), cmd_n, current_n);
	const VehicleRates k4 = rates(advance(x, k3, dt_s), cmd_n, current_n);
	x.p_n += dt_s / 6 * (k1.p_dot_n + 2 * k2.p_dot_n + 2 * k3.p_dot_n + k4.p_dot_n);
	const Eigen::Vector4d dq = dt_s / 6 * (k1.q_dot + 2 * k2.q_dot + 2 * k3.q_dot + k4.q_dot);
	x.q_nb.coeffs() += Eigen::Vector4d(dq[1], dq[2], dq[3], dq[0]);
	x.q_nb.normalize();
	x.nu_b += dt_s / 6 * (k1.nu_dot_b + 2 * k2.nu_dot_b + 2 * k3.nu_dot_b + k4.nu_dot_b);
	x.thrust_n += dt_s / 6 * (k1.thrust_dot + 2 * k2.thrust_dot + 2 * k3.thrust_dot + k4.thrust_dot);
}

}  // namespace auvnav::sim
