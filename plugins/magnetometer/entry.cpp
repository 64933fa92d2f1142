// Plugin entry point (the only exported symbol of libauvnav_plugin_magnetometer.so).
#include <auvnav/plugin_api.h>

#include "magnetometer.h"

AUVNAV_PLUGIN(auvnav::plugins::MagnetometerModel, "magnetometer", "1.0.0",
              "Raw 3-axis magnetometer (CObservationIMU IMU_MAG_*, gauss): hard/soft-iron field model, "
              "tilt-compensated heading or 3-D vector update, disturbance gate")
