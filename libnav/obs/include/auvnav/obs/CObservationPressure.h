#pragma once
/** @file CObservationPressure.h
 *  Absolute pressure (and temperature) from a depth sensor.
 *
 *  Contract: `pressure_pa` is absolute pressure [Pa] at the sensor (atmosphere
 *  included), `temperature_c` the sensor temperature [°C] (NaN if unknown).
 *  Converting to depth (water density, atmospheric pressure) is the consumer's
 *  job. Serialization is versioned; every version stays readable.
 */
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

namespace auvnav::obs
{
class CObservationPressure : public mrpt::obs::CObservation
{
	DEFINE_SERIALIZABLE(CObservationPressure, auvnav::obs)

 public:
	double pressure_pa = 0;           //!< absolute pressure [Pa]
	double temperature_c = 0;         //!< temperature [°C]
	mrpt::poses::CPose3D sensorPose;  //!< sensor pose in the body frame (FRD)

	void getSensorPose(mrpt::poses::CPose3D& out) const override { out = sensorPose; }
	void setSensorPose(const mrpt::poses::CPose3D& p) override { sensorPose = p; }
	void getDescriptionAsText(std::ostream& o) const override;
	bool exportTxtSupported() const override { return true; }
	std::string exportTxtHeader() const override;
	std::string exportTxtDataRow() const override;
};
}  // namespace auvnav::obs
