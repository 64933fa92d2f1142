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
	detail::writeMountedHead(out, *this);
	out << pressure_pa << temperature_c;
}

void CObservationPressure::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	if (version != 0) MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	const auto read = [&](CObservationPressure& r)
	{
		detail::readMountedHead(in, r, "CObservationPressure");
		in >> r.pressure_pa >> r.temperature_c;
	};
	detail::readWhole(*this, read);
}

void CObservationPressure::getDescriptionAsText(std::ostream& o) const
{
	describeMounting(o);
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
