#pragma once
/** @file CObservationTestTag.h
 *  A minimal observation class that is NOT part of libauvnav_obs: it lives in
 *  its own observation library (libauvnav_test_obs.so, built with
 *  auvnav_add_observation_library), so that the tests can check that the
 *  programs read a rawlog holding it only once the library is loaded
 *  (--obs-lib, or obs_libs in the navigator config). */
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

namespace auvnav_test
{
class CObservationTestTag : public mrpt::obs::CObservation
{
	DEFINE_SERIALIZABLE(CObservationTestTag, auvnav_test)

 public:
	double value = 0;  //!< any number (the tests write the sample index)
	mrpt::poses::CPose3D sensorPose;

	void getSensorPose(mrpt::poses::CPose3D& out) const override { out = sensorPose; }
	void setSensorPose(const mrpt::poses::CPose3D& p) override { sensorPose = p; }
};
}  // namespace auvnav_test
