// Plugin entry point (the only exported symbol of libauvnav_plugin_dvl.so).
#include <auvnav/plugin_api.h>

#include "dvl.h"

AUVNAV_PLUGIN(
    auvnav::plugins::DvlModel, "dvl", "1.1.0",
    "DVL bottom-track velocity in instrument, vehicle, Earth (NED/ENU) or beam coordinates, either sign "
    "(lever arm, mounting rotation, Earth-relative body rate)")
