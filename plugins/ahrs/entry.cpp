// Plugin entry point (the only exported symbol of libauvnav_plugin_ahrs.so).
#include <auvnav/plugin_api.h>

#include "ahrs.h"

AUVNAV_PLUGIN(
    auvnav::plugins::AhrsModel, "ahrs", "1.0.0",
    "Attitude output of an AHRS/IMU (CObservationIMU quaternion or yaw/pitch/roll; NED or ENU, true or "
    "magnetic heading) as an SO(3) attitude or heading-only update")
