#pragma once
/** @file pressure.h
 *  Absolute-pressure depth update (plugin "pressure").
 *
 *  Observation: auvnav::obs::CObservationPressure, absolute pressure at the
 *  sensor (atmosphere included). With r_s the sensor position, r_imu the IMU
 *  lever arm (body FRD) and g the filter's gravity state:
 *
 *      z = pressure_pa (1) [Pa]
 *      h = atmospheric_pressure_pa + density · g · depth_s
 *      depth_s = p_n.z + (R_nb (r_s − r_imu)).z
 *
 *  Hydrostatic with a constant density; σ (sigma_pa) is the sensor's noise.
 *  A constant bias (calibration offset, atmospheric pressure that is not the
 *  configured one; bias_sigma_pa) does not average out like noise, and the
 *  43-state layout has no state for it: instead, each update's noise is
 *  raised so that the filter's depth variance does not fall below
 *  (bias_sigma_pa / (density · g))², i.e. the depth is never claimed better
 *  than the bias allows (with sigma_pa alone the depth σ was ~4 mm against
 *  a 50 Pa (5 mm) bias and the depth NEES 1.7× its expected value).
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <string>

#include "plugin_common.h"

namespace auvnav::plugins
{
class PressureModel final : public GatedModel
{
 public:
	/** Pressures outside this range are rejected as absurd [Pa]. */
	static constexpr double kMinPressurePa = 5e4, kMaxPressurePa = 1e8;

	/** `label`, the sensor's name (the plugin factory's argument), is not used. */
	PressureModel(const config::Node& cfg, const std::string& label);

	double density_kg_m3() const { return density_kg_m3_; }
	double atmospheric_pressure_pa() const { return atmospheric_pa_; }
	const Eigen::Vector3d& position_b() const { return position_b_; }

	/** The update's noise variance [Pa²]: sigma_pa², raised when the depth
	 *  variance in ctx.covariance approaches the floor bias_sigma_pa² (the
	 *  update then leaves the floor; at or below it, 10⁶ × the variance). */
	double noiseVariance(const FilterContext& ctx) const;

	static constexpr double kNominalGravity = 9.80665;  //!< [m/s²], only for the floor

 protected:
	uint32_t doUses() const override { return kAttitude | kGravity | kPosition; }
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override;

 private:
	double density_kg_m3_ = 1025;
	double atmospheric_pa_ = 101325;
	double sigma_pa_ = 100;
	double bias_sigma_pa_ = 0;  //!< 0: no floor
	Eigen::Vector3d position_b_;
};
}  // namespace auvnav::plugins
