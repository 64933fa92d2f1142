#pragma once
/** @file sonar_heading.h
 *  Landmark bearings from imaging-sonar frames (plugin "sonar_heading").
 *
 *  Observation: a raw polar sonar frame (mrpt::obs::CObservationImage with
 *  the polar geometry, auvnav/sonar/frame.h). `prepare` detects poles
 *  (OpenCV), associates them with the surveyed pole map using the filter's
 *  mean and covariance (chi-square gate on bearing and range), and then
 *   - mode `update`: one measurement per associated pole, its bearing in
 *     the sonar frame: h(x) = wrap(atan2(ΔE, ΔN) − ψ_s(x)), with ΔN, ΔE from
 *     the sonar head (p_n + R_nb r_s) to the pole and ψ_s the horizontal
 *     direction of the sonar's x axis R_nb R_bs e_x (no Euler angles);
 *     σ² = the detection's σ² + `bearing_sigma_floor_deg`² (mounting);
 *   - mode `validate`: nothing is applied; the landmark heading of the frame
 *     and the filter's heading are appended to `validation_csv` (the
 *     paper's heading check against surveyed poles).
 *  Pure h: depends on its state argument and the measurement's own numbers.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>
#include <auvnav/sonar/pipeline.h>

#include <fstream>
#include <memory>
#include <string>

#include "plugin_common.h"

namespace auvnav::plugins
{
/** Bearing [rad] of the pole at `pole_ne` seen from state x by a sonar at
 *  lever arm `r_s_b` whose x axis is the body x axis turned by `mount_yaw`. */
double predictedBearing(const NavState& x, const Eigen::Vector3d& r_s_b, double mount_yaw_rad,
                        const Eigen::Vector2d& pole_ne);

/** What a bearing measurement carries to h (Measurement::payload): the
 *  associated pole's position in the navigation frame [m]. */
struct PolePosition
{
	double north_m = 0, east_m = 0;
};

class SonarHeadingModel final : public GatedModel
{
 public:
	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	SonarHeadingModel(const config::Node& cfg, const std::string& label);

	bool validateOnly() const { return validate_only_; }
	const sonar::SonarConfig& sonarConfig() const { return sonar_; }

 protected:
	uint32_t doUses() const override { return kAttitude | kPosition; }
	//! Bearings [rad]: every residual component wraps.
	MeasurementStructure doStructure() const override { return {0, ~0u}; }
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	sonar::SonarConfig sonar_;
	bool validate_only_ = true;
	double sigma_floor_rad_ = 0;
	std::unique_ptr<std::ofstream> validation_;
};
}  // namespace auvnav::plugins
