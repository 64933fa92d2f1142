// The BlueROV2-Heavy-like missions (config/missions/bluerov2_*.yaml): each
// runs to the end of its plan within its declared duration, with the sensors
// its header promises, the logger's stamp jitter as configured and the start
// recorded in the ground truth; bad new mission keys are refused by name.
#include <auvnav/io/rawlog.h>
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

#include <auvnav/io/trajectory.h>
#include "mission.h"
#include "sensors.h"

namespace fs = std::filesystem;
using namespace auvnav;

namespace
{
constexpr double kDeg = M_PI / 180;
const std::string kRepo = AUVNAV_SOURCE_DIR;

std::string missionFile(const std::string& name)
{
	return kRepo + "/config/missions/" + name + ".yaml";
}

fs::path scratch(const std::string& name)
{
	// Emptied here; the group's folder goes at exit (scratch_dir.h).
	return auvnav::testing::scratchFolder("sim_brov", name);
}

std::string slurp(const fs::path& p)
{
	std::ifstream f(p, std::ios::binary);
	return {std::istreambuf_iterator<char>(f), {}};
}

double yawOf(const Eigen::Quaterniond& q)
{
	const Eigen::Matrix3d R = q.toRotationMatrix();
	return std::atan2(R(1, 0), R(0, 0));
}

/** A copy of a repo mission with `from` replaced by `to`, its includes made absolute. */
fs::path editedMission(const std::string& name, const std::string& from, const std::string& to,
                       const fs::path& dir)
{
	std::string text = slurp(missionFile(name));
	auto replace = [&](const std::string& a, const std::string& b)
	{
		const auto pos = text.find(a);
		if (pos == std::string::npos) throw std::runtime_error("not in " + name + ": " + a);
		text.replace(pos, a.size(), b);
	};
	replace("../vehicles", kRepo + "/config/vehicles");
	replace("../sensors", kRepo + "/config/sensors");
	replace(from, to);
	fs::create_directories(dir);
	const fs::path p = dir / (name + "_edited.yaml");
	std::ofstream(p) << text;
	return p;
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

TEST(BlueRov2Missions, PoolSquareRunsWithMagnetometerDvlAndDepthOnlyAndJitteredStamps)
{
	const auto spec = sim::MissionSpec::load(missionFile("bluerov2_pool_square"));
	const fs::path d = scratch("pool");
	const auto s = sim::runMission(spec, 1, d.string());
	EXPECT_TRUE(s.plan_completed);
	EXPECT_LE(s.duration_s, spec.max_duration_s);
	EXPECT_GT(s.duration_s, 5 * 60.0);  // three 24 m laps at 0.3 m/s plus 90 s of waiting
	EXPECT_LT(s.duration_s, 10 * 60.0);
	EXPECT_NEAR(s.max_depth_m, 1.5, 0.2);
	EXPECT_EQ(s.observations.count("GPS"), 0u);  // indoors
	EXPECT_EQ(s.observations.count("ADCP"), 0u);
	const double T = s.duration_s;
	EXPECT_NEAR(s.observations.at("IMU") / T, 100, 1);
	EXPECT_NEAR(s.observations.at("MAG") / T, 50, 0.5);
	EXPECT_NEAR(s.observations.at("DVL") / T, 10, 0.2);
	EXPECT_NEAR(s.observations.at("PRESSURE") / T, 10, 0.2);
	// 1.4–2.9 m altitude, inside 0.05–50 m; beam losses and ~1 % whole-ping outages
	EXPECT_GT(double(s.dvl_locked) / s.dvl_total, 0.9);
	EXPECT_EQ(s.stamp_duplicates + s.stamp_out_of_order, 0u);  // off by default

	// The start is the first truth row; the square's corners are visited.
	const auto truth = io::readGroundTruth(d / "ground_truth.csv");
	ASSERT_FALSE(truth.empty());
	EXPECT_NEAR(truth.front().p_n.x(), 2, 1e-6);
	EXPECT_NEAR(truth.front().p_n.y(), 2, 1e-6);
	EXPECT_NEAR(truth.front().p_n.z(), 0.12, 1e-6);
	EXPECT_NEAR(yawOf(truth.front().q_nb), 30 * kDeg, 1e-6);
	for (const Eigen::Vector2d& corner :
	     {Eigen::Vector2d(8, 2), Eigen::Vector2d(8, 8), Eigen::Vector2d(2, 8)})
	{
		double closest = INFINITY;
		for (const auto& r : truth) closest = std::min(closest, (r.p_n.head<2>() - corner).norm());
		EXPECT_LT(closest, 0.6) << corner.transpose();
	}

	// The rawlog: in time order (no anomalies configured), the IMU's stamps
	// jittered by σ 0.5 ms about its regular 100 Hz grid, magnetometer
	// observations carrying only the field.
	io::RawlogReader r(s.rawlog_path);
	const double t0 = spec.start_unix_s;
	mrpt::Clock::time_point last{};
	double sum = 0, sum2 = 0;
	std::size_t n_imu = 0, n_mag = 0;
	while (auto o = r.next())
	{
		EXPECT_GE(o->timestamp, last);
		last = o->timestamp;
		if (o->sensorLabel == "IMU")
		{
			const double t = mrpt::Clock::toDouble(o->timestamp) - t0;
			const double jitter = t - 0.01 * std::round(t / 0.01);
			sum += jitter;
			sum2 += jitter * jitter;
			++n_imu;
		}
		else if (o->sensorLabel == "MAG")
		{
			const auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(o);
			ASSERT_TRUE(imu);
			EXPECT_TRUE(imu->has(mrpt::obs::IMU_MAG_X) && imu->has(mrpt::obs::IMU_MAG_Z));
			EXPECT_FALSE(imu->has(mrpt::obs::IMU_WZ));
			++n_mag;
		}
	}
	ASSERT_GT(n_imu, 10000u);
	EXPECT_EQ(n_mag, s.observations.at("MAG"));
	const double mean = sum / n_imu, sd = std::sqrt(sum2 / n_imu - mean * mean);
	// Stamps are written with 100 ns ticks and read back through a double of
	// Unix time (~0.2 µs resolution): negligible against 0.5 ms.
	EXPECT_NEAR(mean, 0, 4 * 0.0005 / std::sqrt(double(n_imu)) + 1e-6);
	EXPECT_NEAR(sd, 0.0005, 0.03 * 0.0005);
	fs::remove_all(d);
}

TEST(BlueRov2Missions, SameSeedSameBytesWithJitterOn)
{
	const auto spec = sim::MissionSpec::load(missionFile("bluerov2_pool_square"));
	const fs::path a = scratch("det_a"), b = scratch("det_b");
	sim::runMission(spec, 5, a.string());
	sim::runMission(spec, 5, b.string());
	for (const char* f : {"bluerov2_pool_square.rawlog", "ground_truth.csv"})
		EXPECT_EQ(slurp(a / f), slurp(b / f)) << f;
	fs::remove_all(a);
	fs::remove_all(b);
}

TEST(BlueRov2Missions, LawnmowerSurveyIsAboutTwentyMinutesAtTenMetres)
{
	const auto spec = sim::MissionSpec::load(missionFile("bluerov2_lawnmower"));
	const fs::path d = scratch("lawn");
	const auto s = sim::runMission(spec, 2, d.string());
	EXPECT_TRUE(s.plan_completed);
	EXPECT_LE(s.duration_s, spec.max_duration_s);
	EXPECT_GT(s.duration_s, 18 * 60.0);
	EXPECT_LT(s.duration_s, 25 * 60.0);
	EXPECT_NEAR(s.max_depth_m, 10, 0.5);
	EXPECT_GT(s.submerged_distance_m, 450);    // ten 45 m lines and nine 5 m steps
	EXPECT_GT(s.observations.at("GPS"), 30u);  // surface phases only
	EXPECT_GT(double(s.dvl_locked) / s.dvl_total, 0.95);
	const auto truth = io::readGroundTruth(d / "ground_truth.csv");
	EXPECT_NEAR(yawOf(truth.front().q_nb), -20 * kDeg, 1e-6);
	fs::remove_all(d);
}

TEST(BlueRov2Missions, TransitIsALongStraightLineAtFifteenMetres)
{
	const auto spec = sim::MissionSpec::load(missionFile("bluerov2_transit"));
	const fs::path d = scratch("transit");
	const auto s = sim::runMission(spec, 3, d.string());
	EXPECT_TRUE(s.plan_completed);
	EXPECT_LE(s.duration_s, spec.max_duration_s);
	EXPECT_NEAR(s.max_depth_m, 15, 0.6);
	EXPECT_GT(s.submerged_distance_m, 1150);
	// Straight: the leg runs from where the vehicle is when it gets under way
	// (it drifts with the current while floating and diving) to the target;
	// until 5 m before the target the truth stays within 1.5 m of that line.
	const auto truth = io::readGroundTruth(d / "ground_truth.csv");
	const Eigen::Vector2d target(848.5, 848.5);
	std::size_t i0 = 0;
	while (i0 + 1 < truth.size() && truth[i0].p_n.z() < 14) ++i0;  // dived
	const Eigen::Vector2d a = truth[i0].p_n.head<2>();
	const Eigen::Vector2d dir = (target - a).normalized();
	double worst = 0;
	std::size_t on_leg = 0;
	for (std::size_t i = i0; i < truth.size() && (truth[i].p_n.head<2>() - target).norm() > 5; ++i, ++on_leg)
	{
		const Eigen::Vector2d e = truth[i].p_n.head<2>() - a;
		worst = std::max(worst, std::abs(-e.x() * dir.y() + e.y() * dir.x()));
	}
	EXPECT_GT(on_leg, 18000u);  // > 30 min at 10 Hz on the leg
	EXPECT_LT(worst, 1.5);
	fs::remove_all(d);
}

TEST(BlueRov2Missions, BadNewMissionKeysAreRefusedWithTheirNames)
{
	const fs::path d = scratch("badkeys");
	const std::string pool = "bluerov2_pool_square";
	// A magnetometer without the Earth field it should measure.
	expectConfigError(
	    [&]
	    {
		    const auto spec = sim::MissionSpec::load(
		        editedMission(pool, "magnetic_field: {", "unused_field: {", d / "nofield").string());
		    sim::runMission(spec, 1, (d / "out").string());
	    },
	    "magnetic_field");
	expectConfigError(
	    [&] { sim::MissionSpec::load(editedMission(pool, "depth_m: 0.12", "depth_m: -5", d).string()); },
	    "start.depth_m");
	// Sensor and environment keys, set as a mission's sensor_overrides would.
	const std::vector<std::pair<std::string, std::string>> bad = {
	    {"magnetometer.noise_sigma_ut", "-1"},
	    {"magnetometer.rate_hz", "33"},  // not a whole number of 10 ms steps
	    {"magnetometer.enabled", "maybe"},
	    {"magnetometer.hard_iron_ut", "5"},
	    {"gps.enabled", "perhaps"},
	    {"pressure.resolution_pa", "-20"},
	    {"dvl.timestamp_jitter_sigma_s", "0.05"},  // > 0.1 periods at 10 Hz
	    {"imu.duplicate_stamp_probability", "0.9"},
	    {"thrusters.out_of_order_probability", "-0.1"},
	    {"imu.gyro.g_sensitivity_dps_per_g", "abc"},
	    {"imu.accelerometer.scale_factor_error_ppm", "7"},
	};
	for (const auto& [key, value] : bad)
	{
		auto spec = sim::MissionSpec::load(missionFile(pool));
		spec.sensors.set(key, value);
		expectConfigError([&] { sim::runMission(spec, 1, (d / "out").string()); }, key);
	}
	for (const auto& [key, value] : std::vector<std::pair<std::string, std::string>>{
	         {"total_intensity_ut", "0"}, {"declination_deg", "-200"}, {"inclination_deg", "91"}})
	{
		auto spec = sim::MissionSpec::load(missionFile(pool));
		spec.environment.set("magnetic_field." + key, value);
		expectConfigError([&] { sim::runMission(spec, 1, (d / "out").string()); }, "magnetic_field." + key);
	}
	fs::remove_all(d);
}

TEST(BlueRov2Missions, OptionalDuplicateAndOutOfOrderStampsReachTheRawlog)
{
	auto spec = sim::MissionSpec::load(missionFile("bluerov2_pool_square"));
	// Jitter off for this one: a stamp is then exactly on the 10 ms grid,
	// half a period off it (early by 1.5 periods) or a repeat.
	spec.sensors.set("imu.timestamp_jitter_sigma_s", "0");
	spec.sensors.set("imu.duplicate_stamp_probability", "0.01");
	spec.sensors.set("imu.out_of_order_probability", "0.005");
	const fs::path d = scratch("anomalies");
	const auto s = sim::runMission(spec, 4, d.string());
	const double n = s.observations.at("IMU");
	auto binomial4sigma = [n](double q) { return 4 * std::sqrt(n * q * (1 - q)); };
	EXPECT_NEAR(double(s.stamp_duplicates), 0.01 * n, binomial4sigma(0.01));
	EXPECT_NEAR(double(s.stamp_out_of_order), 0.005 * n, binomial4sigma(0.005));
	// The rawlog stays in time order (its writer insists); the anomalies are
	// in the IMU's stamps: repeats, and stamps half a period off the grid.
	io::RawlogReader r(s.rawlog_path);
	const double t0 = spec.start_unix_s;
	mrpt::Clock::time_point prev{}, prev_imu{};
	std::size_t repeated = 0, off_grid = 0, imu = 0;
	while (auto o = r.next())
	{
		EXPECT_GE(o->timestamp, prev);
		prev = o->timestamp;
		if (o->sensorLabel != "IMU") continue;
		if (imu++ > 0) repeated += o->timestamp == prev_imu;
		prev_imu = o->timestamp;
		const double t = mrpt::Clock::toDouble(o->timestamp) - t0;
		const double residual = t - 0.01 * std::round(t / 0.01);
		off_grid += std::abs(residual) > 0.004;  // 0.005 s expected
	}
	// A repeat of an early stamp is off the grid as well, and a repeat can
	// fall next to its original only if no early stamp came between.
	EXPECT_NEAR(double(repeated), double(s.stamp_duplicates), 0.05 * s.stamp_duplicates + 2);
	EXPECT_GE(off_grid, s.stamp_out_of_order);
	EXPECT_LE(double(off_grid), 1.05 * s.stamp_out_of_order + 0.05 * s.stamp_duplicates + 2);
	fs::remove_all(d);
}

TEST(BlueRov2Missions, MagnetometerHeadingInThePoolRawlogMatchesTheTruth)
{
	// End to end: MAG observations from the rawlog (gauss, sensor axes),
	// corrected with the configured hard and soft iron, tilt-compensated with
	// the true roll and pitch, against the true heading.
	const auto spec = sim::MissionSpec::load(missionFile("bluerov2_pool_square"));
	const fs::path d = scratch("maghead");
	const auto s = sim::runMission(spec, 6, d.string());
	const auto truth = io::readGroundTruth(d / "ground_truth.csv");
	const auto mag = spec.sensors.child("magnetometer");
	const Eigen::Vector3d hard_ut = mag.vector3("hard_iron_ut");
	const auto si = mag.numbers("soft_iron");
	Eigen::Matrix3d S;
	S << si[0], si[1], si[2], si[3], si[4], si[5], si[6], si[7], si[8];
	const double decl = spec.environment.child("magnetic_field").number("declination_deg") * kDeg;
	io::RawlogReader r(s.rawlog_path);
	std::vector<double> still_err, all_err;
	while (auto o = r.next())
	{
		if (o->sensorLabel != "MAG") continue;
		const auto imu = std::dynamic_pointer_cast<mrpt::obs::CObservationIMU>(o);
		const Eigen::Vector3d h_ut =
		    100.0 * Eigen::Vector3d(imu->get(mrpt::obs::IMU_MAG_X), imu->get(mrpt::obs::IMU_MAG_Y),
		                            imu->get(mrpt::obs::IMU_MAG_Z));
		const double t = mrpt::Clock::toDouble(o->timestamp);
		const auto& row = io::at(truth, t);
		const Eigen::Matrix3d R_nb = row.q_nb.toRotationMatrix();
		const double yaw = std::atan2(R_nb(1, 0), R_nb(0, 0));
		// Level the body-axes field with the true roll and pitch: R_z(yaw)ᵀ R_nb.
		const Eigen::Vector3d u_h = Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
		                            R_nb * (S.inverse() * (h_ut - hard_ut));
		const double heading = decl - std::atan2(u_h.y(), u_h.x());
		const double err = std::remainder(heading - yaw, 2 * M_PI) / kDeg;  // signed
		all_err.push_back(std::abs(err));
		if (t - spec.start_unix_s < 25) still_err.push_back(err);
	}
	ASSERT_GT(still_err.size(), 1000u);
	std::sort(all_err.begin(), all_err.end());
	double mean = 0, var = 0;
	for (double e : still_err) mean += e / still_err.size();
	for (double e : still_err) var += (e - mean) * (e - mean) / (still_err.size() - 1);
	const double median = all_err[all_err.size() / 2], p95 = all_err[all_err.size() * 95 / 100];
	std::printf(
	    "magnetometer heading error: still (first 25 s, %zu samples) mean %.2f deg, sd %.2f deg; "
	    "whole pool run |error| median %.2f, 95%% %.2f deg\n",
	    still_err.size(), mean, std::sqrt(var), median, p95);
	// Still and level: per sample the 0.3 µT noise across the 16.7 µT
	// horizontal field, 0.3/16.71 rad = 1.03°; the mean is the true mounting
	// misalignment (0.5° yaw, 0.3°/−0.2° tilt seen through tan 70.6° ≈ 2.8).
	EXPECT_NEAR(std::sqrt(var), 1.03, 0.1);
	EXPECT_LT(std::abs(mean), 1.5);
	// Exactly: the noise-free reading of the simulated sensor (true mounting,
	// no thrust) at the start pose gives the bias the rawlog must show.
	sim::MagnetometerSim model(mag, sim::MagneticField::fromConfig(spec.environment.child("magnetic_field")),
	                           8, 1);
	sim::VehicleState x0;
	x0.q_nb = truth.front().q_nb;
	x0.thrust_n = Eigen::VectorXd::Zero(8);
	const Eigen::Vector3d u0 = S.inverse() * (model.expected_ut(x0) - hard_ut);
	const double yaw0 = yawOf(x0.q_nb);
	const Eigen::Vector3d u0_h =
	    Eigen::AngleAxisd(-yaw0, Eigen::Vector3d::UnitZ()).toRotationMatrix() * x0.R_nb() * u0;
	const double bias = std::remainder(decl - std::atan2(u0_h.y(), u0_h.x()) - yaw0, 2 * M_PI) / kDeg;
	EXPECT_NEAR(mean, bias, 4 * 1.03 / std::sqrt(double(still_err.size())) + 0.01);
	EXPECT_GT(std::abs(mean), 4 * 1.03 / std::sqrt(double(still_err.size())));  // the misalignment shows
	// Under way the thruster disturbance (~0.5 µT on a 16.7 µT horizontal
	// field) and the 0.1 s truth spacing add a few degrees.
	EXPECT_LT(median, 3.0);
	EXPECT_LT(p95, 8.0);
	fs::remove_all(d);
}
