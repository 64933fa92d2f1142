#include <auvnav/obs/CObservationDVL.h>
#include <mrpt/serialization/CArchive.h>

#include <iomanip>
#include <sstream>

#include "serialization_utils.h"

using namespace auvnav::obs;

IMPLEMENTS_SERIALIZABLE(CObservationDVL, CObservation, auvnav::obs)

namespace
{
constexpr uint32_t kMaxBeams = 64;
}

uint8_t CObservationDVL::serializeGetVersion() const { return 0; }

void CObservationDVL::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << timestamp << sensorLabel << sensorPose;
	for (double v : velocity_s_mps) out << v;
	for (double c : velocity_cov) out << c;
	out << bottom_lock << altitude_m << beam_inclination_rad;
	out << static_cast<uint32_t>(beams.size());
	for (const auto& b : beams) out << b.range_m << b.valid;
}

void CObservationDVL::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		{
			in >> timestamp >> sensorLabel >> sensorPose;
			for (double& v : velocity_s_mps) in >> v;
			for (double& c : velocity_cov) in >> c;
			in >> bottom_lock >> altitude_m >> beam_inclination_rad;
			beams.resize(detail::readCount(in, kMaxBeams, "DVL beam"));
			for (auto& b : beams) in >> b.range_m >> b.valid;
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

void CObservationDVL::getDescriptionAsText(std::ostream& o) const
{
	CObservation::getDescriptionAsText(o);
	o << "Sensor pose on vehicle (FRD): " << sensorPose << "\n";
	o << "Bottom lock: " << (bottom_lock ? "yes" : "no") << "\n";
	o << "Velocity (sensor frame) [m/s]: " << velocity_s_mps[0] << " " << velocity_s_mps[1] << " "
	  << velocity_s_mps[2] << "\n";
	o << "Altitude [m]: " << altitude_m << "\n";
	o << "Beams (" << beams.size() << ", inclination " << beam_inclination_rad << " rad):";
	for (const auto& b : beams) o << " " << b.range_m << (b.valid ? "" : "(invalid)");
	o << "\n";
}

std::string CObservationDVL::exportTxtHeader() const
{
	return "[VX_MPS]  [VY_MPS]  [VZ_MPS]  [BOTTOM_LOCK]  [ALTITUDE_M]";
}

std::string CObservationDVL::exportTxtDataRow() const
{
	std::ostringstream s;
	s << std::setprecision(9) << velocity_s_mps[0] << " " << velocity_s_mps[1] << " "
	  << velocity_s_mps[2] << " " << (bottom_lock ? 1 : 0) << " " << altitude_m;
	return s.str();
}
