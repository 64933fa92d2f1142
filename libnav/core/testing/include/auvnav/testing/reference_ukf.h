#pragma once
/** @file reference_ukf.h
 *  The test oracle: a PLAIN dense scaled UKF on the manifold state (43 + any
 *  plugin-owned states).
 *
 *  Written independently of ukf.cpp and on purpose without any of its
 *  shortcuts: full Cholesky factor of P, all 2n+1 = 87 sigma points, the full
 *  nonlinear ProcessModel::propagate on every sigma point, h on every sigma
 *  point, iterated manifold means. Only UtWeights::make, attitudeSpreadScale,
 *  the process model and the state's ⊞/⊟ are shared with the code under test.
 */
#include <auvnav/measurement_function.h>
#include <auvnav/process_model.h>
#include <auvnav/state.h>
#include <auvnav/ukf.h>

#include <Eigen/Core>
#include <vector>

namespace auvnav::reference
{
/** Sigma-point spread and one mean and one covariance weight per point. */
struct SigmaWeights
{
	double gamma = 0;
	std::vector<double> wm, wc;  // 2n+1 each; point 0 is the centre
	static SigmaWeights fromUt(const UtWeights& u, int n);
	/** A deliberately WRONG weighting for the "the test can fail" checks:
	 *  the same sigma points, all weights 1/(2n+1). */
	static SigmaWeights uniform(double gamma, int n);
};

/** X_0 = x, X_{2j+1} = x ⊞ γ s_j L_j, X_{2j+2} = x ⊞ −γ s_j L_j, L = chol(P)
 *  (lower), s_j = 1 or the attitude-spread scale of ukf.h (`scale`, empty: 1). */
std::vector<NavState> sigmaPoints(const NavState& x, const Covariance& P, double gamma,
                                  const std::vector<double>& scale = {});
/** s_j of every column (ukf.h: attitudeSpreadScale of γ L_j). */
std::vector<double> spreadScales(const Covariance& P, double gamma, double max_rad);

/** Weighted mean on the manifold: iterate x̄ ← x̄ ⊞ Σ w_i (X_i ⊟ x̄). */
NavState manifoldMean(const std::vector<NavState>& X, const std::vector<double>& w, const NavState& start);

/** Unscented transform of a measurement function (no noise added). */
struct UtResult
{
	Eigen::VectorXd z_mean;
	Eigen::MatrixXd Pzz;  // Σ Wc r rᵀ, r = z_i ⊟ z̄
	Eigen::MatrixXd Pxz;  // Σ Wc (X_i ⊟ x)(z_i ⊟ z̄)ᵀ
};
bool unscentedTransform(const NavState& x, const Covariance& P, const MeasurementFunction& h,
                        const Measurement& m, const FilterContext& ctx, const SigmaWeights& w, UtResult& out,
                        double max_spread_rad = UtParams{}.max_attitude_spread_rad);

/** Unscented prediction: mean and covariance of propagate(X_i) plus Q. */
void unscentedPredict(const ProcessModel& model, const NavState& x, const Covariance& P,
                      const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n, double dt_s,
                      const SigmaWeights& w, NavState& x_out, Covariance& P_out,
                      double max_spread_rad = UtParams{}.max_attitude_spread_rad,
                      Covariance* P_cross = nullptr);

class ReferenceUkf
{
 public:
	ReferenceUkf(const ProcessModel& model, const UtParams& ut);
	void initialize(const NavState& x0, const Covariance& P0);
	const NavState& state() const { return x_; }
	const Covariance& covariance() const { return P_; }

	/** P_cross, if given: Cov(x_k, x_k+1) over all 2n+1 sigma points (the
	 *  smoother's oracle, smoother.h). */
	void predict(const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n, double dt_s,
	             Covariance* P_cross = nullptr);
	/** Ungated update; false if h could not be evaluated or S is not PD. */
	bool update(const MeasurementFunction& model, const Measurement& m, const FilterContext& ctx);

 private:
	ProcessModel model_;
	UtParams ut_;
	SigmaWeights w_;
	double max_spread_rad_;
	NavState x_;
	Covariance P_ = Covariance::Identity(idx::core_dim, idx::core_dim);
};

}  // namespace auvnav::reference
