// ManifoldUkf::predict: the unscented prediction over the blocks that
// propagate nonlinearly, the affine rest in closed form.
#include <auvnav/so3.h>
#include <auvnav/ukf.h>

#include "covariance_kernels.h"
#include "ukf_detail.h"

#include <array>
#include <cmath>

namespace auvnav
{
using namespace ukf_detail;

namespace
{
/** One prediction step of the first kNonlinear coordinates along departures
 *  δ that leave attitude and gyro bias at the centre's x (every Cholesky
 *  column past the gyro bias's). The turns are then the centre's, so the
 *  retraction (state.h) is a plain difference in every coordinate and
 *  propagate(x ⊞ δ) ⊟ propagate(x) = J δ + q(δ) exactly: J is the linear map
 *  (ProcessModel::applyLinearRows) with the current transport's
 *  linearisation, q the transport's second-order part, Δz(δ) ΔD(δ) / D — the
 *  same 2-vector added to both currents. */
class InertialStepMap
{
 public:
	/** x: the centre before the step, R_nb_next its attitude after. */
	InertialStepMap(const ProcessModel& model, const NavState& x, const Eigen::Matrix3d& R_nb_next,
	                const StepDecay& step)
	    : model_(model), step_(step), R_turn_(R_nb_next * x.R_nb.transpose())
	{
		const double D = model.current_far_distance_m, dt = step.dt_s;
		inv_D_ = D > 0 ? 1.0 / D : 0.0;
		// The centre's depth change and far-minus-vehicle current after the
		// decay, as ProcessModel::propagateTurned forms them.
		dz0_m_ = dt * x.v_n.z() + 0.5 * dt * dt * x.a_n.z();
		const Eigen::Vector2d mu =
		    model.prior_mean.segment<2>(idx::current_far) - model.prior_mean.segment<2>(idx::current_vehicle);
		shear0_ = step.current * (x.current_far_ne - x.current_vehicle_ne) + (1 - step.current) * mu;
	}
	/** M ← J M for kNonlinear rows (columns: departures; M's rows of
	 *  attitude and gyro bias are not read and leave zero). With q, q.col(c)
	 *  = q(M.col(c)). */
	template <typename Derived, typename DerivedQ = Eigen::Matrix<double, 2, Eigen::Dynamic>>
	void apply(Eigen::MatrixBase<Derived>& M, Eigen::MatrixBase<DerivedQ>* q = nullptr) const
	{
		const double dt = step_.dt_s;
		M.template topRows<kTurning>().setZero();
		// Δz before the position rows change: the velocity and acceleration's part.
		const Eigen::Matrix<double, 1, Derived::ColsAtCompileTime, Eigen::RowMajor, 1,
		                    Derived::MaxColsAtCompileTime>
		    dz = dt * M.row(idx::vel + 2) + (0.5 * dt * dt) * M.row(idx::acc + 2);
		model_.applyLinearRows(M, step_);
		// The accelerometer bias is held in body axes and its tangent in
		// navigation axes (state.h): a departure turns with the body.
		M.template middleRows<3>(idx::acc_bias) = R_turn_ * M.template middleRows<3>(idx::acc_bias);
		if (inv_D_ == 0)
		{
			if (q) q->setZero();
			return;
		}
		// Row by row (one current axis at a time, all columns at once).
		for (int r = 0; r < 2; ++r)
		{
			const decltype(dz) shear = M.row(idx::current_far + r) - M.row(idx::current_vehicle + r);
			const decltype(dz) linear = inv_D_ * (shear0_[r] * dz + dz0_m_ * shear);
			M.row(idx::current_vehicle + r) += linear;
			M.row(idx::current_far + r) += linear;
			if (q) q->row(r) = inv_D_ * dz.cwiseProduct(shear);
		}
	}

 private:
	const ProcessModel& model_;
	const StepDecay& step_;
	Eigen::Matrix3d R_turn_;  // R_nb after the step times R_nb before, transposed
	double inv_D_ = 0, dz0_m_ = 0;
	Eigen::Vector2d shear0_;
};
}  // namespace

void ManifoldUkf::predict(const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n, double dt,
                          Covariance* P_cross)
{
	constexpr int k = kNonlinear, ks = kTurning;
	const int n = n_, nl = n - k;
	// The filter reads columns past the turning ones only over the first k
	// rows, and so does an observer (its F needs L11 only) unless it wants the
	// whole factor; P_cross reads whole columns.
	const bool wants_full = observer_ && observer_->wantsFullFactor();
	leadingCholeskyColumns(k, wants_full || P_cross ? k : ks);
	// The observer (a smoother) then also needs P's inverse: the remaining
	// columns, without a repair (the filter must not change because it is
	// observed).
	const bool full_factor = wants_full && choleskyColumns(P_, k, n, L_);
	const double g = w_.gamma;
	// Sigma points are propagated only along the first ks Cholesky columns,
	// the ones that turn the attitude; every other pair keeps the centre's
	// attitude and enters in closed form (InertialStepMap).
	std::array<NavState, 2 * ks + 1>& X = sigma_scratch_;
	// Turns shared by sigma points: the navigation frame's (all of them) and
	// the body's at the centre's gyro bias.
	const Eigen::Matrix3d R_earth_turn = so3::Exp(-omega_ie_n * dt);
	const Eigen::Matrix3d R_body_turn = so3::Exp((omega_ib_b - x_.b_w) * dt);
	const StepDecay step = model_.decay(dt);  // the Gauss–Markov φ once, not per point
	// The points' inertial members only, straight into X (their affine rest
	// is never read: it comes from X[0]).
	auto propagate = [&](const NavState& x, NavState& y)
	{
		if (x.b_w == x_.b_w)
			model_.propagateInertialInto(x, R_earth_turn, R_body_turn, step, y);
		else
			model_.propagateInertialInto(x, R_earth_turn, so3::Exp((omega_ib_b - x.b_w) * dt), step, y);
	};
	X[0] = model_.propagateTurned(x_, R_earth_turn, R_body_turn, step);
	std::array<double, ks> scale;
	// The points' coordinates past the inertial block are never read (that
	// part is affine: it comes from X[0] below), so only the inertial
	// blocks are perturbed; the rest holds x's values.
	pair_scratch_[0] = x_;
	pair_scratch_[1] = x_;
	for (int j = 0; j < ks; ++j)
	{
		scale[j] = attitudeTurnScale(g * L_.col(j).head<3>(), ut_.max_attitude_spread_rad);
		x_.boxplusPairBlocks(L_.col(j), g * scale[j], kInertialBlocks, pair_scratch_[0], pair_scratch_[1]);
		propagate(pair_scratch_[0], X[1 + 2 * j]);
		propagate(pair_scratch_[1], X[2 + 2 * j]);
	}
	// The pairs along columns ks… (2(n − ks) points): X± ⊟ X₀ = ±γ J L_j +
	// γ² q(L_j), so the centre's weight carries their d₀ and their sums enter
	// below: the mean's 2W Σ q_j, the covariance's 2W Σ (q_j d₀ᵀ + d₀ q_jᵀ +
	// q_j q_jᵀ) and J (Σ L_j L_jᵀ) Jᵀ = J (P − L_{:,<ks} L_{:,<ks}ᵀ) Jᵀ.
	const InertialStepMap step_map(model_, x_, X[0].R_nb, step);
	const int lumped_pairs = n - ks;
	Eigen::Matrix<double, k, k - ks> JL_rest;
	for (int c = 0; c < k - ks; ++c) JL_rest.col(c) = L_.col(ks + c).head<k>();  // fixed-size column copies
	Eigen::Matrix<double, 2, k - ks> q_rest;
	step_map.apply(JL_rest, &q_rest);
	const Eigen::Vector2d q_each = (g * g) * q_rest.rowwise().sum();  // Σ_j q(γ L_j), both currents
	Eigen::Matrix<double, k, 1> q_sum = Eigen::Matrix<double, k, 1>::Zero();
	q_sum.segment<2>(idx::current_vehicle) = q_each;
	q_sum.segment<2>(idx::current_far) = q_each;
	const Eigen::Matrix2d qq = (g * g * g * g) * (q_rest * q_rest.transpose());

	std::array<double, 2 * ks + 1> wm;
	wm.fill(w_.wi);
	wm[0] = w_.wm0 + 2 * lumped_pairs * w_.wi;
	// A scaled pair (ukf.h) has no point on the manifold at the full step: it
	// is kept as deviations from the centre's propagation, ŷ± = ±a/s + m
	// (a, m: antisymmetric and symmetric parts at the shorter step), and
	// enters the mean and covariance as ŷ± − (x̄ ⊟ X₀).
	std::array<Eigen::Matrix<double, k, 1>, 2 * ks + 1> y;
	bool any_scaled = false;
	for (int j = 0; j < ks; ++j)
		if (scale[j] < 1.0)
		{
			any_scaled = true;
			const Eigen::Matrix<double, k, 1> yp = X[1 + 2 * j].boxminusHead(X[0]),
			                                  ym = X[2 + 2 * j].boxminusHead(X[0]);
			const Eigen::Matrix<double, k, 1> a = 0.5 * (yp - ym) / scale[j], m = 0.5 * (yp + ym);
			y[1 + 2 * j] = m + a;
			y[2 + 2 * j] = m - a;
		}
	auto deviations = [&](const NavState& mean, std::array<Eigen::Matrix<double, k, 1>, 2 * ks + 1>& d)
	{
		const Eigen::Matrix<double, k, 1> mu =
		    any_scaled ? mean.boxminusHead(X[0]) : Eigen::Matrix<double, k, 1>::Zero().eval();
		X[0].boxminusHeadInto(mean, d[0]);
		for (int i = 1; i < 2 * ks + 1; ++i)
			if (scale[(i - 1) / 2] < 1.0)
				d[i] = y[i] - mu;
			else
				X[i].boxminusHeadInto(mean, d[i]);
	};
	// Iterated manifold mean of the inertial block (the affine rest of X[0] is
	// already the exact mean: A x̄ + b). It stops at a step below 1e-12 (in
	// the state's units: rad, m/s, m, …): the second step is already the
	// sums' rounding, so a tighter or σ-relative bound only adds rounds
	// (FilterVsReference bounds the difference from the dense reference).
	NavState mean = X[0];
	std::array<Eigen::Matrix<double, k, 1>, 2 * ks + 1> d;
	for (int iter = 0;; ++iter)
	{
		deviations(mean, d);  // at the mean that leaves the loop: the ones used below
		if (iter == 10) break;
		Eigen::Matrix<double, k, 1> step_head = (2 * w_.wi) * q_sum;  // fixed size: the sums in registers
		for (int i = 0; i < 2 * ks + 1; ++i) step_head += wm[i] * d[i];
		if (step_head.squaredNorm() < 1e-24) break;
		TangentVector mean_step = TangentVector::Zero(n);
		mean_step.head<k>() = step_head;
		mean = mean.boxplus(mean_step);
	}
	// P_NN = Σ W_i d_i d_iᵀ over the propagated points (the centre with the
	// lumped pairs' weight), then the lumped pairs' closed-form sums: their
	// J L_j L_jᵀ Jᵀ (2 W γ² = 1) and the q terms. As one product: columns of
	// Dc (and their weighted DWc) are the points' deviations and the J L_j.
	// (Σ_{j≥ks} J L_j L_jᵀ Jᵀ = J P Jᵀ − (J L_{:,<ks})(J L_{:,<ks})ᵀ over these
	// rows, formed without J P Jᵀ and without the difference's cancellation.)
	Eigen::Matrix<double, k, ks> JL_turn = L_.block<k, ks>(0, 0);
	step_map.apply(JL_turn);
	// The centre's cross terms with the q sums, d₀ q_crossᵀ + q_cross d₀ᵀ,
	// ride along as two more columns.
	constexpr int points = 2 * ks + 1, rows = points + (k - ks) + 2;
	constexpr int kp = (k + 3) / 4 * 4;  // k padded with zero rows to the Gram kernel's 4-row blocks
	const Eigen::Matrix<double, k, 1> q_cross = (2 * w_.wi) * q_sum;
	Eigen::Matrix<double, kp, rows> Dc, DWc;
	for (int i = 0; i < points; ++i) Dc.col(i).head<k>() = d[i];
	Dc.block<k, k - ks>(0, points) = JL_rest;
	Dc.col(rows - 2).head<k>() = q_cross;
	Dc.col(rows - 1).head<k>() = d[0];
	Dc.bottomRows<kp - k>().setZero();
	DWc.col(0) = (w_.wc0 + 2 * lumped_pairs * w_.wi) * Dc.col(0);
	DWc.middleCols<2 * ks>(1) = w_.wi * Dc.middleCols<2 * ks>(1);
	DWc.middleCols<k - ks>(points) = Dc.middleCols<k - ks>(points);
	DWc.col(rows - 2) = Dc.col(rows - 1);
	DWc.col(rows - 1) = Dc.col(rows - 2);
	Eigen::Matrix<double, kp, kp> P_NN;  // its blocks on and below the diagonal; the first k rows and columns
	// Dc's columns of the lumped pairs and q_cross are zero in the rows of
	// attitude and gyro bias (InertialStepMap zeroes them; q lives in the
	// currents), and J L_j above the rows J reaches from L_j's diagonal on:
	// each block column skips the zeros it finds there.
	assert((Dc.block<4, rows - 1 - points>(0, points).array() == 0).all());
	kernels::lowerBlockGram<kp, rows>(DWc, Dc, P_NN, points, rows - 1);
	// The q q term of both currents (their lower triangle).
	for (int r : {idx::current_vehicle, idx::current_far})
		for (int c : {idx::current_vehicle, idx::current_far})
			for (int i = 0; i < 2; ++i)
				for (int j = 0; j < 2; ++j)
					if (r + i >= c + j) P_NN(r + i, c + j) += (2 * w_.wi) * qq(i, j);
	// Pair differences, Σ_j W γ (d₊ⱼ − d₋ⱼ)(·)ᵀ: D_turn for the propagated
	// pairs; J L_j for the lumped ones (2 W γ² = 1).
	Eigen::Matrix<double, k, ks> D_turn;
	for (int j = 0; j < ks; ++j) D_turn.col(j) = (w_.wi * g) * (d[1 + 2 * j] - d[2 + 2 * j]);
	// Cross covariance with the affine part, A's rows there diagonal (a: decay
	// factors): head × tail = Σ_j D_j (a ∘ L_{k:,j})ᵀ = J P_{:k,k:} +
	// (D_turn − J L_{:k,<ks}) L_{k:,<ks}ᵀ, columns scaled by a.
	const TangentVector a = model_.diagonalTailFactors(step);
	// In place in P's top-right block (nothing below reads its old values;
	// the bottom-left mirror is written last).
	auto P_NL = P_.block<k, Eigen::Dynamic>(0, k, k, nl);
	step_map.apply(P_NL);
	const Eigen::Matrix<double, k, ks> D_less_JL = D_turn - JL_turn;
	// Column axpys (a blocked product's set-up costs more here).
	kernels::addCombinationsThenScale(kernels::columns(P_NL.data(), k, nl, P_NL.outerStride()), D_less_JL,
	                                  kernels::columns(&L_(k, 0), nl, ks, L_.outerStride()), a.head(nl));
	Eigen::Matrix<double, k, k> D_pairs;  // for an observer and P_cross: every column's pair difference
	if (observer_ || P_cross)
	{
		D_pairs.leftCols<ks>() = D_turn;
		D_pairs.rightCols<k - ks>() = JL_rest;
	}
	if (P_cross)
	{
		// Cov(x_k, x_k+1): sigma point i deviates from x̄_k by ±γ L_j, so the
		// new inertial block's columns are Σ_j L_j (W γ (d₊ⱼ − d₋ⱼ))ᵀ (pairs
		// along columns j ≥ k leave that block at the centre's: d₊ = d₋);
		// the affine block's are Cov(x, A x + b) = (A P)ᵀ.
		P_cross->resize(n, n);
		P_cross->leftCols(k).noalias() = L_.leftCols(k) * D_pairs.transpose();
		P_cross->rightCols(nl) = (a.asDiagonal() * P_.bottomRows(nl)).transpose();
	}
	// Affine block: A P Aᵀ = P_ij a_i a_j, column by column (contiguous). P
	// is exactly symmetric between steps (initialize() and restore()
	// symmetrise it; every step writes both triangles alike), and a_i a_j =
	// a_j a_i, so it stays so.
	const double speed_through_water = (x_.v_n.head<2>() - x_.current_vehicle_ne).norm();
	kernels::scaleByOuterProduct(P_.bottomRightCorner(nl, nl), a.head(nl));
	// P_NN into P's top-left block as whole fixed-size columns, then its
	// strictly upper part and the bottom-left block as mirrors, by transposed
	// tiles (copies: the same values as entry by entry).
	for (int j = 0; j < k; ++j) P_.col(j).head<k>() = P_NN.col(j).head<k>();
	kernels::mirrorLowerToUpper(P_.topLeftCorner<k, k>());
	P_.bottomLeftCorner(nl, k) = P_.topRightCorner(k, nl).transpose();
	model_.addNoiseCovariance(P_, dt, speed_through_water, x_.v_n.z());
	if (observer_) observer_->onPredict(L_, full_factor, D_pairs, model_, step);
	applySigmaLimits(false);  // part of the prediction's P⁻: process noise to an observer
	mean.R_nb = so3::normalized(mean.R_nb);
	x_ = mean;
}

}  // namespace auvnav
