#pragma once
/** @file CObservationPressure.h
 *  Absolute pressure (and temperature) from a depth sensor.
 *
 *  Contract: `pressure_pa` is absolute pressure [Pa] at the sensor (atmosphere
 *  included), `temperature_c` the sensor temperature [°C] (NaN if unknown).
 *  Converting to depth (water density, atmospheric pressure) is the consumer's
 *  job. Serialization is versioned; every version stays readable.
 */
#include <auvnav/obs/MountedObservation.h>

namespace auvnav::obs
{
class CObservationPressure : public MountedObservation
{
	DEFINE_SERIALIZABLE(CObservationPressure, auvnav::obs)

 public:
	double pressure_pa = 0;    //!< absolute pressure [Pa]
	double temperature_c = 0;  //!< temperature [°C]

	void getDescriptionAsText(std::ostream& o) const override;
	bool exportTxtSupported() const override { return true; }
	std::string exportTxtHeader() const override;
	std::string exportTxtDataRow() const override;
};
}  // namespace auvnav::obs
