#include "sensors.h"

#include <mrpt/obs/gnss_messages_ascii_nmea.h>
#include <mrpt/system/datetime.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>

namespace auvnav::sim
{
namespace
{
constexpr double kDeg = M_PI / 180;

Eigen::Matrix3d rotationFromYprDeg(const Eigen::Vector3d& ypr_deg)
{
	// Euler angles only at the config boundary, converted at once.
	const mrpt::poses::CPose3D p(0, 0, 0, ypr_deg[0] * kDeg, ypr_deg[1] * kDeg, ypr_deg[2] * kDeg);
	return p.getRotationMatrix().asEigen();
}

/** Derives an independent stream from the mission seed and a sensor id. */
uint32_t streamSeed(uint32_t seed, uint32_t sensor_id)
{
	return seed * 7919u + sensor_id * 104729u + 1u;
}

/** Position and velocity of a point fixed on the vehicle at `r_b`. */
struct PointKinematics
{
	Eigen::Vector3d p_n, v_n, v_b;
};
PointKinematics pointOnVehicle(const VehicleState& x, const Eigen::Vector3d& r_b)
{
	const Eigen::Matrix3d R_nb = x.R_nb();
	PointKinematics k;
	k.v_b = x.nu_b.head<3>() + x.nu_b.tail<3>().cross(r_b);
	k.p_n = x.p_n + R_nb * r_b;
	k.v_n = R_nb * k.v_b;
	return k;
}

InertialAxisErrorParams axisParams(const config::Node& n, double unit)
{
	InertialAxisErrorParams p;
	p.random_walk = n.nonNegative("random_walk") * unit;
	p.bias_instability = n.nonNegative("bias_instability") * unit;
	p.bias_tau_s = n.positive("bias_correlation_time_s");
	p.turn_on_sigma = n.nonNegative("turn_on_bias_sigma") * unit;
	return p;
}
}  // namespace

mrpt::poses::CPose3D Mounting::nominalPose() const
{
	mrpt::math::CMatrixDouble33 R(R_bs_nominal);
	return mrpt::poses::CPose3D(R, mrpt::math::CVectorFixedDouble<3>(position_b));
}

Mounting Mounting::fromConfig(const config::Node& n)
{
	Mounting m;
	m.position_b = n.vector3("position_m");
	m.R_bs_nominal = rotationFromYprDeg(n.vector3("orientation_ypr_deg", Eigen::Vector3d::Zero()));
	m.R_bs_true =
	    m.R_bs_nominal * rotationFromYprDeg(n.vector3("misalignment_ypr_deg", Eigen::Vector3d::Zero()));
	return m;
}

// ---------------------------------------------------------------- IMU
ImuSim::ImuSim(const config::Node& n, uint32_t seed)
    : period_s_(1.0 / n.positive("rate_hz")),
      mount_(Mounting::fromConfig(n)),
      label_(n.string("label", "IMU"))
{
	rng_.randomize(streamSeed(seed, 1));
	// Datasheet units in the config: gyro °/√h and °/h; accelerometer mg/√Hz and mg.
	const auto g = n.child("gyro");
	const auto a = n.child("accelerometer");
	InertialAxisErrorParams gp = axisParams(g, 1.0);
	gp.random_walk *= kDeg / 60.0;  // °/√h -> rad/√s
	gp.bias_instability *= kDeg / 3600.0;
	gp.turn_on_sigma *= kDeg / 3600.0;
	InertialAxisErrorParams ap = axisParams(a, 1e-3 * 9.80665);  // mg -> m/s²; mg/√Hz -> m/s²·√s
	for (int i = 0; i < 3; ++i)
	{
		gyro_.emplace_back(gp, rng_);
		accel_.emplace_back(ap, rng_);
	}
	// MEMS calibration errors, fixed per unit (config values, no draw).
	auto scale = [](const config::Node& block)
	{
		const Eigen::Vector3d ppm = block.vector3("scale_factor_error_ppm", Eigen::Vector3d::Zero());
		if ((ppm.array().abs() > 1e5).any())
			block.fail("scale_factor_error_ppm", "expected |error| <= 100000 ppm (10 %) per axis");
		return Eigen::Vector3d(1e-6 * ppm);
	};
	gyro_scale_ = scale(g);
	accel_scale_ = scale(a);
	if (g.has("g_sensitivity_dps_per_g"))
	{
		const auto v = g.numbers("g_sensitivity_dps_per_g");
		if (v.size() != 3 && v.size() != 9)
			g.fail("g_sensitivity_dps_per_g",
			       "expected 3 values (diagonal) or 9 (row-major matrix, row = gyro axis)");
		for (double e : v)
			if (std::abs(e) > 1.0) g.fail("g_sensitivity_dps_per_g", "expected |value| <= 1 deg/s per g");
		Eigen::Matrix3d G = Eigen::Matrix3d::Zero();
		for (int r = 0; r < 3; ++r)
			for (int c = 0; c < 3; ++c)
				if (v.size() == 9) G(r, c) = v[3 * r + c];
		if (v.size() == 3) G.diagonal() << v[0], v[1], v[2];
		G_radps_per_mps2_ = G * (kDeg / 9.80665);  // (deg/s)/g -> (rad/s)/(m/s²)
	}
	has_scale_or_g_ = !gyro_scale_.isZero(0) || !accel_scale_.isZero(0) || !G_radps_per_mps2_.isZero(0);
}

mrpt::obs::CObservationIMU::Ptr ImuSim::sample(const Truth& t, const earth::TangentFrame& frame)
{
	const VehicleState& x = *t.x;
	const Eigen::Matrix3d R_nb = x.R_nb();
	const Eigen::Vector3d r_b = mount_.position_b;
	const Eigen::Vector3d w_b = x.nu_b.tail<3>();
	const Eigen::Vector3d wdot_b = t.nu_dot_b.tail<3>();
	// Acceleration of the IMU point relative to the Earth-fixed frame, in body.
	const Eigen::Vector3d a_cg_b = t.nu_dot_b.head<3>() + w_b.cross(x.nu_b.head<3>());
	const Eigen::Vector3d a_imu_b = a_cg_b + wdot_b.cross(r_b) + w_b.cross(w_b.cross(r_b));
	const PointKinematics imu = pointOnVehicle(x, r_b);
	const Eigen::Vector3d& omega_ie_n = frame.earthRate();
	// Specific force in a rotating Earth frame: a_rel + 2Ω×v − g (g includes centrifugal).
	const Eigen::Vector3d f_b =
	    a_imu_b + R_nb.transpose() * (2 * omega_ie_n.cross(imu.v_n) - frame.gravityNed(imu.p_n));
	const Eigen::Vector3d omega_ib_b = w_b + R_nb.transpose() * omega_ie_n;
	const Eigen::Matrix3d R_sb = mount_.R_bs_true.transpose();
	Eigen::Vector3d f_s = R_sb * f_b;
	Eigen::Vector3d w_s = R_sb * omega_ib_b;
	if (has_scale_or_g_)
	{
		// g-sensitivity acts on the true specific force, before the
		// accelerometer's own scale error.
		w_s = w_s.cwiseProduct(Eigen::Vector3d::Ones() + gyro_scale_) + G_radps_per_mps2_ * f_s;
		f_s = f_s.cwiseProduct(Eigen::Vector3d::Ones() + accel_scale_);
	}

	auto obs = mrpt::obs::CObservationIMU::Create();
	obs->timestamp = t.stamp;
	obs->sensorLabel = label_;
	obs->sensorPose = mount_.nominalPose();
	using namespace mrpt::obs;
	const TIMUDataIndex gyro_idx[3] = {IMU_WX, IMU_WY, IMU_WZ};
	const TIMUDataIndex acc_idx[3] = {IMU_X_ACC, IMU_Y_ACC, IMU_Z_ACC};
	for (int i = 0; i < 3; ++i)
	{
		obs->set(gyro_idx[i], w_s[i] + gyro_[i].sample(period_s_, rng_));
		obs->set(acc_idx[i], f_s[i] + accel_[i].sample(period_s_, rng_));
	}
	return obs;
}

Eigen::Vector3d ImuSim::gyroBias() const
{
	return {gyro_[0].bias(), gyro_[1].bias(), gyro_[2].bias()};
}
Eigen::Vector3d ImuSim::accelBias() const
{
	return {accel_[0].bias(), accel_[1].bias(), accel_[2].bias()};
}

// ---------------------------------------------------------------- DVL
DvlSim::DvlSim(const config::Node& n, uint32_t seed)
    : period_s_(1.0 / n.positive("rate_hz")),
      offset_s_(n.nonNegative("time_offset_s", 0.0)),
      mount_(Mounting::fromConfig(n)),
      inclination_rad_(n.inRange("beam_inclination_deg", 5, 60) * kDeg),
      beam_sigma_mps_(n.nonNegative("beam_velocity_sigma_mps")),
      scale_factor_(n.inRange("scale_factor_error", -0.1, 0.1)),
      min_altitude_m_(n.nonNegative("min_altitude_m")),
      max_range_m_(n.positive("max_altitude_m")),
      beam_dropout_probability_(n.inRange("beam_dropout_probability", 0, 1)),
      label_(n.string("label", "DVL"))
{
	rng_.randomize(streamSeed(seed, 2));
	const int beams = n.integer("beam_count", 4);
	if (beams < 3 || beams > 8) n.fail("beam_count", "expected 3..8 beams");
	// Default: equally spaced, the first 45° off the sensor x axis (a 4-beam
	// Janus head with its beams on the diagonals).
	for (int i = 0; i < beams; ++i) beam_azimuths_rad_.push_back((45.0 + 360.0 * i / beams) * kDeg);
	if (n.has("beam_azimuths_deg"))
	{
		const auto az_deg = n.numbers("beam_azimuths_deg");
		if (az_deg.size() != beam_azimuths_rad_.size())
			n.fail("beam_azimuths_deg", "expected " + std::to_string(beams) + " azimuths (beam_count)");
		for (std::size_t i = 0; i < az_deg.size(); ++i) beam_azimuths_rad_[i] = az_deg[i] * kDeg;
	}
	for (double az : beam_azimuths_rad_)
		beam_dirs_s_.emplace_back(std::sin(inclination_rad_) * std::cos(az),
		                          std::sin(inclination_rad_) * std::sin(az), std::cos(inclination_rad_));
	Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
	for (const auto& d : beam_dirs_s_) AtA += d * d.transpose();
	if (Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(AtA, Eigen::EigenvaluesOnly).eigenvalues()[0] < 1e-3)
		n.fail("beam_azimuths_deg", "the beams do not span 3-D (azimuths too close)");

	const std::string frame = n.string("output_frame", "instrument");
	if (!auvnav::obs::parseDvlFrame(frame, frame_))
		n.fail("output_frame",
		       "expected instrument, vehicle, earth_ned, earth_enu or beam, got '" + frame + "'");
	const std::string sign = n.string("sign", "vehicle_over_bottom");
	if (!auvnav::obs::parseDvlSign(sign, sign_))
		n.fail("sign", "expected vehicle_over_bottom or bottom_over_instrument, got '" + sign + "'");
	// The DVL compass's error has its own stream: neither the setting nor the
	// output frame moves the beam noise of a given seed.
	mrpt::random::CRandomGenerator compass_rng;
	compass_rng.randomize(streamSeed(seed, 12));
	heading_error_rad_ =
	    n.inRange("heading_error_sigma_deg", 0, 90, 0.0) * kDeg * compass_rng.drawGaussian1D_normalized();
	dropout_rate_per_s_ = n.inRange("dropout_rate_per_h", 0, 3600, 0.0) / 3600;
	dropout_duration_s_ = n.inRange("dropout_duration_s", 0, 600, 0.0);
	if (dropout_rate_per_s_ > 0 && !(dropout_duration_s_ > 0))
		n.fail("dropout_duration_s", "must be > 0 when dropout_rate_per_h is set");
	outage_rng_.randomize(streamSeed(seed, 13));
}

void DvlSim::reportVelocity(auvnav::obs::CObservationDVL& obs, const VehicleState& x,
                            const Eigen::Vector3d& v_ls_s, const Eigen::Matrix3d& C_ls_s) const
{
	using auvnav::obs::DvlFrame;
	const double sgn = sign_ == auvnav::obs::DvlSign::BottomOverInstrument ? -1.0 : 1.0;
	auto write = [&obs](const Eigen::Vector3d& v, const Eigen::Matrix3d& C)
	{
		for (int i = 0; i < 3; ++i) obs.velocity_s_mps[i] = v[i];
		for (int r = 0; r < 3; ++r)
			for (int c = 0; c < 3; ++c) obs.velocity_cov[3 * r + c] = C(r, c);
	};
	// Rotation from the sensor frame into the reported one.
	Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
	switch (frame_)
	{
		case DvlFrame::Instrument:
			write(sgn * v_ls_s, C_ls_s);
			return;  // as it always was, bit for bit
		case DvlFrame::Vehicle:
			R = mount_.R_bs_nominal;
			break;
		case DvlFrame::EarthNed:
		case DvlFrame::EarthEnu:
			// The DVL's own attitude sensors see the housing's true attitude;
			// its compass adds a heading error about the down axis.
			R = Eigen::AngleAxisd(heading_error_rad_, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
			    x.R_nb() * mount_.R_bs_true;
			if (frame_ == DvlFrame::EarthEnu)
			{
				Eigen::Matrix3d ned_to_enu;
				ned_to_enu << 0, 1, 0, 1, 0, 0, 0, 0, -1;
				R = ned_to_enu * R;
			}
			break;
		case DvlFrame::Beam:
			return;
	}
	write(sgn * (R * v_ls_s), R * C_ls_s * R.transpose());
}

auvnav::obs::CObservationDVL::Ptr DvlSim::sample(const Truth& t, const Environment& env)
{
	const VehicleState& x = *t.x;
	const PointKinematics s = pointOnVehicle(x, mount_.position_b);
	const Eigen::Matrix3d R_ns = x.R_nb() * mount_.R_bs_true;
	const Eigen::Vector3d v_s = R_ns.transpose() * s.v_n;
	const bool beam_mode = frame_ == auvnav::obs::DvlFrame::Beam;
	const double sgn = sign_ == auvnav::obs::DvlSign::BottomOverInstrument ? -1.0 : 1.0;

	auto obs = auvnav::obs::CObservationDVL::Create();
	obs->timestamp = t.stamp;
	obs->sensorLabel = label_;
	obs->sensorPose = mount_.nominalPose();
	obs->beam_inclination_rad = inclination_rad_;
	obs->frame = frame_;
	obs->sign = sign_;
	obs->beam_velocity_sigma_mps = beam_sigma_mps_;
	bool outage = false;
	if (dropout_rate_per_s_ > 0)
	{
		// Outages start only while locked; the first ping cannot start one.
		if (t.t_s >= outage_until_s_ && last_ping_s_ >= 0 &&
		    outage_rng_.drawUniform(0.0, 1.0) < 1 - std::exp(-dropout_rate_per_s_ * (t.t_s - last_ping_s_)))
		{
			outage_until_s_ = t.t_s - dropout_duration_s_ * std::log(1 - outage_rng_.drawUniform(0.0, 1.0));
			++outages_;
		}
		outage = t.t_s < outage_until_s_;
		last_ping_s_ = t.t_s;
	}
	Eigen::MatrixXd A(beam_dirs_s_.size(), 3);
	Eigen::VectorXd u(beam_dirs_s_.size());
	int valid = 0;
	double altitude_sum = 0;
	for (std::size_t i = 0; i < beam_dirs_s_.size(); ++i)
	{
		const Eigen::Vector3d& d_s = beam_dirs_s_[i];
		auvnav::obs::DvlBeam beam;
		const double slant_max = max_range_m_ / std::cos(inclination_rad_);
		const double range = env.rayToSeabed(s.p_n, R_ns * d_s, slant_max);
		const double vertical = range * std::cos(inclination_rad_);
		const bool dropped = rng_.drawUniform(0.0, 1.0) < beam_dropout_probability_;
		beam.range_m = range > 0 ? range : 0;
		beam.valid =
		    range > 0 && vertical >= min_altitude_m_ && vertical <= max_range_m_ && !dropped && !outage;
		beam.azimuth_rad = beam_azimuths_rad_[i];
		const double radial =
		    (1 + scale_factor_) * d_s.dot(v_s) + beam_sigma_mps_ * rng_.drawGaussian1D_normalized();
		if (beam.valid)
		{
			A.row(valid) = d_s.transpose();
			u[valid] = radial;
			altitude_sum += vertical;
			++valid;
		}
		if (beam_mode) beam.velocity_mps = beam.valid ? sgn * radial : std::nan("");
		obs->beams.push_back(beam);
	}
	obs->bottom_lock = valid >= 3;
	obs->altitude_m = valid > 0 ? altitude_sum / valid : std::nan("");
	if (beam_mode)
	{
		obs->velocity_s_mps.fill(std::nan(""));  // no 3-D velocity in beam coordinates
		obs->velocity_cov.fill(std::nan(""));
	}
	else if (obs->bottom_lock)
	{
		const auto Av = A.topRows(valid);
		const Eigen::Matrix3d AtA = Av.transpose() * Av;
		const Eigen::LDLT<Eigen::Matrix3d> ldlt(AtA);
		const Eigen::Vector3d v = ldlt.solve(Av.transpose() * u.head(valid));
		const Eigen::Matrix3d cov =
		    beam_sigma_mps_ * beam_sigma_mps_ * ldlt.solve(Eigen::Matrix3d::Identity());
		reportVelocity(*obs, x, v, cov);
	}
	return obs;
}

// ---------------------------------------------------------------- ADCP
AdcpSim::AdcpSim(const config::Node& n, uint32_t seed)
    : period_s_(1.0 / n.positive("rate_hz")),
      offset_s_(n.nonNegative("time_offset_s", 0.0)),
      mount_(Mounting::fromConfig(n)),
      blank_m_(n.nonNegative("blank_distance_m")),
      cell_m_(n.positive("cell_size_m")),
      sigma_mps_(n.nonNegative("velocity_sigma_mps")),
      inclination_rad_(n.inRange("beam_inclination_deg", 5, 60) * kDeg),
      min_correlation_(n.inRange("min_correlation", 0, 1)),
      bad_cell_sigma_mps_(n.nonNegative("low_correlation_sigma_mps")),
      cell_count_(n.integer("cell_count")),
      label_(n.string("label", "ADCP"))
{
	if (cell_count_ < 1 || cell_count_ > 256) n.fail("cell_count", "expected 1..256");
	rng_.randomize(streamSeed(seed, 3));
	const double sigma = n.nonNegative("bias_sigma_mps");
	const double tau = n.positive("bias_correlation_time_s");
	bias_ = {GaussMarkov(sigma, tau, rng_), GaussMarkov(sigma, tau, rng_)};
}

double AdcpSim::farRange_m() const
{
	return blank_m_ + cell_count_ * cell_m_;
}

auvnav::obs::CObservationADCP::Ptr AdcpSim::sample(const Truth& t, const Environment& env)
{
	const double dt = t.t_s - last_t_s_;
	last_t_s_ = t.t_s;
	if (dt > 0)
		for (auto& b : bias_) b.advance(dt, rng_);
	const VehicleState& x = *t.x;
	const PointKinematics s = pointOnVehicle(x, mount_.position_b);
	const Eigen::Matrix3d R_ns = x.R_nb() * mount_.R_bs_true;
	const Eigen::Vector3d axis_n = R_ns.col(2);
	// Side lobes contaminate the last (1 − cos θ) of the range to the seabed.
	const double bottom = env.rayToSeabed(s.p_n, axis_n, farRange_m() + 50);
	const double clean_range = bottom > 0 ? bottom * std::cos(inclination_rad_) : INFINITY;

	auto obs = auvnav::obs::CObservationADCP::Create();
	obs->timestamp = t.stamp;
	obs->sensorLabel = label_;
	obs->sensorPose = mount_.nominalPose();
	obs->blank_distance_m = blank_m_;
	obs->cell_size_m = cell_m_;
	obs->velocity_sigma_mps = sigma_mps_;
	const Eigen::Vector3d bias_s(bias_[0].value(), bias_[1].value(), 0.0);
	for (int i = 0; i < cell_count_; ++i)
	{
		auvnav::obs::AdcpCell cell;
		const double d = obs->cellDistance(i);
		const bool in_water = d + 0.5 * cell_m_ <= clean_range;
		const Eigen::Vector3d p_cell = s.p_n + d * axis_n;
		// In water: current relative to the sensor; in the seabed: bottom echo.
		const Eigen::Vector3d rel_n =
		    in_water ? Eigen::Vector3d(env.current(p_cell.z()) - s.v_n) : Eigen::Vector3d(-s.v_n);
		cell.correlation = std::clamp(0.95 - 0.02 * i + 0.03 * rng_.drawGaussian1D_normalized(), 0.0, 1.0);
		const bool good = cell.correlation >= min_correlation_;
		const double sigma = good ? sigma_mps_ : bad_cell_sigma_mps_;
		const Eigen::Vector3d v_s =
		    R_ns.transpose() * rel_n + bias_s +
		    sigma * Eigen::Vector3d(rng_.drawGaussian1D_normalized(), rng_.drawGaussian1D_normalized(),
		                            rng_.drawGaussian1D_normalized());
		for (int k = 0; k < 3; ++k) cell.velocity_s_mps[k] = v_s[k];
		cell.valid = in_water && good;
		obs->cells.push_back(cell);
	}
	return obs;
}

// ---------------------------------------------------------------- pressure
PressureSim::PressureSim(const config::Node& n, uint32_t seed)
    : period_s_(1.0 / n.positive("rate_hz")),
      offset_s_(n.nonNegative("time_offset_s", 0.0)),
      mount_(Mounting::fromConfig(n)),
      sigma_pa_(n.nonNegative("noise_sigma_pa")),
      resolution_pa_(n.inRange("resolution_pa", 0, 1e4, 0.0)),
      label_(n.string("label", "PRESSURE"))
{
	rng_.randomize(streamSeed(seed, 4));
	bias_pa_ = n.nonNegative("bias_sigma_pa") * rng_.drawGaussian1D_normalized();
}

auvnav::obs::CObservationPressure::Ptr PressureSim::sample(const Truth& t, const Environment& env,
                                                           const earth::TangentFrame& frame)
{
	const PointKinematics s = pointOnVehicle(*t.x, mount_.position_b);
	const double depth = std::max(0.0, s.p_n.z());
	const double g = frame.gravityNed(s.p_n).z();
	auto obs = auvnav::obs::CObservationPressure::Create();
	obs->timestamp = t.stamp;
	obs->sensorLabel = label_;
	obs->sensorPose = mount_.nominalPose();
	obs->pressure_pa = env.water().atmospheric_pressure_pa + env.water().density_kg_m3 * g * depth +
	                   bias_pa_ + sigma_pa_ * rng_.drawGaussian1D_normalized();
	if (resolution_pa_ > 0) obs->pressure_pa = resolution_pa_ * std::round(obs->pressure_pa / resolution_pa_);
	obs->temperature_c = env.temperature(depth);
	return obs;
}

// ---------------------------------------------------------------- GPS
GpsSim::GpsSim(const config::Node& n, uint32_t seed)
    : period_s_(1.0 / n.positive("rate_hz")),
      mount_(Mounting::fromConfig(n)),
      sigma_white_m_(n.nonNegative("white_sigma_m")),
      sigma_corr_m_(n.nonNegative("correlated_sigma_m")),
      tau_corr_s_(n.positive("correlation_time_s")),
      sigma_vertical_m_(n.nonNegative("vertical_sigma_m")),
      outlier_probability_(n.inRange("outlier_probability", 0, 1)),
      outlier_min_m_(n.nonNegative("outlier_min_m")),
      outlier_max_m_(n.nonNegative("outlier_max_m")),
      reacquisition_s_(n.nonNegative("reacquisition_s")),
      min_antenna_height_m_(n.nonNegative("min_antenna_height_m")),
      label_(n.string("label", "GPS"))
{
	if (outlier_max_m_ < outlier_min_m_) n.fail("outlier_max_m", "must be >= outlier_min_m");
	rng_.randomize(streamSeed(seed, 5));
	corr_ = {GaussMarkov(sigma_corr_m_, tau_corr_s_, rng_), GaussMarkov(sigma_corr_m_, tau_corr_s_, rng_)};
}

mrpt::obs::CObservationGPS::Ptr GpsSim::sample(const Truth& t, const earth::TangentFrame& frame)
{
	const double dt = t.t_s - last_t_s_;
	last_t_s_ = t.t_s;
	if (dt > 0)
		for (auto& c : corr_) c.advance(dt, rng_);
	const PointKinematics a = pointOnVehicle(*t.x, mount_.position_b);
	const bool above_water = a.p_n.z() < -min_antenna_height_m_;
	if (!above_water)
	{
		surfaced_since_s_ = -1;
		return nullptr;
	}
	if (surfaced_since_s_ < 0) surfaced_since_s_ = t.t_s;
	if (t.t_s - surfaced_since_s_ < reacquisition_s_) return nullptr;

	Eigen::Vector3d p_fix = a.p_n;
	p_fix.x() += corr_[0].value() + sigma_white_m_ * rng_.drawGaussian1D_normalized();
	p_fix.y() += corr_[1].value() + sigma_white_m_ * rng_.drawGaussian1D_normalized();
	p_fix.z() += sigma_vertical_m_ * rng_.drawGaussian1D_normalized();
	if (rng_.drawUniform(0.0, 1.0) < outlier_probability_)
	{
		// Gross multipath-like outlier, as seen in the paper's GPS traces.
		const double mag = rng_.drawUniform(outlier_min_m_, outlier_max_m_);
		const double dir = rng_.drawUniform(0.0, 2 * M_PI);
		p_fix.x() += mag * std::cos(dir);
		p_fix.y() += mag * std::sin(dir);
		++outliers_;
	}
	const earth::Geodetic g = frame.toGeodetic(p_fix);

	mrpt::obs::gnss::Message_NMEA_GGA gga;
	const double unix_s = mrpt::Clock::toDouble(t.stamp);
	const double day_s = std::fmod(unix_s, 86400.0);
	gga.fields.UTCTime.hour = static_cast<uint8_t>(day_s / 3600);
	gga.fields.UTCTime.minute = static_cast<uint8_t>(std::fmod(day_s, 3600.0) / 60);
	gga.fields.UTCTime.sec = std::fmod(day_s, 60.0);
	gga.fields.latitude_degrees = g.lat_rad / kDeg;
	gga.fields.longitude_degrees = g.lon_rad / kDeg;
	gga.fields.altitude_meters = g.h_m;
	gga.fields.fix_quality = 1;
	gga.fields.satellitesUsed = 8;
	gga.fields.HDOP = 1.0f;
	auto obs = mrpt::obs::CObservationGPS::Create();
	obs->timestamp = t.stamp;
	obs->originalReceivedTimestamp = t.stamp;
	obs->sensorLabel = label_;
	obs->sensorPose = mount_.nominalPose();
	obs->setMsg(gga);
	return obs;
}

// ---------------------------------------------------------------- USBL
UsblSim::UsblSim(const config::Node& n, uint32_t seed)
    : period_s_(1.0 / n.positive("rate_hz")),
      mount_(Mounting::fromConfig(n)),
      sigma_m_(n.nonNegative("sigma_m")),
      sigma_range_fraction_(n.inRange("sigma_range_fraction", 0, 1, 0.0)),
      depth_sigma_m_(n.nonNegative("depth_sigma_m", 1.0)),
      latency_s_(n.inRange("latency_s", 0, 60)),
      dropout_probability_(n.inRange("dropout_probability", 0, 1, 0.0)),
      outlier_probability_(n.inRange("outlier_probability", 0, 1, 0.0)),
      outlier_min_m_(n.nonNegative("outlier_min_m", 10.0)),
      outlier_max_m_(n.nonNegative("outlier_max_m", 50.0)),
      report_time_(n.boolean("report_measurement_time", true)),
      report_covariance_(n.boolean("report_covariance", true)),
      label_(n.string("label", "USBL"))
{
	const auto ship = n.numbers("ship_position_ne_m");
	if (ship.size() != 2) n.fail("ship_position_ne_m", "expected [north_m, east_m]");
	ship_n_ = {ship[0], ship[1], n.inRange("transducer_depth_m", 0, 100, 2.0)};
	if (outlier_max_m_ < outlier_min_m_) n.fail("outlier_max_m", "must be >= outlier_min_m");
	rng_.randomize(streamSeed(seed, 14));
	bias_ne_m_ = {n.number("bias_north_m", 0.0), n.number("bias_east_m", 0.0)};
}

auvnav::obs::CObservationUSBL::Ptr UsblSim::sample(const Truth& t, const earth::TangentFrame& frame)
{
	// The same draws for every ping, used or not, so that options never
	// change the fixes of a seed.
	const double u_drop = rng_.drawUniform(0.0, 1.0);
	const Eigen::Vector3d w(rng_.drawGaussian1D_normalized(), rng_.drawGaussian1D_normalized(),
	                        rng_.drawGaussian1D_normalized());
	const double u_out = rng_.drawUniform(0.0, 1.0),
	             out_mag = rng_.drawUniform(outlier_min_m_, outlier_max_m_),
	             out_dir = rng_.drawUniform(0.0, 2 * M_PI);
	if (u_drop < dropout_probability_) return nullptr;

	const Eigen::Vector3d p_t = pointOnVehicle(*t.x, mount_.position_b).p_n;
	const double range = (p_t - ship_n_).norm();
	const double sigma = std::hypot(sigma_m_, sigma_range_fraction_ * range);
	Eigen::Vector3d p_fix = p_t;
	p_fix.head<2>() += bias_ne_m_ + sigma * w.head<2>();
	p_fix.z() += depth_sigma_m_ * w.z();
	if (u_out < outlier_probability_)
	{
		p_fix.x() += out_mag * std::cos(out_dir);
		p_fix.y() += out_mag * std::sin(out_dir);
		++outliers_;
	}
	// Latitude/longitude of the point; depth as a pressure sensor gives it.
	const earth::Geodetic g = frame.toGeodetic(Eigen::Vector3d(p_fix.x(), p_fix.y(), 0.0));
	auto obs = auvnav::obs::CObservationUSBL::Create();
	obs->sensorLabel = label_;
	obs->sensorPose = mount_.nominalPose();
	obs->timestamp = t.stamp + std::chrono::duration_cast<mrpt::Clock::duration>(
	                               std::chrono::duration<double>(latency_s_));
	if (report_time_) obs->measurement_time = t.stamp;
	obs->frame = auvnav::obs::UsblFrame::Geodetic;
	obs->position = {g.lat_rad / kDeg, g.lon_rad / kDeg, p_fix.z()};
	if (report_covariance_)
		obs->covariance_ned_m2 = {
		    sigma * sigma, 0, 0, 0, sigma * sigma, 0, 0, 0, depth_sigma_m_ * depth_sigma_m_};
	obs->slant_range_m = range;
	return obs;
}

// ---------------------------------------------------------------- magnetometer
Eigen::Vector3d MagneticField::fieldNed_ut() const
{
	const double cI = std::cos(inclination_rad), sI = std::sin(inclination_rad);
	return total_intensity_ut *
	       Eigen::Vector3d(cI * std::cos(declination_rad), cI * std::sin(declination_rad), sI);
}

MagneticField MagneticField::fromConfig(const config::Node& n)
{
	MagneticField f;
	// The geomagnetic field at the surface spans about 22–67 µT (WMM).
	f.total_intensity_ut = n.inRange("total_intensity_ut", 15, 70);
	f.declination_rad = n.inRange("declination_deg", -180, 180) * kDeg;
	f.inclination_rad = n.inRange("inclination_deg", -90, 90) * kDeg;
	return f;
}

MagnetometerSim::MagnetometerSim(const config::Node& n, const MagneticField& field,
                                 std::size_t thruster_count, uint32_t seed)
    : period_s_(1.0 / n.positive("rate_hz")),
      offset_s_(n.nonNegative("time_offset_s", 0.0)),
      mount_(Mounting::fromConfig(n)),
      m_n_ut_(field.fieldNed_ut()),
      sigma_ut_(n.nonNegative("noise_sigma_ut")),
      label_(n.string("label", "MAG"))
{
	rng_.randomize(streamSeed(seed, 6));
	hard_iron_ut_ = n.vector3("hard_iron_ut", Eigen::Vector3d::Zero());
	if ((hard_iron_ut_.array().abs() > 1000).any())
		n.fail("hard_iron_ut", "expected |offset| <= 1000 uT per axis");
	if (n.has("soft_iron"))
	{
		const auto v = n.numbers("soft_iron");
		if (v.size() != 9) n.fail("soft_iron", "expected 9 values (3x3 matrix, row-major)");
		for (int r = 0; r < 3; ++r)
			for (int c = 0; c < 3; ++c) soft_iron_(r, c) = v[3 * r + c];
		// A soft-iron matrix is a mild distortion of the field: invertible,
		// orientation-preserving, gains within a factor of a few.
		const Eigen::JacobiSVD<Eigen::Matrix3d> svd(soft_iron_);
		const auto sv = svd.singularValues();
		if (soft_iron_.determinant() <= 0 || sv.minCoeff() < 0.2 || sv.maxCoeff() > 5)
			n.fail("soft_iron",
			       "expected an invertible matrix with positive determinant and singular values in "
			       "[0.2, 5]");
	}
	thruster_gain_ut_per_n_ = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, thruster_count);
	if (n.has("thruster_disturbance_ut_per_n"))
	{
		const auto v = n.numbers("thruster_disturbance_ut_per_n");
		if (v.size() != 3 && v.size() != 3 * thruster_count)
			n.fail("thruster_disturbance_ut_per_n", "expected 3 values (every thruster) or 3 per thruster (" +
			                                            std::to_string(3 * thruster_count) + ")");
		for (std::size_t i = 0; i < thruster_count; ++i)
			for (int k = 0; k < 3; ++k)
			{
				const double g = v.size() == 3 ? v[k] : v[3 * i + k];
				if (std::abs(g) > 10) n.fail("thruster_disturbance_ut_per_n", "expected |gain| <= 10 uT/N");
				thruster_gain_ut_per_n_(k, static_cast<Eigen::Index>(i)) = g;
			}
	}
}

Eigen::Vector3d MagnetometerSim::expected_ut(const VehicleState& x) const
{
	const Eigen::Matrix3d R_ns = x.R_nb() * mount_.R_bs_true;
	Eigen::Vector3d h = soft_iron_ * (R_ns.transpose() * m_n_ut_) + hard_iron_ut_;
	if (x.thrust_n.size() == thruster_gain_ut_per_n_.cols())
		h += thruster_gain_ut_per_n_ * x.thrust_n.cwiseAbs();
	return h;
}

mrpt::obs::CObservationIMU::Ptr MagnetometerSim::sample(const Truth& t)
{
	const Eigen::Vector3d h_ut = expected_ut(*t.x);
	auto obs = mrpt::obs::CObservationIMU::Create();
	obs->timestamp = t.stamp;
	obs->sensorLabel = label_;
	obs->sensorPose = mount_.nominalPose();
	using namespace mrpt::obs;
	const TIMUDataIndex idx[3] = {IMU_MAG_X, IMU_MAG_Y, IMU_MAG_Z};
	constexpr double kGaussPerMicrotesla = 0.01;  // 1 G = 100 µT
	for (int i = 0; i < 3; ++i)
		obs->set(idx[i], kGaussPerMicrotesla * (h_ut[i] + sigma_ut_ * rng_.drawGaussian1D_normalized()));
	return obs;
}

}  // namespace auvnav::sim
