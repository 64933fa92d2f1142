#pragma once
/** @file covariance_kernels.h
 *  The covariance kernels of the filter (ukf.cpp) and the smoother
 *  (smoother.cpp), private to the library: column combinations, a
 *  left-looking Cholesky, triangular solves with a few right-hand sides,
 *  the symmetric downdate P −= W Wᵀ, the lower blocks of a Gram matrix and
 *  the prediction's block operations.
 *
 *  Each is an Eigen expression over maps of the caller's column-major
 *  storage: lazy (coefficient-based) products, which Eigen vectorises down
 *  the rows with whatever vector unit the build targets (SSE2 on the
 *  x86-64 baseline, AVX and FMA with AUVNAV_MARCH=x86-64-v3, NEON on
 *  aarch64), without the packing and blocking set-up that its general
 *  products spend at these small, odd shapes. Whether a product and a sum
 *  are fused is the compiler's choice for the target: results agree with
 *  the dense reference to rounding, not bit for bit across targets.
 *
 *  Contract shared by every kernel: pointers address column-major storage
 *  with the stride given; the ranges named are read or written, nothing
 *  else.
 */
#include <auvnav/ukf.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace auvnav::kernels
{
using ColumnsMap = Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>>;
using ConstColumnsMap = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;
using VectorMap = Eigen::Map<Eigen::VectorXd>;

/** rows × cols at `data` with column stride `stride`. */
inline ColumnsMap columns(double* data, Eigen::Index rows, Eigen::Index cols, Eigen::Index stride)
{
	return ColumnsMap(data, rows, cols, Eigen::OuterStride<>(stride));
}
inline ConstColumnsMap columns(const double* data, Eigen::Index rows, Eigen::Index cols, Eigen::Index stride)
{
	return ConstColumnsMap(data, rows, cols, Eigen::OuterStride<>(stride));
}

/** y −= X c: the column combination Σ_l c_l X_l taken row by row, so that
 *  y is read and written once. */
template <typename Y, typename X, typename C>
inline void subtractCombination(Y&& y, const X& x, const C& c)
{
	y.noalias() -= x.lazyProduct(c);
}

/** y = X c. */
template <typename Y, typename X, typename C>
inline void assignCombination(Y&& y, const X& x, const C& c)
{
	y.noalias() = x.lazyProduct(c);
}

/** Columns [from, to) of the lower Cholesky factor of P over its first
 *  `rows` rows, the columns before `from` already in L over those rows;
 *  left-looking: column j is P's column less L's earlier columns weighted
 *  by L's row j, then scaled by its root. Rows above the diagonal are
 *  zeroed. False where P is not positive definite (columns partly written). */
inline bool choleskyColumns(const Covariance& P, Eigen::Index from, Eigen::Index to, Covariance& L,
                            Eigen::Index rows)
{
	for (Eigen::Index j = from; j < to; ++j)
	{
		const Eigen::Index len = rows - j;
		L.col(j).head(j).setZero();
		auto Lj = L.col(j).segment(j, len);
		Lj = P.col(j).segment(j, len);
		subtractCombination(Lj, L.block(j, 0, len, j), L.row(j).head(j).transpose());
		const double d = Lj[0];
		if (!(d > 0) || !std::isfinite(d)) return false;
		const double root = std::sqrt(d);
		Lj[0] = root;
		Lj.tail(len - 1) /= root;
	}
	return true;
}

/** X ← X L⁻ᵀ in place (solves X Lᵀ = Y, Y given in X; X rows × m, L's
 *  leading m × m block lower; L may be larger): forward over X's columns. */
template <typename Lower>
void solveRightLowerTransposed(ColumnsMap X, const Lower& L)
{
	for (Eigen::Index c = 0; c < X.cols(); ++c)
	{
		subtractCombination(X.col(c), X.leftCols(c), L.row(c).head(c).transpose());
		X.col(c) /= L(c, c);
	}
}

/** X ← X L⁻¹ in place (solves X L = Y; X rows × k, L's leading k × k
 *  block lower; L may be larger):
 *  backward over X's columns. */
template <typename Lower>
void solveRightLower(ColumnsMap X, const Lower& L)
{
	const Eigen::Index k = X.cols();
	for (Eigen::Index c = k - 1; c >= 0; --c)
	{
		const Eigen::Index below = k - 1 - c;
		subtractCombination(X.col(c), X.rightCols(below), L.col(c).segment(c + 1, below));
		X.col(c) /= L(c, c);
	}
}

/** B ← L⁻¹ B in place (forward substitution; B k × m, L's leading k × k
 *  block lower): per column of L, a rank-one update of the rows below. */
template <typename Lower>
void solveLeftLower(ColumnsMap B, const Lower& L)
{
	const Eigen::Index k = B.rows();
	for (Eigen::Index i = 0; i < k; ++i)
	{
		B.row(i) /= L(i, i);
		const Eigen::Index below = k - 1 - i;
		B.bottomRows(below).noalias() -= L.col(i).segment(i + 1, below) * B.row(i);
	}
}

/** B ← L⁻ᵀ B in place (back substitution; B k × m, L's leading k × k block
 *  lower): row i less L's column i below the diagonal times the rows below. */
template <typename Lower>
void solveLeftLowerTransposed(ColumnsMap B, const Lower& L)
{
	const Eigen::Index k = B.rows();
	for (Eigen::Index i = k - 1; i >= 0; --i)
	{
		const Eigen::Index below = k - 1 - i;
		B.row(i).noalias() -= L.col(i).segment(i + 1, below).transpose().lazyProduct(B.bottomRows(below));
		B.row(i) /= L(i, i);
	}
}

/** A(j, i) = A(i, j) for i > j: the strictly upper triangle from the lower. */
template <typename Square>
void mirrorLowerToUpper(Square&& A)
{
	for (Eigen::Index j = 0; j + 1 < A.cols(); ++j)
		A.row(j).tail(A.cols() - 1 - j) = A.col(j).tail(A.rows() - 1 - j).transpose();
}

/** P −= W Wᵀ for a symmetric P (n × n, W n × m), exactly symmetric after:
 *  the lower triangle column by column, then mirrored. */
inline void downdateSymmetric(Covariance& P, const Eigen::Ref<const Eigen::MatrixXd>& W)
{
	const Eigen::Index n = P.rows();
	for (Eigen::Index j = 0; j < n; ++j)
		subtractCombination(P.col(j).tail(n - j), W.bottomRows(n - j), W.row(j).transpose());
	mirrorLowerToUpper(P);
}

/** G = X Yᵀ on the blocks of four columns of G on and below its diagonal
 *  (G, X, Y kp × kp, kp × R, kp × R; above those blocks G is not written).
 *  Y's columns [zero_from, zero_to) are where the caller expects zeros: each
 *  block column leaves out the longest run of them that ends at zero_to and
 *  is zero in its four rows of Y (x · 0 adds nothing; a NaN is not zero). In
 *  the prediction those are the lumped pairs' J L_j, zero above the rows J
 *  reaches from L_j's diagonal on. */
template <int kp, int R>
void lowerBlockGram(const Eigen::Matrix<double, kp, R>& X, const Eigen::Matrix<double, kp, R>& Y,
                    Eigen::Matrix<double, kp, kp>& G, int zero_from = 0, int zero_to = 0)
{
	static_assert(kp % 4 == 0, "lowerBlockGram: kp must be a multiple of 4");
	for (int jb = 0; jb < kp; jb += 4)
	{
		int from = zero_to;
		while (from > zero_from && (Y.template block<4, 1>(jb, from - 1).array() == 0).all()) --from;
		const int below = kp - jb, after = R - zero_to;
		auto G_block = G.template middleCols<4>(jb).bottomRows(below);
		const auto X_rows = X.bottomRows(below);
		const auto Y_rows = Y.template middleRows<4>(jb);
		G_block.noalias() = X_rows.leftCols(from).lazyProduct(Y_rows.leftCols(from).transpose());
		G_block.noalias() += X_rows.rightCols(after).lazyProduct(Y_rows.rightCols(after).transpose());
	}
}

/** Y ← (Y + X Cᵀ) diag(scale): Y rows × cols, X rows × J, C cols × J. */
template <typename Xs, typename Cs, typename Scale>
void addCombinationsThenScale(ColumnsMap Y, const Xs& X, const Cs& C, const Scale& scale)
{
	Y.noalias() += X.lazyProduct(C.transpose());
	Y *= scale.asDiagonal();
}

/** B(i, j) ← B(i, j) · (a_i a_j): A B Aᵀ for a diagonal A = diag(a); a
 *  symmetric B stays exactly symmetric (a_i a_j = a_j a_i). */
template <typename Square, typename Factors>
void scaleByOuterProduct(Square&& B, const Factors& a)
{
	for (Eigen::Index j = 0; j < B.cols(); ++j) B.col(j).array() *= a.array() * a[j];
}

/** X's first K columns ← X_{:,0:K} Fᵀ in place (X rows × ≥ K, F K × K):
 *  panels of eight rows through a copy on the stack, then the last rows. */
template <int K, typename Square>
void rightMultiplyTransposed(ColumnsMap X, const Square& F)
{
	constexpr int kPanel = 8;
	const Eigen::Index rows = X.rows();
	Eigen::Index r = 0;
	for (; r + kPanel <= rows; r += kPanel)
	{
		const Eigen::Matrix<double, kPanel, K> panel = X.template block<kPanel, K>(r, 0);
		X.template block<kPanel, K>(r, 0).noalias() = panel.lazyProduct(F.transpose());
	}
	if (r < rows)
	{
		const Eigen::Matrix<double, Eigen::Dynamic, K, 0, kPanel, K> panel =
		    X.middleRows(r, rows - r).leftCols(K);
		X.middleRows(r, rows - r).leftCols(K).noalias() = panel.lazyProduct(F.transpose());
	}
}

/** Every one of the `count` contiguous entries at `a` finite (no NaN, no
 *  ±Inf): x · 0 is ±0 for a finite x and NaN otherwise, so their sum is 0
 *  exactly when all are (a vectorised sum, unlike a test per entry). */
inline bool allFiniteEntries(const double* a, Eigen::Index count)
{
	return count == 0 || (Eigen::Map<const Eigen::ArrayXd>(a, count) * 0.0).sum() == 0;
}

}  // namespace auvnav::kernels
