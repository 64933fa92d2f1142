#include <auvnav/obs/CObservationPressure.h>
#include <mrpt/serialization/CArchive.h>

#include <iomanip>
#include <sstream>

using namespace auvnav::obs;

IMPLEMENTS_SERIALIZABLE(CObservationPressure, CObservation, auvnav::obs)

uint8_t CObservationPressure::serializeGetVersion() const { return 0; }

void CObservationPressure::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << timestamp << sensorLabel << sensorPose << pressure_pa << temperature_c;
}

void CObservationPressure::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0: in >> timestamp >> sensorLabel >> sensorPose >> pressure_pa >> temperature_c; break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

void CObservationPressure::getDescriptionAsText(std::ostream& o) const
{
	CObservation::getDescriptionAsText(o);
	o << "Sensor pose on vehicle (FRD): " << sensorPose << "\n";
	o << "Pressure [Pa]: " << std::setprecision(10) << pressure_pa << "\n";
	o << "Temperature [degC]: " << temperature_c << "\n";
}

std::string CObservationPressure::exportTxtHeader() const { return "[PRESSURE_PA]  [TEMPERATURE_C]"; }

std::string CObservationPressure::exportTxtDataRow() const
{
	std::ostringstream s;
	s << std::setprecision(12) << pressure_pa << " " << temperature_c;
	return s.str();
}
