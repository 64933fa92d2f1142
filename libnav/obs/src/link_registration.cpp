// Compiled into every program, plugin and library that links auvnav::obs (an
// INTERFACE source of that target). Its call keeps libauvnav_obs in the link
// under --as-needed, which drops a library nothing references by name, and
// registers the observation classes before main: a program that only reads
// rawlogs through MRPT needs no call of its own.
#include <auvnav/obs/register.h>

namespace
{
const bool auvnav_obs_classes_registered = (auvnav::obs::registerAllClasses(), true);
}
