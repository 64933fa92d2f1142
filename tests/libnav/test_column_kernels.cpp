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
	Eigen::MatrixXd X;	// rows × (K + 2): the product touches only the first K columns
	Eigen::MatrixXd F;	// K × K
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
	auto check = [&](const Eigen::MatrixXd& X, const char* path) {
		SCOPED_TRACE(path);
		EXPECT_TRUE((X.leftCols(K).array() == expected.array()).all())
			<< "largest difference " << (X.leftCols(K) - expected).cwiseAbs().maxCoeff();
		EXPECT_TRUE((X.rightCols(2).array() == c.X.rightCols(2).array()).all()) << "columns past K were touched";
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
