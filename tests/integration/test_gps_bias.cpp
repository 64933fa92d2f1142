// The GPS plugin's bias state end to end: a slowly varying GPS error as a
// plugin-owned Gauss–Markov state keeps the position σ honest where fixes
// taken as independent average it away.
//  - usbl_sample mission (5 min on the surface with 1 Hz GPS, then a dive),
//    its USBL denied; the simulator's GPS error has a slow part, σ 3 m
//    over τ 600 s, on top of its 0.8 m white part;
//  - every fix is used (min_interval_s 0) both ways: once as white noise
//    (sigma_m 1 m alone), once with `states: {bias: {σ 3 m, gauss_markov,
//    τ 600 s}}`;
//  - at the dive: with the state the error is inside 3σ of the horizontal
//    position and σ is of the slow error's size; as white noise σ falls to
//    ~0.1 m (300 fixes) and the error, the slow part's value, is far
//    outside it.
// Seeds 1–4 (this test runs seed 2): white 4.24 / 2.63 / 5.65 / 3.18 m
// against σ 0.13 m; with the state 4.41 / 4.19 / 3.88 / 2.28 m against σ
// 2.36 m. (As white noise the resurfacing's fixes can also end the run
// degraded, seed 2's "GPS: NIS 4.21 per dimension"; not on every seed.)
#include <auvnav/navigator.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "harness.h"

namespace fs = std::filesystem;
using namespace auvnav;
using namespace auvnav::test;

namespace
{
const std::string kConfig = std::string(AUVNAV_SOURCE_DIR) + "/config/flatfish.yaml";
const std::string kMission = "config/missions/usbl_sample.yaml";

struct AtDive
{
	double error_m = 0, sigma_m = 0;  // horizontal error; σ of the position's major axis
	std::size_t gps_used = 0;
	NavStatus status = NavStatus::Ok;  // the divergence monitor at the end of the run
	std::string status_reason;
};

AtDive runToDive(const fs::path& dir, bool bias_state)
{
	const auto truth = readTruth(dir / "ground_truth.csv");
	const std::size_t dive = diveAndResurfacing(truth).first;
	if (dive >= truth.size())
	{
		ADD_FAILURE() << "the mission never dives";
		return {};
	}
	std::vector<std::pair<std::string, std::string>> overrides{{"sensors.GPS.config.min_interval_s", "0"},
	                                                           {"sensors.GPS.config.correlated_sigma_m", "0"},
	                                                           {"sensors.GPS.config.sigma_m", "1.0"}};
	if (bias_state)
		for (const auto& [key, value] : {std::pair<std::string, std::string>{"sigma", "3"},
		                                 {"process", "gauss_markov"},
		                                 {"process_sigma", "3"},
		                                 {"tau_s", "600"}})
			overrides.emplace_back("sensors.GPS.config.states.bias." + key, value);
	const RunResult r = runNavigator(kConfig, (dir / "usbl_sample.rawlog").string(), overrides,
	                                 {DenialWindow{{"USBL"}, 0, 1e9}});
	AtDive a;
	a.status = r.status;
	a.status_reason = r.status_reason;
	for (const auto& row : r.rows)
	{
		if (row.t_unix < truth[dive].t_unix) continue;
		a.error_m = (row.p_n - truthAt(truth, row.t_unix).p_n).head<2>().norm();
		a.sigma_m =
		    std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(row.P_ne).eigenvalues().maxCoeff());
		break;
	}
	for (const auto& s : r.stats)
		if (s.label == "GPS") a.gps_used = s.accepted + s.recovered;
	return a;
}
}  // namespace

TEST(GpsBiasState, KeepsThePositionSigmaOfASlowGpsErrorAtTheDive)
{
	const auto dir = simulate(
	    kMission, 2, {{"gps.correlated_sigma_m", "3.0"}, {"gps.correlation_time_s", "600"}}, "_slow_gps");
	const AtDive white = runToDive(dir.path(), false);
	const AtDive state = runToDive(dir.path(), true);
	std::printf(
	    "at the dive: as white noise error %.2f m, sigma %.3f m (%zu fixes); with the bias state error "
	    "%.2f m, sigma %.2f m (%zu fixes)\n",
	    white.error_m, white.sigma_m, white.gps_used, state.error_m, state.sigma_m, state.gps_used);
	EXPECT_GT(state.gps_used, 200u);  // 1 Hz for ~5 min, both ways
	EXPECT_GT(white.gps_used, 200u);
	// With the state: the error inside 3σ, and σ of the slow error's size
	// (it cannot average out over 5 min of a 10 min correlation).
	EXPECT_LT(state.error_m, 3 * state.sigma_m);
	EXPECT_GT(state.sigma_m, 1.0);
	// As white noise: σ averaged down, and the error far outside it.
	EXPECT_LT(white.sigma_m, 0.3);
	EXPECT_GT(white.error_m, 3 * white.sigma_m);
	EXPECT_EQ(state.status, NavStatus::Ok) << state.status_reason;
}
