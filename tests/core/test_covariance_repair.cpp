// Covariance repair (issue 15 item 7): a repair makes P positive definite by
// changing correlations only. The case found in review: with ~9 m² of
// position variance, clipping P's own eigenvalues at 1e-12·λmax raised a
// gyro-bias variance of 1e-12 rad²/s² tenfold; here no variance may move.
#include <auvnav/state.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

using namespace auvnav;

namespace
{
/** A covariance with variances spread over 16 decades and correlations from
 *  a random factor, pushed indefinite by a near-duplicate pair of states. */
Covariance scaledIndefinite(int n, unsigned seed)
{
	std::mt19937 rng(seed);
	std::normal_distribution<double> N;
	Eigen::MatrixXd A(n, n);
	for (int i = 0; i < n; ++i)
		for (int j = 0; j < n; ++j) A(i, j) = N(rng);
	// States 0 and 1 nearly the same, then correlated just beyond 1: the loss
	// of definiteness rounding produces after many updates.
	A.row(1) = A.row(0) + 1e-4 * A.row(2);
	Covariance C = A * A.transpose();
	const Eigen::VectorXd d = C.diagonal().cwiseSqrt().cwiseInverse();
	C = d.asDiagonal() * C * d.asDiagonal();
	C(0, 1) = C(1, 0) = C(0, 1) + 1e-6;
	TangentVector sigma(n);
	for (int i = 0; i < n; ++i) sigma[i] = std::pow(10.0, 0.5 - 8.0 * i / (n - 1));  // 3.2 … 3e-8
	return sigma.asDiagonal() * C * sigma.asDiagonal();
}
}  // namespace

TEST(CovarianceRepair, KeepsEveryVarianceAndMakesPositiveDefinite)
{
	for (unsigned seed = 1; seed <= 5; ++seed)
	{
		const int n = idx::core_dim;
		Covariance P = scaledIndefinite(n, seed);
		ASSERT_NE(Eigen::LLT<Eigen::MatrixXd>(P).info(), Eigen::Success) << "the case must need a repair";
		const TangentVector before = P.diagonal();
		const TangentVector s0 = before.cwiseSqrt();
		const Covariance C0 = s0.cwiseInverse().asDiagonal() * P * s0.cwiseInverse().asDiagonal();
		repairCovariance(P, TangentVector::Constant(n, 1e-30));
		EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(P).info(), Eigen::Success) << "seed " << seed;
		for (int i = 0; i < n; ++i)
			EXPECT_NEAR(P(i, i) / before[i], 1.0, 1e-12) << "seed " << seed << " state " << i;
		EXPECT_LE((P - P.transpose()).cwiseAbs().maxCoeff(), 0.0);
		// Correlations stay correlations, and the well-conditioned part barely moves.
		const TangentVector s = P.diagonal().cwiseSqrt();
		const Covariance C = s.cwiseInverse().asDiagonal() * P * s.cwiseInverse().asDiagonal();
		EXPECT_LE(C.cwiseAbs().maxCoeff(), 1.0 + 1e-12);
		EXPECT_LE((C - C0).cwiseAbs().maxCoeff(), 1e-5) << "seed " << seed;
	}
}

TEST(CovarianceRepair, ScaleOnlyEigenvalueClippingWouldInflateTheSmallVariances)
{
	// The old rule on the same matrix, to show the test above can fail: the
	// smallest variances grow by far more than their own scale.
	Covariance P = scaledIndefinite(idx::core_dim, 1);
	const TangentVector before = P.diagonal();
	Eigen::SelfAdjointEigenSolver<Covariance> es(P);
	const TangentVector ev = es.eigenvalues().cwiseMax(1e-12 * es.eigenvalues().cwiseAbs().maxCoeff());
	P = es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
	EXPECT_GT(P(idx::core_dim - 1, idx::core_dim - 1) / before[idx::core_dim - 1], 10.0);
}

TEST(CovarianceRepair, ANonPositiveVarianceGetsItsFloorAndNoCorrelation)
{
	Covariance P = Covariance::Identity(4, 4);
	P(0, 1) = P(1, 0) = 0.5;
	P(2, 2) = -1e-3;
	P(2, 3) = P(3, 2) = 0.1;
	P(3, 3) = std::nan("");
	TangentVector floor(4);
	floor << 1, 1, 1e-8, 1e-6;
	repairCovariance(P, floor);
	EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(P).info(), Eigen::Success);
	EXPECT_DOUBLE_EQ(P(2, 2), 1e-8);
	EXPECT_DOUBLE_EQ(P(3, 3), 1e-6);
	EXPECT_EQ(P(2, 3), 0.0);
	EXPECT_NEAR(P(0, 1), 0.5, 1e-12);
}

// Sigma limits (issue 15 item 7, filter.sigma_limits): a state's σ is moved
// onto its bound by scaling its row and column; correlations are kept and P
// stays positive definite.
TEST(SigmaLimits, MoveOnlyTheStatesOutsideTheirBoundsAndKeepCorrelations)
{
	const int n = idx::core_dim;
	std::mt19937 rng(7);
	std::normal_distribution<double> N;
	Eigen::MatrixXd A(n, n);
	for (int i = 0; i < n; ++i)
		for (int j = 0; j < n; ++j) A(i, j) = N(rng);
	TangentVector sigma(n);
	for (int i = 0; i < n; ++i) sigma[i] = std::pow(10.0, 1.0 - 6.0 * i / (n - 1));  // 10 … 1e-5
	Covariance P = A * A.transpose() + n * Eigen::MatrixXd::Identity(n, n);
	const TangentVector d = P.diagonal().cwiseSqrt().cwiseInverse();
	P = (sigma.cwiseProduct(d)).asDiagonal() * P * (sigma.cwiseProduct(d)).asDiagonal();
	const Covariance before = P;
	TangentVector lo = TangentVector::Zero(n), hi = TangentVector::Constant(n, INFINITY);
	lo[idx::gyro_bias + 2] = 10 * sigma[idx::gyro_bias + 2];  // a floor above: raised
	hi[idx::pos] = 0.5 * sigma[idx::pos];                     // a ceiling below: lowered
	lo[idx::vel] = 0.5 * sigma[idx::vel];                     // bounds it already meets: untouched
	hi[idx::vel] = 2 * sigma[idx::vel];
	EXPECT_EQ(limitSigmas(P, lo, hi), 2);
	EXPECT_DOUBLE_EQ(std::sqrt(P(idx::gyro_bias + 2, idx::gyro_bias + 2)), lo[idx::gyro_bias + 2]);
	EXPECT_NEAR(std::sqrt(P(idx::pos, idx::pos)), hi[idx::pos], 4e-16 * hi[idx::pos]);
	EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(P).info(), Eigen::Success);
	for (int i = 0; i < n; ++i)
	{
		if (i != idx::gyro_bias + 2 && i != idx::pos)
		{
			EXPECT_EQ(P(i, i), before(i, i)) << i;
		}
		for (int j = 0; j < n; ++j)
		{
			const double r0 = before(i, j) / std::sqrt(before(i, i) * before(j, j));
			const double r1 = P(i, j) / std::sqrt(P(i, i) * P(j, j));
			EXPECT_NEAR(r1, r0, 1e-12) << i << "," << j;
		}
	}
	// Again: nothing left to move.
	EXPECT_EQ(limitSigmas(P, lo, hi), 0);
}
