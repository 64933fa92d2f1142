#pragma once
/** @file level_fit.h
 *  Horizontal magnetometer calibration from a level turn (auvnav-calibrate-mag
 *  --level): what a vehicle that only turns about the vertical determines.
 *
 *  Model: the plugin's raw = b + S · m_s (mag_fit.h) with S block-diagonal,
 *  S = [S₂ 0; 0 1]. Each reading is levelled with the sensor's roll/pitch
 *  (L_i, from the down direction in sensor axes) and the horizontal part of
 *  the calibrated field has a constant length H:
 *      r_i = |P L_i [W₂ (raw_xy − b_xy); raw_z − b_z]| − H,  W₂ = S₂⁻¹,
 *  P the horizontal rows. Fitted: b_xy and the symmetric W₂ (algebraic conic
 *  through the levelled readings, then Levenberg–Marquardt on r_i). b_z is
 *  given (not determined by a level turn: it only enters as b_z · sin(tilt)),
 *  and S_zz = 1. Scale: with horizontal_field_ut (F cos I) the calibrated
 *  horizontal norm equals it; without, det S₂ = 1, i.e. H is the radius of
 *  the circle with the ellipse's area (its semi-axes' geometric mean), the
 *  horizontal intensity the sensor measured, whatever the heading spread.
 *
 *  A soft-iron coupling S_xz, S_yz of the true sensor multiplies the constant
 *  vertical field in a level turn and is absorbed in b_xy (right near level).
 *
 *  Refused (MagCalibrationError): too few readings; the sensor z axis more
 *  than max_tilt_deg from the vertical; no ellipse; the calibrated readings
 *  covering less than min_heading_coverage_deg of heading (360° minus the
 *  largest gap between their azimuths); a residual rms over H above
 *  max_rms_residual_deg (a short, noisy arc can be wrapped by a small wrong
 *  ellipse whose centre the readings surround: a large coverage with a
 *  residual comparable to H); a soft iron the plugin refuses.
 *
 *  Units: µT, degrees where named.
 */
#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "mag_fit.h"

namespace auvnav::magcal
{
struct LevelFitOptions
{
	double horizontal_field_ut = 0;  //!< F·cos(I) [µT]; 0: unknown (det S₂ = 1)
	double hard_iron_z_ut = 0;       //!< b_z, not determined by a level turn [µT]
	double min_heading_coverage_deg = 270;
	double max_tilt_deg = 30;          //!< sensor z axis from the vertical, any reading
	double max_rms_residual_deg = 10;  //!< rms residual / H above this: no ellipse fits
	std::size_t min_samples = 100;
};

struct LevelFitResult
{
	Eigen::Vector3d hard_iron_ut = Eigen::Vector3d::Zero();        //!< (b_x, b_y, the given b_z), sensor axes
	Eigen::Matrix3d soft_iron = Eigen::Matrix3d::Identity();       //!< [S₂ 0; 0 1]
	Eigen::Vector2d hard_iron_sigma_ut = Eigen::Vector2d::Zero();  //!< 1σ of b_xy from the fit's covariance
	double horizontal_field_ut = 0;                                //!< H the fit enforces
	double rms_residual_ut = 0;
	double max_residual_ut = 0;
	double rms_residual_deg = 0;  //!< rms / H: the heading error of a field error that size across the field
	double heading_coverage_deg = 0;
	double vertical_field_ut = 0;     //!< mean levelled vertical component (with the given b_z)
	double vertical_field_sd_ut = 0;  //!< its standard deviation over the readings
	double max_tilt_deg = 0;          //!< largest sensor tilt used in the levelling
	std::size_t samples = 0;
	int iterations = 0;
};

/** Fits b_xy and S₂ to `raw_ut`; `down_s` holds the unit down direction in
 *  sensor axes for each reading, or is empty for a level sensor (down = +z).
 *  Throws MagCalibrationError when refused. */
LevelFitResult fitLevel(const std::vector<Eigen::Vector3d>& raw_ut,
                        const std::vector<Eigen::Vector3d>& down_s, const LevelFitOptions& options);

/** The down direction in the magnetometer's axes at each time `t_mag_s`: minus
 *  the mean specific force of the accelerometer readings within ±window_s/2
 *  (the nearest reading if none), which averages out vibration and the
 *  brief accelerations of manoeuvring; `R_b_mag` is the magnetometer mounting.
 *  Empty when `accel` is. */
std::vector<Eigen::Vector3d> downFromAccel(const std::vector<double>& t_mag_s,
                                           const std::vector<TimedAccel>& accel,
                                           const Eigen::Matrix3d& R_b_mag, double window_s);

/** The plugin's keys for a level fit, with comments saying that b_z and S_zz
 *  are not determined. */
std::string pluginYamlLevel(const LevelFitResult& r, const std::string& source_comment);

}  // namespace auvnav::magcal
