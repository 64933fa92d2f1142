#pragma once
/** @file plugin_common.h
 *  Small helpers shared by the core sensor-model plugins (internal to
 *  plugins/; not installed). Header-only, so that each plugin stays one
 *  self-contained MODULE.
 */
#include <auvnav/config.h>
#include <auvnav/plugin_state.h>
#include <auvnav/state.h>
#include <auvnav/state_block_config.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

namespace auvnav::plugins
{
constexpr double kDeg = M_PI / 180;

/** The `gate_probability` key every plugin has: in (0, 1], 1 disables the
 *  χ² gate. */
inline double gateProbabilityFrom(const config::Node& cfg, double default_value = 0.999)
{
	const double p = cfg.inRange("gate_probability", 0.0, 1.0, default_value);
	if (!(p > 0)) cfg.fail("gate_probability", "expected a probability in (0, 1], got 0");
	return p;
}

/** `obs` as the observation class T, or null with `why` naming the class
 *  expected and the one given: every plugin's first check in prepare. */
template <class T>
const T* observationAs(const mrpt::obs::CObservation& obs, std::string& why)
{
	const auto* typed = dynamic_cast<const T*>(&obs);
	if (!typed)
		why = std::string("expected ") + T::GetRuntimeClassIdStatic().className + ", got " +
		      obs.GetRuntimeClass()->className;
	return typed;
}

/** Mounting rotation R_bs (sensor to body) from yaw, pitch, roll in degrees,
 *  exactly as MRPT's CPose3D (and the simulator) build it: Rz·Ry·Rx. */
inline Eigen::Matrix3d rotationFromYprDeg(const Eigen::Vector3d& ypr_deg)
{
	const mrpt::poses::CPose3D p(0, 0, 0, ypr_deg[0] * kDeg, ypr_deg[1] * kDeg, ypr_deg[2] * kDeg);
	return p.getRotationMatrix().asEigen();
}

/** The optional `states: {bias: …}` of a position-fix plugin (GPS, USBL):
 *  a north/east offset of every fix (state_block_config.h); a disabled
 *  handle if it is not configured. Any other key under `states` is refused. */
inline PluginState horizontalFixBias(const config::Node& cfg)
{
	if (!cfg.has("states")) return {};
	const auto st = cfg.child("states");
	st.allowOnly({"bias"});
	if (!st.has("bias")) return {};
	return PluginState(stateBlockFromConfig(st.child("bias"), "bias", {"n", "e"}));
}

/** Adds the bias state (if enabled) to a fix's north, east. */
template <typename Vec>
void addFixBias(const NavState& x, const PluginState& bias, Vec&& z_ne)
{
	if (!bias.enabled()) return;
	z_ne[0] += bias(x, 0);
	z_ne[1] += bias(x, 1);
}
}  // namespace auvnav::plugins
