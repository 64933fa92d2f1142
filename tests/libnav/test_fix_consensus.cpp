// InitialFixConsensus and RejectedFixRun (auvnav/fix_consensus.h): the first
// position from fixes that agree; a run of rejected fixes that agree on one
// offset told apart from scattered outliers.
#include <auvnav/fix_consensus.h>
#include <gtest/gtest.h>

#include <random>

namespace auvnav
{
namespace
{
InitialFix fixAt(double north_m, double east_m)
{
	InitialFix f;
	f.p_n = Eigen::Vector3d(north_m, east_m, 0);
	f.r_b = Eigen::Vector3d(-0.3, 0, -0.6);
	return f;
}
}  // namespace

TEST(InitialFixConsensus, AWildFirstFixIsOutvotedAndNeverTheStart)
{
	InitialFixConsensus c({5, 10.0, 60.0});
	c.add(0, fixAt(1000, 0));
	for (int k = 1; k <= 4; ++k)
	{
		EXPECT_FALSE(c.agreed()) << k << " good fixes";
		c.add(k, fixAt(50 + 0.5 * k, -20));
	}
	EXPECT_EQ(c.fixes(), 5);
	EXPECT_EQ(c.agreeing(), 4);
	EXPECT_FALSE(c.agreed());  // 4 agree: 5 needed
	c.add(5, fixAt(52.5, -20));
	ASSERT_TRUE(c.agreed());
	EXPECT_DOUBLE_EQ(c.agreed()->p_n.x(), 52.5);  // the newest agreeing fix
	EXPECT_DOUBLE_EQ(c.agreed()->r_b.x(), -0.3);
}

TEST(InitialFixConsensus, NeedsAStrictMajorityOfTheWindow)
{
	// 5 good fixes and 5 wild ones that agree among themselves elsewhere: the
	// median lies between the clusters, nobody is a majority, no start.
	InitialFixConsensus c({5, 10.0, 60.0});
	for (int k = 0; k < 5; ++k) c.add(k, fixAt(0, 0));
	for (int k = 5; k < 10; ++k) c.add(k, fixAt(100, 0));
	EXPECT_FALSE(c.agreed());
	// Old fixes leave the window: the newer cluster alone is a consensus.
	c.add(65.5, fixAt(100, 1));  // keeps those from 5.5 s on: 6..9 and itself
	EXPECT_EQ(c.fixes(), 5);
	ASSERT_TRUE(c.agreed());
	EXPECT_DOUBLE_EQ(c.agreed()->p_n.y(), 1.0);
}

TEST(InitialFixConsensus, OneFixIsTheOldBehaviour)
{
	InitialFixConsensus c({1, 10.0, 60.0});
	EXPECT_FALSE(c.agreed());
	c.add(0, fixAt(7, 8));
	ASSERT_TRUE(c.agreed());
	EXPECT_DOUBLE_EQ(c.agreed()->p_n.x(), 7.0);
}

TEST(RejectedFixRun, AConstantOffsetAgreesAndIsItsWeightedMean)
{
	RejectedFixRun run;
	const Eigen::Matrix2d R = Eigen::Matrix2d::Identity() * 9.0;  // σ 3 m
	run.add(0, {20.5, 1.0}, R);
	run.add(30, {19.0, -2.0}, R);
	run.add(60, {20.5, 1.0}, R);
	EXPECT_TRUE(run.agree(3, 0.99));
	EXPECT_NEAR(run.meanOffset_m(3).x(), 20.0, 1e-12);
	EXPECT_NEAR(run.meanOffset_m(3).y(), 0.0, 1e-12);
	EXPECT_DOUBLE_EQ(run.meanNoise_m2(3)(0, 0), 9.0);
	EXPECT_DOUBLE_EQ(run.firstTime_s(3), 0.0);
	EXPECT_DOUBLE_EQ(run.firstTime_s(2), 30.0);
	EXPECT_FALSE(run.agree(4, 0.99));  // only 3 kept
}

TEST(RejectedFixRun, ScatteredOutliersDoNotAgree)
{
	// GPS-like outliers 10–60 m in random directions, σ 3 m: three in a row
	// must (almost) never be taken for one offset of the state.
	std::mt19937 rng(3);
	std::uniform_real_distribution<double> dist(10, 60), angle(-M_PI, M_PI);
	const Eigen::Matrix2d R = Eigen::Matrix2d::Identity() * 9.0;
	int agreed = 0;
	for (int trial = 0; trial < 1000; ++trial)
	{
		RejectedFixRun run;
		for (int k = 0; k < 3; ++k)
		{
			const double d = dist(rng), a = angle(rng);
			run.add(k, {d * std::cos(a), d * std::sin(a)}, R);
		}
		agreed += run.agree(3, 0.99);
	}
	EXPECT_LT(agreed, 10) << agreed << " of 1000";
}

TEST(RejectedFixRun, ABadNoiseStartsANewRun)
{
	RejectedFixRun run;
	run.add(0, {1, 1}, Eigen::Matrix2d::Identity());
	run.add(1, {1, 1}, Eigen::Matrix2d::Zero());
	EXPECT_EQ(run.size(), 0);
}

}  // namespace auvnav
