#pragma once
// What ukf.cpp, ukf_predict.cpp and ukf_update.cpp share: the state's
// nonlinear blocks and the small in-place helpers of every step.
#include <auvnav/ukf.h>

#include "covariance_kernels.h"

namespace auvnav::ukf_detail
{
// The inertial block and the currents (attitude … position, the two currents)
// predict nonlinearly under the retraction of state.h; the ADCP bias and the
// model parameters are affine and independent of them.
inline constexpr int kNonlinear = idx::adcp_bias;
// Their blocks (the first kNonlinear coordinates).
inline constexpr uint32_t kInertialBlocks = kAttitude | kGyroBias | kAcceleration | kGravity | kAccelBias |
                                            kVelocity | kPosition | kCurrentVehicle | kCurrentFar;
// Of those, attitude and gyro bias turn the attitude; along every other
// direction the retraction is a plain difference (InertialStepMap).
inline constexpr int kTurning = idx::acc;

/** P ← ½(P + Pᵀ), in place over one triangle (the same sums as the
 *  expression, without its temporary: this runs after every step). */
inline void symmetrize(Covariance& P)
{
	const Eigen::Index n = P.rows();
	for (Eigen::Index j = 0; j < n; ++j)
		for (Eigen::Index i = j + 1; i < n; ++i)
		{
			const double s = 0.5 * (P(i, j) + P(j, i));
			P(i, j) = s;
			P(j, i) = s;
		}
}

/** Columns [from, to) of P's lower Cholesky factor over its first `rows`
 *  rows (all with rows < 0): kernels::choleskyColumns. Left-looking
 *  (contiguous column operations without a blocked solver's set-up, which
 *  dominates at these sizes); sigma points read whole columns. */
inline bool choleskyColumns(const Covariance& P, int from, int to, Covariance& L, int rows = -1)
{
	return kernels::choleskyColumns(P, from, to, L, rows < 0 ? P.rows() : rows);
}

using kernels::allFiniteEntries;
template <typename Derived>
bool allFiniteEntries(const Eigen::PlainObjectBase<Derived>& a)
{
	return allFiniteEntries(a.data(), a.size());
}
template <typename Plain, int Options, typename Stride>
bool allFiniteEntries(const Eigen::Map<Plain, Options, Stride>& a)
{
	return allFiniteEntries(a.data(), a.size());  // the update's arena Maps: contiguous
}

}  // namespace auvnav::ukf_detail
