#pragma once
/** @file level_heading.h
 *  A heading measurement that carries no roll/pitch information (internal to
 *  plugins/, header-only; used by the magnetometer and ahrs plugins).
 *
 *  The filter perturbs R_nb on the left about NED axes (so3.h). The Euler yaw
 *  atan2(R(1,0), R(0,0)) depends on the tilt components of that perturbation
 *  whenever the vehicle is pitched or rolled, so a yaw measurement would pull
 *  roll/pitch. Instead a heading here is the azimuth of one body-fixed
 *  direction u_b that the reference attitude (the filter's mean) maps to a
 *  HORIZONTAL vector: rotating a horizontal vector about a horizontal axis
 *  changes the direction of its horizontal part only to second order (and
 *  evenly in the angle), while a rotation by δ about down turns it by exactly
 *  δ. So ∂azimuth/∂δθ_n = (0, 0, 1) at the reference attitude, and the ± tilt
 *  sigma points give equal values: the update cannot move roll or pitch
 *  except through correlations the covariance already holds.
 */
#include <auvnav/angles.h>
#include <Eigen/Core>
#include <cmath>

namespace auvnav::plugins
{
/** Azimuth [rad, clockwise from north seen from above, (-π, π]] of the
 *  horizontal part of R_nb u_b. */
inline double azimuthOf(const Eigen::Matrix3d& R_nb, const Eigen::Vector3d& u_b)
{
	const Eigen::Vector3d u_n = R_nb * u_b;
	return std::atan2(u_n.y(), u_n.x());
}

/** The body direction that `R_nb_ref` maps to its levelled forward axis (the
 *  horizontal part of the body x axis, normalised), so that azimuthOf(R, u_b)
 *  is the usual heading at R = R_nb_ref. Within 30° of pitch ±90° (body x
 *  nearly vertical) the levelled right axis is used instead; the heading is
 *  then offset by a constant, identical in z and h, which cancels in the
 *  residual. */
inline Eigen::Vector3d levelReferenceDirection_b(const Eigen::Matrix3d& R_nb_ref)
{
	Eigen::Vector3d f_n = R_nb_ref.col(0);
	f_n.z() = 0;
	if (f_n.norm() < 0.5)
	{
		f_n = R_nb_ref.col(1);
		f_n.z() = 0;
	}
	return R_nb_ref.transpose() * f_n.normalized();
}

}  // namespace auvnav::plugins
