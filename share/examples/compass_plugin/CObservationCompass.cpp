// The example's observation class (see CObservationCompass.h).
#include "CObservationCompass.h"

#include <mrpt/serialization/CArchive.h>

#include <ostream>

using compass_example::CObservationCompass;

IMPLEMENTS_SERIALIZABLE(CObservationCompass, CObservation, compass_example)

uint8_t CObservationCompass::serializeGetVersion() const
{
	return 0;
}

void CObservationCompass::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << timestamp << sensorLabel << sensorPose << heading_rad;
}

void CObservationCompass::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
			in >> timestamp >> sensorLabel >> sensorPose >> heading_rad;
			break;
		default:
			MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

void CObservationCompass::getDescriptionAsText(std::ostream& o) const
{
	CObservation::getDescriptionAsText(o);
	o << "Magnetic heading [rad]: " << heading_rad << "\n";
}

// Runs when the library is loaded (by the dynamic linker for the plugin, by
// dlopen for --obs-lib): MRPT can then deserialize the class from a rawlog.
// A dynamic initialiser of this file, not MRPT_INITIALIZER: the standard runs
// it after the class's runtime id above, whereas MRPT_INITIALIZER is a
// constructor function, which clang may run first (the class is then
// registered with a null name and cannot be read).
namespace
{
[[maybe_unused]] const bool kRegistered = (mrpt::rtti::registerClass(CLASS_ID(CObservationCompass)), true);
}
