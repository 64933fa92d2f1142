// Plugin entry point (the only exported symbol of libauvnav_plugin_sonar_heading.so).
#include <auvnav/plugin_api.h>

#include "sonar_heading.h"

AUVNAV_PLUGIN(auvnav::plugins::SonarHeadingModel, "sonar_heading", "1.0.0",
              "Surveyed-pole bearings from imaging-sonar frames (OpenCV): heading validation or update")
