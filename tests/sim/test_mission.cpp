// Whole missions: determinism per seed, readable outputs, bad configs refused.
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include "mission.h"

namespace fs = std::filesystem;
using namespace auvnav;

namespace
{
const std::string kMission = std::string(AUVNAV_TEST_DATA_DIR) + "/short_mission.yaml";

std::string slurp(const fs::path& p)
{
	std::ifstream f(p, std::ios::binary);
	return {std::istreambuf_iterator<char>(f), {}};
}

fs::path scratch(const std::string& name)
{
	// Emptied here; the group's folder goes at exit (scratch_dir.h).
	return auvnav::testing::scratchFolder("sim_test", name);
}

const char* kOutputs[] = {"short_test.rawlog", "ground_truth.tum", "ground_truth.csv"};
}  // namespace

TEST(Mission, SameSeedGivesByteIdenticalOutputsOtherSeedDiffers)
{
	const auto spec = sim::MissionSpec::load(kMission);
	const fs::path a = scratch("a"), b = scratch("b"), c = scratch("c");
	const auto sa = sim::runMission(spec, 1, a.string());
	sim::runMission(spec, 1, b.string());
	sim::runMission(spec, 2, c.string());
	EXPECT_TRUE(sa.plan_completed);
	for (const char* f : kOutputs)
	{
		const std::string fa = slurp(a / f);
		EXPECT_GT(fa.size(), 1000u) << f;
		EXPECT_EQ(fa, slurp(b / f)) << f << " differs between two runs with seed 1";
		// The autopilot steers on the true state, so the truth trajectory moves
		// with the seed only through the current's random wander.
		EXPECT_NE(fa, slurp(c / f)) << f << " identical for seeds 1 and 2";
	}
	EXPECT_NE(slurp(a / "ground_truth.csv"), slurp(c / "ground_truth.csv"));  // biases, current wander
	for (const auto& d : {a, b, c}) fs::remove_all(d);
}

TEST(Mission, RawlogHoldsEverySensorInTimeOrder)
{
	const auto spec = sim::MissionSpec::load(kMission);
	const fs::path d = scratch("order");
	const auto summary = sim::runMission(spec, 3, d.string());
	io::RawlogReader r((d / "short_test.rawlog").string());
	std::map<std::string, std::size_t> counts;
	mrpt::Clock::time_point last{};
	std::size_t n = 0;
	while (auto o = r.next())
	{
		EXPECT_GE(o->timestamp, last);
		last = o->timestamp;
		++counts[o->sensorLabel];
		++n;
	}
	EXPECT_EQ(counts, summary.observations);
	for (const char* label : {"IMU", "DVL", "ADCP", "PRESSURE", "GPS", "THRUSTERS"})
		EXPECT_GT(counts[label], 0u) << label;
	// Rates: IMU 100 Hz, DVL 5 Hz, thrusters 12.5 Hz over the mission.
	const double T = summary.duration_s;
	EXPECT_NEAR(counts["IMU"] / T, 100.0, 1.0);
	EXPECT_NEAR(counts["DVL"] / T, 5.0, 0.1);
	EXPECT_NEAR(counts["THRUSTERS"] / T, 12.5, 0.2);
	EXPECT_GT(summary.max_depth_m, 2.5);
	// Ground-truth CSV: header + one row per 0.1 s.
	std::ifstream csv(d / "ground_truth.csv");
	std::string header;
	std::getline(csv, header);
	EXPECT_NE(header.find("gyro_bias_x_radps"), std::string::npos);
	EXPECT_NE(header.find("current_n_mps"), std::string::npos);
	std::size_t rows = 0;
	for (std::string line; std::getline(csv, line);) ++rows;
	EXPECT_NEAR(static_cast<double>(rows), T * 10, 2);
	fs::remove_all(d);
}

TEST(Mission, BadConfigValuesAreRefusedWithFileAndKey)
{
	const fs::path d = scratch("badcfg");
	fs::create_directories(d);
	std::string text = slurp(kMission);
	// Point the relative includes back to the repository.
	const std::string repo = AUVNAV_SOURCE_DIR;
	auto replace = [&](const std::string& from, const std::string& to)
	{
		const auto pos = text.find(from);
		ASSERT_NE(pos, std::string::npos) << from;
		text.replace(pos, from.size(), to);
	};
	replace("../../config/vehicles", repo + "/config/vehicles");
	replace("../../config/sensors", repo + "/config/sensors");
	replace("speed_mps: 0.5}", "speed_mps: -3}");
	std::ofstream(d / "bad.yaml") << text;
	try
	{
		sim::MissionSpec::load((d / "bad.yaml").string());
		const auto spec = sim::MissionSpec::load((d / "bad.yaml").string());
		sim::runMission(spec, 1, (d / "out").string());
		FAIL() << "a negative speed was accepted";
	}
	catch (const config::ConfigError& e)
	{
		const std::string msg = e.what();
		EXPECT_NE(msg.find("bad.yaml"), std::string::npos) << msg;
		EXPECT_NE(msg.find("plan[0].speed_mps"), std::string::npos) << msg;
	}
	fs::remove_all(d);
}

TEST(Mission, ShippedSampleIsReproducedByItsDocumentedCommand)
{
	// share/sample was made by `auvnav-sim config/missions/sample.yaml --seed 1`
	// built with gcc. A clang build (the sanitizer pass, .ci/sanitize) ends the
	// same mission 0.4 s later and 0.19 m away: the closed loop (autopilot,
	// waypoint switching) amplifies last-bit differences of its floating point.
#if defined(__clang__)
	GTEST_SKIP() << "share/sample is reproduced by gcc builds only";
#endif
	// Compare the truth numerically (not bytewise: libm may differ in the last
	// bit between CPUs) and the observation counts per sensor.
	const std::string repo = AUVNAV_SOURCE_DIR;
	const auto spec = sim::MissionSpec::load(repo + "/config/missions/sample.yaml");
	const fs::path d = scratch("sample");
	const auto summary = sim::runMission(spec, 1, d.string());
	auto lastRow = [](const fs::path& csv)
	{
		std::ifstream f(csv);
		std::string line, last;
		while (std::getline(f, line))
			if (!line.empty()) last = line;
		std::vector<double> v;
		std::stringstream ss(last);
		for (std::string cell; std::getline(ss, cell, ',');) v.push_back(std::stod(cell));
		return v;
	};
	const auto mine = lastRow(d / "ground_truth.csv");
	const auto shipped = lastRow(repo + "/share/sample/ground_truth.csv");
	ASSERT_EQ(mine.size(), shipped.size());
	for (std::size_t i = 0; i < mine.size(); ++i) EXPECT_NEAR(mine[i], shipped[i], 1e-3) << "column " << i;
	io::RawlogReader shipped_log(repo + "/share/sample/sample.rawlog");
	std::map<std::string, std::size_t> counts;
	while (auto o = shipped_log.next()) ++counts[o->sensorLabel];
	EXPECT_EQ(counts, summary.observations);
	EXPECT_LT(fs::file_size(repo + "/share/sample/sample.rawlog") +
	              fs::file_size(repo + "/share/sample/ground_truth.csv") +
	              fs::file_size(repo + "/share/sample/ground_truth.tum"),
	          15u * 1000 * 1000);
	fs::remove_all(d);
}
