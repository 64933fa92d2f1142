#include "CObservationTestTag.h"

#include <mrpt/serialization/CArchive.h>

using auvnav_test::CObservationTestTag;

IMPLEMENTS_SERIALIZABLE(CObservationTestTag, CObservation, auvnav_test)

uint8_t CObservationTestTag::serializeGetVersion() const
{
	return 0;
}

void CObservationTestTag::serializeTo(mrpt::serialization::CArchive& out) const
{
	out << timestamp << sensorLabel << sensorPose << value;
}

void CObservationTestTag::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
	switch (version)
	{
		case 0:
			in >> timestamp >> sensorLabel >> sensorPose >> value;
			break;
		default:
			MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
	}
}

// Loading the library registers the class with MRPT (what dlopen of an
// observation library relies on).
// Registered by a dynamic initialiser of this file, which the standard runs
// after the class's runtime id above (share/examples/compass_plugin).
namespace
{
[[maybe_unused]] const bool kRegistered = (mrpt::rtti::registerClass(CLASS_ID(CObservationTestTag)), true);
}
