#pragma once
/** @file compass.h
 *  A magnetic compass (a fluxgate or an AHRS's heading output): the heading
 *  the example out-of-tree plugin share/examples/compass_plugin reads.
 *
 *    psi_m = wrap(psi_true − D + b + w),   w ~ N(0, σ²)
 *
 *  psi_true is the yaw of R_nb (clockwise from true north seen from above),
 *  D the magnetic declination (the environment's magnetic_field.declination_deg,
 *  0 without one), b a constant deviation (`bias_deg`: hard iron, mounting).
 *
 *  Output contract: an mrpt::obs::CObservationIMU labelled `label` (default
 *  "COMPASS") with only IMU_YAW set and marked present: the magnetic heading
 *  [rad] in (−π, π]; sensorPose = the nominal mounting.
 */
#include <auvnav/config.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/random/RandomGenerators.h>

#include <string>

#include "sensors.h"

namespace auvnav::sim
{
class CompassSim
{
 public:
	CompassSim(const config::Node& n, double declination_rad, uint32_t seed);
	double period_s() const { return period_s_; }
	double offset_s() const { return offset_s_; }
	mrpt::obs::CObservationIMU::Ptr sample(const Truth& truth);

 private:
	double period_s_, offset_s_;
	Mounting mount_;
	double declination_rad_, bias_rad_, sigma_rad_;
	std::string label_;
	mrpt::random::CRandomGenerator rng_;
};
}  // namespace auvnav::sim
