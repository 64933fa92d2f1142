// Plugin entry point (the only exported symbol of libauvnav_plugin_gps.so).
#include <auvnav/plugin_api.h>

#include "gps.h"

AUVNAV_PLUGIN(auvnav::plugins::GpsModel, "gps", "1.0.0",
              "GNSS horizontal antenna position from NMEA GGA (lever arm, HDOP scaling, outlier gate)")
