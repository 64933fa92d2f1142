#pragma once
/** @file angles.h
 *  Angles on the circle: the one wrap every part of auvnav uses, so that a
 *  residual, a heading error and a plotted heading agree at ±π.
 */
#include <cmath>

namespace auvnav
{
/** `a_rad` wrapped to (−π, π] [rad]. Exact (std::remainder, no loop, any
 *  magnitude); NaN for NaN or ±∞. */
inline double wrapAngle(double a_rad)
{
	const double w = std::remainder(a_rad, 2 * M_PI);  // [−π, π]
	return w <= -M_PI ? w + 2 * M_PI : w;
}

/** `a_deg` wrapped to (−180, 180] [deg], as wrapAngle. */
inline double wrapAngleDeg(double a_deg)
{
	const double w = std::remainder(a_deg, 360.0);
	return w <= -180.0 ? w + 360.0 : w;
}

}  // namespace auvnav
