#pragma once
/** @file mag_fit.h
 *  Hard- and soft-iron calibration of a 3-axis magnetometer from readings
 *  taken while the sensor turns through many orientations (auvnav-calibrate-mag).
 *
 *  Model (the magnetometer plugin's, magnetometer.h): raw = b + S · m_s with
 *  m_s the undistorted field in sensor axes, |m_s| = F. So the raw readings
 *  lie on the ellipsoid (raw − b)ᵀ S⁻ᵀ S⁻¹ (raw − b) = F².
 *
 *  Fit: (1) algebraic least-squares quadric through the readings (centred
 *  and scaled for conditioning; the coefficient vector is the eigenvector of
 *  the smallest eigenvalue of the 10 × 10 scatter matrix), which must be an
 *  ellipsoid; (2) Gauss–Newton on the geometric residuals
 *  r_i = |W (raw_i − b)| − F over b and the symmetric W = S⁻¹ (9 unknowns),
 *  since the algebraic fit is biased by noise. S is symmetric positive
 *  definite (a rotation between sensor and soft-iron axes is not observable
 *  from the field norm and belongs in the mounting). Given F the calibrated
 *  norm equals F; without it det S = 1 and the calibrated norm is reported.
 *
 *  Refused (MagCalibrationError, the message says what to do): fewer than
 *  min_samples readings; a segment that does not rotate enough (spread
 *  below min_spread: the square root of the smallest over the largest
 *  eigenvalue of the readings' covariance: 1 for a full sphere of
 *  orientations, ~0 for a turn about one axis, whose readings lie on a
 *  circle); a quadric that is not an ellipsoid; a result outside what the
 *  plugin accepts (singular values of S in [0.2, 5]).
 *
 *  Units: µT throughout.
 */
#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace auvnav::magcal
{
class MagCalibrationError : public std::runtime_error
{
 public:
	using std::runtime_error::runtime_error;
};

struct FitOptions
{
	double field_ut = 0;            //!< Earth field strength F [µT]; 0: unknown (det S = 1)
	std::size_t min_samples = 100;  //!< fewer readings are refused
	double min_spread = 0.25;       //!< see the file comment; a turn about one axis gives ~0
};

struct FitResult
{
	Eigen::Vector3d hard_iron_ut = Eigen::Vector3d::Zero();   //!< b [µT], sensor axes
	Eigen::Matrix3d soft_iron = Eigen::Matrix3d::Identity();  //!< S, symmetric positive definite
	double field_ut = 0;         //!< calibrated norm |S⁻¹ (raw − b)| the fit enforces [µT]
	double rms_residual_ut = 0;  //!< RMS of |S⁻¹ (raw − b)| − field_ut [µT]
	double max_residual_ut = 0;  //!< largest |residual| [µT]
	Eigen::Vector3d hard_iron_sigma_ut = Eigen::Vector3d::Zero();  //!< 1σ of b from the fit's covariance
	double spread = 0;                                             //!< see the file comment
	int directions_covered = 0;  //!< of the 12 icosahedron directions, those with ≥ 3 calibrated readings
	static constexpr int kDirections = 12;
	std::size_t samples = 0;
	int iterations = 0;  //!< Gauss–Newton iterations used
};

/** Fits b and S to `raw_ut`; throws MagCalibrationError when refused. */
FitResult fit(const std::vector<Eigen::Vector3d>& raw_ut, const FitOptions& options);

/** An accelerometer reading (specific force) in the body frame. */
struct TimedAccel
{
	double t_s;                //!< relative to Samples::t_first_s
	Eigen::Vector3d f_b_mps2;  //!< IMU_X/Y/Z_ACC rotated by the observation's sensorPose
};

/** Readings of one sensor label from a rawlog. */
struct Samples
{
	std::vector<Eigen::Vector3d> raw_ut;  //!< IMU_MAG_X/Y/Z × 100 (gauss → µT)
	std::vector<double> t_s;              //!< time of each kept reading, relative to t_first_s
	Eigen::Matrix3d R_b_mag = Eigen::Matrix3d::Identity();  //!< magnetometer mounting (first kept reading)
	std::vector<TimedAccel> accel;    //!< readings of the accelerometer label, in time order
	double t_first_s = 0;             //!< time of the label's first reading [s, Unix]
	double t_from_s = 0, t_to_s = 0;  //!< span of the readings kept, relative to t_first_s
	std::size_t unusable = 0;         //!< with the label but missing or non-finite fields
	std::vector<std::string> labels;  //!< every label in the log (for error messages)
};

/** Reads the CObservationIMU readings labelled `label` whose time, relative
 *  to the label's first reading, lies in [from_s, to_s], and every
 *  accelerometer reading labelled `accel_label` (none if empty). Any
 *  observation class auvnav registers may be in the log. Throws
 *  io::RawlogError for an unreadable log. */
Samples readSamples(const std::string& rawlog, const std::string& label, double from_s, double to_s,
                    const std::string& accel_label = "");

/** The magnetometer plugin's keys (hard_iron_ut, soft_iron) with comments
 *  on where they came from and how good the fit is. */
std::string pluginYaml(const FitResult& r, const std::string& source_comment);

/** Centroid c and RMS distance s of `pts` from it: the algebraic fits work
 *  on (p − c)/s, since raw µT squared swamp the constant term. */
template <int N>
void centreAndScale(const std::vector<Eigen::Matrix<double, N, 1>>& pts, Eigen::Matrix<double, N, 1>& c,
                    double& s)
{
	c.setZero();
	for (const auto& p : pts) c += p;
	c /= static_cast<double>(pts.size());
	s = 0;
	for (const auto& p : pts) s += (p - c).squaredNorm();
	s = std::sqrt(s / static_cast<double>(pts.size()));
}

}  // namespace auvnav::magcal
