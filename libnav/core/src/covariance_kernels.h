#pragma once
/** @file covariance_kernels.h
 *  The covariance kernels of the filter (ukf.cpp) and the smoother
 *  (smoother.cpp), private to the library: column combinations, a
 *  left-looking Cholesky, triangular solves with a few right-hand sides,
 *  the symmetric downdate P −= W Wᵀ, the lower blocks of a Gram matrix and
 *  the prediction's block operations.
 *
 *  Written as plain loops over contiguous columns and Eigen block
 *  expressions, with no intrinsics: the compiler vectorises them for
 *  whatever the build targets (SSE2 on the x86-64 baseline, AVX and FMA with
 *  AUVNAV_MARCH=x86-64-v3, NEON on aarch64). Whether a product and a sum are
 *  fused is the compiler's choice for the target: results agree with the
 *  dense reference to rounding, not bit for bit across targets (nor across
 *  CPUs, where the build dispatches, below).
 *
 *  The innermost loops (the passes and the Gram tile: leaves that call
 *  nothing) are marked AUVNAV_KERNEL_CLONES. In a build for the x86-64
 *  baseline (CMake's AUVNAV_CPU_DISPATCH) GCC compiles each of them for the
 *  baseline and for x86-64-v3 (AVX2, FMA), and the loader picks the one the
 *  CPU runs (target_clones). Leaves only: GCC inlines nothing into a
 *  function built for another -march, so a marked caller would still run
 *  its loops at the baseline. Elsewhere the mark is empty.
 *
 *  Contract shared by every kernel: pointers address column-major storage
 *  with the stride given; the ranges named are read or written, nothing
 *  else.
 */
#include <auvnav/ukf.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <type_traits>

#if defined(AUVNAV_CPU_CLONES) && AUVNAV_CPU_CLONES
#define AUVNAV_KERNEL_CLONES __attribute__((target_clones("default", "arch=x86-64-v3")))
#else
#define AUVNAV_KERNEL_CLONES
#endif

// Internal linkage: each including file gets its own copies, inlined where
// they are used, not exported from the library and called through its PLT.
namespace auvnav::kernels
{
namespace
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

namespace detail
{
/** f(std::integral_constant<int, width>) for a pass width of 1 to 4: the
 *  passes below take their column count as a template argument. */
template <typename F>
inline void withWidth(int width, F&& f)
{
	switch (width)
	{
		case 4:
			f(std::integral_constant<int, 4>{});
			break;
		case 3:
			f(std::integral_constant<int, 3>{});
			break;
		case 2:
			f(std::integral_constant<int, 2>{});
			break;
		default:
			f(std::integral_constant<int, 1>{});
			break;
	}
}

/** y[i] (=|+=) Σ_{c<C} a[c] x_c[i] for i < rows (x_c = X + c·xs): one pass
 *  over y for C ≤ 4 columns, y read and written once. A plain loop over
 *  contiguous arrays, which the compiler vectorises for the target: Eigen's
 *  expression evaluators, at these short and odd lengths, spent more
 *  spilling their state than computing. */
template <int C, bool kAssign>
AUVNAV_KERNEL_CLONES inline void combinationPass(double* __restrict y, const double* __restrict X,
                                                 Eigen::Index xs, Eigen::Index rows, const double* a)
{
	const double a0 = a[0], a1 = C > 1 ? a[1] : 0.0, a2 = C > 2 ? a[2] : 0.0, a3 = C > 3 ? a[3] : 0.0;
	const double* __restrict x0 = X;
	const double* __restrict x1 = X + (C > 1 ? xs : 0);
	const double* __restrict x2 = X + (C > 2 ? 2 * xs : 0);
	const double* __restrict x3 = X + (C > 3 ? 3 * xs : 0);
	for (Eigen::Index i = 0; i < rows; ++i)
	{
		double s = x0[i] * a0;
		if constexpr (C > 1) s += x1[i] * a1;
		if constexpr (C > 2) s += x2[i] * a2;
		if constexpr (C > 3) s += x3[i] * a3;
		y[i] = kAssign ? s : y[i] + s;
	}
}

/** y (=|+=) sign · X c over X's columns in passes of four. y: a contiguous
 *  vector; X: column-major with contiguous columns; c: any vector
 *  expression of X's column count. */
template <bool kAssign, typename Y, typename X, typename Coef>
inline void combination(Y& y, const X& x, const Coef& c, double sign)
{
	static_assert(!X::IsRowMajor, "combination: X must be column-major");
	eigen_assert(x.innerStride() == 1 && y.innerStride() == 1 && x.rows() == y.size() &&
	             c.size() == x.cols());
	const Eigen::Index m = x.cols(), rows = x.rows(), xs = x.outerStride();
	if (m == 0)
	{
		if constexpr (kAssign) y.setZero();
		return;
	}
	double* out = y.data();
	bool assign = kAssign;
	for (Eigen::Index l = 0; l < m; l += 4)
	{
		const int width = static_cast<int>(std::min<Eigen::Index>(4, m - l));
		double a[4] = {0, 0, 0, 0};
		for (int k = 0; k < width; ++k) a[k] = sign * c[l + k];
		const double* X_l = x.data() + l * xs;
		withWidth(width,
		          [&](auto w)
		          {
			          if (assign)
				          combinationPass<decltype(w)::value, true>(out, X_l, xs, rows, a);
			          else
				          combinationPass<decltype(w)::value, false>(out, X_l, xs, rows, a);
		          });
		assign = false;
	}
}
}  // namespace detail

/** y −= X c: the column combination Σ_l c_l X_l (X rows × m, c m). */
template <typename Y, typename X, typename C>
inline void subtractCombination(Y&& y, const X& x, const C& c)
{
	detail::combination<false>(y, x, c, -1.0);
}

/** y += X c. */
template <typename Y, typename X, typename C>
inline void addCombination(Y&& y, const X& x, const C& c)
{
	detail::combination<false>(y, x, c, 1.0);
}

/** y = X c. */
template <typename Y, typename X, typename C>
inline void assignCombination(Y&& y, const X& x, const C& c)
{
	detail::combination<true>(y, x, c, 1.0);
}

namespace detail
{
/** y0[i] −= Σ_{c<C} a[c] x_c[i], y1[i] −= Σ_{c<C} b[c] x_c[i] for i < rows
 *  (x_c = X + c·xs): two columns in one pass, each x_c[i] loaded once. */
template <int C>
AUVNAV_KERNEL_CLONES inline void pairSubtractPass(double* __restrict y0, double* __restrict y1,
                                                  const double* __restrict X, Eigen::Index xs,
                                                  Eigen::Index rows, const double* a, const double* b)
{
	double ac[4], bc[4];
	for (int c = 0; c < 4; ++c) ac[c] = c < C ? a[c] : 0.0, bc[c] = c < C ? b[c] : 0.0;
	const double* __restrict x0 = X;
	const double* __restrict x1 = X + (C > 1 ? xs : 0);
	const double* __restrict x2 = X + (C > 2 ? 2 * xs : 0);
	const double* __restrict x3 = X + (C > 3 ? 3 * xs : 0);
	for (Eigen::Index i = 0; i < rows; ++i)
	{
		double s0 = x0[i] * ac[0], s1 = x0[i] * bc[0];
		if constexpr (C > 1) s0 += x1[i] * ac[1], s1 += x1[i] * bc[1];
		if constexpr (C > 2) s0 += x2[i] * ac[2], s1 += x2[i] * bc[2];
		if constexpr (C > 3) s0 += x3[i] * ac[3], s1 += x3[i] * bc[3];
		y0[i] -= s0;
		y1[i] -= s1;
	}
}
}  // namespace detail

/** y0 −= X a and y1 −= X b in passes of four of X's columns (X rows × m,
 *  column-major with stride xs; a and b m entries each, at strides
 *  a_stride and b_stride). */
inline void subtractPairOfCombinations(double* y0, double* y1, const double* X, Eigen::Index xs,
                                       Eigen::Index rows, Eigen::Index m, const double* a,
                                       Eigen::Index a_stride, const double* b, Eigen::Index b_stride)
{
	for (Eigen::Index l = 0; l < m; l += 4)
	{
		const int width = static_cast<int>(std::min<Eigen::Index>(4, m - l));
		double al[4], bl[4];
		for (int k = 0; k < width; ++k) al[k] = a[(l + k) * a_stride], bl[k] = b[(l + k) * b_stride];
		const double* X_l = X + l * xs;
		detail::withWidth(width, [&](auto w)
		                  { detail::pairSubtractPass<decltype(w)::value>(y0, y1, X_l, xs, rows, al, bl); });
	}
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

/** A(j, i) = A(i, j) for i > j: the strictly upper triangle from the
 *  lower, four columns at a time: each row of the lower block column is
 *  stored as four entries of one column of the upper triangle. */
template <typename Square>
void mirrorLowerToUpper(Square&& A)
{
	const Eigen::Index n = A.cols(), as = A.outerStride();
	double* a = A.data();
	Eigen::Index jb = 0;
	for (; jb + 4 <= n; jb += 4)
	{
		const double* __restrict c0 = a + jb * as;
		const double* __restrict c1 = c0 + as;
		const double* __restrict c2 = c1 + as;
		const double* __restrict c3 = c2 + as;
		a[jb + (jb + 1) * as] = c0[jb + 1];
		a[jb + (jb + 2) * as] = c0[jb + 2];
		a[jb + 1 + (jb + 2) * as] = c1[jb + 2];
		a[jb + (jb + 3) * as] = c0[jb + 3];
		a[jb + 1 + (jb + 3) * as] = c1[jb + 3];
		a[jb + 2 + (jb + 3) * as] = c2[jb + 3];
		for (Eigen::Index i = jb + 4; i < n; ++i)
		{
			double* __restrict row = a + jb + i * as;
			row[0] = c0[i];
			row[1] = c1[i];
			row[2] = c2[i];
			row[3] = c3[i];
		}
	}
	for (; jb < n; ++jb)
		for (Eigen::Index i = jb + 1; i < n; ++i) a[jb + i * as] = a[i + jb * as];
}

/** P −= W Wᵀ for a symmetric P (n × n, W n × m), exactly symmetric after:
 *  the lower triangle two columns at a time (W's rows read once for both),
 *  then mirrored. */
inline void downdateSymmetric(Covariance& P, const Eigen::Ref<const Eigen::MatrixXd>& W)
{
	const Eigen::Index n = P.rows(), m = W.cols(), ps = P.outerStride(), ws = W.outerStride();
	double* p = P.data();
	const double* w = W.data();
	Eigen::Index j = 0;
	for (; j + 2 <= n; j += 2)
	{
		// Row j of column j; then rows j + 1… of both columns.
		P(j, j) -= W.row(j).squaredNorm();
		subtractPairOfCombinations(p + j + 1 + j * ps, p + j + 1 + (j + 1) * ps, w + j + 1, ws, n - j - 1, m,
		                           w + j, ws, w + j + 1, ws);
	}
	if (j < n) P(j, j) -= W.row(j).squaredNorm();
	mirrorLowerToUpper(P);
}

namespace detail
{
/** G's 4 × 4 block at rows ib, columns jb ← Σ_r X(ib.., r) Y(jb.., r)ᵀ over
 *  r in [0, from) and [zero_to, R) (X, Y column-major, `ld` rows): sixteen
 *  sums held in registers while X's and Y's columns stream past. */
template <typename Gram>
AUVNAV_KERNEL_CLONES inline void gramTile(const double* X, const double* Y, int ld, int R, int ib, int jb,
                                          int from, int zero_to, Gram& G)
{
	double acc[4][4] = {};
	auto term = [&](int r)
	{
		const double* x = X + ib + r * ld;
		const double* y = Y + jb + r * ld;
		for (int c = 0; c < 4; ++c)
			for (int i = 0; i < 4; ++i) acc[c][i] += x[i] * y[c];
	};
	for (int r = 0; r < from; ++r) term(r);
	for (int r = zero_to; r < R; ++r) term(r);
	for (int c = 0; c < 4; ++c)
		for (int i = 0; i < 4; ++i) G(ib + i, jb + c) = acc[c][i];
}
}  // namespace detail

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
		for (int ib = jb; ib < kp; ib += 4)
			detail::gramTile(X.data(), Y.data(), kp, R, ib, jb, from, zero_to, G);
	}
}

/** Y ← (Y + X Cᵀ) diag(scale): Y rows × cols, X rows × J, C cols × J. */
template <typename Xs, typename Cs, typename Scale>
void addCombinationsThenScale(ColumnsMap Y, const Xs& X, const Cs& C, const Scale& scale)
{
	for (Eigen::Index c = 0; c < Y.cols(); ++c)
	{
		addCombination(Y.col(c), X, C.row(c).transpose());
		Y.col(c) *= scale[c];
	}
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

}  // namespace
}  // namespace auvnav::kernels
