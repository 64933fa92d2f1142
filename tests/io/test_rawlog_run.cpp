// The one rawlog-run loop (auvnav/rawlog_run.h) on the sample dataset with the
// default configuration: callbacks, early stop, and a bad file reported
// (not thrown) with the navigator finished.
#include <auvnav/config.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/register.h>
#include <auvnav/rawlog_run.h>
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>

#include <string>

using namespace auvnav;

namespace
{
const std::string kRepo = AUVNAV_SOURCE_DIR;
config::Node defaultConfig()
{
	return config::Node::load(kRepo + "/config/flatfish.yaml");
}
}  // namespace

TEST(RawlogRun, CallsBackAndStopsWhenAsked)
{
	obs::registerAllClasses();
	const auto cfg = defaultConfig();
	PluginHost host;
	Navigator nav(cfg, host);
	std::size_t seen = 0, predictions = 0, updates = 0;
	RunCallbacks cb;
	cb.on_observation = [&](const Navigator&) { ++seen; };
	cb.on_predict = [&](const Navigator&) { ++predictions; };
	cb.on_update = [&](const std::string&, double, const Measurement&, const UpdateResult&) { ++updates; };
	cb.stop = [&] { return seen >= 30000; };  // ~40 s of data: initialised, every sensor seen
	const RunSummary run = runRawlog(nav, kRepo + "/share/sample/sample.rawlog", cb);
	EXPECT_TRUE(run.error.empty()) << run.error;
	EXPECT_TRUE(run.interrupted);
	EXPECT_FALSE(run.completed());
	EXPECT_EQ(run.observations, 30000u);
	EXPECT_EQ(seen, 30000u);
	EXPECT_TRUE(nav.initialized());
	EXPECT_EQ(predictions, nav.predictions());
	EXPECT_GT(updates, 0u);
	EXPECT_NEAR(run.data_s, nav.time() - nav.startTime(), 1e-12);
	EXPECT_GT(run.data_s, 10.0);
	EXPECT_EQ(run.stats.size(), nav.stats().size());
	EXPECT_NO_THROW(run.rethrow());
}

TEST(RawlogRun, ABadFileEndsTheRunWithTheErrorAndAFinishedNavigator)
{
	obs::registerAllClasses();
	const auto cfg = defaultConfig();
	PluginHost host;
	Navigator nav(cfg, host);
	const RunSummary run = runRawlog(nav, std::string(AUVNAV_TEST_DATA_DIR) + "/not_a_rawlog.txt");
	EXPECT_FALSE(run.completed());
	EXPECT_FALSE(run.interrupted);
	EXPECT_NE(run.error.find("not_a_rawlog.txt"), std::string::npos) << run.error;
	EXPECT_THROW(run.rethrow(), io::RawlogError);
	EXPECT_EQ(nav.health().status(), NavStatus::NotInitialized);  // finish() ran
	EXPECT_EQ(run.data_s, 0.0);
}

TEST(RawlogRun, AnEmptyLogIsAnErrorNotASilentRun)
{
	obs::registerAllClasses();
	const auto cfg = defaultConfig();
	PluginHost host;
	Navigator nav(cfg, host);
	const auvnav::testing::ScratchDir dir("empty_rawlog");
	const std::string path = (dir / "empty.rawlog").string();
	{
		io::RawlogWriter w(path);  // a valid gzip stream without one object
	}
	const RunSummary run = runRawlog(nav, path);
	EXPECT_FALSE(run.completed());
	EXPECT_NE(run.error.find(path + ": no observations in its "), std::string::npos) << run.error;
	EXPECT_THROW(run.rethrow(), io::RawlogError);
	EXPECT_EQ(run.observations, 0u);
}

TEST(RawlogRun, ALogWithoutTheImuIsAnErrorListingItsLabels)
{
	obs::registerAllClasses();
	auto cfg = defaultConfig();
	cfg.set("imu.label", "IMU2");  // the sample's IMU is 'IMU'
	PluginHost host;
	Navigator nav(cfg, host);
	std::size_t seen = 0;
	RunCallbacks cb;
	cb.on_observation = [&](const Navigator&) { ++seen; };
	const RunSummary run = runRawlog(nav, kRepo + "/share/sample/sample.rawlog", cb);
	EXPECT_FALSE(run.completed());
	EXPECT_NE(run.error.find("no IMU observation with label 'IMU2' (imu.label) among " +
	                         std::to_string(seen) + " observations (ADCP "),
	          std::string::npos)
	    << run.error;
	EXPECT_NE(run.error.find(", IMU 82672, "), std::string::npos) << run.error;
	EXPECT_EQ(run.labels.at("IMU"), 82672u);
}
