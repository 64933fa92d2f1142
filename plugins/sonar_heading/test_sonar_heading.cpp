// sonar_heading plugin: the bearing model against hand-computed cases, the
// contract on a synthetic frame, validation mode (logs, never applies), and an
// update that pulls a wrong heading toward the truth.
#include <auvnav/so3.h>
#include <auvnav/sonar/frame.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/testing/scratch_dir.h>
#include <auvnav/testing/sonar_frames.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "plugin_test_support.h"
#include "sonar_heading.h"

using namespace auvnav::plugins;
namespace fs = std::filesystem;

namespace
{

/** Writes a pole map and a sonar config into a temp folder; returns the plugin YAML. */
std::string pluginYaml(const std::string& mode, const fs::path& dir)
{
	fs::create_directories(dir);
	std::ofstream(dir / "poles.yaml") << "poles:\n"
	                                     "  - {id: A, north_m: 20, east_m: -6, radius_m: 0.15}\n"
	                                     "  - {id: B, north_m: 25, east_m: 7, radius_m: 0.15}\n"
	                                     "  - {id: C, north_m: 14, east_m: 3, radius_m: 0.15}\n";
	std::ofstream(dir / "sonar.yaml")
	    << "pole_map: poles.yaml\nmount: {position_m: [0.9, 0, 0.1], yaw_deg: 0}\n";
	return "sonar_config: sonar.yaml\nmode: " + mode +
	       "\nvalidation_csv: validation.csv\nconfig_dir: " + dir.string() + "\n";
}

/** A frame as the sonar at x would see the map's poles (flat seabed from 6 m). */
mrpt::obs::CObservationImage::Ptr frameSeenFrom(const NavState& x, const SonarHeadingModel& m, unsigned seed)
{
	const auto g = at::geminiGeometry();
	std::vector<at::SyntheticPole> poles;
	for (const auto& p : m.sonarConfig().map.poles)
	{
		const double b = predictedBearing(x, m.sonarConfig().position_b, 0.0, p.ne_m);
		const Eigen::Vector3d s = x.p_n + x.R_nb * m.sonarConfig().position_b;
		const double r = (p.ne_m - s.head<2>()).norm() - p.radius_m;
		if (g.inView(b, r)) poles.push_back({b, r, p.radius_m});
	}
	return sonar::makeFrame(at::renderPolarFrame(g, poles, seed), g, "SONAR", 1492693200.0 + seed);
}

/** A navigation-grade covariance: position 0.5 m, heading 3° (1σ). */
Covariance navCovariance()
{
	Covariance P = at::TypicalCovariance();
	P.block<3, 3>(idx::pos, idx::pos) = 0.25 * Eigen::Matrix3d::Identity();
	P(idx::att + 2, idx::att + 2) = std::pow(3 * kDeg, 2);
	return P;
}

NavState levelAt(double yaw_deg)
{
	NavState x;
	x.R_nb = so3::Exp(Eigen::Vector3d(0, 0, yaw_deg * kDeg));
	x.p_n = {0, 0, 3};
	x.g = 9.78;
	return x;
}
}  // namespace

TEST(SonarHeading, PredictedBearingHandComputed)
{
	NavState x = levelAt(90);  // facing east
	EXPECT_NEAR(predictedBearing(x, Eigen::Vector3d::Zero(), 0, {0, 10}), 0.0, 1e-12);
	EXPECT_NEAR(predictedBearing(x, Eigen::Vector3d::Zero(), 0, {10, 0}), -90 * kDeg, 1e-12);
	EXPECT_NEAR(predictedBearing(x, Eigen::Vector3d::Zero(), 0, {-10, 0}), 90 * kDeg, 1e-12);
	// Lever arm 1 m forward (east): the pole 10 m east is 9 m ahead, 1 m north → bearing −atan(1/9).
	EXPECT_NEAR(predictedBearing(x, {1, 0, 0}, 0, {1, 10}), -std::atan2(1.0, 9.0), 1e-12);
	// A sonar yawed 30° to starboard sees the same pole 30° further to port.
	EXPECT_NEAR(predictedBearing(x, Eigen::Vector3d::Zero(), 30 * kDeg, {0, 10}), -30 * kDeg, 1e-12);
	// Across ±180°: facing west, a pole just south-west-ish wraps correctly.
	x = levelAt(179);
	EXPECT_NEAR(predictedBearing(x, Eigen::Vector3d::Zero(), 0, {-10, -10 * std::tan(2 * kDeg)}), 3 * kDeg,
	            1e-9);
}

TEST(SonarHeading, UpdateModeIsWellFormedOnASyntheticFrame)
{
	const auvnav::testing::ScratchDir scratch("sonar_heading_wf");
	const fs::path& dir = scratch.path();
	SonarHeadingModel m(pt::configText(pluginYaml("update", dir)), "SONAR");
	at::TestContext tc;
	const NavState x = levelAt(5);
	const Covariance P = navCovariance();
	tc.ctx().mean = &x;
	tc.ctx().covariance = &P;
	const auto obs = frameSeenFrom(x, m, 3);
	std::vector<Measurement> out;
	std::string why;
	ASSERT_EQ(m.prepare(*obs, tc.ctx(), out, why), PrepareStatus::Ok) << why;
	EXPECT_GE(out.size(), 2u);
	EXPECT_TRUE(at::IsWellFormed(m, *obs, tc.ctx(), x));
	EXPECT_TRUE(at::IsWellFormed(m, *obs, tc.ctx(), at::RandomNavState(7)));
	// Not an image, or an image without polar geometry (and none configured): invalid.
	mrpt::obs::CObservationImage camera;
	camera.sensorLabel = "SONAR";
	EXPECT_EQ(m.prepare(camera, tc.ctx(), out, why), PrepareStatus::Invalid);
	// No filter yet: skipped.
	at::TestContext bare;
	EXPECT_EQ(m.prepare(*obs, bare.ctx(), out, why), PrepareStatus::Skip);
}

TEST(SonarHeading, ValidationModeLogsAndNeverApplies)
{
	const auvnav::testing::ScratchDir scratch("sonar_heading_val");
	const fs::path& dir = scratch.path();
	{
		SonarHeadingModel m(pt::configText(pluginYaml("validate", dir)), "SONAR");
		EXPECT_TRUE(m.validateOnly());
		at::TestContext tc;
		const NavState truth = levelAt(12);
		NavState believed = truth;
		believed.R_nb = so3::Exp(Eigen::Vector3d(0, 0, 2 * kDeg)) * truth.R_nb;  // 2° off
		const Covariance P = navCovariance();
		tc.ctx().mean = &believed;
		tc.ctx().covariance = &P;
		ManifoldUkf ukf(ProcessModel{}, UtParams{});
		ukf.initialize(believed, P);
		const auto r = at::ApplyObservation(ukf, m, *frameSeenFrom(truth, m, 5), tc.ctx());
		ASSERT_EQ(r.status, PrepareStatus::Ok) << r.why;
		EXPECT_TRUE(r.updates.empty());
		EXPECT_TRUE(at::NavStateIdentical(ukf.state(), believed));
	}
	std::ifstream csv(dir / "validation.csv");
	std::string header, line;
	ASSERT_TRUE(std::getline(csv, header));
	ASSERT_TRUE(std::getline(csv, line)) << "no validation line";
	// time, poles, landmark heading, σ, filter heading, σ, difference ≈ −2°.
	std::vector<double> v;
	std::stringstream ss(line);
	for (std::string f; std::getline(ss, f, ',');) v.push_back(std::stod(f));
	ASSERT_EQ(v.size(), 7u);
	EXPECT_NEAR(v[2], 12.0, 0.5);
	EXPECT_NEAR(v[4], 14.0, 1e-6);
	EXPECT_NEAR(v[6], -2.0, 0.5);
}

TEST(SonarHeading, UpdatePullsAWrongHeadingTowardTheTruth)
{
	const auvnav::testing::ScratchDir scratch("sonar_heading_upd");
	const fs::path& dir = scratch.path();
	SonarHeadingModel m(pt::configText(pluginYaml("update", dir)), "SONAR");
	const NavState truth = levelAt(-20);
	NavState start = truth;
	start.R_nb = so3::Exp(Eigen::Vector3d(0, 0, 1.5 * kDeg)) * truth.R_nb;
	Covariance P = at::TypicalCovariance();
	P(idx::att + 2, idx::att + 2) = std::pow(2 * kDeg, 2);
	P.block<3, 3>(idx::pos, idx::pos) = 0.04 * Eigen::Matrix3d::Identity();
	ManifoldUkf ukf(ProcessModel{}, UtParams{});
	ukf.initialize(start, P);
	at::TestContext tc;
	for (unsigned seed = 1; seed <= 5; ++seed)
	{
		const NavState mean = ukf.state();
		const Covariance cov = ukf.covariance();
		tc.ctx().mean = &mean;
		tc.ctx().covariance = &cov;
		const auto r = at::ApplyObservation(ukf, m, *frameSeenFrom(truth, m, seed), tc.ctx());
		ASSERT_EQ(r.status, PrepareStatus::Ok) << r.why;
		EXPECT_FALSE(r.updates.empty());
	}
	const auto yaw = [](const NavState& x) { return std::atan2(x.R_nb(1, 0), x.R_nb(0, 0)); };
	const double err = std::abs(auvnav::wrapAngle(yaw(ukf.state()) - yaw(truth)));
	EXPECT_LT(err, 0.3 * kDeg) << "from 1.5°";
	EXPECT_LT(std::sqrt(ukf.covariance()(idx::att + 2, idx::att + 2)), 0.5 * kDeg);
}

TEST(SonarHeading, RejectsBadConfigNamingTheKey)
{
	const auvnav::testing::ScratchDir scratch("sonar_heading_bad");
	const fs::path& dir = scratch.path();
	std::string yaml = pluginYaml("update", dir);
	yaml.replace(yaml.find("mode: update"), 12, "mode: apply");
	try
	{
		SonarHeadingModel m(pt::configText(yaml), "SONAR");
		FAIL() << "accepted mode 'apply'";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find("mode"), std::string::npos) << e.what();
	}
	EXPECT_THROW(SonarHeadingModel(pt::configText("sonar_config: /nonexistent/sonar.yaml\n"), "SONAR"),
	             std::exception);
}

TEST(SonarHeading, ModuleExportsEntryAndCreates)
{
	const auvnav::testing::ScratchDir scratch("sonar_heading_mod");
	const fs::path& dir = scratch.path();
	EXPECT_TRUE(
	    pt::ModuleLoadsAndCreates("sonar_heading", pluginYaml("validate", dir), kAttitude | kPosition));
}
