// The MEMS vehicle's sensors (config/sensors/bluerov2_sensors.yaml): the
// magnetometer against its field model with hard/soft iron and thruster
// disturbance, the IMU's scale factor and g-sensitivity, the logger clock's
// jitter and anomalies, and every new config key refused with its name.
#include <auvnav/config.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "guidance.h"
#include "logger_clock.h"
#include "sensors.h"
#include "sim_test_config.h"

using namespace auvnav;
using namespace auvnav::sim;

namespace
{
constexpr double kDeg = M_PI / 180;
constexpr std::size_t kThrusters = 8;  // the BlueROV2 Heavy

config::Node bluerovSensors()
{
	return config::Node::load(std::string(AUVNAV_SOURCE_DIR) + "/config/sensors/bluerov2_sensors.yaml");
}

/** Esbjerg-like field: F 50.3 µT, D +3°, I 70.6° (the pool mission's). */
MagneticField poolField()
{
	MagneticField f;
	f.total_intensity_ut = 50.3;
	f.declination_rad = 3.0 * kDeg;
	f.inclination_rad = 70.6 * kDeg;
	return f;
}

/** The repo's magnetometer distortion, mounted without misalignment, so the
 *  test can predict the reading exactly. */
config::Node alignedMag(const std::string& thruster_gains = "[0.02, -0.015, 0.04]")
{
	return config::Node::fromText(
	    "rate_hz: 50\nposition_m: [0.05, 0, -0.05]\nnoise_sigma_ut: 0.3\nhard_iron_ut: [12.0, -7.5, 20.0]\n"
	    "soft_iron: [1.04, 0.03, -0.02, 0.03, 0.97, 0.01, -0.02, 0.01, 1.01]\n"
	    "thruster_disturbance_ut_per_n: " +
	        thruster_gains + "\n",
	    "<aligned magnetometer>");
}

Eigen::Vector3d magUt(const mrpt::obs::CObservationIMU& o)
{
	using namespace mrpt::obs;
	return 100.0 * Eigen::Vector3d(o.get(IMU_MAG_X), o.get(IMU_MAG_Y), o.get(IMU_MAG_Z));  // gauss -> µT
}

struct Pose
{
	VehicleState x;
	Truth t;
	Pose(double yaw_deg, double pitch_deg, double roll_deg)
	{
		x.q_nb = Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()) *
		         Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitY()) *
		         Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitX());
		x.thrust_n = Eigen::VectorXd::Zero(kThrusters);
		t.x = &x;
	}
};

Eigen::Vector3d meanMagUt(MagnetometerSim& mag, const Truth& t, int n)
{
	Eigen::Vector3d sum = Eigen::Vector3d::Zero();
	for (int k = 0; k < n; ++k) sum += magUt(*mag.sample(t));
	return sum / n;
}

template <class F>
void expectConfigError(F&& f, const std::string& key)
{
	try
	{
		f();
		ADD_FAILURE() << "a bad " << key << " was accepted";
	}
	catch (const config::ConfigError& e)
	{
		EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
	}
}
}  // namespace

TEST(MagnetometerSim, OutputIsAnImuObservationWithOnlyTheMagneticFieldInGauss)
{
	const auto cfg = bluerovSensors().child("magnetometer");
	MagnetometerSim mag(cfg, poolField(), kThrusters, 1);
	Pose p(40, 0, 0);
	const auto o = mag.sample(p.t);
	EXPECT_EQ(o->sensorLabel, "MAG");
	for (int i = 0; i < mrpt::obs::COUNT_IMU_DATA_FIELDS; ++i)
	{
		const bool is_mag =
		    i == mrpt::obs::IMU_MAG_X || i == mrpt::obs::IMU_MAG_Y || i == mrpt::obs::IMU_MAG_Z;
		EXPECT_EQ(o->dataIsPresent[i], is_mag) << "field " << i;
	}
	// Gauss: a ~50 µT field plus ~25 µT hard iron reads a few tenths of a gauss.
	const double norm_g = magUt(*o).norm() / 100;
	EXPECT_GT(norm_g, 0.3);
	EXPECT_LT(norm_g, 0.8);
	EXPECT_NEAR(o->sensorPose.x(), 0.05, 1e-12);
	EXPECT_NEAR(o->sensorPose.z(), -0.05, 1e-12);
	EXPECT_NEAR(mag.period_s(), 0.02, 1e-12);
}

TEST(MagnetometerSim, RemovingTheKnownHardAndSoftIronLeavesTheFieldStrength)
{
	// Repo config, misalignment included: a rotation, so the norm is unchanged.
	const auto cfg = bluerovSensors().child("magnetometer");
	MagnetometerSim mag(cfg, poolField(), kThrusters, 2);
	const Eigen::Matrix3d S_inv = mag.softIron().inverse();
	const int n = 400;
	double worst_raw_ut = 0;
	// Per-axis σ of the mean 0.3/√400 = 0.015 µT; through S⁻¹ (gains ≈ 1) the
	// norm's σ is about the same: 4σ = 0.06 µT.
	for (double yaw = -180; yaw < 180; yaw += 45)
		for (const auto& [pitch, roll] : std::vector<std::pair<double, double>>{{0, 0}, {-25, 10}, {15, -35}})
		{
			Pose p(yaw, pitch, roll);
			const Eigen::Vector3d h = meanMagUt(mag, p.t, n);
			const Eigen::Vector3d u = S_inv * (h - mag.hardIron_ut());
			EXPECT_NEAR(u.norm(), 50.3, 0.06) << "yaw " << yaw << " pitch " << pitch << " roll " << roll;
			worst_raw_ut = std::max(worst_raw_ut, std::abs(h.norm() - 50.3));
		}
	// Without the correction the norm is far off somewhere: the test can tell.
	EXPECT_GT(worst_raw_ut, 5.0);
}

TEST(MagnetometerSim, UndistortedReadingIsTheEarthFieldInBodyAxesAndGivesTheHeading)
{
	MagnetometerSim mag(alignedMag(), poolField(), kThrusters, 3);
	const Eigen::Matrix3d S_inv = mag.softIron().inverse();
	const Eigen::Vector3d m_n = poolField().fieldNed_ut();
	EXPECT_NEAR(m_n.norm(), 50.3, 1e-9);
	EXPECT_NEAR(m_n.z(), 50.3 * std::sin(70.6 * kDeg), 1e-9);  // NED: the field dips downward here
	const int n = 400;
	const double sigma_mean = 0.3 / std::sqrt(n);
	double worst_raw_rad = 0;
	for (double yaw = -170; yaw < 180; yaw += 40)
	{
		// Tilted: every body axis against the model.
		Pose tilted(yaw, 12, -20);
		const Eigen::Vector3d u = S_inv * (meanMagUt(mag, tilted.t, n) - mag.hardIron_ut());
		const Eigen::Vector3d m_b = tilted.x.R_nb().transpose() * m_n;
		for (int i = 0; i < 3; ++i)
			EXPECT_NEAR(u[i], m_b[i], 5 * sigma_mean) << "yaw " << yaw << " axis " << i;
		// Level: heading = declination − atan2(u_y, u_x), noise-limited to
		// 5σ/(F cos I) = 0.25° for the 16.7 µT horizontal field.
		Pose level(yaw, 0, 0);
		const Eigen::Vector3d ul = S_inv * (meanMagUt(mag, level.t, n) - mag.hardIron_ut());
		const double heading = 3.0 * kDeg - std::atan2(ul.y(), ul.x());
		const double err = std::remainder(heading - yaw * kDeg, 2 * M_PI);
		EXPECT_LT(std::abs(err), 0.25 * kDeg) << "yaw " << yaw;
		// The raw reading's heading (hard iron left in) is degrees off.
		const Eigen::Vector3d raw = meanMagUt(mag, level.t, n);
		const double raw_err =
		    std::remainder(3.0 * kDeg - std::atan2(raw.y(), raw.x()) - yaw * kDeg, 2 * M_PI);
		worst_raw_rad = std::max(worst_raw_rad, std::abs(raw_err));
	}
	// The raw reading's heading (hard iron left in) is tens of degrees off somewhere.
	EXPECT_GT(worst_raw_rad, 10 * kDeg);
}

TEST(MagnetometerSim, ThrusterDisturbanceIsTheGainTimesTheAbsoluteThrust)
{
	const int n = 2000;
	const double sigma_diff = 0.3 * std::sqrt(2.0 / n);
	Pose p(75, 0, 0);
	{
		// One gain for all thrusters: Σ|F| = 10 + 5 + 20 + 3 = 38 N.
		MagnetometerSim mag(alignedMag(), poolField(), kThrusters, 4);
		const Eigen::Vector3d quiet = meanMagUt(mag, p.t, n);
		p.x.thrust_n << 10, -5, 20, 0, 0, 3, 0, 0;
		const Eigen::Vector3d busy = meanMagUt(mag, p.t, n);
		const Eigen::Vector3d expected = 38 * Eigen::Vector3d(0.02, -0.015, 0.04);
		for (int i = 0; i < 3; ++i) EXPECT_NEAR(busy[i] - quiet[i], expected[i], 5 * sigma_diff) << i;
		EXPECT_GT(expected.norm(), 20 * sigma_diff);  // the effect is well resolved
	}
	{
		// Per-thruster gains: only thruster 3 (index 2) disturbs, along −y.
		std::string gains = "[";
		for (std::size_t i = 0; i < kThrusters; ++i)
			gains += std::string(i ? ", " : "") + (i == 2 ? "0, -0.1, 0" : "0, 0, 0");
		MagnetometerSim mag(alignedMag(gains + "]"), poolField(), kThrusters, 5);
		p.x.thrust_n.setZero();
		const Eigen::Vector3d quiet = meanMagUt(mag, p.t, n);
		p.x.thrust_n << 30, 30, -15, 30, 0, 0, 0, 0;
		const Eigen::Vector3d busy = meanMagUt(mag, p.t, n);
		EXPECT_NEAR(busy.x() - quiet.x(), 0, 5 * sigma_diff);
		EXPECT_NEAR(busy.y() - quiet.y(), -1.5, 5 * sigma_diff);
		EXPECT_NEAR(busy.z() - quiet.z(), 0, 5 * sigma_diff);
	}
}

TEST(MagnetometerSim, BadConfigValuesNameTheKey)
{
	const auto field = poolField();
	auto make = [&](const std::string& extra)
	{
		// A later duplicate key would be ambiguous: build the text from scratch.
		return config::Node::fromText("rate_hz: 50\nposition_m: [0, 0, 0]\nnoise_sigma_ut: 0.3\n" + extra,
		                              "<bad mag>");
	};
	expectConfigError([&]
	                  { MagnetometerSim(make("soft_iron: [1, 0, 0, 0, -1, 0, 0, 0, 1]\n"), field, 8, 1); },
	                  "soft_iron");  // a reflection
	expectConfigError([&] { MagnetometerSim(make("soft_iron: [1, 0, 0, 0, 1, 0]\n"), field, 8, 1); },
	                  "soft_iron");
	expectConfigError([&] { MagnetometerSim(make("soft_iron: [9, 0, 0, 0, 1, 0, 0, 0, 1]\n"), field, 8, 1); },
	                  "soft_iron");
	expectConfigError([&] { MagnetometerSim(make("hard_iron_ut: [0, 0]\n"), field, 8, 1); }, "hard_iron_ut");
	expectConfigError([&] { MagnetometerSim(make("hard_iron_ut: [0, 5000, 0]\n"), field, 8, 1); },
	                  "hard_iron_ut");
	expectConfigError(
	    [&] { MagnetometerSim(make("thruster_disturbance_ut_per_n: [0, 0, 0, 0]\n"), field, 8, 1); },
	    "thruster_disturbance_ut_per_n");
	expectConfigError([&]
	                  { MagnetometerSim(make("thruster_disturbance_ut_per_n: [0, 50, 0]\n"), field, 8, 1); },
	                  "thruster_disturbance_ut_per_n");
	expectConfigError(
	    [&]
	    {
		    MagnetometerSim(
		        config::Node::fromText("rate_hz: 50\nposition_m: [0, 0, 0]\nnoise_sigma_ut: -1\n"), field, 8,
		        1);
	    },
	    "noise_sigma_ut");
	expectConfigError(
	    [&]
	    {
		    MagnetometerSim(config::Node::fromText("rate_hz: 0\nposition_m: [0, 0, 0]\nnoise_sigma_ut: 1\n"),
		                    field, 8, 1);
	    },
	    "rate_hz");
	auto fieldFrom = [](const std::string& text)
	{ return MagneticField::fromConfig(config::Node::fromText(text)); };
	expectConfigError([&]
	                  { fieldFrom("total_intensity_ut: 200\ndeclination_deg: 0\ninclination_deg: 60\n"); },
	                  "total_intensity_ut");
	expectConfigError([&]
	                  { fieldFrom("total_intensity_ut: 50\ndeclination_deg: 190\ninclination_deg: 60\n"); },
	                  "declination_deg");
	expectConfigError([&] { fieldFrom("total_intensity_ut: 50\ndeclination_deg: 0\ninclination_deg: 95\n"); },
	                  "inclination_deg");
	expectConfigError([&] { fieldFrom("total_intensity_ut: 50\ninclination_deg: 60\n"); }, "declination_deg");
}

// ---------------------------------------------------------------- IMU

namespace
{
/** A noise-free, bias-free IMU with the given extra gyro/accel keys. */
config::Node exactImu(const std::string& gyro_extra, const std::string& accel_extra)
{
	const std::string zero =
	    "random_walk: 0, bias_instability: 0, bias_correlation_time_s: 300, turn_on_bias_sigma: 0";
	return config::Node::fromText("rate_hz: 100\nposition_m: [0, 0, 0]\ngyro: {" + zero + gyro_extra +
	                                  "}\naccelerometer: {" + zero + accel_extra + "}\n",
	                              "<exact imu>");
}

struct ImuReading
{
	Eigen::Vector3d w, f;
};
ImuReading read(ImuSim& imu, const Truth& t, const earth::TangentFrame& frame)
{
	using namespace mrpt::obs;
	const auto o = imu.sample(t, frame);
	return {{o->get(IMU_WX), o->get(IMU_WY), o->get(IMU_WZ)},
	        {o->get(IMU_X_ACC), o->get(IMU_Y_ACC), o->get(IMU_Z_ACC)}};
}
}  // namespace

TEST(ImuSim, ScaleFactorAndGSensitivityShowInTheOutputAsConfigured)
{
	const earth::TangentFrame frame({55.47 * kDeg, 8.45 * kDeg, 0});
	// The repo's MEMS figures (bluerov2_sensors.yaml).
	const std::string sf_g =
	    ", scale_factor_error_ppm: [2500, -1800, 1200], g_sensitivity_dps_per_g: "
	    "[0.015, 0.004, -0.003, -0.002, 0.012, 0.005, 0.003, -0.004, 0.015]";
	const std::string sf_a = ", scale_factor_error_ppm: [-1500, 2000, 800]";
	ImuSim ideal(exactImu("", ""), 1), mems(exactImu(sf_g, sf_a), 1);
	Eigen::Matrix3d G;
	G << 0.015, 0.004, -0.003, -0.002, 0.012, 0.005, 0.003, -0.004, 0.015;
	const Eigen::Vector3d sg(2500e-6, -1800e-6, 1200e-6), sa(-1500e-6, 2000e-6, 800e-6);

	Pose p(130, -20, 30);
	p.x.p_n = {0, 0, 5};
	p.x.nu_b << 0.3, -0.1, 0.05, 0.4, -0.3, 0.8;  // moving and turning fast
	p.t.nu_dot_b << 0.1, 0.05, -0.02, 0.2, 0.1, -0.3;
	const ImuReading truth = read(ideal, p.t, frame), out = read(mems, p.t, frame);
	const Eigen::Vector3d w_expected =
	    truth.w.cwiseProduct(Eigen::Vector3d::Ones() + sg) + G * (truth.f / 9.80665) * kDeg;
	const Eigen::Vector3d f_expected = truth.f.cwiseProduct(Eigen::Vector3d::Ones() + sa);
	for (int i = 0; i < 3; ++i)
	{
		EXPECT_NEAR(out.w[i], w_expected[i], 1e-12) << i;
		EXPECT_NEAR(out.f[i], f_expected[i], 1e-12) << i;
	}
	// The sizes the datasheet figures give here: a 0.8 rad/s yaw rate with a
	// 0.12 % error is 1 mrad/s, the tilted gravity through G some 0.1–0.3 mrad/s.
	EXPECT_NEAR(out.w.z() - truth.w.z(), 1200e-6 * truth.w.z() + (G.row(2) * truth.f)(0) / 9.80665 * kDeg,
	            1e-12);
	EXPECT_GT((out.w - truth.w).norm(), 5e-4);
	EXPECT_GT((out.f - truth.f).norm(), 0.005);

	// Diagonal form: 3 values = each axis to its own specific force. Level at
	// rest the gyro z reads −g·G_zz extra (f_z = −g in FRD).
	ImuSim diag(exactImu(", g_sensitivity_dps_per_g: [0.01, 0.02, 0.05]", ""), 1);
	Pose level(0, 0, 0);
	level.x.p_n = {0, 0, 5};
	const ImuReading a = read(ideal, level.t, frame), b = read(diag, level.t, frame);
	EXPECT_NEAR(b.w.z() - a.w.z(), 0.05 * kDeg * a.f.z() / 9.80665, 1e-12);
	EXPECT_NEAR(b.w.z() - a.w.z(), -0.05 * kDeg, 0.0005 * kDeg);
	EXPECT_NEAR(b.w.x() - a.w.x(), 0.0, 1e-12);
}

TEST(ImuSim, BadScaleFactorOrGSensitivityNamesTheKey)
{
	expectConfigError([] { ImuSim(exactImu(", scale_factor_error_ppm: [1, 2]", ""), 1); },
	                  "gyro.scale_factor_error_ppm");
	expectConfigError([] { ImuSim(exactImu("", ", scale_factor_error_ppm: [0, 200000, 0]"), 1); },
	                  "accelerometer.scale_factor_error_ppm");
	expectConfigError([] { ImuSim(exactImu(", g_sensitivity_dps_per_g: [0.1, 0.1, 0.1, 0.1]", ""), 1); },
	                  "gyro.g_sensitivity_dps_per_g");
	expectConfigError([] { ImuSim(exactImu(", g_sensitivity_dps_per_g: [0.1, 3, 0.1]", ""), 1); },
	                  "gyro.g_sensitivity_dps_per_g");
}

TEST(ImuSim, RepoMemsFiguresLoad)
{
	// ARW 0.34 °/√h with an 8 °/h floor and τ 300 s: the Gauss–Markov σ
	// needed is several times the floor; loading must find it.
	const auto imu_cfg = bluerovSensors().child("imu");
	ImuSim imu(imu_cfg, 1);
	EXPECT_NEAR(imu.period_s(), 0.01, 1e-12);
	// The turn-on bias (0.1 °/s σ) dominates: |bias| below 5σ per axis.
	EXPECT_LT(imu.gyroBias().cwiseAbs().maxCoeff(), 5 * 0.1 * kDeg + 1e-3);
}

// ---------------------------------------------------------------- logger clock

TEST(LoggerClock, JitterHasTheConfiguredSigmaAndKeepsTheSensorsOrder)
{
	const double period = 0.2, sigma = 0.003;
	StampParams p;
	p.jitter_sigma_s = sigma;
	LoggerClock clk(p, period, 42);
	const auto t0 = mrpt::Clock::fromDouble(1669975200.0);
	const int n = 20000;
	std::vector<double> jitter;
	mrpt::Clock::time_point last{};
	for (int k = 0; k < n; ++k)
	{
		const auto t = t0 + std::chrono::microseconds(200000LL * k);
		const auto s = clk.stamp(t);
		EXPECT_EQ(s.recorded, s.jittered);  // no anomalies configured
		EXPECT_GT(s.recorded, last);
		last = s.recorded;
		jitter.push_back(std::chrono::duration<double>(s.jittered - t).count());
	}
	const double mean = std::accumulate(jitter.begin(), jitter.end(), 0.0) / n;
	double var = 0;
	for (double j : jitter) var += (j - mean) * (j - mean);
	const double sd = std::sqrt(var / (n - 1));
	EXPECT_NEAR(mean, 0, 4 * sigma / std::sqrt(n));
	// σ of a sample σ: σ/√(2n) = 0.5 %; 3 % is generous yet catches a wrong unit or clip.
	EXPECT_NEAR(sd, sigma, 0.03 * sigma);
	EXPECT_EQ(clk.duplicates(), 0u);
	EXPECT_EQ(clk.outOfOrder(), 0u);
}

TEST(LoggerClock, DuplicateAndOutOfOrderStampsAtTheConfiguredRates)
{
	const double period = 0.01;
	StampParams p;
	p.jitter_sigma_s = 0.0005;
	p.duplicate_probability = 0.02;
	p.out_of_order_probability = 0.01;
	LoggerClock clk(p, period, 7);
	const auto t0 = mrpt::Clock::fromDouble(1669975200.0);
	const int n = 50000;
	int dup = 0, ooo = 0;
	mrpt::Clock::time_point prev{};
	for (int k = 0; k < n; ++k)
	{
		const auto t = t0 + std::chrono::microseconds(10000LL * k);
		const auto s = clk.stamp(t);
		if (k > 0 && s.recorded == prev) ++dup;
		if (k > 0 && s.recorded < prev) ++ooo;
		prev = s.recorded;
	}
	auto binomial4sigma = [](double q) { return 4 * std::sqrt(n * q * (1 - q)); };
	EXPECT_NEAR(double(clk.duplicates()), 0.02 * n, binomial4sigma(0.02));
	EXPECT_NEAR(double(clk.outOfOrder()), 0.01 * n, binomial4sigma(0.01));
	// Every injected duplicate repeats its predecessor's stamp.
	EXPECT_EQ(static_cast<std::size_t>(dup), clk.duplicates());
	// An injected early stamp precedes its predecessor unless that one was
	// itself early or a duplicate of an older stamp (3 % of the time).
	EXPECT_LE(static_cast<std::size_t>(ooo), clk.outOfOrder());
	EXPECT_GE(double(ooo), 0.95 * clk.outOfOrder());
}

TEST(LoggerClock, DefaultsLeaveTheStampAloneAndBadValuesNameTheKey)
{
	const auto none = StampParams::fromConfig(config::Node::fromText("rate_hz: 5\n"), 0.2);
	EXPECT_FALSE(none.active());
	LoggerClock clk(none, 0.2, 1);
	const auto t = mrpt::Clock::fromDouble(1669975200.25);
	EXPECT_EQ(clk.stamp(t).recorded, t);
	EXPECT_EQ(clk.maxEarly_s(), 0.0);
	auto params = [](const std::string& text)
	{ return StampParams::fromConfig(config::Node::fromText(text), 0.01); };
	expectConfigError([&] { params("timestamp_jitter_sigma_s: 0.002\n"); },
	                  "timestamp_jitter_sigma_s");  // > 0.1 period
	expectConfigError([&] { params("timestamp_jitter_sigma_s: -0.001\n"); }, "timestamp_jitter_sigma_s");
	expectConfigError([&] { params("duplicate_stamp_probability: 0.7\n"); }, "duplicate_stamp_probability");
	expectConfigError([&] { params("out_of_order_probability: -0.1\n"); }, "out_of_order_probability");
}

// ---------------------------------------------------------------- pressure

TEST(PressureSim, ReadingsAreOnTheResolutionGrid)
{
	const auto cfg = bluerovSensors().child("pressure");
	PressureSim ps(cfg, 3);
	const Environment env = Environment::fromConfig(test::flatEnvironment(20), 1);
	const earth::TangentFrame frame({55.47 * kDeg, 8.45 * kDeg, 0});
	Pose p(0, 0, 0);
	p.x.p_n = {0, 0, 4.321};
	double sum = 0;
	const int n = 2000;
	for (int k = 0; k < n; ++k)
	{
		const double pa = ps.sample(p.t, env, frame)->pressure_pa;
		EXPECT_NEAR(std::remainder(pa, 20.0), 0.0, 1e-6) << pa;  // 0.2 mbar steps
		sum += pa;
	}
	// Mean within the per-run bias (500 Pa σ, < 4σ) of the hydrostatic value.
	const double depth_sensor = 4.321 - 0.05;
	const double expected =
	    101325 + 1025 * frame.gravityNed(Eigen::Vector3d(0, 0, depth_sensor)).z() * depth_sensor;
	EXPECT_NEAR(sum / n, expected, 2000);
	expectConfigError(
	    []
	    {
		    PressureSim(config::Node::fromText("rate_hz: 10\nposition_m: [0, 0, 0]\nnoise_sigma_pa: 20\n"
		                                       "bias_sigma_pa: 0\nresolution_pa: -20\n"),
		                1);
	    },
	    "resolution_pa");
}

// ---------------------------------------------------------------- autopilot

TEST(Controller, RollGainsNeedThrustersThatSpanRoll)
{
	PlanStep hold;  // hold heading at 2 m for a while
	hold.kind = PlanStep::Kind::Wait;
	hold.duration_s = 100;
	hold.surface = false;
	hold.depth_m = 2;
	const std::vector<PlanStep> plan{hold};
	ControllerGains k;
	k.roll_kp = 5;
	// FlatFish: two heave thrusters on the centre line cannot roll it.
	expectConfigError([&] { Controller(VehicleParams::fromConfig(test::repoVehicle()), k, plan); },
	                  "controller.roll_kp");
	// The BlueROV2 Heavy's four vertical thrusters can: a roll error gives a
	// restoring roll moment through the allocation.
	const auto heavy = VehicleParams::fromConfig(
	    config::Node::load(std::string(AUVNAV_SOURCE_DIR) + "/config/vehicles/bluerov2_heavy.yaml"));
	Controller c(heavy, k, plan);
	VehicleState x;
	x.q_nb = Eigen::AngleAxisd(10 * kDeg, Eigen::Vector3d::UnitX());  // rolled 10° to starboard
	x.p_n = {0, 0, 2};
	x.thrust_n = Eigen::VectorXd::Zero(8);
	const Eigen::VectorXd u = c.command(x, 0, 0.05);
	const Vector6d tau = heavy.configurationMatrix() * u;
	EXPECT_NEAR(tau[3], -5 * 10 * kDeg, 1e-6);  // −kp · roll
}

// ---------------------------------------------------------------- DVL outages

TEST(DvlSim, WholePingOutagesAtTheConfiguredRateAndLength)
{
	// Rate 120/h, mean 3 s: with outages starting only while locked, the
	// unlocked fraction is r d / (1 + r d) = 0.1 / 1.1 = 9.1 %.
	auto cfg = bluerovSensors().child("dvl");
	cfg.set("dropout_rate_per_h", "120");
	cfg.set("dropout_duration_s", "3");
	cfg.set("beam_dropout_probability", "0");
	DvlSim dvl(cfg, 11);
	const Environment env = Environment::fromConfig(test::flatEnvironment(20), 1);
	Pose p(0, 0, 0);
	p.x.p_n = {0, 0, 10};
	const double dt = 0.2;
	const int n = 10 * 3600 * 5;  // 10 h of pings at 5 Hz
	int unlocked = 0, runs = 0;
	bool was_locked = true;
	for (int k = 0; k < n; ++k)
	{
		p.t.t_s = k * dt;
		const bool locked = dvl.sample(p.t, env)->bottom_lock;
		unlocked += !locked;
		runs += !locked && was_locked;
		was_locked = locked;
	}
	// Each outage is a run of lost pings; one starting at the first ping
	// after another ends merges with it (~2 %).
	const double outages = double(dvl.outages());
	EXPECT_LE(runs, outages);
	EXPECT_GE(runs, 0.96 * outages);
	const double hours_locked = (n - unlocked) * dt / 3600;
	// ~1100 outages: Poisson 4σ ≈ 12 %.
	EXPECT_NEAR(outages / hours_locked, 120, 4 * std::sqrt(120 * hours_locked) / hours_locked);
	// Mean length in pings × 0.2 s: 3 s plus up to one ping of rounding.
	const double mean_s = unlocked * dt / outages;
	EXPECT_GT(mean_s, 2.8);
	EXPECT_LT(mean_s, 3.4);
	EXPECT_NEAR(double(unlocked) / n, 0.1 / 1.1, 0.01);
	auto bad = bluerovSensors().child("dvl");
	bad.set("dropout_duration_s", "0");
	expectConfigError([&] { DvlSim(bad, 1); }, "dvl.dropout_duration_s");
	bad.set("dropout_rate_per_h", "-1");
	expectConfigError([&] { DvlSim(bad, 1); }, "dvl.dropout_rate_per_h");
}
