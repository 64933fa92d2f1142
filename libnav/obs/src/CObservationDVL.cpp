#include <auvnav/enum_names.h>
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

constexpr const char* kFrameNames[] = {"instrument", "vehicle", "earth_ned", "earth_enu", "beam"};
constexpr const char* kSignNames[] = {"vehicle_over_bottom", "bottom_over_instrument"};
constexpr uint8_t kFrameCount = sizeof(kFrameNames) / sizeof(kFrameNames[0]);
constexpr uint8_t kSignCount = sizeof(kSignNames) / sizeof(kSignNames[0]);
static_assert(auvnav::namesEveryValue(kFrameNames, DvlFrame::Beam));
static_assert(auvnav::namesEveryValue(kSignNames, DvlSign::BottomOverInstrument));

constexpr const char* kClass = "CObservationDVL";

bool readFlag(mrpt::serialization::CArchive& in, const char* field)
{
	return detail::readFlag(in, kClass, field);
}
}  // namespace

namespace auvnav::obs
{
const char* dvlFrameName(DvlFrame f)
{
	return auvnav::nameOf(kFrameNames, f, "unknown");
}

const char* dvlSignName(DvlSign s)
{
	return auvnav::nameOf(kSignNames, s, "unknown");
}

bool parseDvlFrame(const std::string& name, DvlFrame& out)
{
	return auvnav::parseName(kFrameNames, name, out);
}

bool parseDvlSign(const std::string& name, DvlSign& out)
{
	return auvnav::parseName(kSignNames, name, out);
}
}  // namespace auvnav::obs

uint8_t CObservationDVL::serializeGetVersion() const
{
	return 1;
}

// Version 1 layout: timestamp, label, sensorPose, velocity (3 doubles),
// covariance (9), bottom_lock (u8), altitude, inclination, frame (u8),
// sign (u8), beam σ, beam count (u32), per beam: range, valid (u8),
// velocity, azimuth.
void CObservationDVL::serializeTo(mrpt::serialization::CArchive& out) const
{
	// Never write what the reader would refuse.
	if (static_cast<uint8_t>(frame) >= kFrameCount || static_cast<uint8_t>(sign) >= kSignCount)
		THROW_EXCEPTION_FMT("CObservationDVL: invalid frame %u or sign %u",
		                    unsigned(static_cast<uint8_t>(frame)), unsigned(static_cast<uint8_t>(sign)));
	detail::writeMountedHead(out, *this);
	for (double v : velocity_s_mps) out << v;
	for (double c : velocity_cov) out << c;
	detail::writeFlag(out, bottom_lock);
	out << altitude_m << beam_inclination_rad;
	out << static_cast<uint8_t>(frame) << static_cast<uint8_t>(sign) << beam_velocity_sigma_mps;
	out << static_cast<uint32_t>(beams.size());
	for (const auto& b : beams)
	{
		out << b.range_m;
		detail::writeFlag(out, b.valid);
		out << b.velocity_mps << b.azimuth_rad;
	}
}

void CObservationDVL::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	if (version > 1) MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	const auto read = [&](CObservationDVL& r)
	{
		detail::readMountedHead(in, r, kClass);
		for (double& v : r.velocity_s_mps) in >> v;
		for (double& c : r.velocity_cov) in >> c;
		r.bottom_lock = readFlag(in, "bottom_lock");
		in >> r.altitude_m >> r.beam_inclination_rad;
		// Version 0 knew the instrument frame and the sensor's own sign only:
		// it keeps the fresh object's frame, sign, beam velocity, azimuth and
		// sigma (Instrument, VehicleOverBottom, 0).
		if (version >= 1)
		{
			r.frame = static_cast<DvlFrame>(detail::readCode(in, kFrameCount, kClass, "frame"));
			r.sign = static_cast<DvlSign>(detail::readCode(in, kSignCount, kClass, "sign"));
			in >> r.beam_velocity_sigma_mps;
		}
		r.beams.resize(detail::readCount(in, kMaxBeams, "DVL beam"));
		for (auto& b : r.beams)
		{
			in >> b.range_m;
			b.valid = readFlag(in, "beam valid");
			if (version >= 1) in >> b.velocity_mps >> b.azimuth_rad;
		}
	};
	detail::readWhole(*this, read);
}

void CObservationDVL::getDescriptionAsText(std::ostream& o) const
{
	describeMounting(o);
	o << "Frame: " << dvlFrameName(frame) << ", sign: " << dvlSignName(sign)
	  << (sign == DvlSign::BottomOverInstrument ? " (seabed relative to the instrument, RDI PD0)" : "")
	  << "\n";
	o << "Bottom lock: " << (bottom_lock ? "yes" : "no") << "\n";
	if (frame != DvlFrame::Beam)
		o << "Velocity (" << dvlFrameName(frame) << ") [m/s]: " << velocity_s_mps[0] << " "
		  << velocity_s_mps[1] << " " << velocity_s_mps[2] << "\n";
	o << "Altitude [m]: " << altitude_m << "\n";
	o << "Beam velocity sigma [m/s]: " << beam_velocity_sigma_mps
	  << (beam_velocity_sigma_mps > 0 ? "" : " (unknown)") << "\n";
	o << "Beams (" << beams.size() << ", inclination " << beam_inclination_rad
	  << " rad): range [m] / azimuth [rad]" << (frame == DvlFrame::Beam ? " / velocity [m/s]" : "") << "\n";
	for (const auto& b : beams)
	{
		o << "  " << b.range_m << " / " << b.azimuth_rad;
		if (frame == DvlFrame::Beam) o << " / " << b.velocity_mps;
		o << (b.valid ? "" : " (invalid)") << "\n";
	}
}

std::string CObservationDVL::exportTxtHeader() const
{
	return "[VX_MPS]  [VY_MPS]  [VZ_MPS]  [BOTTOM_LOCK]  [ALTITUDE_M]  "
	       "[FRAME 0=instrument 1=vehicle 2=earth_ned 3=earth_enu 4=beam]  "
	       "[SIGN 0=vehicle_over_bottom 1=bottom_over_instrument]  [BEAM_COUNT]  "
	       "then per beam: [BEAM_VELOCITY_MPS] [VALID]";
}

std::string CObservationDVL::exportTxtDataRow() const
{
	std::ostringstream s;
	s << std::setprecision(9) << velocity_s_mps[0] << " " << velocity_s_mps[1] << " " << velocity_s_mps[2]
	  << " " << (bottom_lock ? 1 : 0) << " " << altitude_m << " " << unsigned(static_cast<uint8_t>(frame))
	  << " " << unsigned(static_cast<uint8_t>(sign)) << " " << beams.size();
	for (const auto& b : beams) s << " " << b.velocity_mps << " " << (b.valid ? 1 : 0);
	return s.str();
}
