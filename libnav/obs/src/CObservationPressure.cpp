#include <auvnav/obs/CObservationPressure.h>
#include <mrpt/serialization/CArchive.h>

#include <iomanip>
#include <sstream>

#include "serialization_utils.h"

using namespace auvnav::obs;

IMPLEMENTS_SERIALIZABLE(CObservationPressure, CObservation, auvnav::obs)

uint8_t CObservationPressure::serializeGetVersion() const
{
	return 0;
}

void CObservationPressure::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << timestamp << sensorLabel << sensorPose << pressure_pa << temperature_c;
}

void CObservationPressure::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	// Read into a fresh object and adopt it only once the whole record is
	// valid: a record refused half-way leaves this one untouched.
	constexpr const char* kClass = "CObservationPressure";
	CObservationPressure r;
	switch (version)
	{
		case 0:
			in >> r.timestamp;
			r.sensorLabel = detail::readLabel(in, kClass);
			detail::readPose(in, r.sensorPose, kClass);
			in >> r.pressure_pa >> r.temperature_c;
			break;
		default:
			MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
	*this = std::move(r);
}

void CObservationPressure::getDescriptionAsText(std::ostream& o) const
{
	CObservation::getDescriptionAsText(o);
	o << "Sensor pose on vehicle (FRD): " << sensorPose << "\n";
	o << "Pressure [Pa]: " << std::setprecision(10) << pressure_pa << "\n";
	o << "Temperature [degC]: " << temperature_c << "\n";
}

std::string CObservationPressure::exportTxtHeader() const
{
	return "[PRESSURE_PA]  [TEMPERATURE_C]";
}

std::string CObservationPressure::exportTxtDataRow() const
{
	std::ostringstream s;
	s << std::setprecision(12) << pressure_pa << " " << temperature_c;
	return s.str();
}
