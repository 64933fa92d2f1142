#pragma once
/** @file magnetometer.h
 *  Raw 3-axis magnetometer update (plugin "magnetometer").
 *
 *  Observation (fixed contract; auvnav-sim and auvnav-import write it):
 *  mrpt::obs::CObservationIMU with IMU_MAG_X/Y/Z present, in GAUSS
 *  (1 G = 100 µT), in the sensor axes; sensorPose is the sensor's mounting in
 *  the body frame (FRD; its rotation is R_bs). Navigation frame NED.
 *
 *  Field model (µT), m_n from the config (total intensity F, declination D,
 *  inclination I, positive down):
 *      m_n = F [cos I cos D, cos I sin D, sin I]
 *      m_s = b_hard + S_soft · R_bsᵀ · R_nbᵀ · m_n          (raw reading)
 *  and the calibrated reading m_c = S_soft⁻¹ (m_s − b_hard), |m_c| ≈ F.
 *
 *  Modes:
 *   - `vector`: z = the raw reading m_s [µT] (3), h as above, R = σ² I₃.
 *   - `heading` (default): a tilt-compensated heading, 1-D. The calibrated
 *     field in body axes m_b = R_bs m_c is levelled with the filter's mean
 *     attitude R̂ (the state's tilt); its azimuth α (in NED) says the
 *     vehicle's heading is off by D − α. z = ψ̂ + D − α, h(x) = the heading
 *     of x measured as the azimuth of a body direction R̂ places horizontally
 *     (level_heading.h: no roll/pitch information), residual wrapped.
 *     R = heading_sigma².
 *
 *  Disturbance gate (in prepare, before the filter's χ² gate): the reading is
 *  skipped, with a reason and counted (disturbedCount()), when the calibrated
 *  norm |m_c| is off F by more than `norm_tolerance`·F, or when the dip angle
 *  of R̂ R_bs m_c is off I by more than `dip_tolerance_deg` (dip needs the
 *  mean; without one only the norm is checked). Thruster currents, a nearby
 *  hull or a battery change the norm and dip long before they are caught by
 *  a heading innovation.
 *
 *  Invalid (counted by the host): wrong class, a missing IMU_MAG_* field,
 *  a non-finite value. Skipped: disturbed, rate-limited (`min_interval_s`),
 *  heading mode without a filter mean.
 *
 *  h reads only the attitude: uses() = kAttitude. h is pure: R_bs (vector
 *  mode) or u_b (heading mode) travel in the Measurement's payload
 *  (MountingRotation, ReferenceDirection).
 *
 *  Optional plugin-owned state (heading mode; `states: {heading_bias: …}`,
 *  state_block_config.h): a heading bias b [rad], h = heading + b. Thruster
 *  currents and a nearby hull bend the measured heading by degrees for as
 *  long as a leg lasts; as white noise such errors average down and the
 *  heading σ ends far below them. A Gauss–Markov b with the errors' σ and
 *  correlation time keeps them in the state, so the heading σ stays as large
 *  as what the magnetometer can actually tell (uses() adds kPluginStates).
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <cstddef>
#include <string>

#include "plugin_common.h"

namespace auvnav::plugins
{
/** Earth field in NED [µT] from total intensity [µT], declination and
 *  inclination [rad] (positive east / down). */
Eigen::Vector3d earthField_n(double total_ut, double declination_rad, double inclination_rad);

/** The raw reading [µT, sensor axes] the model predicts. */
Eigen::Vector3d predictedReading_s(const Eigen::Matrix3d& R_nb, const Eigen::Matrix3d& R_bs,
                                   const Eigen::Vector3d& m_n_ut, const Eigen::Vector3d& b_hard_ut,
                                   const Eigen::Matrix3d& S_soft);

/** Payloads of the two modes' measurements (Measurement::payload): the
 *  sensor-to-body rotation R_bs as a unit quaternion (vector mode), and the
 *  level reference direction u_b in body axes (heading mode). */
struct MountingRotation
{
	double w = 1, x = 0, y = 0, z = 0;
};
struct ReferenceDirection
{
	double x = 0, y = 0, z = 0;
};

class MagnetometerModel final : public GatedModel
{
 public:
	enum class Mode
	{
		Vector,
		Heading
	};

	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	MagnetometerModel(const config::Node& cfg, const std::string& label);

	Mode mode() const { return mode_; }
	const Eigen::Vector3d& field_n_ut() const { return m_n_ut_; }
	const Eigen::Vector3d& hardIron_ut() const { return b_hard_ut_; }
	const Eigen::Matrix3d& softIron() const { return S_soft_; }
	double headingSigma_rad() const { return heading_sigma_rad_; }
	double noise_ut() const { return noise_ut_; }
	//! Readings skipped by the disturbance gate (norm or dip) so far.
	std::size_t disturbedCount() const { return disturbed_; }
	//! Readings skipped by min_interval_s so far.
	std::size_t rateLimitedCount() const { return min_interval_.skippedCount(); }

 protected:
	uint32_t doUses() const override { return kAttitude | heading_bias_.uses(); }
	std::vector<PluginState*> doStates() override { return {&heading_bias_}; }
	//! Heading mode: z and h are headings [rad], the residual wraps.
	MeasurementStructure doStructure() const override { return {0, mode_ == Mode::Heading ? ~0u : 0u}; }
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	Mode mode_ = Mode::Heading;
	double field_ut_ = 0;
	double declination_rad_ = 0;
	double inclination_rad_ = 0;
	Eigen::Vector3d m_n_ut_ = Eigen::Vector3d::Zero();
	Eigen::Vector3d b_hard_ut_ = Eigen::Vector3d::Zero();
	Eigen::Matrix3d S_soft_ = Eigen::Matrix3d::Identity();
	Eigen::Matrix3d S_soft_inv_ = Eigen::Matrix3d::Identity();
	double noise_ut_ = 2.0;
	double heading_sigma_rad_ = 0;
	double norm_tolerance_ = 0.1;
	double dip_tolerance_rad_ = 0;
	MinInterval min_interval_;
	std::size_t disturbed_ = 0;
	PluginState heading_bias_;  // [rad], heading mode, if configured
};
}  // namespace auvnav::plugins
