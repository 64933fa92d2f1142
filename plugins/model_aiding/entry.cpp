// Plugin entry point (the only exported symbol of libauvnav_plugin_model_aiding.so).
#include <auvnav/plugin_api.h>

#include "model_aiding.h"

AUVNAV_PLUGIN(auvnav::plugins::ModelAidingModel, "model_aiding", "1.0.0",
              "Model aiding: thruster wrench vs Fossen's simplified model with estimated inertia and damping")
