#pragma once
/** @file ahrs.h
 *  Attitude from an IMU that computes its own (plugin "ahrs"): an AHRS or
 *  MEMS "orientation" output.
 *
 *  Observation: mrpt::obs::CObservationIMU with IMU_ORI_QUAT_W/X/Y/Z
 *  (preferred, used when all four are present) or IMU_YAW/IMU_PITCH/IMU_ROLL
 *  [rad]. Either gives R_rs, the sensor axes in the AHRS's reference frame
 *  (v_r = R_rs v_s; for the angles R_rs = Rz(yaw) Ry(pitch) Rx(roll) about
 *  the reference frame's axes, as MRPT's CPose3D). Config `reference_frame`:
 *  `ned` (x north, z down) or `enu` (x east, z up, yaw counter-clockwise
 *  from east, as ROS REP-103); `heading_reference` `magnetic` rotates the
 *  reference frame by `declination_deg` (magnetic north is D east of true
 *  north). Mounting R_bs: `orientation_ypr_deg` if given, else the
 *  observation's sensorPose (what auvnav-import writes); an ENU device with
 *  FLU sensor axes aligned with the body is mounted roll 180°.
 *
 *      R_nb,meas = R_nr · R_rs · R_bsᵀ,   R_nr = Rz_NED(D) · (ENU→NED or I)
 *
 *  Measurement (full attitude, 3): the attitude residual on SO(3),
 *      r = Log(R_nb,meas · R_nbᵀ)  (left, NED axes, as so3.h),
 *  carried as z = 0 and h(x) = Log(R_nb · R_nb,measᵀ) = −r (R_nb,meas in
 *  the payload AhrsReference as a quaternion), so that the filter's averaging of
 *  predicted measurements happens in one chart centred on the measurement.
 *  R = J diag(σ_roll², σ_pitch², σ_heading²) Jᵀ: an Euler-angle error of the
 *  AHRS mapped to NED rotation axes, J = [body x, levelled body y, down]
 *  of the measured attitude (no angles needed), plus a floor of 1e-6 of the
 *  largest variance near pitch ±90°, where J loses rank.
 *
 *  `heading_only`: a 1-D wrapped heading, the azimuth of a body direction the
 *  filter's mean places horizontally (level_heading.h), so that an AHRS's
 *  roll/pitch (biased in accelerated motion) never enters the filter.
 *
 *  Invalid: wrong class, neither a full quaternion nor all three angles,
 *  non-finite values, a quaternion whose norm is off 1 by more than 10 %.
 *  Skipped: min_interval_s. uses() = kAttitude.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <cstddef>
#include <optional>
#include <string>

#include "plugin_common.h"

namespace auvnav::plugins
{
class AhrsModel final : public GatedModel
{
 public:
	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	AhrsModel(const config::Node& cfg, const std::string& label);

	bool headingOnly() const { return heading_only_; }
	//! R_nr: the AHRS reference frame's axes in NED (frame convention and declination).
	const Eigen::Matrix3d& R_nr() const { return R_nr_; }
	std::size_t rateLimitedCount() const { return min_interval_.skippedCount(); }

	/** The body attitude the observation reports, R_nb,meas; nullopt with
	 *  `why` for an unusable observation. */
	std::optional<Eigen::Matrix3d> measuredAttitude(const mrpt::obs::CObservation& obs,
	                                                std::string& why) const;

 protected:
	uint32_t doUses() const override { return kAttitude; }
	//! heading_only: a heading [rad], the residual wraps; else z = 0 and h = −r
	//! are already a rotation vector in one chart: a plain difference.
	MeasurementStructure doStructure() const override { return {0, heading_only_ ? ~0u : 0u}; }
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	Eigen::Matrix3d R_nr_ = Eigen::Matrix3d::Identity();
	std::optional<Eigen::Matrix3d> R_bs_config_;  // orientation_ypr_deg, else the observation's sensorPose
	double sigma_roll_rad_ = 0, sigma_pitch_rad_ = 0, sigma_heading_rad_ = 0;
	bool heading_only_ = false;
	MinInterval min_interval_;
};
}  // namespace auvnav::plugins
