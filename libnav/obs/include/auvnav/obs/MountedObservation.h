#pragma once
/** @file MountedObservation.h
 *  Base of the auvnav observations taken by a sensor mounted at a fixed pose
 *  on the vehicle (DVL, ADCP, pressure, USBL transponder).
 *
 *  Contract:
 *  - `sensorPose` is the sensor's pose in the body frame (FRD);
 *    getSensorPose()/setSensorPose() read and write exactly that member.
 *  - Not registered with MRPT and never serialized on its own: each derived
 *    class names mrpt::obs::CObservation as its RTTI parent and writes
 *    `sensorPose` itself, so this base changes no record layout.
 */
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <ostream>

namespace auvnav::obs
{
class MountedObservation : public mrpt::obs::CObservation
{
 public:
	mrpt::poses::CPose3D sensorPose;  //!< sensor pose in the body frame (FRD)

	void getSensorPose(mrpt::poses::CPose3D& out) const override { out = sensorPose; }
	void setSensorPose(const mrpt::poses::CPose3D& p) override { sensorPose = p; }

 protected:
	/** The start of every derived getDescriptionAsText(): CObservation's
	 *  text, then the line "<what> pose on vehicle (FRD): <sensorPose>". */
	void describeMounting(std::ostream& o, const char* what = "Sensor") const
	{
		CObservation::getDescriptionAsText(o);
		o << what << " pose on vehicle (FRD): " << sensorPose << "\n";
	}
};
}  // namespace auvnav::obs
