// filter.sigma_limits (issue 15 item 7): per-state bounds on the 1σ from the
// config, held after every prediction and update of a real run (the shipped
// sample), and refused with the key named when they cannot be right.
#include <auvnav/config.h>
#include <auvnav/navigator.h>
#include <auvnav/rawlog_run.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace auvnav;

namespace
{
const std::string kConfig = std::string(AUVNAV_SOURCE_DIR) + "/config/flatfish.yaml";
const std::string kSample = std::string(AUVNAV_SOURCE_DIR) + "/share/sample/sample.rawlog";

struct Sigmas
{
	double max_pos_n = 0;  // [m] largest north σ after the start
	double min_vel_e = 1;  // [m/s] smallest east velocity σ
	std::size_t hits = 0;
};

Sigmas run(const std::vector<std::pair<std::string, std::string>>& overrides)
{
	auto cfg = config::Node::load(kConfig);
	// A start more certain than the GPS: the position σ then grows above it.
	cfg.set("filter.initial.position_sigma_m", "0.5");
	for (const auto& [k, v] : overrides) cfg.set(k, v);
	PluginHost host;
	Navigator nav(cfg, host);
	Sigmas s;
	auto look = [&](const Navigator& n)
	{
		const Covariance& P = n.filter().covariance();
		s.max_pos_n = std::max(s.max_pos_n, std::sqrt(P(idx::pos, idx::pos)));
		s.min_vel_e = std::min(s.min_vel_e, std::sqrt(P(idx::vel + 1, idx::vel + 1)));
	};
	nav.on_predict = look;
	nav.on_update = [&](const std::string&, double, const Measurement&, const UpdateResult&) { look(nav); };
	const RunSummary r = runRawlog(nav, kSample);
	r.rethrow();
	s.hits = nav.filter().sigmaLimitHits();
	return s;
}
}  // namespace

TEST(SigmaLimits, AFloorAndACeilingHoldThroughARealRun)
{
	const Sigmas free = run({});
	EXPECT_EQ(free.hits, 0u);
	// Bounds the free run crosses, so that the test can fail.
	ASSERT_GT(free.max_pos_n, 0.6);
	const double floor = 3 * free.min_vel_e, ceiling = (0.5 + free.max_pos_n) / 2;
	char floor_text[32], ceiling_text[32];
	std::snprintf(floor_text, sizeof floor_text, "%.17g", floor);
	std::snprintf(ceiling_text, sizeof ceiling_text, "%.17g", ceiling);
	const Sigmas limited =
	    run({{"filter.sigma_limits.vel_e.min", floor_text}, {"filter.sigma_limits.pos.max", ceiling_text}});
	std::printf(
	    "free: pos_n sigma up to %.3f m, vel_e sigma down to %.3g m/s; limited (floor %.3g, "
	    "ceiling %.3f): %.3f m, %.3g m/s, %zu hits\n",
	    free.max_pos_n, free.min_vel_e, floor, ceiling, limited.max_pos_n, limited.min_vel_e, limited.hits);
	EXPECT_GT(limited.hits, 0u);
	EXPECT_LE(limited.max_pos_n, ceiling * (1 + 1e-12));
	EXPECT_GE(limited.min_vel_e, floor * (1 - 1e-12));
	EXPECT_NEAR(limited.min_vel_e, floor, 1e-9 * floor);  // it wanted to go lower: held on the floor
	EXPECT_NEAR(limited.max_pos_n, ceiling, 1e-9 * ceiling);
}

TEST(SigmaLimits, BadLimitsAreRefusedNamingTheKey)
{
	auto expectRefused =
	    [](const std::vector<std::pair<std::string, std::string>>& overrides, const std::string& what)
	{
		auto cfg = config::Node::load(kConfig);
		for (const auto& [k, v] : overrides) cfg.set(k, v);
		PluginHost host;
		try
		{
			Navigator nav(cfg, host);
			ADD_FAILURE() << "accepted; expected: " << what;
		}
		catch (const config::ConfigError& e)
		{
			EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
		}
	};
	expectRefused({{"filter.sigma_limits.gyro_bais.min", "1e-6"}},
	              "filter.sigma_limits.gyro_bais: unknown key (did you mean 'gyro_bias'");
	expectRefused({{"filter.sigma_limits.pos.mx", "3"}},
	              "filter.sigma_limits.pos.mx: unknown key (did you mean 'max'");
	expectRefused({{"filter.sigma_limits.vel.min", "2"}, {"filter.sigma_limits.vel.max", "1"}},
	              "filter.sigma_limits.vel.max: is below min");
	expectRefused({{"filter.sigma_limits.vel.min", "-1"}}, "filter.sigma_limits.vel.min");
	// The start's own σ must lie inside (1° heading ceiling against 30° initial).
	expectRefused({{"filter.sigma_limits.att_d.max", "0.017"}},
	              "filter.sigma_limits.att_d: its initial sigma");
}
