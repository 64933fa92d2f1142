// The smoother's in-place product X_{:,0:K} ← X_{:,0:K} Fᵀ
// (rightMultiplyTransposed, libnav/src/column_kernels.h, private to the
// library: included here by path) against the column-axpy form it replaced,
// bit for bit on both paths, and against Eigen's product as an independent
// oracle.
#include "../../libnav/src/column_kernels.h"

#include <gtest/gtest.h>

#include <random>

namespace auvnav
{
namespace
{
struct Case
{
	Eigen::MatrixXd X;  // rows × (K + 2): the product touches only the first K columns
	Eigen::MatrixXd F;  // K × K
};

Case makeCase(int rows, int K, unsigned seed)
{
	std::mt19937 rng(seed);
	std::normal_distribution<double> normal;
	Case c{Eigen::MatrixXd(rows, K + 2), Eigen::MatrixXd(K, K)};
	for (Eigen::Index i = 0; i < c.X.size(); ++i) c.X.data()[i] = normal(rng);
	for (Eigen::Index i = 0; i < c.F.size(); ++i) c.F.data()[i] = normal(rng);
	return c;
}

/** Y = 0 − Σ_l X_l (−F(j, l)) column by column: what the smoother computed
 *  before, into a separate Y. */
Eigen::MatrixXd byColumnAxpys(const Case& c, int K)
{
	Eigen::MatrixXd Y(c.X.rows(), K);
	for (int j = 0; j < K; ++j)
		subtractAllColumns<false, true>(Y.col(j).data(), 0, c.X.rows(), c.X.data(), c.X.outerStride(), K,
		                                [&](Eigen::Index l) { return -c.F(j, l); });
	return Y;
}

template <int K>
void checkShape(int rows)
{
	SCOPED_TRACE(testing::Message() << "K = " << K << ", rows = " << rows);
	const Case c = makeCase(rows, K, static_cast<unsigned>(97 * K + rows));
	const Eigen::MatrixXd expected = byColumnAxpys(c, K);
	const Eigen::MatrixXd oracle = c.X.leftCols(K) * c.F.transpose();
	auto check = [&](const Eigen::MatrixXd& X, const char* path)
	{
		SCOPED_TRACE(path);
		EXPECT_TRUE((X.leftCols(K).array() == expected.array()).all())
		    << "largest difference " << (X.leftCols(K) - expected).cwiseAbs().maxCoeff();
		EXPECT_TRUE((X.rightCols(2).array() == c.X.rightCols(2).array()).all())
		    << "columns past K were touched";
		EXPECT_LT((X.leftCols(K) - oracle).cwiseAbs().maxCoeff(), 1e-12 * (1 + oracle.cwiseAbs().maxCoeff()));
	};
	Eigen::MatrixXd base = c.X;
	rightMultiplyTransposedBody<Pack2, K>(base.data(), rows, base.outerStride(), c.F.data());
	check(base, "baseline (SSE2 or scalar)");
#if AUVNAV_AVX_KERNELS
	if (detail::cpuHasAvx())
	{
		Eigen::MatrixXd wide = c.X;
		rightMultiplyTransposedAvx<K>(wide.data(), rows, wide.outerStride(), c.F.data());
		check(wide, "AVX");
	}
#endif
}

// Row counts past every panel boundary (8, 4, 2, 1), and K with each
// remainder of the groups of four and the blocks of three.
TEST(FilterKernels, InPlaceRightProductEqualsTheColumnAxpysBitForBit)
{
	for (int rows : {1, 2, 3, 4, 5, 6, 7, 8, 9, 13, 15, 86, 101})
	{
		checkShape<23>(rows);  // the smoother's k: 23 % 4 = 3, 23 % 3 = 2
		checkShape<7>(rows);   // 7 % 3 = 1
		checkShape<8>(rows);   // whole groups of four
		checkShape<1>(rows);
	}
}
}  // namespace
}  // namespace auvnav

namespace auvnav
{
namespace
{
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

Eigen::MatrixXd randomMatrix(int rows, int cols, unsigned seed)
{
	std::mt19937 rng(seed);
	std::normal_distribution<double> normal;
	Eigen::MatrixXd X(rows, cols);
	for (Eigen::Index i = 0; i < X.size(); ++i) X.data()[i] = normal(rng);
	return X;
}
}  // namespace

TEST(FilterKernels, TriangularSolvesAgreeWithEigen)
{
	// Every solve form on the shapes the update (k ≤ 43 unknowns, m ≤ 6
	// right-hand sides) and the smoother (F: 23 × 23; the transport: n × 6)
	// use, against Eigen's triangular solvers.
	for (int k : {1, 2, 3, 5, 8, 23, 43})
		for (int m : {1, 3, 4, 6})
		{
			const unsigned seed = static_cast<unsigned>(100 * k + m);
			const Eigen::MatrixXd Lf = lowerFactor(k, seed);
			const Eigen::MatrixXd L = Lf.topRows(k);
			const auto Ll = L.triangularView<Eigen::Lower>();
			auto at = [&](Eigen::Index i, Eigen::Index j) { return Lf(i, j); };
			const std::string where = "k " + std::to_string(k) + ", m " + std::to_string(m);

			// Left solves: B is k × m (stride k + 2).
			const Eigen::MatrixXd B0 = randomMatrix(k + 2, m, seed + 1);
			Eigen::MatrixXd B = B0;
			solveLeftLower(B.data(), k, B.outerStride(), m, Lf.data(), Lf.outerStride());
			const Eigen::MatrixXd fwd = Ll.solve(B0.topRows(k));
			EXPECT_LT((B.topRows(k) - fwd).cwiseAbs().maxCoeff(), 1e-12 * (1 + fwd.cwiseAbs().maxCoeff()))
			    << where;
			EXPECT_TRUE(B.bottomRows(2) == B0.bottomRows(2)) << where << ": rows past k written";
			B = B0;
			solveLeftLowerTransposed(B.data(), k, B.outerStride(), m, Lf.data(), Lf.outerStride());
			const Eigen::MatrixXd back = Ll.transpose().solve(B0.topRows(k));
			EXPECT_LT((B.topRows(k) - back).cwiseAbs().maxCoeff(), 1e-12 * (1 + back.cwiseAbs().maxCoeff()))
			    << where;
			EXPECT_TRUE(B.bottomRows(2) == B0.bottomRows(2)) << where << ": rows past k written";

			// Right solves: X is rows × k (stride rows + 1), rows past an
			// eight-row panel.
			const int rows = 2 * k + 11;
			const Eigen::MatrixXd X0 = randomMatrix(rows + 1, k, seed + 2);
			Eigen::MatrixXd X = X0;
			solveRightLowerTransposed(X.data(), rows, X.outerStride(), k, at);
			const Eigen::MatrixXd xlt = Ll.transpose().solve<Eigen::OnTheRight>(X0.topRows(rows));
			EXPECT_LT((X.topRows(rows) - xlt).cwiseAbs().maxCoeff(), 1e-12 * (1 + xlt.cwiseAbs().maxCoeff()))
			    << where;
			EXPECT_TRUE(X.bottomRows(1) == X0.bottomRows(1)) << where << ": rows past `rows` written";
			X = X0;
			solveRightLower(X.data(), rows, X.outerStride(), k, at);
			const Eigen::MatrixXd xl = Ll.solve<Eigen::OnTheRight>(X0.topRows(rows));
			EXPECT_LT((X.topRows(rows) - xl).cwiseAbs().maxCoeff(), 1e-12 * (1 + xl.cwiseAbs().maxCoeff()))
			    << where;
			EXPECT_TRUE(X.bottomRows(1) == X0.bottomRows(1)) << where << ": rows past `rows` written";
		}
}

TEST(FilterKernels, TriangularSolvesCanFail)
{
	// The bound above is sharp: each solve with one entry of L moved by
	// 1e-8 (relative) is caught by it.
	const int k = 23, m = 3;
	const Eigen::MatrixXd Lf = lowerFactor(k, 7);
	Eigen::MatrixXd Lp = Lf;
	Lp(k - 1, 3) *= 1 + 1e-8;
	const auto Ll = Lf.topRows(k).triangularView<Eigen::Lower>();
	auto beyond = [](const Eigen::MatrixXd& a, const Eigen::MatrixXd& b)
	{ return (a - b).cwiseAbs().maxCoeff() > 1e-12 * (1 + b.cwiseAbs().maxCoeff()); };
	const Eigen::MatrixXd B0 = randomMatrix(k, m, 8);
	Eigen::MatrixXd B = B0;
	solveLeftLower(B.data(), k, B.outerStride(), m, Lp.data(), Lp.outerStride());
	EXPECT_TRUE(beyond(B, Ll.solve(B0)));
	B = B0;
	solveLeftLowerTransposed(B.data(), k, B.outerStride(), m, Lp.data(), Lp.outerStride());
	EXPECT_TRUE(beyond(B, Ll.transpose().solve(B0)));
	auto at = [&](Eigen::Index i, Eigen::Index j) { return Lp(i, j); };
	const Eigen::MatrixXd X0 = randomMatrix(40, k, 9);
	Eigen::MatrixXd X = X0;
	solveRightLowerTransposed(X.data(), 40, X.outerStride(), k, at);
	EXPECT_TRUE(beyond(X, Ll.transpose().solve<Eigen::OnTheRight>(X0)));
	X = X0;
	solveRightLower(X.data(), 40, X.outerStride(), k, at);
	EXPECT_TRUE(beyond(X, Ll.solve<Eigen::OnTheRight>(X0)));
}
}  // namespace auvnav

namespace auvnav
{
namespace
{
/** Cholesky columns [from, to) over `rows` rows as ukf.cpp's baseline path
 *  forms them (a fused multiply-subtract per earlier column). */
bool columnPassCholesky(const Eigen::MatrixXd& P, int from, int to, Eigen::MatrixXd& L, int rows)
{
	return choleskyColumnsFused(P.data(), P.outerStride(), from, to, L.data(), L.outerStride(), rows);
}
}  // namespace

#if AUVNAV_AVX_KERNELS
// The register-held packets (choleskyColumnsAvx) take the baseline's fused
// operations entry by entry: equal bit for bit, for every remainder of the
// rows below the diagonal (masked last packets) and any number of earlier
// columns, for the filter's split (leading columns over all rows,
// the next over the first k only) and a start past column 0.
TEST(FilterKernels, PacketCholeskyEqualsTheColumnPassesBitForBit)
{
	if (!detail::cpuHasAvx()) GTEST_SKIP() << "this CPU has no AVX";
	for (int n : {1, 2, 3, 4, 5, 7, 9, 23, 43, 50})
	{
		const Eigen::MatrixXd A = randomMatrix(n, n + 2, static_cast<unsigned>(31 + n));
		const Eigen::MatrixXd P = A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
		for (int k : {n, std::max(1, n / 2 + 1)})
			for (int whole : {0, std::min(k, 3), k})
			{
				SCOPED_TRACE(testing::Message()
				             << "n = " << n << ", k = " << k << ", whole columns " << whole);
				Eigen::MatrixXd expected = Eigen::MatrixXd::Constant(n, n, 7.0), got = expected;
				ASSERT_TRUE(columnPassCholesky(P, 0, whole, expected, n));
				ASSERT_TRUE(columnPassCholesky(P, whole, k, expected, k));
				ASSERT_TRUE(choleskyColumnsAvx(P.data(), P.outerStride(), 0, whole, got.data(),
				                               got.outerStride(), n));
				ASSERT_TRUE(choleskyColumnsAvx(P.data(), P.outerStride(), whole, k, got.data(),
				                               got.outerStride(), k));
				// Every entry, the untouched ones (7) included: nothing is written past the rows asked for.
				EXPECT_TRUE((got.array() == expected.array()).all())
				    << "largest difference " << (got - expected).cwiseAbs().maxCoeff();
				// And it is the factor: L11 L11ᵀ = P11 over the first k.
				const Eigen::MatrixXd L11 = got.topLeftCorner(k, k).triangularView<Eigen::Lower>();
				EXPECT_LT((L11 * L11.transpose() - P.topLeftCorner(k, k)).cwiseAbs().maxCoeff(),
				          1e-12 * P.cwiseAbs().maxCoeff());
				// The rest of a full factor, started past column 0.
				if (k < n && whole == k)
				{
					Eigen::MatrixXd rest_expected = expected, rest_got = got;
					ASSERT_TRUE(columnPassCholesky(P, k, n, rest_expected, n));
					ASSERT_TRUE(choleskyColumnsAvx(P.data(), P.outerStride(), k, n, rest_got.data(),
					                               rest_got.outerStride(), n));
					EXPECT_TRUE((rest_got.array() == rest_expected.array()).all());
				}
			}
	}
}

// The tiled transposed copy against the entry-by-entry one, bit for bit,
// for every remainder of four in both directions, with room around the
// blocks (strides larger than the blocks) that must stay untouched.
TEST(FilterKernels, TransposedTilesEqualTheEntryCopyBitForBit)
{
	if (!detail::cpuHasAvx()) GTEST_SKIP() << "this CPU has no AVX";
	for (int rows : {0, 1, 3, 4, 5, 8, 20, 23})
		for (int cols : {0, 1, 2, 4, 7, 20, 23})
		{
			SCOPED_TRACE(testing::Message() << rows << " rows, " << cols << " columns");
			const Eigen::MatrixXd src = randomMatrix(rows + 3, cols + 1, 13u + rows * 31 + cols);
			Eigen::MatrixXd expected = Eigen::MatrixXd::Constant(cols + 2, rows + 2, 7.0), got = expected;
			copyTransposedByEntries(src.data(), src.outerStride(), rows, cols, expected.data(),
			                        expected.outerStride());
			copyTransposedAvx(src.data(), src.outerStride(), rows, cols, got.data(), got.outerStride());
			EXPECT_TRUE((got.array() == expected.array()).all());
			// And it is the transpose.
			EXPECT_TRUE(
			    (got.topLeftCorner(cols, rows).array() == src.topLeftCorner(rows, cols).transpose().array())
			        .all());
		}
}
#endif

// The mirror of a lower triangle: the upper one becomes its transpose, the
// lower one and everything past n stays, on whichever path this CPU runs.
TEST(FilterKernels, MirrorLowerToUpperMakesTheBlockSymmetric)
{
	for (int n : {1, 2, 3, 4, 5, 8, 9, 23, 24})
	{
		const Eigen::MatrixXd A0 = randomMatrix(n + 3, n + 1, 17u + n);
		Eigen::MatrixXd A = A0;
		mirrorLowerToUpper(A.data(), A.outerStride(), n);
		for (int j = 0; j < n + 1; ++j)
			for (int i = 0; i < n + 3; ++i)
			{
				const double want = (i < j && j < n) ? A0(j, i) : A0(i, j);
				EXPECT_EQ(A(i, j), want) << "n = " << n << ", entry (" << i << ", " << j << ")";
			}
	}
}

#if AUVNAV_AVX_KERNELS
// The prediction's cross block and affine block on the AVX path against
// their baselines (the filter's own, column_kernels.h), bit for bit, for row
// counts with every remainder of four.
TEST(FilterKernels, PredictionBlockKernelsEqualTheirLoopsBitForBit)
{
	if (!detail::cpuHasAvx()) GTEST_SKIP() << "this CPU has no AVX";
	for (int rows : {1, 2, 3, 4, 5, 23, 24})
		for (int cols : {1, 6, 20})
		{
			SCOPED_TRACE(testing::Message() << rows << " rows, " << cols << " columns");
			const int J = 6;
			const Eigen::MatrixXd Y0 = randomMatrix(rows, cols, 5u + rows),
			                      X = randomMatrix(rows, J, 7u + rows);
			const Eigen::MatrixXd coef =
			    randomMatrix(cols + 3, J, 11u + cols);  // coef(c, j), stride cols + 3
			const Eigen::VectorXd scale = Eigen::VectorXd::Random(cols);
			Eigen::MatrixXd expected = Y0, got = Y0;
			addColumnCombinationsByColumns(expected.data(), rows, expected.outerStride(), cols, X.data(),
			                               X.outerStride(), J, coef.data(), coef.outerStride(), scale.data());
			addColumnCombinationsAvx(got.data(), rows, got.outerStride(), cols, X.data(), X.outerStride(), J,
			                         coef.data(), coef.outerStride(), scale.data());
			EXPECT_TRUE((got.array() == expected.array()).all());

			const int n = rows;
			Eigen::MatrixXd B = randomMatrix(n + 2, n, 13u + n),
			                B_loop = B;  // an n × n block of a taller matrix
			const Eigen::VectorXd a = Eigen::VectorXd::Random(n);
			scaleByOuterProductByEntries(B_loop.data(), B_loop.outerStride(), n, a.data());
			scaleByOuterProductAvx(B.data(), B.outerStride(), n, a.data());
			EXPECT_TRUE((B.array() == B_loop.array()).all())
			    << "rows past the block must stay as they were too";
		}
}

// The Gram kernel's AVX path (two row blocks sharing Y's broadcasts, and
// each block column skipping the zeros it finds in Y's columns zero_from..
// zero_to: all of them in rows 0..3, a shorter run ending at zero_to in rows
// 4..7, a run broken by a NaN in rows 8..11) against the baseline kernel,
// bit for bit.
template <int kp, int R>
void checkGram(int zero_from, int zero_to)
{
	SCOPED_TRACE(testing::Message() << "kp " << kp << ", R " << R << ", zeros in columns " << zero_from
	                                << ".." << zero_to);
	Eigen::MatrixXd X = randomMatrix(kp, R, 3u + kp), Y = randomMatrix(kp, R, 5u + R);
	Y.block(0, zero_from, 4, zero_to - zero_from).setZero();
	const int half = (zero_from + zero_to) / 2;
	if (kp >= 8) Y.block(4, half, 4, zero_to - half).setZero();
	if (kp >= 12 && zero_to > zero_from)
	{
		Y.block(8, zero_from, 4, zero_to - zero_from).setZero();
		Y(9, half) = std::nan("");  // not zero: the skip stops there, and the NaN reaches the sums
	}
	Eigen::MatrixXd expected = Eigen::MatrixXd::Constant(kp, kp, 3.0), got = expected;
	lowerBlockGram<kp, R>(X.data(), Y.data(), expected.data());
	lowerBlockGramAvx<kp, R>(X.data(), Y.data(), got.data(), zero_from, zero_to);
	EXPECT_TRUE((got.array() == expected.array() || (got.array().isNaN() && expected.array().isNaN())).all())
	    << "largest difference " << (got - expected).cwiseAbs().maxCoeff();
	const Eigen::MatrixXd G = X * Y.transpose();
	for (int j = 0; j < kp; ++j)
		for (int i = j / 4 * 4; i < kp; ++i)
			if (std::isnan(G(i, j)))
				EXPECT_TRUE(std::isnan(got(i, j))) << "(" << i << ", " << j << ")";
			else
				EXPECT_NEAR(got(i, j), G(i, j), 1e-12 * (1 + std::abs(G(i, j))));
}

TEST(FilterKernels, GramBlocksEqualTheBaselineBitForBit)
{
	if (!detail::cpuHasAvx()) GTEST_SKIP() << "this CPU has no AVX";
	checkGram<24, 32>(13, 31);  // the prediction's shape and zeros
	checkGram<24, 32>(0, 0);
	checkGram<4, 5>(0, 0);   // one row block
	checkGram<8, 7>(2, 5);   // one pair
	checkGram<12, 9>(0, 9);  // a pair and a single block
	checkGram<20, 3>(1, 2);
}

TEST(FilterKernels, PacketCholeskyFailsWhereNotPositiveDefinite)
{
	if (!detail::cpuHasAvx()) GTEST_SKIP() << "this CPU has no AVX";
	Eigen::MatrixXd P = Eigen::MatrixXd::Identity(9, 9);
	P(6, 5) = P(5, 6) = 1.0;  // columns 5 and 6 equal there: singular at column 6
	Eigen::MatrixXd L = Eigen::MatrixXd::Zero(9, 9);
	EXPECT_TRUE(choleskyColumnsAvx(P.data(), 9, 0, 6, L.data(), 9, 9));
	EXPECT_FALSE(choleskyColumnsAvx(P.data(), 9, 6, 9, L.data(), 9, 9));
	P(6, 5) = P(5, 6) = 0.0;
	P(8, 8) = std::nan("");
	EXPECT_FALSE(choleskyColumnsAvx(P.data(), 9, 0, 9, L.data(), 9, 9));
}
#endif
}  // namespace auvnav
