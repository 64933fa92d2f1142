#pragma once
/** @file geometry.h
 *  Geometry of a raw polar imaging-sonar frame (Tritech Gemini 720i-like).
 *
 *  A raw frame is an 8-bit image with one column per beam and one row per
 *  range bin: column c looks along bearing θ(c), row r is at slant range ρ(r).
 *  Beams are spread uniformly in bearing over the horizontal aperture, bins
 *  uniformly in range (an assumption: the real Gemini's beam spacing is close
 *  to, not exactly, uniform). Bearing is measured in the sonar head's x–y
 *  plane from its x axis (forward) towards +y (starboard), i.e. clockwise
 *  seen from above, the same sense as the vehicle's yaw in NED/FRD.
 *
 *  In a CObservationImage the geometry is carried by the camera model as
 *  linear "polar intrinsics" (see frame.h): column = cx + fx·θ, row = cy + fy·ρ.
 */
#include <auvnav/config.h>

#include <Eigen/Core>
#include <string>

namespace auvnav::sonar
{
struct PolarGeometry
{
	int beam_count = 256;     //!< image columns
	int range_bins = 400;     //!< image rows
	double aperture_rad = 0;  //!< horizontal aperture (130° for the Gemini 720i)
	double min_range_m = 0;   //!< centre of the first bin [m]
	double max_range_m = 0;   //!< centre of the last bin [m]

	/** Throws std::invalid_argument naming the field if not usable. */
	void validate() const;
	/** From `beam_count, range_bins, aperture_deg, min_range_m, max_range_m`;
	 *  a bad value fails naming the key. */
	static PolarGeometry fromConfig(const config::Node& n);

	double bearingStep_rad() const { return aperture_rad / beam_count; }
	double rangeStep_m() const { return (max_range_m - min_range_m) / (range_bins - 1); }
	/** Bearing of a (fractional) column: beams centred in equal slices. */
	double bearingOfColumn(double column) const
	{
		return -0.5 * aperture_rad + (column + 0.5) * bearingStep_rad();
	}
	double columnOfBearing(double bearing_rad) const
	{
		return (bearing_rad + 0.5 * aperture_rad) / bearingStep_rad() - 0.5;
	}
	double rangeOfRow(double row) const { return min_range_m + row * rangeStep_m(); }
	double rowOfRange(double range_m) const { return (range_m - min_range_m) / rangeStep_m(); }
	bool inView(double bearing_rad, double range_m) const
	{
		return std::abs(bearing_rad) <= 0.5 * aperture_rad && range_m >= min_range_m &&
		       range_m <= max_range_m;
	}
	/** Point in the sonar's x–y plane (x forward, y starboard) [m]. */
	static Eigen::Vector2d toCartesian(double bearing_rad, double range_m);
	static void toPolar(const Eigen::Vector2d& xy_m, double& bearing_rad, double& range_m);
};

}  // namespace auvnav::sonar
