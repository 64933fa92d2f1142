#pragma once
/** @file earth.h
 *  The Earth as seen from auvnav's navigation frame (see frames.h): a local
 *  NED tangent frame fixed to the Earth at a geodetic origin.
 *
 *  All geodesy and gravity come from GeographicLib (WGS-84): conversions
 *  between tangent-frame NED and geodetic coordinates, the WGS-84 normal
 *  gravity (gravitation plus centrifugal) anywhere, and the Earth rotation
 *  rate. Angles in radians at this API, metres for lengths.
 */
#include <Eigen/Core>
#include <memory>

namespace auvnav::earth
{
/** WGS-84 Earth rotation rate [rad/s] (GeographicLib::Constants). */
double rotationRate();

/** WGS-84 normal gravity magnitude [m/s²] at geodetic latitude `lat_rad` and
 *  ellipsoidal height `h_m` (negative below the ellipsoid, e.g. under water). */
double normalGravity(double lat_rad, double h_m);

/** Earth rotation vector in a NED frame at latitude `lat_rad` [rad/s]. */
Eigen::Vector3d earthRateNed(double lat_rad);

struct Geodetic
{
	double lat_rad = 0, lon_rad = 0, h_m = 0;
};

/** An Earth-fixed NED tangent frame at a geodetic origin. */
class TangentFrame
{
 public:
	explicit TangentFrame(const Geodetic& origin);
	~TangentFrame();
	TangentFrame(const TangentFrame&);
	TangentFrame& operator=(const TangentFrame&);

	const Geodetic& origin() const { return origin_; }
	Geodetic toGeodetic(const Eigen::Vector3d& p_n) const;
	Eigen::Vector3d toNed(const Geodetic& g) const;

	/** Normal gravity vector (down-positive NED) at tangent position `p_n`,
	 *  expressed in this frame: magnitude and direction both follow the
	 *  ellipsoid, so away from the origin it tilts by ~distance/R_earth. */
	Eigen::Vector3d gravityNed(const Eigen::Vector3d& p_n) const;

	/** Earth rotation vector in this (Earth-fixed) frame [rad/s]; constant. */
	const Eigen::Vector3d& earthRate() const { return omega_ie_n_; }

 private:
	struct Impl;
	std::unique_ptr<Impl> impl_;
	Geodetic origin_;
	Eigen::Vector3d omega_ie_n_;
};

}  // namespace auvnav::earth
