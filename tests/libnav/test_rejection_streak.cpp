// RejectionStreak (auvnav/rejection_streak.h): a drifting bias of the state is
// told apart from outliers by the agreement of the rejected innovations.
#include <auvnav/rejection_streak.h>
#include <gtest/gtest.h>

#include <random>

namespace auvnav
{
namespace
{
const Eigen::MatrixXd kR = Eigen::MatrixXd::Identity(3, 3) * 0.01 * 0.01;  // DVL-like, σ 1 cm/s

/** Fraction of 1000 trials in which 5 rejections at 5 Hz, ν = bias + drift·t + `spread`·σ·noise,
 *  are judged a bias of the state. */
double fractionJudgedBias(const Eigen::Vector3d& bias, const Eigen::Vector3d& drift_per_s, double spread)
{
	std::mt19937 rng(7);
	std::normal_distribution<double> nd;
	int yes = 0;
	for (int trial = 0; trial < 1000; ++trial)
	{
		RejectionStreak s;
		for (int k = 0; k < 5; ++k)
		{
			const double t = 0.2 * k;
			const Eigen::Vector3d noise(nd(rng), nd(rng), nd(rng));
			s.add(t, bias + drift_per_s * t + spread * 0.01 * noise, kR);
		}
		yes += s.consistentBias(5, 0.99);
	}
	return yes / 1000.0;
}
}  // namespace

TEST(RejectionStreak, ConstantOrDriftingBiasOfTheStateIsRecognised)
{
	// The circle case: the filter's velocity 0.3 m/s off and growing by 0.1 m/s per second.
	EXPECT_GT(fractionJudgedBias({0.3, -0.1, 0}, {0, 0, 0}, 1.0), 0.97);
	EXPECT_GT(fractionJudgedBias({0.3, -0.1, 0}, {0.1, 0.05, 0}, 1.0), 0.97);
}

TEST(RejectionStreak, OutliersAreNotABias)
{
	// Scattered 10x their noise (spikes, lock on fish): almost never a bias.
	EXPECT_LT(fractionJudgedBias({0.3, -0.1, 0}, {0, 0, 0}, 10.0), 0.01);
	// A single spike among consistent rejections breaks the fit.
	RejectionStreak s;
	for (int k = 0; k < 5; ++k) s.add(0.2 * k, Eigen::Vector3d(0.3, 0, k == 2 ? 0.5 : 0), kR);
	EXPECT_FALSE(s.consistentBias(5, 0.99));
}

TEST(RejectionStreak, NeedsEnoughRejectionsOfOneDimension)
{
	RejectionStreak s;
	for (int k = 0; k < 4; ++k) s.add(0.2 * k, Eigen::Vector3d(0.3, 0, 0), kR);
	EXPECT_FALSE(s.consistentBias(5, 0.99));
	s.add(0.8, Eigen::Vector3d(0.3, 0, 0), kR);
	EXPECT_TRUE(s.consistentBias(5, 0.99));
	s.add(1.0, Eigen::Vector2d(0.3, 0), Eigen::MatrixXd::Identity(2, 2) * 1e-4);  // another measurement type
	EXPECT_EQ(s.size(), 1);
	EXPECT_FALSE(s.consistentBias(5, 0.99));
	s.add(1.2, Eigen::Vector2d(NAN, 0), Eigen::MatrixXd::Identity(2, 2) * 1e-4);
	EXPECT_EQ(s.size(), 0);
	EXPECT_FALSE(s.consistentBias(2, 0.99));  // fewer than 3 can never fit a drift
}

}  // namespace auvnav
