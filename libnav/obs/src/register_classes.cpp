// Registers the auvnav observation classes with MRPT's class registry when the
// library is loaded, so MRPT's own tools (rawlog-edit --plugins, RawLogViewer)
// can deserialize them.
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/obs/CObservationUSBL.h>
#include <auvnav/obs/register.h>
#include <mrpt/core/initializer.h>

MRPT_INITIALIZER(registerAllClasses_auvnav_obs)
{
	using mrpt::rtti::registerClass;
	registerClass(CLASS_ID(auvnav::obs::CObservationDVL));
	registerClass(CLASS_ID(auvnav::obs::CObservationADCP));
	registerClass(CLASS_ID(auvnav::obs::CObservationPressure));
	registerClass(CLASS_ID(auvnav::obs::CObservationThrusters));
	registerClass(CLASS_ID(auvnav::obs::CObservationUSBL));
}

void auvnav::obs::registerAllClasses()
{
	registerAllClasses_auvnav_obs();
}
