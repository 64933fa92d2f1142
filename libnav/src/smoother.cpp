// Unscented RTS backward pass (smoother.h).
#include <auvnav/smoother.h>
#include <auvnav/so3.h>

#include <Eigen/Cholesky>

namespace auvnav
{
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
	// G = C P⁻⁻¹, i.e. Gᵀ = P⁻⁻¹ Cᵀ (P⁻ symmetric).
	const Covariance G = llt.solve(step.P_cross.transpose()).transpose();
	const TangentVector dx = G * x_next.boxminus(step.x_predicted);
	Covariance P = step.P_filtered;
	P.noalias() += G * (P_next - step.P_predicted) * G.transpose();
	P = 0.5 * (P + P.transpose());
	if (!dx.allFinite() || !P.allFinite() || !(P.diagonal().array() > 0).all()) return false;
	x_out = step.x_filtered.boxplus(dx);
	x_out.R_nb = so3::normalized(x_out.R_nb);
	P_out = P;
	return true;
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

}  // namespace auvnav
