// The filter's covariance kernels (libnav/core/src/covariance_kernels.h, private
// to the library) against Eigen's general products and solvers as oracles,
// on the shapes the filter and the smoother use: within rounding of the
// oracle, nothing written outside the ranges each kernel names, and every
// bound sharp enough to catch one entry moved by 1e-8.
#include <covariance_kernels.h>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <random>
#include <string>

namespace auvnav::kernels
{
namespace
{
Eigen::MatrixXd randomMatrix(int rows, int cols, unsigned seed)
{
	std::mt19937 rng(seed);
	std::normal_distribution<double> normal;
	Eigen::MatrixXd X(rows, cols);
	for (Eigen::Index i = 0; i < X.size(); ++i) X.data()[i] = normal(rng);
	return X;
}

/** A well-conditioned lower-triangular k × k (a Cholesky factor's shape:
 *  positive diagonal), in a matrix with a larger stride. */
Eigen::MatrixXd lowerFactor(int k, unsigned seed)
{
	std::mt19937 rng(seed);
	std::normal_distribution<double> normal;
	std::uniform_real_distribution<double> diag(0.5, 2.0);
	Eigen::MatrixXd L = Eigen::MatrixXd::Zero(k + 3, k);  // stride k + 3
	for (int j = 0; j < k; ++j)
	{
		L(j, j) = diag(rng);
		for (int i = j + 1; i < k; ++i) L(i, j) = 0.3 * normal(rng);
	}
	return L;
}

/** A symmetric positive definite n × n with unit-order entries, exactly
 *  symmetric (a product's fused multiply-adds may round (i, j) and (j, i)
 *  differently). */
Covariance spd(int n, unsigned seed)
{
	const Eigen::MatrixXd A = randomMatrix(n, n, seed);
	const Eigen::MatrixXd P = A * A.transpose() + n * Eigen::MatrixXd::Identity(n, n);
	return 0.5 * (P + P.transpose());
}

double relativeGap(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b)
{
	return (a - b).cwiseAbs().maxCoeff() / (1 + b.cwiseAbs().maxCoeff());
}

constexpr double kTol = 1e-12;
}  // namespace

TEST(CovarianceKernels, CombinationsEqualTheProduct)
{
	for (int rows : {1, 2, 3, 7, 8, 43, 86})
		for (int m : {0, 1, 3, 4, 5, 13})
		{
			const Eigen::MatrixXd X = randomMatrix(rows + 2, m, 10u * rows + m);
			const Eigen::VectorXd c = randomMatrix(m, 1, 7u * rows + m);
			const Eigen::VectorXd y0 = randomMatrix(rows + 1, 1, 3u * rows + m);
			Eigen::VectorXd y = y0;
			subtractCombination(y.head(rows), columns(X.data(), rows, m, X.outerStride()), c);
			const Eigen::VectorXd want = y0.head(rows) - X.topRows(rows) * c;
			EXPECT_LT(relativeGap(y.head(rows), want), kTol) << rows << " × " << m;
			EXPECT_EQ(y[rows], y0[rows]) << "an entry past the range was written";
			assignCombination(y.head(rows), X.topRows(rows), c);
			const Eigen::VectorXd product = X.topRows(rows) * c;
			EXPECT_LT(relativeGap(y.head(rows), product), kTol);
		}
}

TEST(CovarianceKernels, CholeskyColumnsEqualEigensFactorAndRefuseAnIndefiniteMatrix)
{
	for (int n : {1, 2, 5, 18, 23, 43})
	{
		const Covariance P = spd(n, 5u + n);
		const Eigen::MatrixXd want = P.llt().matrixL();
		Covariance L = Covariance::Constant(n, n, 7.0);  // rows above the diagonal must be zeroed
		const int split = n / 2;
		// In two calls, as the filter factors the nonlinear block first.
		ASSERT_TRUE(choleskyColumns(P, 0, split, L, n));
		ASSERT_TRUE(choleskyColumns(P, split, n, L, n));
		EXPECT_LT(relativeGap(L, want), kTol) << "n = " << n;
	}
	Covariance P = spd(9, 3);
	P(6, 6) = -1;
	Covariance L(9, 9);
	EXPECT_FALSE(choleskyColumns(P, 0, 9, L, 9));
	P(6, 6) = std::nan("");
	EXPECT_FALSE(choleskyColumns(P, 0, 9, L, 9));
}

TEST(CovarianceKernels, TriangularSolvesAgreeWithEigen)
{
	// Every solve form on the shapes the update (k ≤ 43 unknowns, m ≤ 6
	// right-hand sides) and the smoother (F: 23 × 23; the transport: n × 6)
	// use.
	for (int k : {1, 2, 3, 5, 8, 23, 43})
		for (int m : {1, 3, 4, 6})
		{
			const unsigned seed = static_cast<unsigned>(100 * k + m);
			const Eigen::MatrixXd Lf = lowerFactor(k, seed);
			const Eigen::MatrixXd L = Lf.topRows(k);
			const auto Ll = L.triangularView<Eigen::Lower>();
			const ConstColumnsMap L_map =
			    columns(static_cast<const double*>(Lf.data()), k, k, Lf.outerStride());
			const std::string where = "k " + std::to_string(k) + ", m " + std::to_string(m);

			// Left solves: B is k × m (stride k + 2).
			const Eigen::MatrixXd B0 = randomMatrix(k + 2, m, seed + 1);
			Eigen::MatrixXd B = B0;
			solveLeftLower(columns(B.data(), k, m, B.outerStride()), L_map);
			EXPECT_LT(relativeGap(B.topRows(k), Ll.solve(B0.topRows(k))), kTol) << where;
			EXPECT_TRUE(B.bottomRows(2) == B0.bottomRows(2)) << where << ": rows past k written";
			B = B0;
			solveLeftLowerTransposed(columns(B.data(), k, m, B.outerStride()), L_map);
			EXPECT_LT(relativeGap(B.topRows(k), Ll.transpose().solve(B0.topRows(k))), kTol) << where;
			EXPECT_TRUE(B.bottomRows(2) == B0.bottomRows(2)) << where << ": rows past k written";

			// Right solves: X is rows × k (stride rows + 1).
			const int rows = 2 * k + 11;
			const Eigen::MatrixXd X0 = randomMatrix(rows + 1, k, seed + 2);
			Eigen::MatrixXd X = X0;
			solveRightLowerTransposed(columns(X.data(), rows, k, X.outerStride()), L);
			EXPECT_LT(relativeGap(X.topRows(rows), Ll.transpose().solve<Eigen::OnTheRight>(X0.topRows(rows))),
			          kTol)
			    << where;
			EXPECT_TRUE(X.bottomRows(1) == X0.bottomRows(1)) << where << ": rows past `rows` written";
			X = X0;
			solveRightLower(columns(X.data(), rows, k, X.outerStride()), L);
			EXPECT_LT(relativeGap(X.topRows(rows), Ll.solve<Eigen::OnTheRight>(X0.topRows(rows))), kTol)
			    << where;
			EXPECT_TRUE(X.bottomRows(1) == X0.bottomRows(1)) << where << ": rows past `rows` written";
		}
}

TEST(CovarianceKernels, TriangularSolveBoundsAreSharp)
{
	// Each solve with one entry of L moved by 1e-8 (relative) is caught by
	// the bound the test above uses.
	const int k = 23, m = 3;
	const Eigen::MatrixXd Lf = lowerFactor(k, 7);
	Eigen::MatrixXd Lp = Lf;
	Lp(k - 1, 3) *= 1 + 1e-8;
	const auto Ll = Lf.topRows(k).triangularView<Eigen::Lower>();
	const ConstColumnsMap Lp_map = columns(static_cast<const double*>(Lp.data()), k, k, Lp.outerStride());
	const Eigen::MatrixXd Lp_square = Lp.topRows(k);
	auto beyond = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return relativeGap(a, b) > kTol; };
	const Eigen::MatrixXd B0 = randomMatrix(k, m, 8);
	Eigen::MatrixXd B = B0;
	solveLeftLower(columns(B.data(), k, m, k), Lp_map);
	EXPECT_TRUE(beyond(B, Ll.solve(B0)));
	B = B0;
	solveLeftLowerTransposed(columns(B.data(), k, m, k), Lp_map);
	EXPECT_TRUE(beyond(B, Ll.transpose().solve(B0)));
	const Eigen::MatrixXd X0 = randomMatrix(40, k, 9);
	Eigen::MatrixXd X = X0;
	solveRightLowerTransposed(columns(X.data(), 40, k, 40), Lp_square);
	EXPECT_TRUE(beyond(X, Ll.transpose().solve<Eigen::OnTheRight>(X0)));
	X = X0;
	solveRightLower(columns(X.data(), 40, k, 40), Lp_square);
	EXPECT_TRUE(beyond(X, Ll.solve<Eigen::OnTheRight>(X0)));
}

TEST(CovarianceKernels, DowndateIsTheProductAndExactlySymmetric)
{
	for (int n : {1, 2, 5, 23, 43})
		for (int m : {1, 3, 6, 9})
		{
			const Covariance P0 = spd(n, 11u * n + m);
			const Eigen::MatrixXd W = 0.2 * randomMatrix(n, m, 13u * n + m);
			Covariance P = P0;
			downdateSymmetric(P, W);
			const Eigen::MatrixXd want = P0 - W * W.transpose();
			EXPECT_LT(relativeGap(P, want), kTol) << n << " × " << m;
			EXPECT_TRUE((P.array() == P.transpose().array()).all()) << "not exactly symmetric";
		}
}

TEST(CovarianceKernels, MirrorLowerToUpperMakesTheBlockSymmetric)
{
	for (int n : {1, 2, 3, 4, 5, 8, 9, 23, 24})
	{
		const Eigen::MatrixXd A0 = randomMatrix(n + 3, n + 1, 17u + n);
		Eigen::MatrixXd A = A0;
		mirrorLowerToUpper(A.topLeftCorner(n, n));
		for (int j = 0; j < n + 1; ++j)
			for (int i = 0; i < n + 3; ++i)
			{
				const double want = (i < j && j < n) ? A0(j, i) : A0(i, j);
				EXPECT_EQ(A(i, j), want) << "n = " << n << ", entry (" << i << ", " << j << ")";
			}
	}
}

TEST(CovarianceKernels, LowerBlockGramSkipsOnlyZeros)
{
	constexpr int kp = 20, R = 14;
	const Eigen::Matrix<double, kp, R> X = randomMatrix(kp, R, 21);
	Eigen::Matrix<double, kp, R> Y = randomMatrix(kp, R, 22);
	// Columns [5, 12) of Y zero above a staircase (the prediction's shape).
	for (int c = 5; c < 12; ++c) Y.col(c).head(2 * (c - 5)).setZero();
	const Eigen::Matrix<double, kp, kp> want = X * Y.transpose();
	Eigen::Matrix<double, kp, kp> G;
	G.setConstant(std::nan(""));
	lowerBlockGram<kp, R>(X, Y, G, 5, 12);
	for (int jb = 0; jb < kp; jb += 4)
	{
		const auto blocks = G.middleCols<4>(jb).bottomRows(kp - jb);
		EXPECT_LT(relativeGap(blocks, want.middleCols<4>(jb).bottomRows(kp - jb)), kTol)
		    << "column block " << jb;
	}
	// A non-zero in the expected run is not skipped.
	Y(0, 8) = 1.5;
	const Eigen::Matrix<double, kp, kp> want2 = X * Y.transpose();
	lowerBlockGram<kp, R>(X, Y, G, 5, 12);
	EXPECT_LT(relativeGap(G.leftCols<4>(), want2.leftCols<4>()), kTol);
}

TEST(CovarianceKernels, PredictionBlocksEqualTheirDefinitions)
{
	for (int rows : {1, 3, 4, 18})
		for (int cols : {1, 2, 5, 25})
		{
			const int J = 6;
			const Eigen::MatrixXd Y0 = randomMatrix(rows + 1, cols, 31u * rows + cols);
			const Eigen::MatrixXd X = randomMatrix(rows, J, 32u * rows + cols);
			const Eigen::MatrixXd C = randomMatrix(cols + 2, J, 33u * rows + cols);  // stride cols + 2
			const Eigen::VectorXd scale = randomMatrix(cols, 1, 34u * rows + cols);
			Eigen::MatrixXd Y = Y0;
			addCombinationsThenScale(columns(Y.data(), rows, cols, Y.outerStride()), X,
			                         columns(C.data(), cols, J, C.outerStride()), scale);
			const Eigen::MatrixXd want =
			    (Y0.topRows(rows) + X * C.topRows(cols).transpose()) * scale.asDiagonal();
			EXPECT_LT(relativeGap(Y.topRows(rows), want), kTol) << rows << " × " << cols;
			EXPECT_TRUE(Y.bottomRows(1) == Y0.bottomRows(1));
		}
	for (int n : {1, 4, 25})
	{
		const Covariance B0 = spd(n, 40u + n);
		const Eigen::VectorXd a = randomMatrix(n, 1, 41u + n);
		Covariance B = B0;
		scaleByOuterProduct(B, a);
		EXPECT_LT(relativeGap(B, a.asDiagonal() * B0 * a.asDiagonal()), kTol);
		EXPECT_TRUE((B.array() == B.transpose().array()).all());
	}
}

template <int K>
void checkRightProduct(int rows)
{
	SCOPED_TRACE(testing::Message() << "K = " << K << ", rows = " << rows);
	const Eigen::MatrixXd X0 = randomMatrix(rows, K + 2, static_cast<unsigned>(97 * K + rows));
	const Eigen::MatrixXd F = randomMatrix(K, K, static_cast<unsigned>(98 * K + rows));
	const Eigen::MatrixXd want = X0.leftCols(K) * F.transpose();
	Eigen::MatrixXd X = X0;
	rightMultiplyTransposed<K>(columns(X.data(), rows, K + 2, X.outerStride()), F);
	EXPECT_LT(relativeGap(X.leftCols(K), want), kTol);
	EXPECT_TRUE(X.rightCols(2) == X0.rightCols(2)) << "columns past K were touched";
}

TEST(CovarianceKernels, InPlaceRightProductEqualsTheProduct)
{
	for (int rows : {1, 2, 3, 7, 8, 9, 15, 16, 17, 46, 86})
	{
		checkRightProduct<1>(rows);
		checkRightProduct<5>(rows);
		checkRightProduct<23>(rows);
	}
}

TEST(CovarianceKernels, FinitenessSeesEveryEntry)
{
	Eigen::VectorXd a = Eigen::VectorXd::LinSpaced(37, -3, 1e300);
	EXPECT_TRUE(allFiniteEntries(a.data(), a.size()));
	EXPECT_TRUE(allFiniteEntries(a.data(), 0));
	for (Eigen::Index i = 0; i < a.size(); ++i)
		for (double bad : {std::nan(""), std::numeric_limits<double>::infinity(),
		                   -std::numeric_limits<double>::infinity()})
		{
			Eigen::VectorXd b = a;
			b[i] = bad;
			EXPECT_FALSE(allFiniteEntries(b.data(), b.size())) << "entry " << i;
		}
}
}  // namespace auvnav::kernels
