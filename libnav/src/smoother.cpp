// Unscented RTS backward pass (smoother.h).
#include <auvnav/smoother.h>
#include <auvnav/so3.h>

#include <Eigen/Cholesky>
#include <array>

namespace auvnav
{
namespace
{
/** The smoothed estimate x_f ⊞ dx with covariance P (symmetrised) into the
 *  outputs, or false (outputs untouched: the caller's filtered estimate) if
 *  it is not finite or a variance is not positive. */
bool acceptSmoothed(const NavState& x_f, const TangentVector& dx, Covariance& P, NavState& x_out, Covariance& P_out)
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

RtsStep predictRecorded(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n,
						double dt_s, double t_s)
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

void RtsStretchRecorder::begin(const ManifoldUkf& ukf, double t_s)
{
	const int n = ukf.dim();
	current_ = RtsStretch{};
	current_.t_s = t_s;
	current_.x_filtered = ukf.state();
	current_.P_filtered = ukf.covariance();
	current_.sum_dx = TangentVector::Zero(n);
	current_.sum_dP = Covariance::Zero(n, n);
	X_ = ukf.covariance();	// M = I
	X_mean_ = X_;
	repairs_at_begin_ = ukf.choleskyRepairs();
	open_ = true;
	predicted_ = false;
}

void RtsStretchRecorder::onPredict(const Eigen::Ref<const Eigen::MatrixXd>& L11, const Eigen::Ref<const Eigen::MatrixXd>& D,
								   const ProcessModel& model, const StepDecay& step)
{
	if (!open_) return;
	// X ← X⁺ Fᵀ with F = [D L11⁻¹, 0; 0, A_rest] (ukf.h StepObserver): the
	// first k columns X_{:,1:k} L11⁻ᵀ Dᵀ, the others as A scales P's rows.
	const int k = static_cast<int>(L11.rows()), n = static_cast<int>(X_.rows());
	for (Covariance* X : {&X_, &X_mean_})
	{
		scratch_ = X->transpose();
		model.applyLinearRows(scratch_, step);
		Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, idx::max_dim, idx::max_dim> Y = X->leftCols(k);
		L11.triangularView<Eigen::Lower>().transpose().solveInPlace<Eigen::OnTheRight>(Y);
		X->leftCols(k).noalias() = Y * D.transpose();
		X->rightCols(n - k) = scratch_.bottomRows(n - k).transpose();
	}
}

void RtsStretchRecorder::onUpdate(const Eigen::Ref<const Eigen::MatrixXd>& B, const Eigen::Ref<const Eigen::VectorXd>& u,
								  const Eigen::Ref<const Eigen::MatrixXd>& W)
{
	if (!open_ || current_.broken) return;
	const int k = static_cast<int>(B.rows());
	// M W = X P⁻¹ W = X_{:,1:k} B (and the same for the mean's M).
	const Eigen::MatrixXd MW = X_.leftCols(k) * B, MmW = X_mean_.leftCols(k) * B;
	current_.sum_dx.noalias() += MmW * u;
	current_.sum_dP.noalias() += MW * MW.transpose();
	X_.noalias() -= MW * W.transpose();
	X_mean_.noalias() -= MmW * W.transpose();
}

void RtsStretchRecorder::onOtherChange(const Covariance& P_before, const Covariance& P_after, const TangentVector& dx)
{
	if (!open_ || current_.broken) return;
	// M itself is unchanged (X P⁻¹ before); X follows P, and the change
	// enters the sums as an update's would.
	const Eigen::LLT<Covariance> llt(P_before);
	if (llt.info() != Eigen::Success)
	{
		current_.broken = true;
		return;
	}
	const Covariance M = llt.solve(X_.transpose()).transpose(), Mm = llt.solve(X_mean_.transpose()).transpose();
	current_.sum_dx.noalias() += Mm * dx;
	scratch_.noalias() = M * (P_before - P_after);
	current_.sum_dP.noalias() += scratch_ * M.transpose();
	X_.noalias() = M * P_after;
	X_mean_.noalias() = Mm * P_after;
}

void RtsStretchRecorder::foldTransport(const ManifoldUkf& ukf)
{
	if (!predicted_) return;
	predicted_ = false;
	if (current_.broken) return;
	// M_mean ← M_mean T_t, T_t = I + E on the columns where T_t is not the
	// identity: attitude (velocity, acceleration and currents turn with it)
	// and the accelerometer bias (kept in IMU axes); central differences at
	// a step far below any σ and far above rounding. On X_mean = M_mean P:
	// X_mean += (M_mean E) P, M_mean E = X_mean P⁻¹ E (six columns).
	constexpr double kEps = 1e-6;
	const NavState& x = ukf.state();
	const Covariance& P = ukf.covariance();
	const int n = x.dim();
	Eigen::Matrix<double, Eigen::Dynamic, 6, 0, idx::max_dim, 6> E(n, 6);
	TangentVector e = TangentVector::Zero(n);
	std::array<int, 6> cols{};
	int c = 0;
	for (int first : {static_cast<int>(idx::att), static_cast<int>(idx::acc_bias)})
		for (int i = first; i < first + 3; ++i, ++c)
		{
			e[i] = kEps;
			E.col(c) = (x.boxplus(e).boxminus(x_predicted_) - x.boxplus(-e).boxminus(x_predicted_)) / (2 * kEps);
			E(i, c) -= 1;
			e[i] = 0;
			cols[c] = i;
		}
	const Eigen::LLT<Covariance> llt(P);
	if (llt.info() != Eigen::Success)
	{
		current_.broken = true;
		return;
	}
	const Eigen::Matrix<double, Eigen::Dynamic, 6, 0, idx::max_dim, 6> ME = X_mean_ * llt.solve(E);
	for (int j = 0; j < 6; ++j) X_mean_.noalias() += ME.col(j) * P.row(cols[j]);
}

bool RtsStretchRecorder::predict(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b,
								 const Eigen::Vector3d& omega_ie_n, double dt_s)
{
	if (!open_)
	{
		ukf.predict(omega_ib_b, omega_ie_n, dt_s);
		return true;
	}
	foldTransport(ukf);
	ukf.setStepObserver(this);
	ukf.predict(omega_ib_b, omega_ie_n, dt_s);
	x_predicted_ = ukf.state();
	predicted_ = true;
	++current_.ticks;
	if (ukf.choleskyRepairs() != repairs_at_begin_) current_.broken = true;
	return !current_.broken;
}

RtsStretch RtsStretchRecorder::close(const ManifoldUkf& ukf, double t_s)
{
	foldTransport(ukf);
	RtsStretch done = std::move(current_);
	// A repaired P is not a Bayesian step: the stretch keeps its filtered estimate.
	if (ukf.choleskyRepairs() != repairs_at_begin_) done.broken = true;
	const Eigen::LLT<Covariance> llt(ukf.covariance());
	if (llt.info() != Eigen::Success) done.broken = true;
	if (!done.broken)
	{
		done.M = llt.solve(X_.transpose()).transpose();	// M = X P⁻¹ (P symmetric)
		done.M_mean = llt.solve(X_mean_.transpose()).transpose();
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
