// Plugin entry point (the only exported symbol of libauvnav_plugin_pressure.so).
#include <auvnav/plugin_api.h>

#include "pressure.h"

AUVNAV_PLUGIN(auvnav::plugins::PressureModel, "pressure", "1.0.0",
              "Absolute pressure to depth (hydrostatic, constant density, lever arm)")
