#pragma once
/** @file usbl.h
 *  USBL acoustic position fix of the vehicle's transponder (plugin "usbl").
 *
 *  Observation: auvnav::obs::CObservationUSBL (a geodetic fix or one in the
 *  navigation frame). With r_t the transponder and r_imu the IMU lever arm
 *  (body FRD) and b an optional plugin-owned bias of the fixes (north, east):
 *
 *      z = transponder north, east [, down] in the navigation frame [m]
 *      h = (p_n + R_nb (r_t − r_imu)).head<2 or 3>() + [b_n, b_e (, 0)]
 *
 *  Noise: the fix's own covariance (use_reported_covariance) or, without one,
 *  σ² = sigma_m² + (sigma_range_fraction · slant range)² per horizontal axis
 *  (USBL bearing errors grow with range), depth_sigma_m for the depth.
 *  The depth is used only with use_depth: a pressure sensor knows it better.
 *
 *  Timing: the fix's measurement time (the observation's measurement_time,
 *  else its timestamp minus the sensor entry's latency_s) is what
 *  measurementTime() returns; the navigator applies the fix at that time.
 *
 *  Bias (`states: {bias: {sigma: …}}`, state_block_config.h): a horizontal
 *  offset shared by consecutive fixes (the ship's GNSS, a mounting or
 *  sound-speed error), estimated as a plugin-owned state; usually a
 *  gauss_markov process with a τ of minutes.
 */
#include <auvnav/config.h>

#include <Eigen/Core>
#include <string>

#include "position_fix_model.h"

namespace auvnav::plugins
{
/** One USBL fix: the transponder's position [m, navigation frame; down NaN
 *  if the fix has no depth] and its covariance [m², NED]. */
struct UsblFix
{
	Eigen::Vector3d p_n = Eigen::Vector3d::Zero();
	Eigen::Matrix3d C_n = Eigen::Matrix3d::Zero();
};

class UsblModel final : public PositionFixModel<UsblFix>
{
 public:
	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	UsblModel(const config::Node& cfg, const std::string& label);

 protected:
	double doMeasurementTime(const mrpt::obs::CObservation& obs, double stamp_s) const override;

 private:
	/** The fix in the navigation frame and its covariance (Ok), or why not. */
	PrepareStatus decodeFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, UsblFix& fix,
	                        std::string& why) const override;
	/** North, east (and, with use_depth, down) with the fix's covariance. */
	PrepareStatus measureFix(const UsblFix& fix, const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                         std::vector<Measurement>& out, std::string& why) override;
	bool useDepth() const { return measuredAxes() == 3; }

	double sigma_m_ = 2.0, sigma_range_fraction_ = 0.01, depth_sigma_m_ = 1.0;
	bool use_reported_covariance_ = true;
};
}  // namespace auvnav::plugins
