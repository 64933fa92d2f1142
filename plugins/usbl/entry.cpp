// Plugin entry point (the only exported symbol of libauvnav_plugin_usbl.so).
#include <auvnav/plugin_api.h>

#include "usbl.h"

AUVNAV_PLUGIN(
    auvnav::plugins::UsblModel, "usbl", "1.0.0",
    "USBL acoustic position fix of the transponder (measurement time, lever arm, range-dependent noise, "
    "optional bias state)")
