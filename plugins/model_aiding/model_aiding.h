#pragma once
/** @file model_aiding.h
 *  Model-aiding update (plugin "model_aiding"; Arnold & Medagoda 2018, II-B).
 *
 *  Observation: auvnav::obs::CObservationThrusters, the commanded effort of
 *  each thruster. Measurement: the body wrench they produce,
 *      z = T · f(u)   (6: forces [N] and torques [N·m], body FRD at the CG)
 *  with T the thruster configuration matrix ([d_i; r_i × d_i] per column) and
 *  f the per-thruster force model (force commands × forward/reverse gain, or
 *  k·rpm·|rpm|). Prediction with Fossen's simplified model:
 *      h = M·ν̇_r + C(ν_r)·ν_r + D_l·ν_r + D_q·(|ν_r| ∘ ν_r) + g(R_nb)
 *      ν_r = [v_b; ω_b],  v_b = R_nbᵀ(v_n − c_n) − ω × r_imu  (relative to the water)
 *      ν̇_r = [a_b − ω × v_b; α_b],  the body-axes rate of ν_r for a current constant in n
 *      a_b = R_nbᵀ a_n − α × r_imu − ω × (ω × r_imu)           (at the CG)
 *      ω = omega_ib_b − b_w − R_nbᵀ omega_ie_n,  α = the context's angular acceleration
 *      C(ν)ν = [ω × p₁; v × p₁ + ω × p₂],  [p₁; p₂] = sym(M)·ν   (Fossen 2011, eq. 6.43)
 *      g(R) = −[(W − B)·R_nbᵀ k; r_G × R_nbᵀ k W − r_B × R_nbᵀ k B]   (k = NED down)
 *  M is rigid body plus added mass; with a constant, irrotational current the
 *  rigid-body and added-mass terms combine in ν_r (Fossen 2011, property 10.1).
 *  The Coriolis–centripetal term (on by default, `coriolis: false` drops it and
 *  uses M·[a_b; α_b], the paper's form) carries the Munk moment
 *  (M_yy − M_xx)·u·v, through which the yaw row sees the sway velocity that
 *  the weakly damped sway row cannot. M, D_l, D_q are the configured diagonal matrices
 *  with rows x, y, columns x, y, ψ replaced by the filter's parameter states
 *  (state.h: exp() of the stored surge/sway entries, so they stay positive).
 *  Noise: per-DOF σ, inflated by `surface_noise_factor` while the vehicle is
 *  shallower than `surface_depth_m` (waves and partial buoyancy there).
 *  h is a pure function of its arguments: no mutable model is shared
 *  between sigma points.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "thrust_response.h"

#include "plugin_common.h"

namespace auvnav::plugins
{
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/** The configured (non-estimated) part of the vehicle model. */
struct VehicleModel
{
	Matrix6d M = Matrix6d::Identity(), D_l = Matrix6d::Zero(), D_q = Matrix6d::Zero();
	double weight_n = 0, buoyancy_n = 0;
	Eigen::Vector3d r_g_b = Eigen::Vector3d::Zero(), r_b_b = Eigen::Vector3d::Zero();
	bool coriolis = true;  //!< include C(ν_r)ν_r (see file doc)
};

/** C(ν)ν of a (symmetrised) inertia matrix M for ν = [v; ω]. */
Vector6d coriolisWrench(const Matrix6d& M, const Vector6d& nu);

/** Fossen's simplified model: the wrench needed for state x (see file doc). */
Vector6d predictedWrench(const VehicleModel& vm, const NavState& x, const Eigen::Vector3d& omega_b,
                         const Eigen::Vector3d& alpha_b, const Eigen::Vector3d& r_imu_b);

/** predictedWrench for a model whose M, D_l and D_q are diagonal (as the
 *  configuration's *_diag keys give them) before the estimated 2×3
 *  sub-blocks are placed: the same wrench without the products by zeros
 *  (each evaluation runs once per sigma point, 87 per update). */
Vector6d predictedWrenchDiagonal(const VehicleModel& vm, const NavState& x, const Eigen::Vector3d& omega_b,
                                 const Eigen::Vector3d& alpha_b, const Eigen::Vector3d& r_imu_b);

/** Restoring forces and moments g(R) (subtracted from thrust in the equation). */
Vector6d restoringWrench(const VehicleModel& vm, const Eigen::Matrix3d& R_nb);

class ModelAidingModel final : public GatedModel
{
 public:
	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	ModelAidingModel(const config::Node& cfg, const std::string& label);

	/** Wrench of thruster efforts u (in the configured unit). */
	Vector6d thrustWrench(const std::vector<double>& effort) const;
	/** Each thruster's force for efforts u: the force model and its gain. */
	Eigen::VectorXd thrusterForces(const std::vector<double>& effort) const;
	const VehicleModel& vehicle() const { return vm_; }
	const Eigen::Matrix<double, 6, Eigen::Dynamic>& configurationMatrix() const { return T_; }

 protected:
	uint32_t doUses() const override
	{
		return kAttitude | kGyroBias | kAcceleration | kVelocity | kCurrentVehicle | kInertia |
		       kDampingLinear | kDampingQuadratic;
	}
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	VehicleModel vm_;
	Eigen::Matrix<double, 6, Eigen::Dynamic> T_;
	std::vector<double> gain_forward_, gain_reverse_;
	bool rpm_ = false;
	double rpm_coefficient_ = 0;
	Vector6d sigma_ = Vector6d::Ones();
	double surface_depth_m_ = 1.0, surface_factor_ = 10.0;
	std::vector<int> dofs_;       // rows of the wrench used (default all six)
	bool diagonal_base_ = false;  // vm_'s matrices diagonal: predictedWrenchDiagonal
	// Thrust dynamics (`time_constant_s` of the thrusters): the wrench is the
	// response to the commands so far, at the filter time less FilterContext::alpha_delay_s.
	bool thrust_lag_ = false;
	ThrustResponse response_;
	double time_constant_sigma_s_ = 0;
	static constexpr double kMaxCommandGap_s = 1.0;  // longer: the response starts over

	/** The wrench the thrusters give at the filter's time from the commands
	 *  so far, then holds this observation's; false (and `why`) when the
	 *  response starts over. `rate` is its time derivative. */
	bool laggedWrench(const std::vector<double>& effort, const FilterContext& ctx, Vector6d& wrench,
	                  Vector6d& rate, std::string& why);
};
}  // namespace auvnav::plugins
