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
 *  Hydrostatic with a constant density; σ (sigma_pa) covers the sensor's
 *  noise and its constant bias.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <string>

namespace auvnav::plugins
{
class PressureModel final : public SafeMeasurementModel
{
   public:
	/** Pressures outside this range are rejected as absurd [Pa]. */
	static constexpr double kMinPressurePa = 5e4, kMaxPressurePa = 1e8;

	PressureModel(const config::Node& cfg, const std::string& label);

	uint32_t uses() const noexcept override { return kAttitude | kGravity | kPosition; }
	double gateProbability() const noexcept override { return gate_probability_; }

	double density_kg_m3() const { return density_kg_m3_; }
	double atmospheric_pressure_pa() const { return atmospheric_pa_; }
	const Eigen::Vector3d& position_b() const { return position_b_; }

   protected:
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
							std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
				   Eigen::Ref<Eigen::VectorXd> z_pred) const override;

   private:
	std::string label_;
	double density_kg_m3_ = 1025;
	double atmospheric_pa_ = 101325;
	double sigma_pa_ = 100;
	Eigen::Vector3d position_b_;
	double gate_probability_ = 0.999;
};
}  // namespace auvnav::plugins
