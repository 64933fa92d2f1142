// Unscented RTS backward pass (smoother.h).
#include <auvnav/smoother.h>
#include <auvnav/so3.h>

#include "covariance_kernels.h"

#include <Eigen/Cholesky>
#include <array>

namespace auvnav
{
namespace
{
/** The smoothed estimate x_f ⊞ dx with covariance P (symmetrised) into the
 *  outputs, or false (outputs untouched: the caller's filtered estimate) if
 *  it is not finite or a variance is not positive. */
bool acceptSmoothed(const NavState& x_f, const TangentVector& dx, Covariance& P, NavState& x_out,
                    Covariance& P_out)
{
	P = 0.5 * (P + P.transpose());
	if (!dx.allFinite() || !P.allFinite() || !(P.diagonal().array() > 0).all()) return false;
	x_out = x_f.boxplus(dx);
	x_out.R_nb = so3::normalized(x_out.R_nb);
	P_out = P;
	return true;
}
/** The RTS gain G = C P⁻⁻¹, i.e. Gᵀ = P⁻⁻¹ Cᵀ (P⁻ symmetric), by the
 *  factor of P⁻: no inverse is formed. */
Covariance rtsGain(const Eigen::LLT<Covariance>& llt_P_predicted, const Covariance& P_cross)
{
	return llt_P_predicted.solve(P_cross.transpose()).transpose();
}
}  // namespace

RtsStep predictRecorded(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b,
                        const Eigen::Vector3d& omega_ie_n, double dt_s, double t_s)
{
	RtsStep step;
	step.t_s = t_s;
	step.x_filtered = ukf.state();
	step.P_filtered = ukf.covariance();
	ukf.predict(omega_ib_b, omega_ie_n, dt_s, &step.P_cross);
	step.x_predicted = ukf.state();
	step.P_predicted = ukf.covariance();
	return step;
}

bool rtsBackwardStep(const RtsStep& step, const NavState& x_next, const Covariance& P_next, NavState& x_out,
                     Covariance& P_out)
{
	x_out = step.x_filtered;
	P_out = step.P_filtered;
	const Eigen::LLT<Covariance> llt(step.P_predicted);
	if (llt.info() != Eigen::Success) return false;
	const Covariance G = rtsGain(llt, step.P_cross);
	const TangentVector dx = G * x_next.boxminus(step.x_predicted);
	Covariance P = step.P_filtered;
	P.noalias() += G * (P_next - step.P_predicted) * G.transpose();
	return acceptSmoothed(step.x_filtered, dx, P, x_out, P_out);
}

std::vector<SmoothedEstimate> smoothRts(const std::vector<RtsStep>& steps, const NavState& x_end,
                                        const Covariance& P_end, double t_end_s)
{
	std::vector<SmoothedEstimate> out(steps.size() + 1);
	out.back() = SmoothedEstimate{t_end_s, x_end, P_end, true};
	for (std::size_t k = steps.size(); k-- > 0;)
	{
		SmoothedEstimate& e = out[k];
		e.t_s = steps[k].t_s;
		e.smoothed = rtsBackwardStep(steps[k], out[k + 1].x, out[k + 1].P, e.x, e.P);
	}
	return out;
}

namespace
{
//! The columns where the correction transport T_t is not the identity:
//! attitude (velocity, acceleration and currents turn with it) and the
//! accelerometer bias (kept in IMU axes).
//! The prediction's nonlinear (sigma-point) block: the states before the ADCP bias (ukf.cpp).
constexpr int kNonlinearStates = idx::adcp_bias;
constexpr std::array<int, 6> kTransportColumns{idx::att,      idx::att + 1,      idx::att + 2,
                                               idx::acc_bias, idx::acc_bias + 1, idx::acc_bias + 2};
}  // namespace

void RtsStretchRecorder::begin(const ManifoldUkf& ukf, double t_s)
{
	const int n = ukf.dim();
	current_ = RtsStretch{};
	current_.t_s = t_s;
	current_.x_filtered = ukf.state();
	current_.P_filtered = ukf.covariance();
	current_.sum_dx = TangentVector::Zero(n);
	current_.sum_dP = Covariance::Zero(n, n);
	XX_.resize(2 * n, n);
	XX_.topRows(n) = ukf.covariance();  // M = I
	XX_.bottomRows(n) = ukf.covariance();
	MW_pending_.resize(2 * n, kMaxPending);
	W_pending_.resize(n, kMaxPending);
	pending_ = 0;
	MW_dP_.resize(n, kMaxDpPending);
	dP_pending_ = 0;
	repairs_seen_ = ukf.choleskyRepairs();
	open_ = true;
	predicted_ = transport_pending_ = false;
	dx_since_transport_ = TangentVector::Zero(n);
	ticks_since_transport_ = 0;
}

void RtsStretchRecorder::onPredict(const Covariance& L, bool full, const Eigen::Ref<const Eigen::MatrixXd>& D,
                                   const ProcessModel& model, const StepDecay& step)
{
	if (!open_ || current_.broken) return;
	flushUpdates();
	const int k = static_cast<int>(D.rows()), n = static_cast<int>(L.rows());
	if (k != kNonlinearStates || (transport_pending_ && !full))
	{
		current_.broken = true;  // P not positive definite: no gain
		return;
	}
	if (transport_pending_)
	{
		// P⁻¹ E = L⁻ᵀ L⁻¹ E by forward and back substitution (covariance_kernels.h).
		Eigen::Matrix<double, Eigen::Dynamic, 6, 0, idx::max_dim, 6> S = E_;
		const kernels::ConstColumnsMap L_n = kernels::columns(L.data(), n, n, L.outerStride());
		kernels::solveLeftLower(kernels::columns(S.data(), n, 6, S.outerStride()), L_n);
		kernels::solveLeftLowerTransposed(kernels::columns(S.data(), n, 6, S.outerStride()), L_n);
		// P's rows at the six columns, from L (row c of L has c + 1 entries).
		Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, idx::max_dim> P_rows(6, n);
		for (int j = 0; j < 6; ++j)
		{
			const int c = kTransportColumns[j];
			P_rows.row(j).noalias() = L.row(c).head(c + 1) * L.leftCols(c + 1).transpose();
		}
		// X_mean += (X_mean P⁻¹ E) P_{cols,:}: two products of rank six, as
		// column combinations (Eigen's blocked products spend their set-up
		// on these shapes).
		ME_.resize(n, 6);
		double* X_mean = XX_.data() + n;  // rows n… of XX
		const Eigen::Index xs = XX_.outerStride();
		kernels::ColumnsMap X_mean_n = kernels::columns(X_mean, n, n, xs);
		for (int j = 0; j < 6; ++j) kernels::assignCombination(ME_.col(j), X_mean_n, S.col(j));
		for (int c = 0; c < n; ++c) kernels::subtractCombination(X_mean_n.col(c), ME_, -P_rows.col(c));
		transport_pending_ = false;
	}
	// [X; X_mean] ← [X; X_mean] Fᵀ, F = [D L11⁻¹, 0; 0, diag(a)] (ukf.h
	// StepObserver): the first k columns times L11⁻ᵀ Dᵀ, the others scaled.
	// F L11 = D by columns from the last: F_c = (D_c − Σ_{l>c} F_l L_lc) / L_cc,
	// as column combinations (covariance_kernels.h).
	Eigen::Matrix<double, kNonlinearStates, kNonlinearStates> F = D;
	kernels::solveRightLower(kernels::columns(F.data(), k, k, k), L);
	// X_{:,1:k} ← X_{:,1:k} Fᵀ in place (eight-row panels).
	kernels::rightMultiplyTransposed<kNonlinearStates>(
	    kernels::columns(XX_.data(), 2 * n, XX_.cols(), XX_.outerStride()), F);
	TangentVector a = TangentVector::Ones(n);
	model.applyLinearRows(a, step);  // rows k… only scale: their factors
	XX_.rightCols(n - k) *= a.tail(n - k).asDiagonal();
}

void RtsStretchRecorder::onUpdate(const Eigen::Ref<const Eigen::MatrixXd>& B,
                                  const Eigen::Ref<const Eigen::VectorXd>& u,
                                  const Eigen::Ref<const Eigen::MatrixXd>& W)
{
	if (!open_ || current_.broken) return;
	const int k = static_cast<int>(B.rows()), n = static_cast<int>(W.rows()), m = static_cast<int>(B.cols());
	if (m > kMaxPending)
	{
		applyWideUpdate(B, u, W);
		return;
	}
	if (pending_ + m > kMaxPending) flushUpdates();
	// M W = X_now P⁻¹ W = X_now_{:,1:k} B, for X and X_mean at once, with
	// X_now = X − MW_p W_pᵀ (this tick's earlier updates, not yet applied).
	// m is small (3 for most sensors): a column kernel per column of B.
	auto MW = MW_pending_.middleCols(pending_, m);
	for (int j = 0; j < m; ++j) kernels::assignCombination(MW.col(j), XX_.leftCols(k), B.col(j));
	if (pending_ > 0)
	{
		// Coefficient-wise and by column combinations: Eigen's blocked
		// products cost more in set-up than these few multiply-adds.
		const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPending, kMaxPending> C =
		    W_pending_.topLeftCorner(k, pending_).transpose().lazyProduct(B);
		for (int j = 0; j < m; ++j)
			kernels::subtractCombination(MW.col(j), MW_pending_.leftCols(pending_), C.col(j));
	}
	current_.sum_dx.noalias() += MW.bottomRows(n) * u;
	W_pending_.middleCols(pending_, m) = W;
	pending_ += m;
}

void RtsStretchRecorder::applyWideUpdate(const Eigen::Ref<const Eigen::MatrixXd>& B,
                                         const Eigen::Ref<const Eigen::VectorXd>& u,
                                         const Eigen::Ref<const Eigen::MatrixXd>& W)
{
	flushUpdates();
	const int k = static_cast<int>(B.rows()), n = static_cast<int>(W.rows());
	const Eigen::MatrixXd MW = XX_.leftCols(k) * B;
	current_.sum_dx.noalias() += MW.bottomRows(n) * u;
	kernels::downdateSymmetric(current_.sum_dP, MW.topRows(n));  // − Σ M ΔP Mᵀ while open (flushDp)
	XX_.noalias() -= MW * W.transpose();
}

void RtsStretchRecorder::flushUpdates()
{
	if (pending_ == 0) return;
	const int n = static_cast<int>(XX_.cols());
	// M W goes on to Σ M ΔP Mᵀ's columns (a wider rank update later), and
	// X and X_mean move now.
	if (dP_pending_ + pending_ > kMaxDpPending) flushDp();
	MW_dP_.middleCols(dP_pending_, pending_) = MW_pending_.topLeftCorner(n, pending_);
	dP_pending_ += pending_;
	// XX −= MW Wᵀ column by column (r ≈ 5 columns of MW per column of XX).
	for (int c = 0; c < n; ++c)
		kernels::subtractCombination(XX_.col(c), MW_pending_.leftCols(pending_),
		                             W_pending_.row(c).head(pending_).transpose());
	pending_ = 0;
}

void RtsStretchRecorder::flushDp()
{
	if (dP_pending_ == 0) return;
	// While the stretch is open, sum_dP holds −Σ M ΔP Mᵀ, so that the rank
	// update is the filter's symmetric downdate kernel. close() turns the
	// sign back.
	kernels::downdateSymmetric(current_.sum_dP, MW_dP_.leftCols(dP_pending_));
	dP_pending_ = 0;
}

void RtsStretchRecorder::onOtherChange(const Covariance& P_before, const Covariance& P_after,
                                       const TangentVector& dx)
{
	if (!open_ || current_.broken) return;
	flushUpdates();
	// M itself is unchanged (X P⁻¹ before); X follows P, and the change
	// enters the sums as an update's would.
	const int n = static_cast<int>(P_before.rows());
	const Eigen::LLT<Covariance> llt(P_before);
	if (llt.info() != Eigen::Success)
	{
		current_.broken = true;
		return;
	}
	const Covariance M = llt.solve(XX_.topRows(n).transpose()).transpose(),
	                 Mm = llt.solve(XX_.bottomRows(n).transpose()).transpose();
	current_.sum_dx.noalias() += Mm * dx;
	scratch_.noalias() = M * (P_before - P_after);
	current_.sum_dP.noalias() -= scratch_ * M.transpose();  // − Σ while open (flushDp)
	XX_.topRows(n).noalias() = M * P_after;
	XX_.bottomRows(n).noalias() = Mm * P_after;
}

void RtsStretchRecorder::takeTransport(const ManifoldUkf& ukf, bool now)
{
	if (predicted_)
	{
		predicted_ = false;
		// The tick's update correction, summed over the ticks since the last
		// transport (each in its own tick's tangent: equal to first order).
		dx_since_transport_ += ukf.state().boxminus(x_predicted_);
		++ticks_since_transport_;
	}
	if (ticks_since_transport_ == 0 || (!now && ticks_since_transport_ < kTransportEveryTicks)) return;
	// T = ∂/∂b [(x ⊞ b) ⊟ x⁻] at b = 0 on its six columns, with x⁻ = x ⊞ (−Σ dx):
	// E = T − I is first order in the corrections, so the ticks' transports
	// add up to first order (smoother.h); central differences at a step far
	// below any σ and far above rounding.
	constexpr double kEps = 1e-6;
	const NavState& x = ukf.state();
	// x⁻ with x⁻ ⊞ Σ dx = x (the inverse of the tick's own ⊟ at N = 1), by
	// fixed-point steps from x ⊞ (−Σ dx): ⊞ is not its own inverse here.
	NavState x_before = x.boxplus(-dx_since_transport_);
	for (int it = 0; it < 3; ++it)
		x_before = x_before.boxplus(-x_before.boxplus(dx_since_transport_).boxminus(x));
	const int n = x.dim();
	E_.resize(n, 6);
	TangentVector e = TangentVector::Zero(n);
	for (int j = 0; j < 6; ++j)
	{
		const int i = kTransportColumns[j];
		e[i] = kEps;
		E_.col(j) = (x.boxplus(e).boxminus(x_before) - x.boxplus(-e).boxminus(x_before)) / (2 * kEps);
		E_(i, j) -= 1;
		e[i] = 0;
	}
	dx_since_transport_.setZero();
	ticks_since_transport_ = 0;
	transport_pending_ = true;
}

bool RtsStretchRecorder::predict(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b,
                                 const Eigen::Vector3d& omega_ie_n, double dt_s)
{
	if (!open_)
	{
		ukf.predict(omega_ib_b, omega_ie_n, dt_s);
		return true;
	}
	takeTransport(ukf);
	ukf.setStepObserver(this);
	ukf.predict(omega_ib_b, omega_ie_n, dt_s);
	x_predicted_ = ukf.state();
	predicted_ = true;
	++current_.ticks;
	checkRepairs(ukf);
	return !current_.broken;
}

void RtsStretchRecorder::checkRepairs(const ManifoldUkf& ukf, bool reset)
{
	// A repaired P is not a Bayesian step: the stretch keeps its filtered estimate.
	if (!reset && open_ && ukf.choleskyRepairs() != repairs_seen_) current_.broken = true;
	repairs_seen_ = ukf.choleskyRepairs();
}

RtsStretch RtsStretchRecorder::close(const ManifoldUkf& ukf, double t_s)
{
	takeTransport(ukf, true);
	flushUpdates();
	flushDp();
	const int n = ukf.dim();
	checkRepairs(ukf);
	RtsStretch done = std::move(current_);
	done.sum_dP.triangularView<Eigen::StrictlyUpper>() = done.sum_dP.transpose();  // the lower triangle rules
	done.sum_dP = -done.sum_dP;  // −Σ M ΔP Mᵀ while open (flushDp)
	const Eigen::LLT<Covariance> llt(ukf.covariance());
	if (llt.info() != Eigen::Success) done.broken = true;
	if (!done.broken)
	{
		if (transport_pending_)
		{
			const Covariance& P = ukf.covariance();
			const SixColumns ME = XX_.bottomRows(n) * llt.solve(E_);
			for (int j = 0; j < 6; ++j)
				XX_.bottomRows(n).noalias() += ME.col(j) * P.row(kTransportColumns[j]);
		}
		done.M = llt.solve(XX_.topRows(n).transpose()).transpose();  // M = X P⁻¹ (P symmetric)
		done.M_mean = llt.solve(XX_.bottomRows(n).transpose()).transpose();
	}
	begin(ukf, t_s);
	return done;
}

bool rtsStretchBackward(const RtsStretch& s, const NavState& x_end_filtered, const Covariance& P_end_filtered,
                        const NavState& x_end_smoothed, const Covariance& P_end_smoothed, NavState& x_out,
                        Covariance& P_out)
{
	x_out = s.x_filtered;
	P_out = s.P_filtered;
	if (s.broken) return false;
	const TangentVector dx = s.sum_dx + s.M_mean * x_end_smoothed.boxminus(x_end_filtered);
	Covariance P = s.P_filtered - s.sum_dP;
	P.noalias() += s.M * (P_end_smoothed - P_end_filtered) * s.M.transpose();
	return acceptSmoothed(s.x_filtered, dx, P, x_out, P_out);
}

}  // namespace auvnav
