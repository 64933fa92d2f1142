#pragma once
/** @file sensors.h
 *  Simulated sensors. Each turns the true vehicle state into the observation
 *  a real instrument would log, with the error sources named in its config
 *  (values and their datasheet sources are in config/sensors/). Each sensor
 *  owns its random stream, so enabling one sensor never changes another's
 *  noise for the same seed.
 */
#include <auvnav/config.h>
#include <auvnav/earth.h>
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationUSBL.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/random/RandomGenerators.h>

#include <Eigen/Core>
#include <array>
#include <optional>

#include "environment.h"
#include "logger_clock.h"
#include "noise.h"
#include "vehicle.h"

namespace auvnav::sim
{
/** What the sensors may look at: the true state at one instant. */
struct Truth
{
	double t_s = 0;                   //!< mission time [s]
	mrpt::Clock::time_point stamp;    //!< absolute time of this instant
	const VehicleState* x = nullptr;  //!< true vehicle state
	Vector6d nu_dot_b = Vector6d::Zero();
	Eigen::Vector3d current_n{0, 0, 0};  //!< water current at the vehicle
};

/** Mounting of a sensor on the vehicle: nominal (what the observation and the
 *  navigator's config say) and true (nominal rotated by a small misalignment). */
struct Mounting
{
	Eigen::Vector3d position_b{0, 0, 0};
	Eigen::Matrix3d R_bs_nominal = Eigen::Matrix3d::Identity();
	Eigen::Matrix3d R_bs_true = Eigen::Matrix3d::Identity();
	mrpt::poses::CPose3D nominalPose() const;
	static Mounting fromConfig(const config::Node& n);
};

/** Inertial measurement unit: angular rate and specific force of the IMU
 *  point in sensor axes, each axis with white noise, turn-on bias and bias
 *  wander (noise.h); optionally (MEMS) a per-axis scale-factor error
 *  (`scale_factor_error_ppm`, gyro and accelerometer) and the gyro's
 *  g-sensitivity (`g_sensitivity_dps_per_g`: 3 values = each gyro axis
 *  sensitive to the specific force along its own axis, or 9 values = the full
 *  matrix row-major, row = gyro axis, column = specific-force axis). Both are
 *  fixed config values (a unit's calibration error), so they cost no random
 *  draw and leave the noise of a seed unchanged. */
class ImuSim
{
 public:
	ImuSim(const config::Node& n, uint32_t seed);
	double period_s() const { return period_s_; }
	/** Specific force and inertial angular rate at the IMU, with errors. */
	mrpt::obs::CObservationIMU::Ptr sample(const Truth& truth, const earth::TangentFrame& frame);
	Eigen::Vector3d gyroBias() const;
	Eigen::Vector3d accelBias() const;

 private:
	double period_s_;
	Mounting mount_;
	mrpt::random::CRandomGenerator rng_;
	std::vector<InertialAxisError> gyro_, accel_;
	// Deterministic MEMS errors (config values, no random draw): output =
	// (1 + scale) ∘ true + G_g · f (gyro only) + bias + noise, in sensor axes.
	Eigen::Vector3d gyro_scale_ = Eigen::Vector3d::Zero(), accel_scale_ = Eigen::Vector3d::Zero();
	Eigen::Matrix3d G_radps_per_mps2_ = Eigen::Matrix3d::Zero();  //!< gyro g-sensitivity
	bool has_scale_or_g_ = false;
	std::string label_;
};

/** A Janus DVL: per-beam radial velocities (noise, scale factor, the true
 *  misalignment, random beam loss, bottom lock inside the altitude window),
 *  reported as a real DVL is configured to (`output_frame`, `sign`):
 *  - instrument: the least-squares 3-D velocity in the sensor frame (default);
 *  - vehicle: that velocity rotated by the NOMINAL mounting (the DVL's own
 *    alignment setting; the true misalignment stays in it);
 *  - earth_ned / earth_enu: rotated by the DVL's own attitude sensors, i.e.
 *    the TRUE attitude of the instrument, with a heading error constant per
 *    run (`heading_error_sigma_deg`, default 0);
 *  - beam: the radial velocities themselves (NaN for invalid beams), no 3-D
 *    velocity (NaN);
 *  - sign bottom_over_instrument (Teledyne RDI PD0) negates every velocity.
 *  The radial draws are the same in every mode, so for one seed the modes
 *  differ only in how the same ping is reported.
 *  Optional whole-ping outages (small DVLs lose lock in bursts: turns, weed,
 *  aerated water): they start as a Poisson process of `dropout_rate_per_h`
 *  while locked and last an exponential time of mean `dropout_duration_s`;
 *  during one every beam is invalid. Own stream; off by default. */
class DvlSim
{
 public:
	DvlSim(const config::Node& n, uint32_t seed);
	double period_s() const { return period_s_; }
	double offset_s() const { return offset_s_; }
	auvnav::obs::CObservationDVL::Ptr sample(const Truth& truth, const Environment& env);
	/** The DVL compass's heading error of this run [rad] (Earth frames only). */
	double headingError_rad() const { return heading_error_rad_; }
	/** Whole-ping outages begun so far. */
	std::size_t outages() const { return outages_; }

 private:
	/** Writes the least-squares sensor-frame velocity `v_ls_s` and its
	 *  covariance `C_ls_s` in the configured frame and sign. */
	void reportVelocity(auvnav::obs::CObservationDVL& obs, const VehicleState& x,
	                    const Eigen::Vector3d& v_ls_s, const Eigen::Matrix3d& C_ls_s) const;

	double period_s_, offset_s_;
	Mounting mount_;
	double inclination_rad_, beam_sigma_mps_, scale_factor_, min_altitude_m_, max_range_m_,
	    beam_dropout_probability_;
	std::vector<Eigen::Vector3d> beam_dirs_s_;
	std::vector<double> beam_azimuths_rad_;
	auvnav::obs::DvlFrame frame_ = auvnav::obs::DvlFrame::Instrument;
	auvnav::obs::DvlSign sign_ = auvnav::obs::DvlSign::VehicleOverBottom;
	double heading_error_rad_ = 0;
	double dropout_rate_per_s_ = 0, dropout_duration_s_ = 0;
	double outage_until_s_ = -1, last_ping_s_ = -1;
	std::size_t outages_ = 0;
	mrpt::random::CRandomGenerator outage_rng_;
	mrpt::random::CRandomGenerator rng_;
	std::string label_;
};

class AdcpSim
{
 public:
	AdcpSim(const config::Node& n, uint32_t seed);
	double period_s() const { return period_s_; }
	double offset_s() const { return offset_s_; }
	auvnav::obs::CObservationADCP::Ptr sample(const Truth& truth, const Environment& env);
	Eigen::Vector2d bias() const { return {bias_[0].value(), bias_[1].value()}; }
	double farRange_m() const;

 private:
	double period_s_, offset_s_;
	Mounting mount_;
	double blank_m_, cell_m_, sigma_mps_, inclination_rad_, min_correlation_, bad_cell_sigma_mps_;
	int cell_count_;
	std::array<GaussMarkov, 2> bias_;
	double last_t_s_ = 0;
	mrpt::random::CRandomGenerator rng_;
	std::string label_;
};

/** Absolute pressure at the sensor: atmosphere + ρ g depth + a constant bias
 *  per run + white noise, rounded to the sensor's resolution (`resolution_pa`,
 *  0 = none) as a digital sensor (MS5837 class) reports it. */
class PressureSim
{
 public:
	PressureSim(const config::Node& n, uint32_t seed);
	double period_s() const { return period_s_; }
	double offset_s() const { return offset_s_; }
	auvnav::obs::CObservationPressure::Ptr sample(const Truth& truth, const Environment& env,
	                                              const earth::TangentFrame& frame);

 private:
	double period_s_, offset_s_;
	Mounting mount_;
	double sigma_pa_, bias_pa_, resolution_pa_;
	mrpt::random::CRandomGenerator rng_;
	std::string label_;
};

class GpsSim
{
 public:
	GpsSim(const config::Node& n, uint32_t seed);
	double period_s() const { return period_s_; }
	/** A fix, or nothing when the antenna is under water or reacquiring. */
	mrpt::obs::CObservationGPS::Ptr sample(const Truth& truth, const earth::TangentFrame& frame);
	std::size_t outliers() const { return outliers_; }

 private:
	double period_s_;
	Mounting mount_;
	double sigma_white_m_, sigma_corr_m_, tau_corr_s_, sigma_vertical_m_, outlier_probability_,
	    outlier_min_m_, outlier_max_m_, reacquisition_s_, min_antenna_height_m_;
	std::array<GaussMarkov, 2> corr_;
	double last_t_s_ = 0;
	double surfaced_since_s_ = -1;  // −1: antenna under water
	std::size_t outliers_ = 0;
	mrpt::random::CRandomGenerator rng_;
	std::string label_;
};

/** A ship's USBL tracking the vehicle's transponder (`usbl:`): the ship holds
 *  station at `ship_position_ne_m` with its transducer `transducer_depth_m`
 *  deep; each ping (`rate_hz`) is lost with `dropout_probability`, else the
 *  fix is the true transponder position plus a constant horizontal bias
 *  (`bias_north_m`, `bias_east_m`, config values: the ship's GNSS and alignment), white noise of
 *  σ = hypot(sigma_m, sigma_range_fraction · slant range) per horizontal axis
 *  (`depth_sigma_m` vertically) and, with `outlier_probability`, a gross
 *  error of outlier_min_m..outlier_max_m in a random direction (multipath).
 *  The fix reaches the logger `latency_s` after it was taken (travel time,
 *  processing, telemetry): the observation's timestamp is that arrival time,
 *  its measurement_time the fix time (or unset, `report_measurement_time:
 *  false`, as a system that does not say). Geodetic fix with the covariance
 *  the error model gives (`report_covariance`). The random draws per ping do
 *  not depend on the latency or the reporting options, so for one seed those
 *  variants log the same fixes. Own stream. */
class UsblSim
{
 public:
	UsblSim(const config::Node& n, uint32_t seed);
	double period_s() const { return period_s_; }
	/** A fix (timestamp = arrival), or nothing (dropout). */
	auvnav::obs::CObservationUSBL::Ptr sample(const Truth& truth, const earth::TangentFrame& frame);
	std::size_t outliers() const { return outliers_; }

 private:
	double period_s_;
	Mounting mount_;
	Eigen::Vector3d ship_n_;
	double sigma_m_, sigma_range_fraction_, depth_sigma_m_, latency_s_, dropout_probability_,
	    outlier_probability_, outlier_min_m_, outlier_max_m_;
	Eigen::Vector2d bias_ne_m_;
	bool report_time_, report_covariance_;
	std::size_t outliers_ = 0;
	mrpt::random::CRandomGenerator rng_;
	std::string label_;
};

/** The Earth's magnetic field at the mission site (environment.magnetic_field):
 *  total intensity F [µT], declination D (east of true north) and inclination I
 *  (below the horizontal, positive down: northern hemisphere), constant over
 *  the mission. m_n = F [cos I cos D, cos I sin D, sin I] in NED. */
struct MagneticField
{
	double total_intensity_ut = 50, declination_rad = 0, inclination_rad = 0;
	Eigen::Vector3d fieldNed_ut() const;
	static MagneticField fromConfig(const config::Node& n);
};

/** A 3-axis magnetometer (MMC5983/HMC5883 class on a small vehicle):
 *    h_s = S · R_sn m_n + b_hard + Σ_i g_i |F_i| + w,   w ~ N(0, σ² I)
 *  with the soft-iron matrix S (`soft_iron`, 9 values row-major, default
 *  identity), hard-iron offset b_hard (`hard_iron_ut`), a disturbance
 *  proportional to the force each thruster produces now, |F_i| [N] (motor
 *  currents grow with it; `thruster_disturbance_ut_per_n`: 3 values for
 *  every thruster or 3 per thruster) and white noise (`noise_sigma_ut`).
 *  R_sn uses the TRUE mounting (nominal + misalignment); the nominal one is
 *  written as sensorPose.
 *
 *  Output contract (the navigator's magnetometer plugin reads exactly this):
 *  an mrpt::obs::CObservationIMU labelled `label` (default "MAG") with only
 *  IMU_MAG_X/Y/Z set and marked present, in GAUSS (MRPT's unit; 1 G = 100 µT),
 *  in the sensor axes (FRD when mounted with zero orientation, i.e. the
 *  IMU/body axes), sensorPose = the nominal mounting. */
class MagnetometerSim
{
 public:
	MagnetometerSim(const config::Node& n, const MagneticField& field, std::size_t thruster_count,
	                uint32_t seed);
	double period_s() const { return period_s_; }
	double offset_s() const { return offset_s_; }
	mrpt::obs::CObservationIMU::Ptr sample(const Truth& truth);
	/** The noise-free reading for a state [µT] (for tests and evaluation). */
	Eigen::Vector3d expected_ut(const VehicleState& x) const;
	const Eigen::Matrix3d& softIron() const { return soft_iron_; }
	const Eigen::Vector3d& hardIron_ut() const { return hard_iron_ut_; }

 private:
	double period_s_, offset_s_;
	Mounting mount_;
	Eigen::Vector3d m_n_ut_;
	Eigen::Matrix3d soft_iron_ = Eigen::Matrix3d::Identity();
	Eigen::Vector3d hard_iron_ut_ = Eigen::Vector3d::Zero();
	Eigen::Matrix<double, 3, Eigen::Dynamic> thruster_gain_ut_per_n_;
	double sigma_ut_;
	mrpt::random::CRandomGenerator rng_;
	std::string label_;
};

}  // namespace auvnav::sim
