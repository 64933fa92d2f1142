#pragma once
// Small configs shared by the simulator tests: the sensor suite of
// config/sensors/flatfish_sensors.yaml, loaded from the repository, and
// vehicle/environment fragments written inline where a test needs exact values.
#include <auvnav/config.h>

#include <string>

namespace auvnav::sim::test
{
inline config::Node repoSensors()
{
	return config::Node::load(std::string(AUVNAV_SOURCE_DIR) + "/config/sensors/flatfish_sensors.yaml");
}
inline config::Node repoVehicle()
{
	return config::Node::load(std::string(AUVNAV_SOURCE_DIR) + "/config/vehicles/flatfish.yaml");
}

/** Environment with a flat seabed at `seabed_m`, a uniform current and no tide. */
inline config::Node flatEnvironment(double seabed_m, double current_n = 0, double current_e = 0)
{
	const std::string c = "[" + std::to_string(current_n) + ", " + std::to_string(current_e) + "]";
	return config::Node::fromText(
	    "current: {surface_ne_mps: " + c + ", deep_ne_mps: " + c +
	        ", shear_depth_m: 10, tidal_amplitude_ne_mps: [0, 0], tidal_period_s: 44712, "
	        "tidal_phase_deg: 0, wander_sigma_mps: 0, wander_tau_s: 3600}\n"
	        "seabed: {depth_at_origin_m: " +
	        std::to_string(seabed_m) +
	        ", slope_ne: [0, 0], undulation_m: 0, wavelength_m: 100}\n"
	        "water: {density_kg_m3: 1025, atmospheric_pressure_pa: 101325, surface_temperature_c: 27, "
	        "temperature_gradient_c_per_m: -0.05}\n",
	    "<flat environment>");
}
}  // namespace auvnav::sim::test
