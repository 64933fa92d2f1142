// Plugin entry point (the only exported symbol of libauvnav_plugin_inertial.so).
#include <auvnav/plugin_api.h>

#include "inertial.h"

AUVNAV_PLUGIN(
    auvnav::plugins::InertialModel, "inertial", "1.0.0",
    "Accelerometer update of the acceleration state (specific force, attitude, gravity, accel bias)")
