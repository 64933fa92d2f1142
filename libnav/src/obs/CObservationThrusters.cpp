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

uint8_t CObservationThrusters::serializeGetVersion() const { return 0; }

void CObservationThrusters::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << timestamp << sensorLabel << static_cast<uint8_t>(unit);
	out << static_cast<uint32_t>(effort.size());
	for (double e : effort) out << e;
}

void CObservationThrusters::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		{
			uint8_t u = 0;
			in >> timestamp >> sensorLabel >> u;
			if (u > static_cast<uint8_t>(EffortUnit::Speed_rpm))
				THROW_EXCEPTION_FMT("corrupt data: unknown thruster effort unit %u", unsigned(u));
			unit = static_cast<EffortUnit>(u);
			effort.resize(detail::readCount(in, kMaxThrusters, "thruster"));
			for (double& e : effort) in >> e;
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

void CObservationThrusters::getDescriptionAsText(std::ostream& o) const
{
	CObservation::getDescriptionAsText(o);
	o << "Thrusters: " << effort.size() << ", unit: "
	  << (unit == EffortUnit::Force_N ? "N (commanded force)" : "rpm") << "\nEfforts:";
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
