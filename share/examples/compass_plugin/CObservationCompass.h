#pragma once
/** @file CObservationCompass.h
 *  The example plugin's own observation class: one magnetic-compass heading.
 *  It lives in its own observation library, libcompass_obs.so
 *  (auvnav_add_observation_library in CMakeLists.txt), which registers it
 *  with MRPT's class registry when loaded. The plugin links the library; the
 *  auvnav programs load it before they read a rawlog holding the class
 *  (`--obs-lib libcompass_obs.so`, or `obs_libs` in the sensor's entry).
 *
 *  Contract: `heading_rad` is the magnetic heading [rad] of the sensor's x
 *  axis, clockwise from magnetic north seen from above (the yaw of the body
 *  FRD frame in NED when mounted aligned), any finite value (wrapped by the
 *  reader). Serialization is versioned: version 0 = timestamp, sensorLabel,
 *  sensorPose, heading_rad; a new field means a version 1 that still reads 0.
 */
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

namespace compass_example
{
class CObservationCompass : public mrpt::obs::CObservation
{
	DEFINE_SERIALIZABLE(CObservationCompass, compass_example)

 public:
	double heading_rad = 0;           //!< magnetic heading [rad]
	mrpt::poses::CPose3D sensorPose;  //!< mounting in the body frame (FRD)

	void getSensorPose(mrpt::poses::CPose3D& out) const override { out = sensorPose; }
	void setSensorPose(const mrpt::poses::CPose3D& p) override { sensorPose = p; }
	void getDescriptionAsText(std::ostream& o) const override;
};
}  // namespace compass_example
