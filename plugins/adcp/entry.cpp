// Plugin entry point (the only exported symbol of libauvnav_plugin_adcp.so).
#include <auvnav/plugin_api.h>

#include "adcp.h"

AUVNAV_PLUGIN(
    auvnav::plugins::AdcpModel, "adcp", "1.0.0",
    "ADCP current-profile aiding: per-cell water velocity, two-state linear current profile, ADCP bias")
