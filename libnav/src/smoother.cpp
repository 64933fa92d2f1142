// Unscented RTS backward pass (smoother.h).
#include <auvnav/smoother.h>
#include <auvnav/so3.h>

#include <Eigen/Cholesky>

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
	current_.M = Covariance::Identity(n, n);
	current_.M_mean = Covariance::Identity(n, n);
	current_.sum_dx = TangentVector::Zero(n);
	current_.sum_dP = Covariance::Zero(n, n);
	open_ = true;
	predicted_ = false;
}

void RtsStretchRecorder::foldUpdates(const ManifoldUkf& ukf)
{
	// Tick t's updates: dx_t = x_t ⊟ x⁻_t and ΔP_t = P⁻_t − P_t, carried back by M_t.
	if (!predicted_) return;
	const NavState& x = ukf.state();
	const TangentVector dx = x.boxminus(x_predicted_);
	current_.sum_dx.noalias() += current_.M_mean * dx;
	scratch_.noalias() = current_.M * (P_predicted_ - ukf.covariance());
	current_.sum_dP.noalias() += scratch_ * current_.M.transpose();
	// M_mean ← M_mean T_t on the columns where T_t is not the identity:
	// attitude (velocity, acceleration and currents turn with it) and the
	// accelerometer bias (kept in IMU axes). Central differences at a step
	// far below any σ and far above rounding.
	constexpr double kEps = 1e-6;
	const int n = x.dim();
	Eigen::Matrix<double, Eigen::Dynamic, 6, 0, idx::max_dim, 6> T(n, 6);
	TangentVector e = TangentVector::Zero(n);
	int c = 0;
	for (int first : {static_cast<int>(idx::att), static_cast<int>(idx::acc_bias)})
		for (int i = first; i < first + 3; ++i, ++c)
		{
			e[i] = kEps;
			T.col(c) = (x.boxplus(e).boxminus(x_predicted_) - x.boxplus(-e).boxminus(x_predicted_)) / (2 * kEps);
			e[i] = 0;
		}
	const Eigen::Matrix<double, Eigen::Dynamic, 6, 0, idx::max_dim, 6> MT = current_.M_mean * T;
	current_.M_mean.middleCols<3>(idx::att) = MT.leftCols<3>();
	current_.M_mean.middleCols<3>(idx::acc_bias) = MT.rightCols<3>();
	predicted_ = false;
}

bool RtsStretchRecorder::predict(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b,
								 const Eigen::Vector3d& omega_ie_n, double dt_s)
{
	if (!open_)
	{
		ukf.predict(omega_ib_b, omega_ie_n, dt_s);
		return true;
	}
	foldUpdates(ukf);
	ukf.predict(omega_ib_b, omega_ie_n, dt_s, &P_cross_);
	x_predicted_ = ukf.state();
	P_predicted_ = ukf.covariance();
	predicted_ = true;
	++current_.ticks;
	if (current_.broken) return false;	// the stretch keeps its filtered estimate anyway
	const Eigen::LLT<Covariance> llt(P_predicted_);
	if (llt.info() != Eigen::Success)
	{
		current_.broken = true;
		return false;
	}
	G_ = rtsGain(llt, P_cross_);
	scratch_.noalias() = current_.M * G_;
	current_.M.swap(scratch_);
	scratch_.noalias() = current_.M_mean * G_;
	current_.M_mean.swap(scratch_);
	return true;
}

RtsStretch RtsStretchRecorder::close(const ManifoldUkf& ukf, double t_s)
{
	foldUpdates(ukf);
	RtsStretch done = std::move(current_);
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
