#pragma once
/** @file compass.h
 *  Example out-of-tree auvnav plugin "compass": a magnetic-compass heading
 *  update on the attitude.
 *
 *  Observation: mrpt::obs::CObservationIMU with IMU_YAW set: the magnetic
 *  heading [rad], clockwise from magnetic north seen from above (the yaw of
 *  the body FRD frame in the NED frame). Other IMU fields are ignored.
 *
 *      z = wrap(IMU_YAW + declination)          (1) [rad], true heading
 *      h = atan2(R_nb(1,0), R_nb(0,0))           yaw of R_nb (Z-Y-X Euler angles)
 *      r = wrap(z − h)                           wrap to (−π, π]
 *
 *  The compass is assumed aligned with the body axes (a mounting yaw offset
 *  can be folded into declination_deg). Near ±90° pitch the yaw is
 *  ill-defined: real compasses are tilt-compensated and the sigma covers it.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>

#include <Eigen/Core>
#include <string>

namespace compass_example
{
class CompassModel final : public auvnav::SafeMeasurementModel
{
   public:
	CompassModel(const auvnav::config::Node& cfg, const std::string& label);

	uint32_t uses() const noexcept override { return auvnav::kAttitude; }
	double gateProbability() const noexcept override { return gate_probability_; }
	/** r = wrap(z − z_pred) into (−π, π]: the boxminus of the circle. */
	void residual(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::Ref<const Eigen::VectorXd>& z_pred,
				  Eigen::Ref<Eigen::VectorXd> r) const noexcept override;

	/** An angle wrapped into (−π, π]. */
	static double wrapAngle(double a);
	/** Heading (yaw) of a body-to-NED rotation [rad], in (−π, π]. */
	static double yawOf(const Eigen::Matrix3d& R_nb);

	double declination_rad() const { return declination_rad_; }
	double sigma_rad() const { return sigma_rad_; }

   protected:
	auvnav::PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const auvnav::FilterContext& ctx,
									std::vector<auvnav::Measurement>& out, std::string& why) override;
	bool doPredict(const auvnav::NavState& x, const auvnav::Measurement& m, const auvnav::FilterContext& ctx,
				   Eigen::Ref<Eigen::VectorXd> z_pred) const override;

   private:
	std::string label_;
	double declination_rad_ = 0;
	double sigma_rad_ = 0;
	double gate_probability_ = 0.999;
};
}  // namespace compass_example
