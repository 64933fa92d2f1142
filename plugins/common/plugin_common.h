#pragma once
/** @file plugin_common.h
 *  Small helpers shared by the core sensor-model plugins (internal to
 *  plugins/; not installed). Header-only, so that each plugin stays one
 *  self-contained MODULE.
 */
#include <auvnav/config.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>
#include <cmath>
#include <string>

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

}  // namespace auvnav::plugins
