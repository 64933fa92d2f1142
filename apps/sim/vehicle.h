#pragma once
/** @file vehicle.h
 *  The simulator's "true" vehicle: a 6-DOF rigid body after Fossen (2011),
 *  deliberately richer than the simplified model the filter's model-aiding
 *  uses, so that model-aiding meets real mismatch:
 *    (M_RB + M_A) ν̇ = τ_thr + τ_tether − C_RB(ν)ν − C_A(ν_r)ν_r − D(ν_r)ν_r − g(R) (+ current term)
 *  with ν = [v_b; ω_b] over ground, ν_r = ν − [R_bn v_c; 0] relative to the
 *  water, full Coriolis/centripetal terms, linear + quadratic damping,
 *  restoring forces with partial buoyancy when breaching the surface,
 *  thrusters with saturation, efficiency errors and first-order lag, and an
 *  optional tether drag. Body frame FRD at the centre of gravity (frames.h).
 */
#include <auvnav/config.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace auvnav::sim
{
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct Thruster
{
	Eigen::Vector3d position_b{0, 0, 0};   //!< thruster location [m], body FRD
	Eigen::Vector3d direction_b{1, 0, 0};  //!< unit force direction for positive effort
	double max_force_n = 60;               //!< saturation [N]
	double time_constant_s = 0.15;         //!< first-order lag of the produced force
	double efficiency_forward = 1.0;       //!< true force / commanded force, positive effort
	double efficiency_reverse = 1.0;       //!< same, negative effort
};

struct VehicleParams
{
	Matrix6d M = Matrix6d::Identity();  //!< total inertia incl. added mass [kg, kg·m²]
	double mass_kg = 1;                 //!< rigid-body mass (rest of M is added mass)
	Matrix6d D_l = Matrix6d::Zero();    //!< linear damping
	Matrix6d D_q = Matrix6d::Zero();    //!< quadratic damping, τ_q = D_q (|ν_r| ∘ ν_r)
	double weight_n = 0, buoyancy_n = 0;
	Eigen::Vector3d r_g_b{0, 0, 0};  //!< centre of gravity [m], body
	Eigen::Vector3d r_b_b{0, 0, 0};  //!< centre of buoyancy [m], body
	double hull_height_m = 0.5;      //!< for partial buoyancy at the surface
	//! Extra damping [heave N/(m/s), roll, pitch N·m/(rad/s)] while the hull
	//! breaks the surface (wave radiation), faded out as the hull submerges.
	Eigen::Vector3d surface_damping{0, 0, 0};
	std::vector<Thruster> thrusters;
	// Tether drag (unmodelled by the filter): horizontal quadratic drag on the
	// wetted tether length, applied at the attachment point.
	bool tether_enabled = false;
	double tether_drag_n_per_m = 0;    //!< N per metre of tether per (m/s)²
	double tether_extra_length_m = 0;  //!< tether in the water beyond the depth
	Eigen::Vector3d tether_attach_b{0, 0, 0};

	/** Thruster configuration matrix (6 x n): column i = [d_i; r_i × d_i]. */
	Eigen::Matrix<double, 6, Eigen::Dynamic> configurationMatrix() const;

	static VehicleParams fromConfig(const config::Node& node);
};

struct VehicleState
{
	Eigen::Vector3d p_n{0, 0, 0};  //!< CG position, NED tangent frame [m]
	Eigen::Quaterniond q_nb{1, 0, 0, 0};
	Vector6d nu_b = Vector6d::Zero();  //!< [v_b; ω_b] over ground [m/s, rad/s]
	Eigen::VectorXd thrust_n;          //!< force each thruster produces now [N]

	Eigen::Matrix3d R_nb() const { return q_nb.toRotationMatrix(); }
	Eigen::Vector3d v_n() const { return q_nb * nu_b.head<3>(); }
};

/** Time derivative of the state, with the pieces the IMU model needs. */
struct VehicleRates
{
	Eigen::Vector3d p_dot_n;
	Eigen::Vector4d q_dot;  // (w, x, y, z)
	Vector6d nu_dot_b;
	Eigen::VectorXd thrust_dot;
};

class Vehicle
{
 public:
	explicit Vehicle(VehicleParams p);
	const VehicleParams& params() const { return p_; }

	/** State derivative given commanded thruster forces `cmd_n` (held
	 *  constant over the step) and the water current at the vehicle. */
	VehicleRates rates(const VehicleState& x, const Eigen::VectorXd& cmd_n,
	                   const Eigen::Vector3d& current_n) const;

	/** One classical Runge–Kutta step of `dt_s`; renormalises the quaternion. */
	void step(VehicleState& x, const Eigen::VectorXd& cmd_n, const Eigen::Vector3d& current_n,
	          double dt_s) const;

	/** Restoring forces/moments g(R) with the buoyancy reduced when the hull
	 *  breaches the surface (depth of the CG `depth_m`). */
	Vector6d restoring(const Eigen::Matrix3d& R_nb, double depth_m) const;

	/** Forces the thrusters really produce from commands (saturation and
	 *  direction-dependent efficiency); the lag is in the state. */
	Eigen::VectorXd steadyThrust(const Eigen::VectorXd& cmd_n) const;

 private:
	VehicleParams p_;
	Matrix6d M_inv_;
	Matrix6d M_A_;
	Eigen::Matrix<double, 6, Eigen::Dynamic> tcm_;
};

/** Coriolis–centripetal matrix of a symmetric inertia matrix (Fossen 2011, eq. 6.43). */
Matrix6d coriolisMatrix(const Matrix6d& M, const Vector6d& nu);

Eigen::Matrix3d skew(const Eigen::Vector3d& v);

}  // namespace auvnav::sim
