#pragma once
/** @file dvl.h
 *  DVL bottom-track velocity update (plugin "dvl").
 *
 *  Observation: auvnav::obs::CObservationDVL, the velocity of the sensor over
 *  the seabed in the sensor frame. With r_s the DVL position and R_bs its
 *  mounting rotation (sensor to body), r_imu the IMU lever arm:
 *
 *      z = velocity_s_mps (3) [m/s]
 *      h = R_bsᵀ (R_nbᵀ v_n + ω × (r_s − r_imu))
 *      ω = omega_ib_b − b_w − R_nbᵀ omega_ie_n   (body rate relative to the Earth)
 *
 *  v_n is the IMU point's velocity, so the lever-arm term moves it to the DVL.
 *  Noise: the observation's velocity covariance (beam geometry × beam noise)
 *  plus extra_sigma_mps² I for what the covariance does not know (mounting
 *  misalignment, scale factor, sound speed); if the covariance is zero or
 *  unusable, sigma_mps² I replaces it.
 *
 *  The mounting comes from the configuration (default: the FlatFish nominal
 *  mounting) or, with `use_observation_pose: true`, from each observation's
 *  sensorPose. It travels to h in Measurement::aux: [0..2] = r_s [m, body FRD],
 *  [3..5] = rotation vector of R_bs [rad].
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <string>

namespace auvnav::plugins
{
class DvlModel final : public SafeMeasurementModel
{
   public:
	DvlModel(const config::Node& cfg, const std::string& label);

	uint32_t uses() const noexcept override { return kAttitude | kGyroBias | kVelocity; }
	double gateProbability() const noexcept override { return gate_probability_; }

	const Eigen::Vector3d& position_b() const { return position_b_; }
	const Eigen::Matrix3d& R_bs() const { return R_bs_; }

   protected:
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
							std::vector<Measurement>& out, std::string& why) override;
	bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
				   Eigen::Ref<Eigen::VectorXd> z_pred) const override;

   private:
	std::string label_;
	Eigen::Vector3d position_b_;
	Eigen::Matrix3d R_bs_;
	bool use_observation_pose_ = false;
	double sigma_mps_ = 0.02;
	double extra_sigma_mps_ = 0.005;
	double gate_probability_ = 0.999;
};
}  // namespace auvnav::plugins
