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
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <string>

namespace auvnav::plugins
{
class UsblModel final : public SafeMeasurementModel
{
 public:
	UsblModel(const config::Node& cfg, const std::string& label);

	const Eigen::Vector3d& position_b() const { return position_b_; }

 protected:
	uint32_t doUses() const override { return kAttitude | kPosition | bias_.uses(); }
	double doGateProbability() const override { return gate_probability_; }
	bool doReportsPositionFix() const override { return true; }
	bool doInitialFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, InitialFix& out) override;
	std::vector<PluginState*> doStates() override { return {&bias_}; }
	double doMeasurementTime(const mrpt::obs::CObservation& obs, double stamp_s) const override;
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	/** The fix in the navigation frame and its covariance (Ok), or why not. */
	PrepareStatus decodeFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        Eigen::Vector3d& p_n, Eigen::Matrix3d& C_n, std::string& why) const;

	std::string label_;
	Eigen::Vector3d position_b_;
	double sigma_m_ = 2.0, sigma_range_fraction_ = 0.01, depth_sigma_m_ = 1.0;
	bool use_reported_covariance_ = true, use_depth_ = false;
	double gate_probability_ = 0.999;
	PluginState bias_;  // (b_n, b_e) if configured
};
}  // namespace auvnav::plugins
