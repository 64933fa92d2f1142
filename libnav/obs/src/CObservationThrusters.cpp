#include <auvnav/obs/CObservationThrusters.h>
#include <mrpt/serialization/CArchive.h>

#include <iomanip>
#include <sstream>

#include "serialization_utils.h"

using namespace auvnav::obs;

IMPLEMENTS_SERIALIZABLE(CObservationThrusters, CObservation, auvnav::obs)

namespace
{
constexpr uint32_t kMaxThrusters = 64;
}

uint8_t CObservationThrusters::serializeGetVersion() const
{
	return 0;
}

void CObservationThrusters::serializeTo(mrpt::serialization::CArchive& out) const
{
	detail::writeHead(out, *this);
	out << static_cast<uint8_t>(unit);
	out << static_cast<uint32_t>(effort.size());
	for (double e : effort) out << e;
}

void CObservationThrusters::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	constexpr const char* kClass = "CObservationThrusters";
	if (version != 0) MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	const auto read = [&](CObservationThrusters& r)
	{
		detail::readHead(in, r, kClass);
		constexpr uint8_t kUnitCount = static_cast<uint8_t>(EffortUnit::Speed_rpm) + 1;
		r.unit = static_cast<EffortUnit>(detail::readCode(in, kUnitCount, kClass, "unit"));
		r.effort.resize(detail::readCount(in, kMaxThrusters, "thruster"));
		for (double& e : r.effort) in >> e;
	};
	detail::readWhole(*this, read);
}

void CObservationThrusters::getDescriptionAsText(std::ostream& o) const
{
	CObservation::getDescriptionAsText(o);
	o << "Thrusters: " << effort.size()
	  << ", unit: " << (unit == EffortUnit::Force_N ? "N (commanded force)" : "rpm") << "\nEfforts:";
	for (double e : effort) o << " " << e;
	o << "\n";
}

std::string CObservationThrusters::exportTxtHeader() const
{
	return "[UNIT 0=N 1=rpm]  [COUNT]  [EFFORT_1] ... [EFFORT_N]";
}

std::string CObservationThrusters::exportTxtDataRow() const
{
	std::ostringstream s;
	s << std::setprecision(9) << int(unit) << " " << effort.size();
	for (double e : effort) s << " " << e;
	return s.str();
}
