// Acceptance of the navigator on simulated missions (issue: navigator):
//  - square_5x50m: GPS before diving only, initial heading 10° off (σ 30°):
//    horizontal error at resurfacing < 0.5 % of the distance travelled
//    submerged and inside the filter's 2σ, for ≥ 4 of 5 seeds;
//  - heading: GPS withheld all along, initial heading offsets +15°, 0°, −15°
//    (σ 30°): heading error < 1° after 15 min and inside 3σ after the first
//    minute, for every offset and 3 seeds.
// The full sets are labelled `slow`; one seed of each runs by default.
#include <auvnav/so3.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "harness.h"

namespace fs = std::filesystem;
using namespace auvnav;
using namespace auvnav::test;

namespace
{
constexpr double kDeg = M_PI / 180;
const std::string kConfig = std::string(AUVNAV_SOURCE_DIR) + "/config/flatfish.yaml";
// The acceptance is stated for inertial + DVL + pressure (+ GPS): the default
// configuration's ADCP and model-aiding sensors are denied all along.
const DenialWindow kInertialDvlPressureOnly{{"ADCP", "THRUSTERS"}, 0.0, 1e9};

std::string fmt(double v)
{
	return std::to_string(v);
}

struct SquareOutcome
{
	double error_m = 0, distance_m = 0, two_sigma_m = 0, heading_err_deg = 0;
	bool pass() const { return error_m < 0.005 * distance_m && error_m <= two_sigma_m; }
};

SquareOutcome runSquare(unsigned seed)
{
	const auto dir = simulate("config/missions/square_5x50m.yaml", seed);
	const auto truth = readTruth(dir / "ground_truth.csv");
	const auto span = diveAndResurfacing(truth);
	const std::size_t dive = span.first, surf = span.second;
	EXPECT_LT(surf, truth.size());
	const double t0 = truth.front().t_unix;
	const double true_heading0 = yawOf(truth.front().q_nb.toRotationMatrix());

	auto cfg = config::Node::load(kConfig);
	cfg.set("filter.initial.heading_deg", fmt(true_heading0 / kDeg + 10.0));
	cfg.set("filter.initial.heading_sigma_deg", "30");
	PluginHost host;
	Navigator nav(cfg, host);
	DenialWindow gps_off;  // GPS before diving only
	gps_off.labels = {"GPS"};
	gps_off.from_s = truth[dive].t_unix - t0;
	gps_off.to_s = 1e9;
	nav.addDenial(gps_off);
	nav.addDenial(kInertialDvlPressureOnly);
	SquareOutcome out;
	bool recorded = false;
	nav.on_predict = [&](const Navigator& n)
	{
		if (recorded || n.time() < truth[surf].t_unix) return;
		recorded = true;
		const HorizontalError e = horizontalError(n, truth);
		out.error_m = e.error_m;
		out.two_sigma_m = e.two_sigma_m;
		const auto& tr = truthAt(truth, n.time());
		out.heading_err_deg =
		    wrapAngle(yawOf(n.filter().state().R_nb) - yawOf(tr.q_nb.toRotationMatrix())) / kDeg;
	};
	runRawlog(nav, (dir / "square_5x50m.rawlog").string()).rethrow();
	EXPECT_TRUE(recorded);
	out.distance_m = truth[surf].distance_m - truth[dive].distance_m;
	return out;
}

void squareSeeds(const std::vector<unsigned>& seeds, int min_pass)
{
	int passed = 0;
	std::printf(
	    "square_5x50m: seed | error at resurfacing [m] | distance submerged [m] | error %% | 2 sigma [m] | "
	    "heading err [deg]\n");
	for (unsigned s : seeds)
	{
		const auto o = runSquare(s);
		std::printf("  %u | %.2f | %.0f | %.3f %% | %.2f | %.3f | %s\n", s, o.error_m, o.distance_m,
		            100 * o.error_m / o.distance_m, o.two_sigma_m, o.heading_err_deg,
		            o.pass() ? "pass" : "FAIL");
		passed += o.pass();
	}
	EXPECT_GE(passed, min_pass);
}

struct HeadingOutcome
{
	double error_15min_deg = 0, sigma_15min_deg = 0, worst_ratio_after_1min = 0;
	//! Worst |roll error| / σ on the straight surface line (1–7 min): before
	//! the first turn nothing separates roll from accelerometer bias, so the
	//! roll σ must stay at the bias's share (it fell to 0.016° against a 0.08°
	//! error while the heading converged, when the bias was perturbed in IMU
	//! axes).
	double worst_roll_ratio_line = 0;
	bool pass() const
	{
		return std::abs(error_15min_deg) < 1.0 && worst_ratio_after_1min <= 3.0 &&
		       worst_roll_ratio_line <= 3.0;
	}
};

HeadingOutcome runHeading(const fs::path& dir, double offset_deg, double sigma_deg = 30)
{
	const auto truth = readTruth(dir / "ground_truth.csv");
	const double t0 = truth.front().t_unix;
	const double true_heading0 = yawOf(truth.front().q_nb.toRotationMatrix());
	const auto run = runNavigator(kConfig, (dir / "heading.rawlog").string(),
	                              {{"filter.initial.heading_deg", fmt(true_heading0 / kDeg + offset_deg)},
	                               {"filter.initial.heading_sigma_deg", fmt(sigma_deg)},
	                               {"filter.initial.position", "config"},
	                               {"filter.initial.north_m", "0"},
	                               {"filter.initial.east_m", "0"}},
	                              {DenialWindow{{"GPS"}, 0.0, 1e9},  // GPS withheld for the whole run
	                               kInertialDvlPressureOnly});
	HeadingOutcome o;
	bool at15 = false;
	for (const auto& r : run.rows)
	{
		const Eigen::Matrix3d R_true = truthAt(truth, r.t_unix).q_nb.toRotationMatrix();
		const double err = wrapAngle(yawOf(r.R_nb) - yawOf(R_true));
		if (r.t_unix - t0 > 60)
			o.worst_ratio_after_1min = std::max(o.worst_ratio_after_1min, std::abs(err) / r.headingSigma());
		if (r.t_unix - t0 > 60 && r.t_unix - t0 < 420)
		{
			// Roll: the tilt error about the vehicle's horizontal forward axis.
			const Eigen::Vector3d tilt = so3::Log(r.R_nb * R_true.transpose());
			Eigen::Vector3d fwd(R_true(0, 0), R_true(1, 0), 0);
			fwd.normalize();
			const double roll_err = fwd.dot(tilt), roll_sigma = std::sqrt(fwd.dot(r.P_att * fwd));
			o.worst_roll_ratio_line = std::max(o.worst_roll_ratio_line, std::abs(roll_err) / roll_sigma);
		}
		if (!at15 && r.t_unix - t0 >= 900)
		{
			at15 = true;
			o.error_15min_deg = err / kDeg;
			o.sigma_15min_deg = r.headingSigma() / kDeg;
		}
	}
	EXPECT_TRUE(at15);
	for (const auto& s : run.stats)
	{
		if (s.label == "GPS")
		{
			EXPECT_EQ(s.accepted, 0u) << "GPS must be withheld";
		}
	}
	return o;
}

void headingSeeds(const std::vector<unsigned>& seeds, const std::vector<double>& offsets,
                  double sigma_deg = 30)
{
	std::printf("initial heading sigma %.0f deg\n", sigma_deg);
	std::printf(
	    "heading (no GPS): seed | offset [deg] | error at 15 min [deg] | sigma at 15 min [deg] | worst "
	    "|err|/sigma after 1 min | worst |roll err|/sigma on the surface line\n");
	for (unsigned s : seeds)
	{
		const auto dir = simulate("config/missions/heading.yaml", s);
		for (double off : offsets)
		{
			const auto o = runHeading(dir.path(), off, sigma_deg);
			std::printf("  %u | %+.0f | %+.3f | %.3f | %.2f | %.2f | %s\n", s, off, o.error_15min_deg,
			            o.sigma_15min_deg, o.worst_ratio_after_1min, o.worst_roll_ratio_line,
			            o.pass() ? "pass" : "FAIL");
			EXPECT_TRUE(o.pass()) << "seed " << s << " offset " << off;
		}
	}
}
}  // namespace

TEST(SquareMission, OneSeedResurfacesWithinHalfPercent)
{
	squareSeeds({1}, 1);
}
TEST(SquareMissionSlow, FiveSeedsResurfaceWithinHalfPercent)
{
	squareSeeds({1, 2, 3, 4, 5}, 4);
}
TEST(HeadingMission, OneSeedGyrocompassesWithoutGps)
{
	headingSeeds({1}, {15.0});
}
TEST(HeadingMissionSlow, ThreeSeedsThreeOffsetsGyrocompassWithoutGps)
{
	headingSeeds({1, 2, 3}, {15.0, 0.0, -15.0});
}
// The heading unknown (σ 180°) from half a turn off: the sigma points of an
// attitude σ this large wrap around the circle unless their spread is
// limited (ukf.h, max_attitude_spread_rad); without the limit the heading
// was −111° off after 15 min with a σ of 1.4°.
TEST(HeadingMission, HalfTurnOffWithUnknownHeadingGyrocompasses)
{
	headingSeeds({1}, {180.0}, 180);
}
TEST(HeadingMissionSlow, EveryInitialHeadingWithUnknownHeadingGyrocompasses)
{
	headingSeeds({1, 2}, {0.0, 45.0, -45.0, 90.0, -90.0, 135.0, -135.0, 180.0}, 180);
}
