#pragma once
/** @file plugin_common.h
 *  Small helpers shared by the core sensor-model plugins (internal to
 *  plugins/; not installed). Header-only, so that each plugin stays one
 *  self-contained MODULE.
 */
#include <auvnav/config.h>
#include <auvnav/state.h>
#include <auvnav/state_block_config.h>
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

/** Mounting rotation R_bs (sensor to body) from yaw, pitch, roll in degrees,
 *  exactly as MRPT's CPose3D (and the simulator) build it: Rz·Ry·Rx. */
inline Eigen::Matrix3d rotationFromYprDeg(const Eigen::Vector3d& ypr_deg)
{
	const mrpt::poses::CPose3D p(0, 0, 0, ypr_deg[0] * kDeg, ypr_deg[1] * kDeg, ypr_deg[2] * kDeg);
	return p.getRotationMatrix().asEigen();
}

/** The optional `states: {bias: …}` of a position-fix plugin (GPS, USBL):
 *  a north/east offset of every fix (state_block_config.h), appended to
 *  `blocks`. True if it is configured; any other key under `states` is
 *  refused. */
inline bool horizontalFixBias(const config::Node& cfg, std::vector<StateBlockSpec>& blocks)
{
	if (!cfg.has("states")) return false;
	const auto st = cfg.child("states");
	st.allowOnly({"bias"});
	if (!st.has("bias")) return false;
	blocks.push_back(stateBlockFromConfig(st.child("bias"), "bias", {"n", "e"}));
	return true;
}

/** Adds the bias state at NavState::extra[at], [at + 1] to a fix's north,
 *  east; false for a state built without it. at < 0: no bias. */
template <typename Vec>
bool addFixBias(const NavState& x, int at, Vec&& z_ne)
{
	if (at < 0) return true;
	if (x.extra.size() < at + 2) return false;
	z_ne[0] += x.extra[at];
	z_ne[1] += x.extra[at + 1];
	return true;
}
}  // namespace auvnav::plugins
