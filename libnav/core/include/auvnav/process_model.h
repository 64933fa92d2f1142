#pragma once
/** @file process_model.h
 *  The inertial process model (Arnold & Medagoda 2018, II-A, done right):
 *  constant acceleration for translation (with the ½·a·dt² term), attitude
 *  from the gyro minus its bias minus the Earth rate, exact first-order
 *  Gauss–Markov discretisation for biases, currents and model parameters for
 *  any dt, and process noise that scales with dt (not dt²).
 */
#include <auvnav/state.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace auvnav
{
/** A first-order Gauss–Markov process: x' = φ(x − μ) + μ, φ = e^{−dt/τ},
 *  added variance σ²(1 − φ²) (exact for any dt). */
struct GaussMarkov
{
	double sigma = 0;     //!< stationary standard deviation
	double tau_s = 3600;  //!< correlation time [s]
	double phi(double dt_s) const;
	double variance(double dt_s) const;
};

struct ProcessNoise
{
	double gyro_arw = 0;         //!< gyro angle random walk [rad/√s]
	GaussMarkov gyro_bias;       //!< [rad/s]
	GaussMarkov accel_bias;      //!< [m/s²]
	double jerk_psd = 0.01;      //!< white jerk PSD of the constant-acceleration model [(m/s³)²·s]
	double velocity_psd = 1e-6;  //!< extra white velocity noise [(m/s)²/s]
	double gravity_psd = 1e-12;  //!< gravity random walk [(m/s²)²/s]
	GaussMarkov current;         //!< water currents [m/s]
	double current_spatial_var_per_m =
	    0;  //!< extra current variance per metre moved through water [(m/s)²/m]
	//! Current variance added per metre of depth change [(m/s)²/m]: the part of
	//! the vertical profile the linear vehicle/far model does not capture.
	double current_vertical_var_per_m = 0;
	GaussMarkov adcp_bias;          //!< [m/s]
	double parameter_tau_s = 3600;  //!< model parameter correlation time [s]
	//! Stationary σ of the 18 model parameters in tangent order (on the log
	//! scale for the diagonal entries, see state.h).
	Eigen::Matrix<double, 18, 1> parameter_sigma = Eigen::Matrix<double, 18, 1>::Zero();
};

/** The process of one plugin-owned coordinate (state.h StateProcess). */
struct ExtraStateProcess
{
	StateProcess kind = StateProcess::RandomConstant;
	double sigma = 0, tau_s = 0;
	double phi(double dt_s) const
	{
		return kind == StateProcess::GaussMarkov ? std::exp(-dt_s / tau_s) : 1.0;
	}
	/** Added variance over a step of dt_s in which the vehicle moved
	 *  distance_m through the water (RandomWalkPerMetre reads only that). */
	double variance(double dt_s, double distance_m) const;
};

/** What one step of dt_s does to the Gauss–Markov states: their decay
 *  factors φ = exp(−dt/τ) (1 for a random walk or constant), computed once
 *  per step by ProcessModel::decay rather than per sigma point. */
struct StepDecay
{
	double dt_s = 0;
	double gyro_bias = 1, accel_bias = 1, current = 1, adcp_bias = 1, parameters = 1;
	std::array<double, idx::max_extra> extra{};  //!< plugin-owned coordinates, in order
};

struct ProcessModel
{
	ProcessNoise noise;
	//! Plugin-owned coordinates 43…, in order (all linear and independent).
	std::vector<ExtraStateProcess> extra;
	/** Distance below the vehicle [m] the far-current state refers to: the
	 *  current profile is c(d) = c_vehicle + (d / D)(c_far − c_vehicle) for a
	 *  point d metres below the vehicle (ADCP plugin, Arnold & Medagoda II-C).
	 *  When > 0 both currents follow that profile as the vehicle changes depth
	 *  (our extension: diving by Δz shifts both by Δz·(c_far − c_vehicle)/D,
	 *  the profile's gradient, which stays); 0 disables the transport. */
	double current_far_distance_m = 0;
	/** Means the Gauss–Markov states relax to (tangent order, Euclidean part):
	 *  zero biases and currents, the system-identification parameter prior. */
	TangentVector prior_mean = TangentVector::Zero(idx::core_dim);

	/** State dimension: 43 + plugin-owned coordinates. */
	int dim() const { return idx::core_dim + static_cast<int>(extra.size()); }
	/** Appends a plugin's block (its mean becomes the prior mean). Throws
	 *  std::invalid_argument if the block is unusable or there is no room. */
	void appendBlock(const StateBlockSpec& block);
	/** Mean propagation of one state by `dt_s` with raw gyro `omega_ib_b` and
	 *  Earth rate `omega_ie_n` (a pure function: used per sigma point). */
	NavState propagate(const NavState& x, const Eigen::Vector3d& omega_ib_b,
	                   const Eigen::Vector3d& omega_ie_n, double dt_s) const;
	/** The same with the navigation frame's turn over the step given,
	 *  R_earth_turn = Exp(−ω_ie_n dt) (computed once for all sigma points). */
	NavState propagateTurned(const NavState& x, const Eigen::Vector3d& omega_ib_b,
	                         const Eigen::Matrix3d& R_earth_turn, const StepDecay& step) const;
	/** The same with the body's turn given too, R_body_turn =
	 *  Exp((ω_ib_b − x.b_w) dt) (shared by sigma points with the centre's bias). */
	NavState propagateTurned(const NavState& x, const Eigen::Matrix3d& R_earth_turn,
	                         const Eigen::Matrix3d& R_body_turn, const StepDecay& step) const;
	/** The inertial members of propagateTurned (attitude … position and the
	 *  two currents: the first idx::adcp_bias coordinates) into y, bit for
	 *  bit; y's other members are left as they are. y is not x. For sigma
	 *  points whose affine rest is never read (the prediction takes it from
	 *  the centre's), with no state built or copied per point. */
	void propagateInertialInto(const NavState& x, const Eigen::Matrix3d& R_earth_turn,
	                           const Eigen::Matrix3d& R_body_turn, const StepDecay& step, NavState& y) const;
	/** The decay factors of a step of `dt_s` (StepDecay). */
	StepDecay decay(double dt_s) const;

	/** Process noise covariance over `dt_s` (tangent space, dim() × dim()). `speed_through_water_mps`
	 *  (horizontal) scales the spatial part of the current noise, `vertical_speed_mps` (its
	 *  magnitude) the vertical part; both make the distance through the water,
	 *  hypot(speed_through_water, vertical_speed) · dt, that a plugin state's
	 *  RandomWalkPerMetre process scales with. */
	Covariance noiseCovariance(double dt_s, double speed_through_water_mps,
	                           double vertical_speed_mps = 0) const;
	/** P += noiseCovariance(…), touching only Q's non-zero entries (the same
	 *  sums: the filter's every-tick form, without a dense Q). */
	void addNoiseCovariance(Covariance& P, double dt_s, double speed_through_water_mps,
	                        double vertical_speed_mps = 0) const;

	/** The linear part (everything but attitude and gyro bias) as the map
	 *  x_L ↦ A x_L + b in tangent coordinates; applies A to the rows of `M`
	 *  (tangent rows 6…; rows 0..5 untouched). M has the first idx::adcp_bias
	 *  rows (the inertial block and the currents) or more: rows past those
	 *  only as far as M has them. */
	template <typename Derived>
	void applyLinearRows(Eigen::MatrixBase<Derived>& M, double dt_s) const
	{
		applyLinearRows(M, decay(dt_s));
	}
	/** The same with the step's decay factors given. */
	template <typename Derived>
	void applyLinearRows(Eigen::MatrixBase<Derived>& M, const StepDecay& step) const;
	/** A's rows from idx::adcp_bias on (ADCP bias, model parameters, plugin
	 *  coordinates) are diagonal: each coordinate only decays. Their factors,
	 *  in order (dim() − idx::adcp_bias of them), so that A P Aᵀ over that
	 *  block is P_ij · a_i a_j (applyLinearRows on those rows does the same). */
	TangentVector diagonalTailFactors(const StepDecay& step) const;

 private:
	/** Calls add(i, j, q) once for every non-zero entry q of the process noise. */
	template <typename AddEntry>
	void forEachNoiseEntry(double dt_s, double speed_through_water_mps, double vertical_speed_mps,
	                       AddEntry&& add) const;
};

// ---------------------------------------------------------------- inline
template <typename Derived>
void ProcessModel::applyLinearRows(Eigen::MatrixBase<Derived>& M, const StepDecay& step) const
{
	const double dt_s = step.dt_s;
	// p += v dt + ½ a dt² (old v), then v += a dt; a and g are constant.
	M.template middleRows<3>(idx::pos) +=
	    dt_s * M.template middleRows<3>(idx::vel) + (0.5 * dt_s * dt_s) * M.template middleRows<3>(idx::acc);
	M.template middleRows<3>(idx::vel) += dt_s * M.template middleRows<3>(idx::acc);
	M.template middleRows<3>(idx::acc_bias) *= step.accel_bias;
	M.template middleRows<4>(idx::current_vehicle) *= step.current;  // both current states
	if (M.rows() < idx::core_dim) return;                            // the inertial block and currents only
	M.template middleRows<2>(idx::adcp_bias) *= step.adcp_bias;
	M.template middleRows<18>(idx::inertia) *= step.parameters;
	const int extra_rows =
	    std::min<int>(static_cast<int>(M.rows()) - idx::core_dim, static_cast<int>(extra.size()));
	for (int i = 0; i < extra_rows; ++i)
		if (extra[i].kind == StateProcess::GaussMarkov) M.row(idx::extra + i) *= step.extra[i];
}

}  // namespace auvnav
