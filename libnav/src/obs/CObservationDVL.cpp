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

/** A uint8 that must be below `count`. MRPT reads a bool by copying the byte
 *  into it, so any other byte value would be undefined behaviour: we read the
 *  byte and refuse what no writer produces. */
uint8_t readCode(mrpt::serialization::CArchive& in, uint8_t count, const char* what)
{
	uint8_t v = 0;
	in >> v;
	if (v >= count)
		THROW_EXCEPTION_FMT("corrupt data: DVL %s code %u out of range 0..%u", what, unsigned(v),
							unsigned(count - 1));
	return v;
}

bool readFlag(mrpt::serialization::CArchive& in, const char* what) { return readCode(in, 2, what) != 0; }

void writeFlag(mrpt::serialization::CArchive& out, bool b) { out << static_cast<uint8_t>(b ? 1 : 0); }

/** The fields versions 0 and 1 share, in their order, up to the beam
 *  inclination. */
void readCommonHead(mrpt::serialization::CArchive& in, CObservationDVL& d)
{
	in >> d.timestamp >> d.sensorLabel >> d.sensorPose;
	for (double& v : d.velocity_s_mps) in >> v;
	for (double& c : d.velocity_cov) in >> c;
	d.bottom_lock = readFlag(in, "bottom_lock");
	in >> d.altitude_m >> d.beam_inclination_rad;
}
}  // namespace

namespace auvnav::obs
{
const char* dvlFrameName(DvlFrame f)
{
	const auto i = static_cast<uint8_t>(f);
	return i < kFrameCount ? kFrameNames[i] : "unknown";
}

const char* dvlSignName(DvlSign s)
{
	const auto i = static_cast<uint8_t>(s);
	return i < kSignCount ? kSignNames[i] : "unknown";
}

bool parseDvlFrame(const std::string& name, DvlFrame& out)
{
	for (uint8_t i = 0; i < kFrameCount; ++i)
		if (name == kFrameNames[i])
		{
			out = static_cast<DvlFrame>(i);
			return true;
		}
	return false;
}

bool parseDvlSign(const std::string& name, DvlSign& out)
{
	for (uint8_t i = 0; i < kSignCount; ++i)
		if (name == kSignNames[i])
		{
			out = static_cast<DvlSign>(i);
			return true;
		}
	return false;
}
}  // namespace auvnav::obs

uint8_t CObservationDVL::serializeGetVersion() const { return 1; }

// Version 1 layout: timestamp, label, sensorPose, velocity (3 doubles),
// covariance (9), bottom_lock (u8), altitude, inclination, frame (u8),
// sign (u8), beam σ, beam count (u32), per beam: range, valid (u8),
// velocity, azimuth.
void CObservationDVL::serializeTo(mrpt::serialization::CArchive& out) const
{
	// Never write what the reader would refuse.
	if (static_cast<uint8_t>(frame) >= kFrameCount || static_cast<uint8_t>(sign) >= kSignCount)
		THROW_EXCEPTION_FMT("CObservationDVL: invalid frame %u or sign %u", unsigned(static_cast<uint8_t>(frame)),
							unsigned(static_cast<uint8_t>(sign)));
	out << timestamp << sensorLabel << sensorPose;
	for (double v : velocity_s_mps) out << v;
	for (double c : velocity_cov) out << c;
	writeFlag(out, bottom_lock);
	out << altitude_m << beam_inclination_rad;
	out << static_cast<uint8_t>(frame) << static_cast<uint8_t>(sign) << beam_velocity_sigma_mps;
	out << static_cast<uint32_t>(beams.size());
	for (const auto& b : beams)
	{
		out << b.range_m;
		writeFlag(out, b.valid);
		out << b.velocity_mps << b.azimuth_rad;
	}
}

void CObservationDVL::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
		{
			readCommonHead(in, *this);
			// Version 0 knew the instrument frame and the sensor's own sign only.
			frame = DvlFrame::Instrument;
			sign = DvlSign::VehicleOverBottom;
			beam_velocity_sigma_mps = 0;
			beams.resize(detail::readCount(in, kMaxBeams, "DVL beam"));
			for (auto& b : beams)
			{
				in >> b.range_m;
				b.valid = readFlag(in, "beam valid");
				b.velocity_mps = 0;
				b.azimuth_rad = 0;
			}
		}
		break;
		case 1:
		{
			readCommonHead(in, *this);
			frame = static_cast<DvlFrame>(readCode(in, kFrameCount, "frame"));
			sign = static_cast<DvlSign>(readCode(in, kSignCount, "sign"));
			in >> beam_velocity_sigma_mps;
			beams.resize(detail::readCount(in, kMaxBeams, "DVL beam"));
			for (auto& b : beams)
			{
				in >> b.range_m;
				b.valid = readFlag(in, "beam valid");
				in >> b.velocity_mps >> b.azimuth_rad;
			}
		}
		break;
		default: MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

void CObservationDVL::getDescriptionAsText(std::ostream& o) const
{
	CObservation::getDescriptionAsText(o);
	o << "Sensor pose on vehicle (FRD): " << sensorPose << "\n";
	o << "Frame: " << dvlFrameName(frame) << ", sign: " << dvlSignName(sign)
	  << (sign == DvlSign::BottomOverInstrument ? " (seabed relative to the instrument, RDI PD0)" : "") << "\n";
	o << "Bottom lock: " << (bottom_lock ? "yes" : "no") << "\n";
	if (frame != DvlFrame::Beam)
		o << "Velocity (" << dvlFrameName(frame) << ") [m/s]: " << velocity_s_mps[0] << " " << velocity_s_mps[1]
		  << " " << velocity_s_mps[2] << "\n";
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
	s << std::setprecision(9) << velocity_s_mps[0] << " " << velocity_s_mps[1] << " " << velocity_s_mps[2] << " "
	  << (bottom_lock ? 1 : 0) << " " << altitude_m << " " << unsigned(static_cast<uint8_t>(frame)) << " "
	  << unsigned(static_cast<uint8_t>(sign)) << " " << beams.size();
	for (const auto& b : beams) s << " " << b.velocity_mps << " " << (b.valid ? 1 : 0);
	return s.str();
}
