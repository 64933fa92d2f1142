#include <auvnav/obs/CObservationUSBL.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <iomanip>
#include <sstream>

#include "serialization_utils.h"

using namespace auvnav::obs;

IMPLEMENTS_SERIALIZABLE(CObservationUSBL, CObservation, auvnav::obs)

uint8_t CObservationUSBL::serializeGetVersion() const
{
	return 0;
}

void CObservationUSBL::serializeTo(mrpt::serialization::CArchive& out) const
{
	detail::writeMountedHead(out, *this);
	out << measurement_time << static_cast<uint8_t>(frame);
	for (double v : position) out << v;
	for (double v : covariance_ned_m2) out << v;
	out << slant_range_m << transponder_id;
}

void CObservationUSBL::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	constexpr const char* kClass = "CObservationUSBL";
	if (version != 0) MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	const auto read = [&](CObservationUSBL& r)
	{
		detail::readMountedHead(in, r, kClass);
		in >> r.measurement_time;
		// A corrupt byte must not become an enum value no code handles.
		constexpr uint8_t kFrameCount = static_cast<uint8_t>(UsblFrame::LocalNed) + 1;
		r.frame = static_cast<UsblFrame>(detail::readCode(in, kFrameCount, kClass, "frame"));
		for (double& v : r.position) in >> v;
		for (double& v : r.covariance_ned_m2) in >> v;
		in >> r.slant_range_m >> r.transponder_id;
	};
	detail::readWhole(*this, read);
}

bool CObservationUSBL::hasCovariance() const
{
	for (double v : covariance_ned_m2)
		if (!std::isfinite(v)) return false;
	return true;
}

void CObservationUSBL::getDescriptionAsText(std::ostream& o) const
{
	describeMounting(o, "Transponder");
	o << "Measurement time: "
	  << (measurement_time == INVALID_TIMESTAMP ? std::string("(not given)")
	                                            : mrpt::system::dateTimeLocalToString(measurement_time))
	  << "\n";
	o << std::setprecision(10);
	if (frame == UsblFrame::Geodetic)
		o << "Latitude [deg]: " << position[0] << "  longitude [deg]: " << position[1]
		  << "  depth [m]: " << position[2] << "\n";
	else
		o << "North, east, down from the origin [m]: " << position[0] << " " << position[1] << " "
		  << position[2] << "\n";
	o << "Covariance NED [m^2]:";
	for (double v : covariance_ned_m2) o << " " << v;
	o << "\nSlant range [m]: " << slant_range_m << "  transponder: " << transponder_id << "\n";
}

std::string CObservationUSBL::exportTxtHeader() const
{
	return "[MEASUREMENT_TIME_S]  [FRAME]  [POS0]  [POS1]  [POS2]  [C_NN]  [C_EE]  [C_DD]  [SLANT_RANGE_M]  "
	       "[ID]";
}

std::string CObservationUSBL::exportTxtDataRow() const
{
	std::ostringstream s;
	s << std::setprecision(12)
	  << (measurement_time == INVALID_TIMESTAMP ? std::nan("") : mrpt::Clock::toDouble(measurement_time))
	  << " " << static_cast<int>(frame) << " " << position[0] << " " << position[1] << " " << position[2]
	  << " " << covariance_ned_m2[0] << " " << covariance_ned_m2[4] << " " << covariance_ned_m2[8] << " "
	  << slant_range_m << " " << transponder_id;
	return s.str();
}
