#pragma once
/** @file compass.h
 *  Example out-of-tree auvnav plugin "compass": a magnetic-compass heading
 *  update on the attitude.
 *
 *  Observation: the plugin's own class compass_example::CObservationCompass
 *  (heading_rad; CObservationCompass.h, in libcompass_obs.so), or an
 *  mrpt::obs::CObservationIMU with IMU_YAW set (what auvnav-sim's compass
 *  writes). Both carry the magnetic heading [rad], clockwise from magnetic
 *  north seen from above (the yaw of the body FRD frame in the NED frame).
 *
 *      z = wrap(heading + declination)          (1) [rad], true heading
 *      h = atan2(R_nb(1,0), R_nb(0,0)) + b       yaw of R_nb (Z-Y-X Euler angles)
 *      r = wrap(z − h)                           wrap to (−π, π] (structure())
 *
 *  b is the plugin's own state "heading_bias" [rad] when the config has
 *  `states: {heading_bias: {sigma_deg: …}}` (auvnav/state_block_config.h;
 *  the compass's deviation: hard iron, mounting), else 0. The navigator
 *  appends it after the paper's 43 states (states.csv: COMPASS.heading_bias)
 *  and propagates it with the declared process; h reads it through its
 *  handle, heading_bias_.value(x) (auvnav/plugin_state.h).
 *
 *  The compass is assumed aligned with the body axes (a mounting yaw offset
 *  can be folded into declination_deg). Near ±90° pitch the yaw is
 *  ill-defined: real compasses are tilt-compensated and the sigma covers it.
 */
#include <auvnav/angles.h>
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>
#include <auvnav/plugin_state.h>
#include <auvnav/state.h>

#include <Eigen/Core>
#include <string>

namespace compass_example
{
class CompassModel final : public auvnav::SafeMeasurementModel
{
 public:
	CompassModel(const auvnav::config::Node& cfg, const std::string& label);

	/** Heading (yaw) of a body-to-NED rotation [rad], in (−π, π]. */
	static double yawOf(const Eigen::Matrix3d& R_nb);

	double declination_rad() const { return declination_rad_; }
	double sigma_rad() const { return sigma_rad_; }

 protected:
	uint32_t doUses() const override { return auvnav::kAttitude | heading_bias_.uses(); }
	/** The state the model owns (disabled, and so skipped by the host, without `states:`). */
	std::vector<auvnav::PluginState*> doStates() override { return {&heading_bias_}; }
	double doGateProbability() const override { return gate_probability_; }
	/** z and h are angles: the filter wraps the residual, z − h, into (−π, π]. */
	auvnav::MeasurementStructure doStructure() const override { return {0, 1u}; }
	auvnav::PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const auvnav::FilterContext& ctx,
	                                std::vector<auvnav::Measurement>& out, std::string& why) override;
	bool doPredict(const auvnav::NavState& x, const auvnav::Measurement& m, const auvnav::FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	std::string label_;
	double declination_rad_ = 0;
	double sigma_rad_ = 0;
	double gate_probability_ = 0.999;
	auvnav::PluginState heading_bias_;  // [rad], if configured
};
}  // namespace compass_example
