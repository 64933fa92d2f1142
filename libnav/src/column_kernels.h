#pragma once
/** @file column_kernels.h
 *  The covariance kernels of ukf.cpp and smoother.cpp (private to the
 *  library): y −= Σ_c coef_c X_c over up to four columns at once, the
 *  symmetric rank-m downdate P −= W Wᵀ written one triangle and mirrored,
 *  and the lower blocks of a Gram matrix X Yᵀ. They replace Eigen's
 *  products at these small, odd shapes, where Eigen's kernels cost more in
 *  set-up than in arithmetic and its packet width is fixed at compile time.
 *
 *  Three paths, the same arithmetic: every entry takes the same products
 *  summed in the same order, as separate IEEE multiplies and adds (never a
 *  fused multiply-add), so results are equal bit for bit whichever path ran:
 *   - 256-bit AVX packets, when the CPU has AVX (checked at run time, so the
 *     build keeps the x86-64 baseline); four rows per instruction;
 *   - 128-bit SSE2 packets (the baseline of x86-64);
 *   - a scalar loop elsewhere.
 *  The AVX kernels repeat the SSE2 step and the scalar tail for their last
 *  rows: calling the baseline kernels there instead was not inlined across
 *  the target attribute and cost ~5 k instructions an IMU tick.
 *
 *  wideKernels() says which path runs; setWideKernels() exists for the test
 *  that compares the paths (FilterKernels.AvxAndBaselinePathsAgreeBitForBit
 *  in tests/libnav/test_filter_vs_reference.cpp).
 */
#include <auvnav/ukf.h>

#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <type_traits>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define AUVNAV_AVX_KERNELS 1
#include <immintrin.h>
#else
#define AUVNAV_AVX_KERNELS 0
#endif
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace auvnav
{
namespace detail
{
/** Whether the CPU (and the OS, which must save the wide registers) has AVX
 *  and FMA (fused multiply-add; every x86-64 CPU with AVX2 has it): the wide
 *  path needs both, its kernels that fuse products and sums matching their
 *  baselines' std::fma. */
inline bool cpuHasAvx()
{
#if AUVNAV_AVX_KERNELS
	__builtin_cpu_init();
	return __builtin_cpu_supports("avx") && __builtin_cpu_supports("fma");
#else
	return false;
#endif
}
/** Whether the AVX path runs: on when the CPU has AVX (setWideKernels);
 *  one flag for every file of the library that includes this header. */
inline std::atomic<bool> g_wide_kernels{cpuHasAvx()};
}  // namespace detail

namespace
{
using detail::g_wide_kernels;

/** y[i] −= Σ_c coef[c] X[c·x_stride + i] for i in [from, to), C ≤ 4
 *  columns of X at once so that y is loaded and stored once; the sums
 *  associate as ((x₀a + x₁b) + x₂c) + x₃d. With kMirror each new y[i] is
 *  also stored at mirror[i·mirror_stride] (a symmetric matrix's other
 *  triangle). SSE2 packets where the compiler has them (it left these
 *  multi-stream loops scalar); the scalar loop is the same arithmetic. */
template <int C, bool kMirror = false, bool kAssign = false>
void subtractColumns(double* __restrict y, Eigen::Index from, Eigen::Index to, const double* __restrict X,
                     Eigen::Index x_stride, const double* coef, double* __restrict mirror = nullptr,
                     Eigen::Index mirror_stride = 0)
{
	const double* X0 = X;
	const double* X1 = C > 1 ? X + x_stride : X;
	const double* X2 = C > 2 ? X + 2 * x_stride : X;
	const double* X3 = C > 3 ? X + 3 * x_stride : X;
	Eigen::Index i = from;
#if defined(__SSE2__)
	const __m128d a = _mm_set1_pd(coef[0]);
	const __m128d b = _mm_set1_pd(C > 1 ? coef[1] : 0.0);
	const __m128d c = _mm_set1_pd(C > 2 ? coef[2] : 0.0);
	const __m128d d = _mm_set1_pd(C > 3 ? coef[3] : 0.0);
	for (; i + 2 <= to; i += 2)
	{
		__m128d s = _mm_mul_pd(_mm_loadu_pd(X0 + i), a);
		if constexpr (C > 1) s = _mm_add_pd(s, _mm_mul_pd(_mm_loadu_pd(X1 + i), b));
		if constexpr (C > 2) s = _mm_add_pd(s, _mm_mul_pd(_mm_loadu_pd(X2 + i), c));
		if constexpr (C > 3) s = _mm_add_pd(s, _mm_mul_pd(_mm_loadu_pd(X3 + i), d));
		const __m128d v = _mm_sub_pd(kAssign ? _mm_setzero_pd() : _mm_loadu_pd(y + i), s);
		_mm_storeu_pd(y + i, v);
		if constexpr (kMirror)
		{
			_mm_storel_pd(mirror + i * mirror_stride, v);
			_mm_storeh_pd(mirror + (i + 1) * mirror_stride, v);
		}
	}
#endif
	for (; i < to; ++i)
	{
		double s = X0[i] * coef[0];
		if constexpr (C > 1) s = s + X1[i] * coef[1];
		if constexpr (C > 2) s = s + X2[i] * coef[2];
		if constexpr (C > 3) s = s + X3[i] * coef[3];
		const double v = (kAssign ? 0.0 : y[i]) - s;
		y[i] = v;
		if constexpr (kMirror) mirror[i * mirror_stride] = v;
	}
}

#if AUVNAV_AVX_KERNELS
/** subtractColumns with four rows per packet (AVX, no FMA: the same
 *  arithmetic); the rows past the last whole packet as the scalar loop. */
template <int C, bool kMirror = false, bool kAssign = false>
__attribute__((target("avx"))) void subtractColumnsAvx(double* __restrict y, Eigen::Index from,
                                                       Eigen::Index to, const double* __restrict X,
                                                       Eigen::Index x_stride, const double* coef,
                                                       double* __restrict mirror = nullptr,
                                                       Eigen::Index mirror_stride = 0)
{
	const double* X0 = X;
	const double* X1 = C > 1 ? X + x_stride : X;
	const double* X2 = C > 2 ? X + 2 * x_stride : X;
	const double* X3 = C > 3 ? X + 3 * x_stride : X;
	Eigen::Index i = from;
	const __m256d a = _mm256_set1_pd(coef[0]);
	const __m256d b = _mm256_set1_pd(C > 1 ? coef[1] : 0.0);
	const __m256d c = _mm256_set1_pd(C > 2 ? coef[2] : 0.0);
	const __m256d d = _mm256_set1_pd(C > 3 ? coef[3] : 0.0);
	for (; i + 4 <= to; i += 4)
	{
		__m256d s = _mm256_mul_pd(_mm256_loadu_pd(X0 + i), a);
		if constexpr (C > 1) s = _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(X1 + i), b));
		if constexpr (C > 2) s = _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(X2 + i), c));
		if constexpr (C > 3) s = _mm256_add_pd(s, _mm256_mul_pd(_mm256_loadu_pd(X3 + i), d));
		const __m256d v = _mm256_sub_pd(kAssign ? _mm256_setzero_pd() : _mm256_loadu_pd(y + i), s);
		_mm256_storeu_pd(y + i, v);
		if constexpr (kMirror)
		{
			const __m128d lo = _mm256_castpd256_pd128(v), hi = _mm256_extractf128_pd(v, 1);
			_mm_storel_pd(mirror + i * mirror_stride, lo);
			_mm_storeh_pd(mirror + (i + 1) * mirror_stride, lo);
			_mm_storel_pd(mirror + (i + 2) * mirror_stride, hi);
			_mm_storeh_pd(mirror + (i + 3) * mirror_stride, hi);
		}
	}
	if (i + 2 <= to)  // two rows left: a 128-bit step, as the SSE2 path's
	{
		__m128d s2 = _mm_mul_pd(_mm_loadu_pd(X0 + i), _mm256_castpd256_pd128(a));
		if constexpr (C > 1) s2 = _mm_add_pd(s2, _mm_mul_pd(_mm_loadu_pd(X1 + i), _mm256_castpd256_pd128(b)));
		if constexpr (C > 2) s2 = _mm_add_pd(s2, _mm_mul_pd(_mm_loadu_pd(X2 + i), _mm256_castpd256_pd128(c)));
		if constexpr (C > 3) s2 = _mm_add_pd(s2, _mm_mul_pd(_mm_loadu_pd(X3 + i), _mm256_castpd256_pd128(d)));
		const __m128d v = _mm_sub_pd(kAssign ? _mm_setzero_pd() : _mm_loadu_pd(y + i), s2);
		_mm_storeu_pd(y + i, v);
		if constexpr (kMirror)
		{
			_mm_storel_pd(mirror + i * mirror_stride, v);
			_mm_storeh_pd(mirror + (i + 1) * mirror_stride, v);
		}
		i += 2;
	}
	for (; i < to; ++i)
	{
		double s = X0[i] * coef[0];
		if constexpr (C > 1) s = s + X1[i] * coef[1];
		if constexpr (C > 2) s = s + X2[i] * coef[2];
		if constexpr (C > 3) s = s + X3[i] * coef[3];
		const double v = (kAssign ? 0.0 : y[i]) - s;
		y[i] = v;
		if constexpr (kMirror) mirror[i * mirror_stride] = v;
	}
}
#endif

/** subtractColumns over m columns of X, in passes of four (then the rest).
 *  kAssign: y's old values are not read, y = 0 − Σ … (what a zeroed y
 *  would give, bit for bit, without the zeroing pass). */
template <bool kMirror = false, bool kAssign = false, typename Coef>
void subtractAllColumns(double* y, Eigen::Index from, Eigen::Index to, const double* X, Eigen::Index x_stride,
                        Eigen::Index m, Coef&& coef_of, double* mirror = nullptr,
                        Eigen::Index mirror_stride = 0)
{
#if AUVNAV_AVX_KERNELS
	const bool wide = g_wide_kernels.load(std::memory_order_relaxed);
#endif
	for (Eigen::Index l = 0; l < m; l += 4)
	{
		const Eigen::Index cnt = std::min<Eigen::Index>(4, m - l);
		double coef[4] = {0, 0, 0, 0};
		for (Eigen::Index c = 0; c < cnt; ++c) coef[c] = coef_of(l + c);
		const double* Xl = X + l * x_stride;
		auto pass = [&](auto assign)
		{
			constexpr bool kA = decltype(assign)::value;
#if AUVNAV_AVX_KERNELS
			if (wide)
			{
				switch (cnt)
				{
					case 4:
						subtractColumnsAvx<4, kMirror, kA>(y, from, to, Xl, x_stride, coef, mirror,
						                                   mirror_stride);
						break;
					case 3:
						subtractColumnsAvx<3, kMirror, kA>(y, from, to, Xl, x_stride, coef, mirror,
						                                   mirror_stride);
						break;
					case 2:
						subtractColumnsAvx<2, kMirror, kA>(y, from, to, Xl, x_stride, coef, mirror,
						                                   mirror_stride);
						break;
					default:
						subtractColumnsAvx<1, kMirror, kA>(y, from, to, Xl, x_stride, coef, mirror,
						                                   mirror_stride);
						break;
				}
				return;
			}
#endif
			switch (cnt)
			{
				case 4:
					subtractColumns<4, kMirror, kA>(y, from, to, Xl, x_stride, coef, mirror, mirror_stride);
					break;
				case 3:
					subtractColumns<3, kMirror, kA>(y, from, to, Xl, x_stride, coef, mirror, mirror_stride);
					break;
				case 2:
					subtractColumns<2, kMirror, kA>(y, from, to, Xl, x_stride, coef, mirror, mirror_stride);
					break;
				default:
					subtractColumns<1, kMirror, kA>(y, from, to, Xl, x_stride, coef, mirror, mirror_stride);
					break;
			}
		};
		if constexpr (kAssign)
		{
			if (l == 0)
				pass(std::true_type{});
			else
				pass(std::false_type{});
		}
		else
			pass(std::false_type{});
	}
	if (kAssign && m == 0)
		for (Eigen::Index i = from; i < to; ++i) y[i] = 0.0;
}

#if AUVNAV_AVX_KERNELS
/** Four rows at p, or (kPartial) only the lanes in `mask`, the others 0. */
template <bool kPartial>
__attribute__((target("avx"))) inline __m256d loadRowsAvx(const double* p, __m256i mask)
{
	if constexpr (kPartial)
		return _mm256_maskload_pd(p, mask);
	else
		return _mm256_loadu_pd(p);
}

/** The mask of a packet's first `lanes` rows (0..4), for masked loads and
 *  stores of a column's last rows. */
__attribute__((target("avx"))) inline __m256i firstLanesAvx(Eigen::Index lanes)
{
	alignas(32) static constexpr int64_t kLanes[8] = {-1, -1, -1, -1, 0, 0, 0, 0};
	return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kLanes + 4 - lanes));
}

/** Rows [r, r + 4) of Cholesky column j before its scaling: P's column
 *  less L_l L(j, l) for l = 0, 1, …, j − 1, each a fused multiply-subtract
 *  (one rounding), so each entry takes exactly the operations of
 *  choleskyColumnsFused (bit for bit). kPartial: only the lanes in `mask`
 *  are loaded (the column's last rows; nothing past them is read). */
template <bool kPartial>
__attribute__((target("avx,fma"))) inline __m256d choleskyBlockAvx(const double* Pj, const double* L,
                                                                   Eigen::Index ls, Eigen::Index j,
                                                                   Eigen::Index r, __m256i mask)
{
	auto load = [mask](const double* p) __attribute__((target("avx")))
	{
		return loadRowsAvx<kPartial>(p, mask);
	};
	__m256d acc = load(Pj + r);
	const double* Lr = L + r;    // rows r… of column 0
	const double* Lrow = L + j;  // row j of column 0
	for (Eigen::Index l = 0; l < j; ++l)
		acc = _mm256_fnmadd_pd(load(Lr + l * ls), _mm256_broadcast_sd(Lrow + l * ls), acc);
	return acc;
}

/** Y_c ← (Y_c + Σ_{j<J} coef[c + j·cs] X_j) · scale[c] for the columns
 *  c < cols of Y (rows × cols, stride ys; X rows × J, stride xs): the
 *  prediction's cross block, a J-column axpy per column then its decay.
 *  Each four-row packet of Y_c is held in a register over the J terms,
 *  each a fused multiply-add in j order, then scaled: the operations of
 *  the column axpys (std::fma), bit for bit. The last rows by masked loads
 *  and stores. */
__attribute__((target("avx,fma"))) inline void addColumnCombinationsAvx(double* Y, Eigen::Index rows,
                                                                        Eigen::Index ys, Eigen::Index cols,
                                                                        const double* X, Eigen::Index xs,
                                                                        Eigen::Index J, const double* coef,
                                                                        Eigen::Index cs, const double* scale)
{
	const Eigen::Index whole = rows / 4 * 4;
	const __m256i mask = firstLanesAvx(rows - whole);
	for (Eigen::Index c = 0; c < cols; ++c)
	{
		double* y = Y + c * ys;
		const double* cf = coef + c;
		const __m256d sc = _mm256_broadcast_sd(scale + c);
		for (Eigen::Index r = 0; r < whole; r += 4)
		{
			__m256d acc = _mm256_loadu_pd(y + r);
			for (Eigen::Index j = 0; j < J; ++j)
				acc = _mm256_fmadd_pd(_mm256_broadcast_sd(cf + j * cs), _mm256_loadu_pd(X + j * xs + r), acc);
			_mm256_storeu_pd(y + r, _mm256_mul_pd(acc, sc));
		}
		if (whole < rows)
		{
			__m256d acc = _mm256_maskload_pd(y + whole, mask);
			for (Eigen::Index j = 0; j < J; ++j)
				acc = _mm256_fmadd_pd(_mm256_broadcast_sd(cf + j * cs),
				                      _mm256_maskload_pd(X + j * xs + whole, mask), acc);
			_mm256_maskstore_pd(y + whole, mask, _mm256_mul_pd(acc, sc));
		}
	}
}

/** B(i, j) ← B(i, j) · (a[i] · a[j]) over a square n × n block (stride
 *  bs): A B Aᵀ for a diagonal A, four rows per packet (the scalar loop's
 *  operations, bit for bit), the last rows masked. */
__attribute__((target("avx"))) inline void scaleByOuterProductAvx(double* B, Eigen::Index bs, Eigen::Index n,
                                                                  const double* a)
{
	const Eigen::Index whole = n / 4 * 4;
	const __m256i mask = firstLanesAvx(n - whole);
	for (Eigen::Index j = 0; j < n; ++j)
	{
		double* col = B + j * bs;
		const __m256d aj = _mm256_broadcast_sd(a + j);
		for (Eigen::Index i = 0; i < whole; i += 4)
			_mm256_storeu_pd(
			    col + i, _mm256_mul_pd(_mm256_loadu_pd(col + i), _mm256_mul_pd(_mm256_loadu_pd(a + i), aj)));
		if (whole < n)
			_mm256_maskstore_pd(col + whole, mask,
			                    _mm256_mul_pd(_mm256_maskload_pd(col + whole, mask),
			                                  _mm256_mul_pd(_mm256_maskload_pd(a + whole, mask), aj)));
	}
}

/** choleskyBlockAvx for rows [r, r + 8) (two packets sharing the
 *  broadcasts of row j), no partial packet. */
__attribute__((target("avx,fma"))) inline void choleskyBlockPairAvx(const double* Pj, const double* L,
                                                                    Eigen::Index ls, Eigen::Index j,
                                                                    Eigen::Index r, __m256d& lo, __m256d& hi)
{
	lo = _mm256_loadu_pd(Pj + r);
	hi = _mm256_loadu_pd(Pj + r + 4);
	const double* Lr = L + r;    // rows r… of column 0
	const double* Lrow = L + j;  // row j of column 0
	for (Eigen::Index l = 0; l < j; ++l)
	{
		const __m256d c = _mm256_broadcast_sd(Lrow + l * ls);
		lo = _mm256_fnmadd_pd(_mm256_loadu_pd(Lr + l * ls), c, lo);
		hi = _mm256_fnmadd_pd(_mm256_loadu_pd(Lr + l * ls + 4), c, hi);
	}
}

/** Left-looking Cholesky columns [from, to) of P (stride ps) into L (stride
 *  ls), rows j… up to `rows` (the columns before `from` already in L over
 *  those rows; rows above the diagonal zeroed), four rows per packet with
 *  each packet kept in a register over all earlier columns (one fused
 *  multiply-subtract each), the last rows by masked loads and stores. The same operations per entry as
 *  choleskyColumnsFused (ukf.cpp's baseline), so the same bits; false
 *  where P is not positive definite (columns partly written). */
__attribute__((target("avx,fma"))) inline bool choleskyColumnsAvx(const double* P, Eigen::Index ps,
                                                                  Eigen::Index from, Eigen::Index to,
                                                                  double* L, Eigen::Index ls,
                                                                  Eigen::Index rows)
{
	for (Eigen::Index j = from; j < to; ++j)
	{
		double* Lj = L + j * ls;
		const double* Pj = P + j * ps;
		for (Eigen::Index i = 0; i < j; ++i) Lj[i] = 0.0;
		const Eigen::Index whole_end = j + (rows - j) / 4 * 4;
		const Eigen::Index left = rows - whole_end;  // 0..3 rows in a last, partial packet
		const __m256i mask = firstLanesAvx(left);
		// The packet holding the diagonal first: its root scales the rest.
		const __m256d first = whole_end > j ? choleskyBlockAvx<false>(Pj, L, ls, j, j, mask)
		                                    : choleskyBlockAvx<true>(Pj, L, ls, j, j, mask);
		const double d = _mm256_cvtsd_f64(first);
		if (!(d > 0) || !std::isfinite(d)) return false;
		const double root = std::sqrt(d);
		const __m256d div = _mm256_set1_pd(root);
		// Lane 0 is the root itself, the others divided by it.
		const __m256d scaled = _mm256_blend_pd(_mm256_div_pd(first, div), div, 0x1);
		if (whole_end > j)
			_mm256_storeu_pd(Lj + j, scaled);
		else
		{
			_mm256_maskstore_pd(Lj + j, mask, scaled);
			continue;
		}
		Eigen::Index r = j + 4;
		for (; r + 8 <= whole_end; r += 8)
		{
			__m256d lo, hi;
			choleskyBlockPairAvx(Pj, L, ls, j, r, lo, hi);
			_mm256_storeu_pd(Lj + r, _mm256_div_pd(lo, div));
			_mm256_storeu_pd(Lj + r + 4, _mm256_div_pd(hi, div));
		}
		if (r < whole_end)
			_mm256_storeu_pd(Lj + r, _mm256_div_pd(choleskyBlockAvx<false>(Pj, L, ls, j, r, mask), div));
		if (left > 0)
			_mm256_maskstore_pd(Lj + whole_end, mask,
			                    _mm256_div_pd(choleskyBlockAvx<true>(Pj, L, ls, j, whole_end, mask), div));
	}
	return true;
}
#endif

/** Left-looking Cholesky columns [from, to) of P (stride ps) into L (stride
 *  ls) over rows j… up to `rows`, the columns before `from` already in L
 *  over those rows; rows above the diagonal zeroed. Entry (i, j) is P(i, j)
 *  less L(i, l) L(j, l) for l = 0, 1, …, j − 1, each by std::fma (one
 *  rounding: a third fewer instructions on the AVX path than a product and
 *  a sum, and no less accurate), then the column's root and the division of
 *  the rest by it. False where P is not positive definite (columns partly
 *  written). The baseline path; choleskyColumnsAvx takes the same
 *  operations per entry. */
inline bool choleskyColumnsFused(const double* P, Eigen::Index ps, Eigen::Index from, Eigen::Index to,
                                 double* L, Eigen::Index ls, Eigen::Index rows)
{
	for (Eigen::Index j = from; j < to; ++j)
	{
		double* Lj = L + j * ls;
		for (Eigen::Index i = 0; i < j; ++i) Lj[i] = 0.0;
		for (Eigen::Index i = j; i < rows; ++i)
		{
			double acc = P[j * ps + i];
			for (Eigen::Index l = 0; l < j; ++l) acc = std::fma(-L[l * ls + i], L[l * ls + j], acc);
			Lj[i] = acc;
		}
		const double d = Lj[j];
		if (!(d > 0) || !std::isfinite(d)) return false;
		const double root = std::sqrt(d);
		Lj[j] = root;
		for (Eigen::Index i = j + 1; i < rows; ++i) Lj[i] /= root;
	}
	return true;
}

// Triangular solves for the small shapes of the update and the smoother
// (m ≤ ~6 right-hand sides, k ≤ 43 unknowns), where Eigen's blocked solvers
// spend more on packing than on arithmetic. L is lower triangular, read
// through `L(i, j)` (i ≥ j) or, for the dot-product forms, as a column-major
// array with its stride. Each form fixes its order of operations: callers
// that must stay bit for bit with an earlier build use the same form.

/** X ← X L⁻ᵀ in place, i.e. solves X Lᵀ = Y for X (Y given in X): rows
 *  [0, rows) of m columns (stride xs), L m × m. Forward over X's columns,
 *  column c less Σ_{l<c} L(c, l) X_l as column axpys, then divided by
 *  L(c, c). */
template <typename Lower>
void solveRightLowerTransposed(double* X, Eigen::Index rows, Eigen::Index xs, Eigen::Index m, const Lower& L)
{
	for (Eigen::Index c = 0; c < m; ++c)
	{
		double* Xc = X + c * xs;
		subtractAllColumns(Xc, 0, rows, X, xs, c, [&](Eigen::Index l) { return L(c, l); });
		const double d = L(c, c);
		for (Eigen::Index r = 0; r < rows; ++r) Xc[r] /= d;
	}
}

/** X ← X L⁻¹ in place, i.e. solves X L = Y (Y given in X): rows [0, rows)
 *  of k columns (stride xs), L k × k. Backward over X's columns, column c
 *  less Σ_{l>c} X_l L(l, c) as column axpys, then divided by L(c, c). */
template <typename Lower>
void solveRightLower(double* X, Eigen::Index rows, Eigen::Index xs, Eigen::Index k, const Lower& L)
{
	for (Eigen::Index c = k - 1; c >= 0; --c)
	{
		double* Xc = X + c * xs;
		subtractAllColumns(Xc, 0, rows, X + (c + 1) * xs, xs, k - 1 - c,
		                   [&](Eigen::Index l) { return L(c + 1 + l, c); });
		const double d = L(c, c);
		for (Eigen::Index r = 0; r < rows; ++r) Xc[r] /= d;
	}
}

/** B ← L⁻¹ B in place (forward substitution): k rows of m columns (stride
 *  bs), L k × k column-major with stride ls. Per column of L, an axpy of
 *  its part below the diagonal into every column of B. */
inline void solveLeftLower(double* B, Eigen::Index k, Eigen::Index bs, Eigen::Index m, const double* L,
                           Eigen::Index ls)
{
	for (Eigen::Index i = 0; i < k; ++i)
	{
		const double* Li = L + i * ls;
		for (Eigen::Index j = 0; j < m; ++j)
		{
			double* b = B + j * bs;
			b[i] /= Li[i];
			const double bi = b[i];
			for (Eigen::Index r = i + 1; r < k; ++r) b[r] -= Li[r] * bi;
		}
	}
}

/** B ← L⁻ᵀ B in place (back substitution): k rows of m columns (stride bs),
 *  L k × k column-major with stride ls. B(i, j) less the dot of L's column
 *  i below the diagonal with B's rows below i, then divided by L(i, i). The
 *  m columns side by side and four partial sums per dot: the entries of a
 *  column depend on each other in turn, and one running sum made each step
 *  wait for the one before. */
inline void solveLeftLowerTransposed(double* B, Eigen::Index k, Eigen::Index bs, Eigen::Index m,
                                     const double* L, Eigen::Index ls)
{
	for (Eigen::Index i = k - 1; i >= 0; --i)
	{
		const double* Li = L + i * ls + i + 1;
		const Eigen::Index len = k - 1 - i;
		for (Eigen::Index j = 0; j < m; ++j)
		{
			const double* b = B + j * bs + i + 1;
			double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
			Eigen::Index l = 0;
			for (; l + 4 <= len; l += 4)
			{
				s0 += Li[l] * b[l];
				s1 += Li[l + 1] * b[l + 1];
				s2 += Li[l + 2] * b[l + 2];
				s3 += Li[l + 3] * b[l + 3];
			}
			for (; l < len; ++l) s0 += Li[l] * b[l];
			B[j * bs + i] = (B[j * bs + i] - ((s0 + s1) + (s2 + s3))) / L[i * ls + i];
		}
	}
}

/** Columns j and j + 1 of a symmetric P less C columns of W (X, stride
 *  x_stride) times their rows j and j + 1 (a, b): rows j… of column j and
 *  j + 1… of column j + 1, each new entry also stored at its mirror. Each
 *  entry less x_c·a_c for c = 0, 1, … in turn, one fused multiply-subtract
 *  each (std::fma: one rounding; the AVX path's FMA instructions give the
 *  same numbers with a third fewer instructions than a product and a sum). */
template <int C>
void downdateColumnPair(double* __restrict P, Eigen::Index n, Eigen::Index j, const double* __restrict X,
                        Eigen::Index x_stride, const double* a, const double* b)
{
	double* __restrict P0 = P + j * n;
	double* __restrict P1 = P0 + n;
	auto less = [&](double v, const double* c, Eigen::Index i)
	{
		for (int k = 0; k < C; ++k) v = std::fma(-X[k * x_stride + i], c[k], v);
		return v;
	};
	P0[j] = less(P0[j], a, j);  // the diagonal of column j (its own mirror)
	for (Eigen::Index i = j + 1; i < n; ++i)
	{
		const double v0 = less(P0[i], a, i), v1 = less(P1[i], b, i);
		P0[i] = v0;
		P1[i] = v1;
		P[i * n + j] = v0;
		P[i * n + j + 1] = v1;
	}
}

#if AUVNAV_AVX_KERNELS
/** downdateColumnPair with four rows per packet (AVX and FMA). */
template <int C>
__attribute__((target("avx,fma"))) void downdateColumnPairAvx(double* __restrict P, Eigen::Index n,
                                                              Eigen::Index j, const double* __restrict X,
                                                              Eigen::Index x_stride, const double* a,
                                                              const double* b)
{
	double* __restrict P0 = P + j * n;
	double* __restrict P1 = P0 + n;
	auto less = [&](double v, const double* c, Eigen::Index i) __attribute__((target("avx,fma")))
	{
		for (int k = 0; k < C; ++k) v = std::fma(-X[k * x_stride + i], c[k], v);
		return v;
	};
	P0[j] = less(P0[j], a, j);
	Eigen::Index i = j + 1;
	__m256d ca[4], cb[4];
	for (int c = 0; c < C; ++c)
	{
		ca[c] = _mm256_set1_pd(a[c]);
		cb[c] = _mm256_set1_pd(b[c]);
	}
	for (; i + 4 <= n; i += 4)
	{
		__m256d v0 = _mm256_loadu_pd(P0 + i), v1 = _mm256_loadu_pd(P1 + i);
		for (int c = 0; c < C; ++c)
		{
			const __m256d x = _mm256_loadu_pd(X + c * x_stride + i);
			v0 = _mm256_fnmadd_pd(x, ca[c], v0);
			v1 = _mm256_fnmadd_pd(x, cb[c], v1);
		}
		_mm256_storeu_pd(P0 + i, v0);
		_mm256_storeu_pd(P1 + i, v1);
		// Mirrors: rows i…i+3 of columns j, j+1 are the adjacent pairs
		// (j, j+1) of columns i…i+3. unpacklo/hi work within 128-bit lanes:
		// lo = (v0₀, v1₀ | v0₂, v1₂), hi = (v0₁, v1₁ | v0₃, v1₃).
		const __m256d lo = _mm256_unpacklo_pd(v0, v1), hi = _mm256_unpackhi_pd(v0, v1);
		_mm_storeu_pd(P + i * n + j, _mm256_castpd256_pd128(lo));
		_mm_storeu_pd(P + (i + 1) * n + j, _mm256_castpd256_pd128(hi));
		_mm_storeu_pd(P + (i + 2) * n + j, _mm256_extractf128_pd(lo, 1));
		_mm_storeu_pd(P + (i + 3) * n + j, _mm256_extractf128_pd(hi, 1));
	}
	if (i + 2 <= n)  // two rows left: a 128-bit step
	{
		__m128d v0 = _mm_loadu_pd(P0 + i), v1 = _mm_loadu_pd(P1 + i);
		for (int c = 0; c < C; ++c)
		{
			const __m128d x = _mm_loadu_pd(X + c * x_stride + i);
			v0 = _mm_fnmadd_pd(x, _mm256_castpd256_pd128(ca[c]), v0);
			v1 = _mm_fnmadd_pd(x, _mm256_castpd256_pd128(cb[c]), v1);
		}
		_mm_storeu_pd(P0 + i, v0);
		_mm_storeu_pd(P1 + i, v1);
		_mm_storeu_pd(P + i * n + j, _mm_unpacklo_pd(v0, v1));
		_mm_storeu_pd(P + (i + 1) * n + j, _mm_unpackhi_pd(v0, v1));
		i += 2;
	}
	for (; i < n; ++i)
	{
		const double v0 = less(P0[i], a, i), v1 = less(P1[i], b, i);
		P0[i] = v0;
		P1[i] = v1;
		P[i * n + j] = v0;
		P[i * n + j + 1] = v1;
	}
}

/** downdateColumnPairAvx over every column pair (0, 1), (2, 3), … of P for
 *  C columns of W (X, stride x_stride): one call per group of columns, not
 *  per pair, with the pairs' coefficients read here. */
template <int C>
__attribute__((target("avx,fma"))) void downdateAllPairsAvx(double* __restrict P, Eigen::Index n,
                                                            const double* __restrict X, Eigen::Index x_stride)
{
	for (Eigen::Index j = 0; j + 2 <= n; j += 2)
	{
		double a[4], b[4];
		for (int c = 0; c < C; ++c)
		{
			a[c] = X[c * x_stride + j];
			b[c] = X[c * x_stride + j + 1];
		}
		downdateColumnPairAvx<C>(P, n, j, X, x_stride, a, b);
	}
}
#endif

/** G(i, j) = Σ_r X(i, r) Y(j, r) on the 4 × 4 blocks of G on and below its
 *  diagonal (blocks above it are not written). G, X and Y are column-major
 *  with leading dimension kp, a multiple of 4; X and Y have R columns. Each
 *  entry is summed in the order r = 0, 1, … from zero, one fused
 *  multiply-add a term (one rounding: std::fma here, the FMA instruction
 *  on the AVX path, the same numbers), on every path; the AVX path keeps a
 *  4 × 4 block in registers (a load of X and four broadcasts of Y per r:
 *  the Gram matrix of the prediction's sigma-point deviations, which dot
 *  products took 2.5 times the instructions for; a multiply and an add a
 *  term took a third more than the fused form). */
template <int kp, int R>
void lowerBlockGram(const double* __restrict X, const double* __restrict Y, double* __restrict G)
{
	static_assert(kp % 4 == 0, "lowerBlockGram: kp must be a multiple of 4");
	for (int jb = 0; jb < kp; jb += 4)
		for (int ib = jb; ib < kp; ib += 4)
			for (int c = 0; c < 4; ++c)
				for (int i = ib; i < ib + 4; ++i)
				{
					double acc = 0;
					for (int r = 0; r < R; ++r) acc = std::fma(X[r * kp + i], Y[r * kp + jb + c], acc);
					G[(jb + c) * kp + i] = acc;
				}
}

#if AUVNAV_AVX_KERNELS
/** Blocks (ib, jb) and, with kTwo, (ib + 4, jb) of lowerBlockGramAvx: eight
 *  accumulators sharing Y's four broadcasts per r. Y's columns [skip_from,
 *  skip_to) are skipped: the caller's zeros in these rows of Y (a term
 *  x · 0 added to a sum leaves it as it is). */
template <int kp, int R, bool kTwo>
__attribute__((target("avx,fma"))) inline void gramBlocksAvx(const double* __restrict X,
                                                             const double* __restrict Y, double* __restrict G,
                                                             int ib, int jb, int skip_from, int skip_to)
{
	__m256d a0 = _mm256_setzero_pd(), a1 = a0, a2 = a0, a3 = a0, b0 = a0, b1 = a0, b2 = a0, b3 = a0;
	auto step = [&](int r) __attribute__((target("avx,fma")))
	{
		const double* y = Y + r * kp + jb;
		const __m256d y0 = _mm256_broadcast_sd(y), y1 = _mm256_broadcast_sd(y + 1),
		              y2 = _mm256_broadcast_sd(y + 2), y3 = _mm256_broadcast_sd(y + 3);
		const __m256d x = _mm256_loadu_pd(X + r * kp + ib);
		a0 = _mm256_fmadd_pd(x, y0, a0);
		a1 = _mm256_fmadd_pd(x, y1, a1);
		a2 = _mm256_fmadd_pd(x, y2, a2);
		a3 = _mm256_fmadd_pd(x, y3, a3);
		if constexpr (kTwo)
		{
			const __m256d x2 = _mm256_loadu_pd(X + r * kp + ib + 4);
			b0 = _mm256_fmadd_pd(x2, y0, b0);
			b1 = _mm256_fmadd_pd(x2, y1, b1);
			b2 = _mm256_fmadd_pd(x2, y2, b2);
			b3 = _mm256_fmadd_pd(x2, y3, b3);
		}
	};
	for (int r = 0; r < skip_from; ++r) step(r);
	for (int r = skip_to; r < R; ++r) step(r);
	_mm256_storeu_pd(G + jb * kp + ib, a0);
	_mm256_storeu_pd(G + (jb + 1) * kp + ib, a1);
	_mm256_storeu_pd(G + (jb + 2) * kp + ib, a2);
	_mm256_storeu_pd(G + (jb + 3) * kp + ib, a3);
	if constexpr (kTwo)
	{
		_mm256_storeu_pd(G + jb * kp + ib + 4, b0);
		_mm256_storeu_pd(G + (jb + 1) * kp + ib + 4, b1);
		_mm256_storeu_pd(G + (jb + 2) * kp + ib + 4, b2);
		_mm256_storeu_pd(G + (jb + 3) * kp + ib + 4, b3);
	}
}

/** lowerBlockGram with 4 × 4 blocks in AVX registers, two row blocks at a
 *  time where there are two (Y's broadcasts shared). Y's columns in
 *  [zero_from, zero_to) are where the caller expects zeros: each block
 *  column skips the longest run of them that ends at zero_to and is zero in
 *  its four rows of Y (the sums are the same; a NaN is not zero). In the
 *  prediction those are the lumped pairs' J L_j, zero above the rows J
 *  reaches from L_j's diagonal on: the skips save a quarter of the terms. */
template <int kp, int R>
__attribute__((target("avx,fma"))) void lowerBlockGramAvx(const double* __restrict X,
                                                          const double* __restrict Y, double* __restrict G,
                                                          int zero_from = 0, int zero_to = 0)
{
	static_assert(kp % 4 == 0, "lowerBlockGram: kp must be a multiple of 4");
	const __m256d zero = _mm256_setzero_pd();
	for (int jb = 0; jb < kp; jb += 4)
	{
		int from = zero_to;
		while (from > zero_from && _mm256_movemask_pd(_mm256_cmp_pd(_mm256_loadu_pd(Y + (from - 1) * kp + jb),
		                                                            zero, _CMP_NEQ_UQ)) == 0)
			--from;
		int ib = jb;
		for (; ib + 8 <= kp; ib += 8) gramBlocksAvx<kp, R, true>(X, Y, G, ib, jb, from, zero_to);
		if (ib < kp) gramBlocksAvx<kp, R, false>(X, Y, G, ib, jb, from, zero_to);
	}
}
#endif

/** lowerBlockGram on the AVX path where the CPU has it. */
template <int kp, int R>
void lowerBlockGramDispatch(const double* X, const double* Y, double* G, int zero_from = 0, int zero_to = 0)
{
#if AUVNAV_AVX_KERNELS
	if (g_wide_kernels.load(std::memory_order_relaxed))
		return lowerBlockGramAvx<kp, R>(X, Y, G, zero_from, zero_to);
#endif
	lowerBlockGram<kp, R>(X, Y, G);
}

/** addColumnCombinationsAvx's baseline, column by column: Y_c ← (Y_c +
 *  Σ_{j<J} coef[c + j·cs] X_j) · scale[c], a fused axpy per term in j order
 *  then the scaling (entry by entry the same operations as the packets). */
inline void addColumnCombinationsByColumns(double* Y, Eigen::Index rows, Eigen::Index ys, Eigen::Index cols,
                                           const double* X, Eigen::Index xs, Eigen::Index J,
                                           const double* coef, Eigen::Index cs, const double* scale)
{
	for (Eigen::Index c = 0; c < cols; ++c)
	{
		double* y = Y + c * ys;
		for (Eigen::Index j = 0; j < J; ++j)
		{
			const double w = coef[c + j * cs];
			const double* x = X + j * xs;
			for (Eigen::Index i = 0; i < rows; ++i) y[i] = std::fma(w, x[i], y[i]);
		}
		for (Eigen::Index i = 0; i < rows; ++i) y[i] *= scale[c];
	}
}

/** scaleByOuterProductAvx's baseline: B(i, j) ← B(i, j) · (a[i] · a[j]). */
inline void scaleByOuterProductByEntries(double* B, Eigen::Index bs, Eigen::Index n, const double* a)
{
	for (Eigen::Index j = 0; j < n; ++j)
	{
		double* col = B + j * bs;
		const double aj = a[j];
		for (Eigen::Index i = 0; i < n; ++i) col[i] *= a[i] * aj;
	}
}

/** addColumnCombinationsByColumns on the AVX path where the CPU has it. */
inline void addColumnCombinations(double* Y, Eigen::Index rows, Eigen::Index ys, Eigen::Index cols,
                                  const double* X, Eigen::Index xs, Eigen::Index J, const double* coef,
                                  Eigen::Index cs, const double* scale)
{
#if AUVNAV_AVX_KERNELS
	if (g_wide_kernels.load(std::memory_order_relaxed))
		return addColumnCombinationsAvx(Y, rows, ys, cols, X, xs, J, coef, cs, scale);
#endif
	addColumnCombinationsByColumns(Y, rows, ys, cols, X, xs, J, coef, cs, scale);
}

/** scaleByOuterProductByEntries on the AVX path where the CPU has it. */
inline void scaleByOuterProduct(double* B, Eigen::Index bs, Eigen::Index n, const double* a)
{
#if AUVNAV_AVX_KERNELS
	if (g_wide_kernels.load(std::memory_order_relaxed)) return scaleByOuterProductAvx(B, bs, n, a);
#endif
	scaleByOuterProductByEntries(B, bs, n, a);
}

/** dst(j, i) = src(i, j) for i < rows, j < cols (column-major, leading
 *  dimensions ss and ds; the two blocks do not overlap): a transposed copy,
 *  one entry at a time. The baseline of copyTransposedAvx. */
inline void copyTransposedByEntries(const double* __restrict src, Eigen::Index ss, Eigen::Index rows,
                                    Eigen::Index cols, double* __restrict dst, Eigen::Index ds)
{
	for (Eigen::Index j = 0; j < cols; ++j)
		for (Eigen::Index i = 0; i < rows; ++i) dst[i * ds + j] = src[j * ss + i];
}

#if AUVNAV_AVX_KERNELS
/** One 4 × 4 tile of copyTransposedAvx: rows i.. of columns j..j+3 of src
 *  (masked loads of the first `lanes` rows when kPartial, nothing read past
 *  them) into columns i.. of dst, rows j..j+3 (`lanes` columns stored). */
template <bool kPartial>
__attribute__((target("avx"))) inline void transposedTileAvx(const double* s, Eigen::Index ss, double* d,
                                                             Eigen::Index ds, Eigen::Index lanes)
{
	const __m256i mask = kPartial ? firstLanesAvx(lanes) : _mm256_setzero_si256();
	const __m256d c0 = loadRowsAvx<kPartial>(s, mask), c1 = loadRowsAvx<kPartial>(s + ss, mask),
	              c2 = loadRowsAvx<kPartial>(s + 2 * ss, mask), c3 = loadRowsAvx<kPartial>(s + 3 * ss, mask);
	const __m256d lo01 = _mm256_unpacklo_pd(c0, c1), hi01 = _mm256_unpackhi_pd(c0, c1),
	              lo23 = _mm256_unpacklo_pd(c2, c3), hi23 = _mm256_unpackhi_pd(c2, c3);
	_mm256_storeu_pd(d, _mm256_permute2f128_pd(lo01, lo23, 0x20));  // row i of src
	if (kPartial && lanes < 2) return;
	_mm256_storeu_pd(d + ds, _mm256_permute2f128_pd(hi01, hi23, 0x20));
	if (kPartial && lanes < 3) return;
	_mm256_storeu_pd(d + 2 * ds, _mm256_permute2f128_pd(lo01, lo23, 0x31));
	if (kPartial && lanes < 4) return;
	_mm256_storeu_pd(d + 3 * ds, _mm256_permute2f128_pd(hi01, hi23, 0x31));
}

/** copyTransposedByEntries by 4 × 4 tiles through registers (four column
 *  loads, two unpacks and two lane swaps each, four column stores) instead
 *  of a strided access per entry; the last rows by a masked tile, the last
 *  columns entry by entry. Copies only: the same bits. */
__attribute__((target("avx"))) inline void copyTransposedAvx(const double* __restrict src, Eigen::Index ss,
                                                             Eigen::Index rows, Eigen::Index cols,
                                                             double* __restrict dst, Eigen::Index ds)
{
	Eigen::Index j = 0;
	for (; j + 4 <= cols; j += 4)
	{
		Eigen::Index i = 0;
		for (; i + 4 <= rows; i += 4) transposedTileAvx<false>(src + j * ss + i, ss, dst + i * ds + j, ds, 4);
		if (i < rows) transposedTileAvx<true>(src + j * ss + i, ss, dst + i * ds + j, ds, rows - i);
	}
	copyTransposedByEntries(src + j * ss, ss, rows, cols - j, dst + j, ds);
}
#endif

/** copyTransposedByEntries on the AVX path where the CPU has it. */
inline void copyTransposed(const double* src, Eigen::Index ss, Eigen::Index rows, Eigen::Index cols,
                           double* dst, Eigen::Index ds)
{
#if AUVNAV_AVX_KERNELS
	if (g_wide_kernels.load(std::memory_order_relaxed))
		return copyTransposedAvx(src, ss, rows, cols, dst, ds);
#endif
	copyTransposedByEntries(src, ss, rows, cols, dst, ds);
}

/** A(j, i) = A(i, j) for i > j < n (column-major, leading dimension as):
 *  the strictly upper triangle from the lower one. Tiles of four columns:
 *  inside a diagonal tile entry by entry, below it by copyTransposed. */
inline void mirrorLowerToUpper(double* A, Eigen::Index as, Eigen::Index n)
{
	for (Eigen::Index jb = 0; jb < n; jb += 4)
	{
		const Eigen::Index w = std::min<Eigen::Index>(4, n - jb);
		for (Eigen::Index j = jb; j < jb + w; ++j)
			for (Eigen::Index i = j + 1; i < jb + w; ++i) A[i * as + j] = A[j * as + i];
		if (jb + w < n) copyTransposed(A + jb * as + jb + w, as, n - jb - w, w, A + (jb + w) * as + jb, as);
	}
}

/** P −= W Wᵀ for a symmetric P, exactly symmetric after: column j's rows
 *  j… are computed and each entry stored at its mirror too (one triangle's
 *  arithmetic with no separate mirroring pass, whose strided loads cost
 *  what the triangle saved), two columns of P at a time sharing the loads
 *  of W. Entry (i, j) is P(i, j) less W(i, l) W(j, l) for l = 0, 1, … in
 *  turn, one fused multiply-subtract each, on either path (the same bits). */
inline void downdateSymmetric(Covariance& P, const Eigen::Ref<const Eigen::MatrixXd>& W)
{
	const Eigen::Index n = P.rows(), m = W.cols(), ws = W.outerStride();
	double* p = P.data();
	Eigen::Index j = 0;
#if AUVNAV_AVX_KERNELS
	// Group by group of W's columns, every pair of P's columns in one call
	// (each entry still takes the groups in order: the same sums).
	if (g_wide_kernels.load(std::memory_order_relaxed))
	{
		for (Eigen::Index l = 0; l < m; l += 4)
		{
			const double* Wl = W.data() + l * ws;
			switch (std::min<Eigen::Index>(4, m - l))
			{
				case 4:
					downdateAllPairsAvx<4>(p, n, Wl, ws);
					break;
				case 3:
					downdateAllPairsAvx<3>(p, n, Wl, ws);
					break;
				case 2:
					downdateAllPairsAvx<2>(p, n, Wl, ws);
					break;
				default:
					downdateAllPairsAvx<1>(p, n, Wl, ws);
					break;
			}
		}
		j = n - n % 2;
	}
#endif
	for (; j + 2 <= n; j += 2)
		for (Eigen::Index l = 0; l < m; l += 4)
		{
			const Eigen::Index cnt = std::min<Eigen::Index>(4, m - l);
			double a[4] = {0, 0, 0, 0}, b[4] = {0, 0, 0, 0};
			for (Eigen::Index c = 0; c < cnt; ++c)
			{
				a[c] = W(j, l + c);
				b[c] = W(j + 1, l + c);
			}
			const double* Wl = W.data() + l * ws;
			switch (cnt)
			{
				case 4:
					downdateColumnPair<4>(p, n, j, Wl, ws, a, b);
					break;
				case 3:
					downdateColumnPair<3>(p, n, j, Wl, ws, a, b);
					break;
				case 2:
					downdateColumnPair<2>(p, n, j, Wl, ws, a, b);
					break;
				default:
					downdateColumnPair<1>(p, n, j, Wl, ws, a, b);
					break;
			}
		}
	if (j < n)  // an odd n's last column: its diagonal alone, the same fused steps
	{
		double v = p[j * n + j];
		for (Eigen::Index l = 0; l < m; ++l) v = std::fma(-W(j, l), W(j, l), v);
		p[j * n + j] = v;
	}
}

/** Two and four doubles as one value (GCC/Clang vector extensions): a
 *  128-bit register in the baseline, a 256-bit one inside a target("avx")
 *  function; element-wise IEEE multiplies and adds (no FMA is enabled, so
 *  none is contracted). Used only inside always-inlined bodies, never
 *  passed between functions (no ABI question). */
typedef double Pack2 __attribute__((vector_size(16)));
typedef double Pack4 __attribute__((vector_size(32)));

/** One row entry of X Fᵀ in the order subtractAllColumns<false, true> with
 *  coefficients −F(j, l) sums it: t_g = ((x_l F_jl + x_l+1 F_j,l+1) + …)
 *  over groups of four l, then ((t_0 + t_1) + t_2) + … (the negations are
 *  exact, so this equals 0 − Σ (−t_g) bit for bit). */
template <int K>
inline double rightTransposedEntry(const double* row, const double* F, int j)
{
	double acc = 0;
	for (int l0 = 0; l0 < K; l0 += 4)
	{
		double t = row[l0] * F[l0 * K + j];
		for (int l = l0 + 1; l < std::min(K, l0 + 4); ++l) t = t + row[l] * F[l * K + j];
		acc = l0 == 0 ? t : acc + t;
	}
	return acc;
}

/** Output columns j … j + JB − 1 (JB ≤ 3) of one panel of P Packs of rows:
 *  `panel` holds its K input columns (P·width contiguous rows each), `out`
 *  points at X(r0, j). The sums of rightTransposedEntry, with up to six
 *  accumulators and six group sums in registers; each group of four l
 *  unrolled (no loop test per multiply). */
template <typename Pack, int P, int K, int JB>
__attribute__((always_inline)) inline void rightTransposedPanelBlock(const double* __restrict panel,
                                                                     const double* __restrict F, int j,
                                                                     double* __restrict out, Eigen::Index xs)
{
	constexpr int w = sizeof(Pack) / sizeof(double), h = P * w;
	Pack acc[P][JB];
	auto group = [&](int l0, auto count)
	{
		constexpr int G = decltype(count)::value;
		Pack t[P][JB];
#pragma GCC unroll 4
		for (int g = 0; g < G; ++g)
		{
			const int l = l0 + g;
			Pack x[P];
#pragma GCC unroll 2
			for (int p = 0; p < P; ++p) __builtin_memcpy(&x[p], panel + l * h + p * w, sizeof(Pack));
#pragma GCC unroll 3
			for (int b = 0; b < JB; ++b)
			{
				const double f = F[l * K + j + b];
#pragma GCC unroll 2
				for (int p = 0; p < P; ++p) t[p][b] = g == 0 ? x[p] * f : t[p][b] + x[p] * f;
			}
		}
#pragma GCC unroll 3
		for (int b = 0; b < JB; ++b)
#pragma GCC unroll 2
			for (int p = 0; p < P; ++p) acc[p][b] = l0 == 0 ? t[p][b] : acc[p][b] + t[p][b];
	};
	int l0 = 0;
	for (; l0 + 4 <= K; l0 += 4) group(l0, std::integral_constant<int, 4>{});
	if constexpr (K % 4 != 0) group(l0, std::integral_constant<int, K % 4>{});
#pragma GCC unroll 3
	for (int b = 0; b < JB; ++b)
#pragma GCC unroll 2
		for (int p = 0; p < P; ++p) __builtin_memcpy(out + b * xs + p * w, &acc[p][b], sizeof(Pack));
}

/** All K output columns of the panel of P Packs of rows at row r (copied to
 *  the stack first: the product is in place), three at a time. */
template <typename Pack, int P, int K>
__attribute__((always_inline)) inline void rightTransposedPanel(double* __restrict X, Eigen::Index r,
                                                                Eigen::Index xs, const double* __restrict F)
{
	constexpr int h = P * static_cast<int>(sizeof(Pack) / sizeof(double));
	alignas(32) double panel[K * h];
	for (int l = 0; l < K; ++l) __builtin_memcpy(panel + l * h, X + l * xs + r, h * sizeof(double));
	int j = 0;
	for (; j + 3 <= K; j += 3) rightTransposedPanelBlock<Pack, P, K, 3>(panel, F, j, X + j * xs + r, xs);
	if constexpr (K % 3 == 2) rightTransposedPanelBlock<Pack, P, K, 2>(panel, F, j, X + j * xs + r, xs);
	if constexpr (K % 3 == 1) rightTransposedPanelBlock<Pack, P, K, 1>(panel, F, j, X + j * xs + r, xs);
}

/** The body of rightMultiplyTransposed: panels of two Packs of rows, then
 *  one Pack, then (AVX) one 128-bit Pack, then a last row alone. */
template <typename Pack, int K>
__attribute__((always_inline)) inline void rightMultiplyTransposedBody(double* __restrict X,
                                                                       Eigen::Index rows, Eigen::Index xs,
                                                                       const double* __restrict F)
{
	constexpr int w = static_cast<int>(sizeof(Pack) / sizeof(double));
	Eigen::Index r = 0;
	for (; r + 2 * w <= rows; r += 2 * w) rightTransposedPanel<Pack, 2, K>(X, r, xs, F);
	if (r + w <= rows)
	{
		rightTransposedPanel<Pack, 1, K>(X, r, xs, F);
		r += w;
	}
	if constexpr (w > 2)
		if (r + 2 <= rows)
		{
			rightTransposedPanel<Pack2, 1, K>(X, r, xs, F);
			r += 2;
		}
	for (; r < rows; ++r)
	{
		double row[K];
		for (int l = 0; l < K; ++l) row[l] = X[l * xs + r];
		for (int j = 0; j < K; ++j) X[j * xs + r] = rightTransposedEntry<K>(row, F, j);
	}
}

#if AUVNAV_AVX_KERNELS
template <int K>
__attribute__((target("avx"))) void rightMultiplyTransposedAvx(double* X, Eigen::Index rows, Eigen::Index xs,
                                                               const double* F)
{
	rightMultiplyTransposedBody<Pack4, K>(X, rows, xs, F);
}
#endif

/** X's first K columns ← X_{:,0:K} Fᵀ in place (X: `rows` rows, column
 *  stride xs; F: K × K, column-major). Entry (r, j) is rightTransposedEntry's
 *  sum whichever path runs (eight-row panels with AVX, four-row ones on the
 *  SSE2 baseline, the same sums): what Y = 0 − Σ_l X_l (−F(j, l)) by
 *  subtractAllColumns<false, true> gave, bit for bit, without Y or its copy
 *  back, and with each load of X shared by three output columns. */
template <int K>
void rightMultiplyTransposed(double* X, Eigen::Index rows, Eigen::Index xs, const double* F)
{
#if AUVNAV_AVX_KERNELS
	if (g_wide_kernels.load(std::memory_order_relaxed)) return rightMultiplyTransposedAvx<K>(X, rows, xs, F);
#endif
	rightMultiplyTransposedBody<Pack2, K>(X, rows, xs, F);
}

}  // namespace
}  // namespace auvnav
