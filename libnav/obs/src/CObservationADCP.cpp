#include <auvnav/obs/CObservationADCP.h>
#include <mrpt/serialization/CArchive.h>

#include <iomanip>
#include <sstream>

#include "serialization_utils.h"

using namespace auvnav::obs;

IMPLEMENTS_SERIALIZABLE(CObservationADCP, CObservation, auvnav::obs)

namespace
{
constexpr uint32_t kMaxCells = 4096;
constexpr const char* kClass = "CObservationADCP";
}  // namespace

uint8_t CObservationADCP::serializeGetVersion() const
{
	return 0;
}

void CObservationADCP::serializeTo(mrpt::serialization::CArchive& out) const
{
	detail::writeMountedHead(out, *this);
	out << blank_distance_m << cell_size_m << velocity_sigma_mps;
	out << static_cast<uint32_t>(cells.size());
	for (const auto& c : cells)
	{
		for (double v : c.velocity_s_mps) out << v;
		out << c.correlation;
		detail::writeFlag(out, c.valid);
	}
}

void CObservationADCP::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	if (version != 0) MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	const auto read = [&](CObservationADCP& r)
	{
		detail::readMountedHead(in, r, kClass);
		in >> r.blank_distance_m >> r.cell_size_m >> r.velocity_sigma_mps;
		r.cells.resize(detail::readCount(in, kMaxCells, "ADCP cell"));
		for (auto& c : r.cells)
		{
			for (double& v : c.velocity_s_mps) in >> v;
			in >> c.correlation;
			c.valid = detail::readFlag(in, kClass, "cell valid");
		}
	};
	detail::readWhole(*this, read);
}

void CObservationADCP::getDescriptionAsText(std::ostream& o) const
{
	describeMounting(o);
	o << "Blank distance [m]: " << blank_distance_m << ", cell size [m]: " << cell_size_m
	  << ", velocity sigma [m/s]: " << velocity_sigma_mps << "\n";
	o << "Cells (" << cells.size() << "): distance [m] | velocity (sensor frame) [m/s] | corr | valid\n";
	for (std::size_t i = 0; i < cells.size(); ++i)
	{
		const auto& c = cells[i];
		o << "  " << cellDistance(i) << " | " << c.velocity_s_mps[0] << " " << c.velocity_s_mps[1] << " "
		  << c.velocity_s_mps[2] << " | " << c.correlation << " | " << (c.valid ? 1 : 0) << "\n";
	}
}

std::string CObservationADCP::exportTxtHeader() const
{
	return "[CELL_COUNT]  then per cell: [VX_MPS] [VY_MPS] [VZ_MPS] [CORRELATION] [VALID]";
}

std::string CObservationADCP::exportTxtDataRow() const
{
	std::ostringstream s;
	s << std::setprecision(9) << cells.size();
	for (const auto& c : cells)
		s << " " << c.velocity_s_mps[0] << " " << c.velocity_s_mps[1] << " " << c.velocity_s_mps[2] << " "
		  << c.correlation << " " << (c.valid ? 1 : 0);
	return s.str();
}
