// The divergence monitor (auvnav/health.h): each status from the inputs that
// should cause it, with its reason.
#include <auvnav/health.h>
#include <gtest/gtest.h>

#include <random>

namespace auvnav
{
namespace
{
UpdateResult result(UpdateStatus s, double nis, int dim = 3)
{
	UpdateResult r;
	r.status = s;
	r.nis = nis;
	r.dim = dim;
	return r;
}

Covariance alignedCovariance()
{
	Covariance P = Covariance::Identity(idx::core_dim, idx::core_dim) * 1e-4;
	P(2, 2) = std::pow(0.5 * M_PI / 180, 2);  // heading σ 0.5°
	P(idx::pos, idx::pos) = P(idx::pos + 1, idx::pos + 1) = 1.0;
	return P;
}

/** `seconds` of 5 Hz 3-D updates with χ²(3) NIS scaled by `nis_scale`. */
void feed(HealthMonitor& h, const std::string& label, double from_s, double seconds, double nis_scale,
          UpdateStatus status = UpdateStatus::Accepted, unsigned seed = 1)
{
	std::mt19937 rng(seed);
	std::chi_squared_distribution<double> chi2(3);
	const NavState x;
	const Covariance P = alignedCovariance();
	for (double t = from_s; t < from_s + seconds; t += 0.2)
	{
		h.onUpdate(label, t, result(status, nis_scale * chi2(rng)));
		if (std::fmod(t, 1.0) < 0.2) h.onState(t, x, P);
	}
}
}  // namespace

TEST(Health, ConsistentAidsAreOk)
{
	HealthMonitor h;
	feed(h, "DVL", 0, 600, 1.0);
	EXPECT_EQ(h.status(), NavStatus::Ok) << h.reason();
	EXPECT_EQ(h.worst(), NavStatus::Ok) << h.worstReason();
}

TEST(Health, SingleOutliersDoNotDegrade)
{
	HealthMonitor h;
	feed(h, "GPS", 0, 100, 1.0);
	h.onUpdate("GPS", 100, result(UpdateStatus::Rejected, 5000));
	feed(h, "GPS", 100.2, 100, 1.0, UpdateStatus::Accepted, 2);
	EXPECT_EQ(h.worst(), NavStatus::Ok) << h.worstReason();
}

TEST(Health, InconsistentNisDegradesAndNamesTheSensor)
{
	HealthMonitor h;
	feed(h, "DVL", 0, 60, 1.0);
	feed(h, "DVL", 60, 60, 3.0, UpdateStatus::Accepted, 3);  // NIS 3 per dimension
	EXPECT_EQ(h.status(), NavStatus::Degraded);
	EXPECT_NE(h.reason().find("DVL: NIS"), std::string::npos) << h.reason();
	// 1.2 per dimension is significant over 150 updates but below the ratio.
	HealthMonitor mild;
	feed(mild, "IMU", 0, 120, 1.2);
	EXPECT_EQ(mild.worst(), NavStatus::Ok) << mild.worstReason();
}

TEST(Health, RejectedStreakDegradesThenDivergesAndStaysMarked)
{
	HealthLimits l;
	l.diverged_after_s = 60;
	HealthMonitor h(l);
	std::vector<NavStatus> changes;
	h.on_change = [&](double, NavStatus s, const std::string&) { changes.push_back(s); };
	feed(h, "DVL", 0, 60, 1.0);
	feed(h, "DVL", 60, 40, 50.0, UpdateStatus::Rejected);
	EXPECT_EQ(h.status(), NavStatus::Degraded) << h.reason();
	feed(h, "DVL", 100, 60, 50.0, UpdateStatus::Rejected);
	EXPECT_EQ(h.status(), NavStatus::Diverged);
	EXPECT_EQ(h.reason().rfind("DVL: ", 0), 0u) << h.reason();
	EXPECT_NE(h.reason().find("updates rejected in 30 s, for 100 s"), std::string::npos) << h.reason();
	// Consistent again: no longer diverged, but not "ok" either.
	feed(h, "DVL", 160, 120, 1.0, UpdateStatus::Accepted, 4);
	EXPECT_EQ(h.status(), NavStatus::Degraded);
	EXPECT_NE(h.reason().find("diverged at"), std::string::npos) << h.reason();
	EXPECT_EQ(h.worst(), NavStatus::Diverged);
	ASSERT_GE(changes.size(), 3u);
	EXPECT_EQ(changes[0], NavStatus::Degraded);
	EXPECT_EQ(changes[1], NavStatus::Diverged);
}

TEST(Health, LargeHeadingOrPositionSigmaIsDegraded)
{
	HealthMonitor h;
	const NavState x;
	Covariance P = alignedCovariance();
	h.onState(0, x, P);
	EXPECT_EQ(h.status(), NavStatus::Ok);
	P(2, 2) = std::pow(90 * M_PI / 180, 2);
	h.onState(1, x, P);
	EXPECT_EQ(h.status(), NavStatus::Degraded);
	EXPECT_NE(h.reason().find("heading not aligned (sigma 90.0 deg"), std::string::npos) << h.reason();
	P = alignedCovariance();
	P(idx::pos, idx::pos) = 80 * 80;
	h.onState(2, x, P);
	EXPECT_NE(h.reason().find("horizontal position sigma 80.0 m"), std::string::npos) << h.reason();
	P = alignedCovariance();
	P(0, 0) = NAN;
	h.onState(3, x, P);
	EXPECT_EQ(h.status(), NavStatus::Diverged);
}

TEST(Health, NotInitializedSaysWhatItWaitedFor)
{
	HealthMonitor h;
	h.setNotInitialized("a valid GPS fix on label 'GPS'");
	EXPECT_EQ(h.status(), NavStatus::NotInitialized);
	EXPECT_EQ(h.reason(), "not initialised: a valid GPS fix on label 'GPS'");
	EXPECT_STREQ(navStatusName(h.status()), "not_initialized");
}

TEST(Health, ConfigKeysAreChecked)
{
	const auto ok = config::Node::fromText("{max_heading_sigma_deg: 10, diverged_after_s: 20}", "test");
	const HealthLimits l = HealthLimits::fromConfig(ok);
	EXPECT_EQ(l.max_heading_sigma_deg, 10);
	EXPECT_EQ(l.diverged_after_s, 20);
	try
	{
		HealthLimits::fromConfig(config::Node::fromText("{max_heading_sigma_dg: 10}", "test"));
		FAIL() << "a misspelled key must be refused";
	}
	catch (const config::ConfigError& e)
	{
		EXPECT_NE(std::string(e.what()).find("max_heading_sigma_dg"), std::string::npos) << e.what();
	}
	EXPECT_THROW(HealthLimits::fromConfig(config::Node::fromText("{rejected_fraction: 1.5}", "test")),
	             config::ConfigError);
}

}  // namespace auvnav
