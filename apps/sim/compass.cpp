#include "compass.h"
#include <auvnav/angles.h>

#include <cmath>

namespace auvnav::sim
{
namespace
{
constexpr double kDeg = M_PI / 180;
}  // namespace

CompassSim::CompassSim(const config::Node& n, double declination_rad, uint32_t seed)
    : period_s_(1.0 / n.positive("rate_hz")),
      offset_s_(n.nonNegative("time_offset_s", 0.0)),
      mount_(Mounting::fromConfig(n)),
      declination_rad_(declination_rad),
      bias_rad_(n.inRange("bias_deg", -180, 180, 0.0) * kDeg),
      sigma_rad_(n.inRange("noise_sigma_deg", 0, 90) * kDeg),
      label_(n.string("label", "COMPASS"))
{
	// Its own random stream (id 41, far from the other sensors' ids), so that
	// enabling the compass leaves every other sensor's noise as it was.
	rng_.randomize(seed * 7919u + 41u * 104729u + 1u);
}

mrpt::obs::CObservationIMU::Ptr CompassSim::sample(const Truth& t)
{
	// The heading of the sensor's x axis (its true mounting) in the NED frame.
	const Eigen::Matrix3d R_ns = t.x->R_nb() * mount_.R_bs_true;
	const double psi_true = std::atan2(R_ns(1, 0), R_ns(0, 0));
	auto obs = mrpt::obs::CObservationIMU::Create();
	obs->timestamp = t.stamp;
	obs->sensorLabel = label_;
	obs->sensorPose = mount_.nominalPose();
	obs->set(mrpt::obs::IMU_YAW, wrapAngle(psi_true - declination_rad_ + bias_rad_ +
	                                       sigma_rad_ * rng_.drawGaussian1D_normalized()));
	return obs;
}
}  // namespace auvnav::sim
