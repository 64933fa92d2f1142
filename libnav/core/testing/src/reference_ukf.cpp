// The plain dense reference UKF (see reference_ukf.h). Deliberately simple.
#include <auvnav/testing/reference_ukf.h>

#include <Eigen/Cholesky>
#include <stdexcept>

namespace auvnav::reference
{
SigmaWeights SigmaWeights::fromUt(const UtWeights& u, int n)
{
	SigmaWeights w;
	w.gamma = u.gamma;
	w.wm.assign(2 * n + 1, u.wi);
	w.wc.assign(2 * n + 1, u.wi);
	w.wm[0] = u.wm0;
	w.wc[0] = u.wc0;
	return w;
}

SigmaWeights SigmaWeights::uniform(double gamma, int n)
{
	SigmaWeights w;
	w.gamma = gamma;
	w.wm.assign(2 * n + 1, 1.0 / (2 * n + 1));
	w.wc = w.wm;
	return w;
}

std::vector<double> spreadScales(const Covariance& P, double gamma, double max_rad)
{
	const Covariance L = Eigen::LLT<Covariance>(P).matrixL();
	std::vector<double> s(P.rows());
	for (int j = 0; j < P.rows(); ++j) s[j] = attitudeSpreadScale(gamma * L.col(j), max_rad);
	return s;
}

std::vector<NavState> sigmaPoints(const NavState& x, const Covariance& P, double gamma,
                                  const std::vector<double>& scale)
{
	const Eigen::LLT<Covariance> llt(P);
	if (llt.info() != Eigen::Success) throw std::runtime_error("reference UKF: P is not positive definite");
	const Covariance L = llt.matrixL();
	std::vector<NavState> X;
	X.reserve(2 * P.rows() + 1);
	X.push_back(x);
	for (int j = 0; j < P.rows(); ++j)
	{
		const TangentVector c = gamma * (scale.empty() ? 1.0 : scale[j]) * L.col(j);
		X.push_back(x.boxplus(c));
		X.push_back(x.boxplus(-c));
	}
	return X;
}

NavState manifoldMean(const std::vector<NavState>& X, const std::vector<double>& w, const NavState& start)
{
	NavState mean = start;
	for (int iter = 0; iter < 50; ++iter)
	{
		TangentVector d = TangentVector::Zero(start.dim());
		for (std::size_t i = 0; i < X.size(); ++i) d += w[i] * X[i].boxminus(mean);
		mean = mean.boxplus(d);
		if (iter > 0 && d.head<3>().norm() < 1e-15) break;
	}
	return mean;
}

void unscentedPredict(const ProcessModel& model, const NavState& x, const Covariance& P,
                      const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n, double dt,
                      const SigmaWeights& w, NavState& x_out, Covariance& P_out, double max_spread_rad,
                      Covariance* P_cross)
{
	const std::vector<double> scale = spreadScales(P, w.gamma, max_spread_rad);
	const std::vector<NavState> X = sigmaPoints(x, P, w.gamma, scale);
	std::vector<NavState> Y = X;
	for (auto& y : Y) y = model.propagate(y, omega_ib_b, omega_ie_n, dt);
	// A scaled pair (ukf.h) has no point of its own: its deviations from Y_0
	// are ŷ± = ±a/s + m, and from a mean x̄ they are ŷ± − (x̄ ⊟ Y_0).
	const int n = static_cast<int>(P.rows());
	std::vector<TangentVector> D(Y.size(), TangentVector::Zero(n));
	for (int j = 0; j < n; ++j)
		if (scale[j] < 1.0)
		{
			const TangentVector yp = Y[1 + 2 * j].boxminus(Y[0]), ym = Y[2 + 2 * j].boxminus(Y[0]);
			const TangentVector a = 0.5 * (yp - ym) / scale[j], m = 0.5 * (yp + ym);
			D[1 + 2 * j] = m + a;
			D[2 + 2 * j] = m - a;
		}
	auto deviation = [&](std::size_t i, const NavState& mean) -> TangentVector
	{
		const bool scaled = i > 0 && scale[(i - 1) / 2] < 1.0;
		return scaled ? TangentVector(D[i] - mean.boxminus(Y[0])) : Y[i].boxminus(mean);
	};
	NavState mean = Y[0];
	for (int iter = 0; iter < 50; ++iter)
	{
		TangentVector d = TangentVector::Zero(n);
		for (std::size_t i = 0; i < Y.size(); ++i) d += w.wm[i] * deviation(i, mean);
		mean = mean.boxplus(d);
		if (iter > 0 && d.head<3>().norm() < 1e-15) break;
	}
	Covariance Pn = Covariance::Zero(n, n);
	for (std::size_t i = 0; i < Y.size(); ++i)
	{
		const TangentVector d = deviation(i, mean);
		Pn += w.wc[i] * d * d.transpose();
	}
	if (P_cross)
	{
		// State deviations as in unscentedTransform: a scaled pair at its full step ±γ L_j.
		const Covariance L = Eigen::LLT<Covariance>(P).matrixL();
		P_cross->setZero(n, n);
		for (std::size_t i = 1; i < Y.size(); ++i)
		{
			const int j = static_cast<int>(i - 1) / 2;
			const TangentVector dx =
			    scale[j] < 1.0 ? TangentVector(((i % 2) ? w.gamma : -w.gamma) * L.col(j)) : X[i].boxminus(x);
			*P_cross += w.wc[i] * dx * deviation(i, mean).transpose();
		}
	}
	const double speed_through_water = (x.v_n.head<2>() - x.current_vehicle_ne).norm();
	Pn += model.noiseCovariance(dt, speed_through_water, x.v_n.z());
	x_out = mean;
	P_out = 0.5 * (Pn + Pn.transpose());
}

bool unscentedTransform(const NavState& x, const Covariance& P, const MeasurementFunction& h,
                        const Measurement& m, const FilterContext& ctx, const SigmaWeights& w, UtResult& out,
                        double max_spread_rad)
{
	const int dim_z = static_cast<int>(m.z.size());
	const std::vector<double> scale = spreadScales(P, w.gamma, max_spread_rad);
	const std::vector<NavState> X = sigmaPoints(x, P, w.gamma, scale);
	const int count = static_cast<int>(X.size());
	Eigen::MatrixXd Z(dim_z, count);
	for (int i = 0; i < count; ++i)
		if (!h.predict(X[i], m, ctx, Z.col(i))) return false;
	// A scaled pair: measurement deviations ±a/s + m about z_0, and state
	// deviations ±γ L_j at the full step (ukf.h).
	auto scaled = [&](int i) { return i > 0 && scale[(i - 1) / 2] < 1.0; };
	Eigen::MatrixXd Dz = Eigen::MatrixXd::Zero(dim_z, count);
	Eigen::VectorXd r(dim_z), rm(dim_z);
	for (int j = 0; j < P.rows(); ++j)
		if (scale[j] < 1.0)
		{
			h.residual(Z.col(1 + 2 * j), Z.col(0), r);
			h.residual(Z.col(2 + 2 * j), Z.col(0), rm);
			const Eigen::VectorXd a = 0.5 * (r - rm) / scale[j], mid = 0.5 * (r + rm);
			Dz.col(1 + 2 * j) = mid + a;
			Dz.col(2 + 2 * j) = mid - a;
		}
	// Mean in the measurement space (the residual is its ⊟): iterate.
	Eigen::VectorXd z_mean = Z.col(0);
	auto zdev = [&](int i, const Eigen::VectorXd& about, Eigen::VectorXd& out_r)
	{
		if (scaled(i))
		{
			Eigen::VectorXd shift(dim_z);
			h.residual(about, Z.col(0), shift);
			out_r = Dz.col(i) - shift;
		}
		else
			h.residual(Z.col(i), about, out_r);
	};
	for (int iter = 0; iter < 50; ++iter)
	{
		Eigen::VectorXd d = Eigen::VectorXd::Zero(dim_z);
		for (int i = 0; i < count; ++i)
		{
			zdev(i, z_mean, r);
			d += w.wm[i] * r;
		}
		z_mean += d;
		if (iter > 0 && d.norm() <= 1e-14 * (1 + z_mean.norm())) break;
	}
	out.z_mean = z_mean;
	out.Pzz = Eigen::MatrixXd::Zero(dim_z, dim_z);
	out.Pxz = Eigen::MatrixXd::Zero(P.rows(), dim_z);
	const Covariance L = Eigen::LLT<Covariance>(P).matrixL();
	for (int i = 0; i < count; ++i)
	{
		zdev(i, z_mean, r);
		out.Pzz += w.wc[i] * r * r.transpose();
		const TangentVector dx = i == 0 ? TangentVector::Zero(P.rows()).eval()
		                         : scaled(i)
		                             ? TangentVector(((i % 2) ? w.gamma : -w.gamma) * L.col((i - 1) / 2))
		                             : X[i].boxminus(x);
		out.Pxz += w.wc[i] * dx * r.transpose();
	}
	return true;
}

ReferenceUkf::ReferenceUkf(const ProcessModel& model, const UtParams& ut)
    : model_(model),
      ut_(ut),
      w_(SigmaWeights::fromUt(UtWeights::make(model.dim(), ut), model.dim())),
      max_spread_rad_(ut.max_attitude_spread_rad)
{
}

void ReferenceUkf::initialize(const NavState& x0, const Covariance& P0)
{
	if (P0.rows() != x0.dim() || x0.dim() != model_.dim())
		throw std::invalid_argument("reference UKF: state, covariance and process model disagree in size");
	w_ = SigmaWeights::fromUt(UtWeights::make(x0.dim(), ut_), x0.dim());
	x_ = x0;
	P_ = 0.5 * (P0 + P0.transpose());
}

void ReferenceUkf::predict(const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n, double dt,
                           Covariance* P_cross)
{
	unscentedPredict(model_, x_, P_, omega_ib_b, omega_ie_n, dt, w_, x_, P_, max_spread_rad_, P_cross);
}

bool ReferenceUkf::update(const MeasurementFunction& model, const Measurement& m, const FilterContext& ctx)
{
	UtResult ut;
	if (!unscentedTransform(x_, P_, model, m, ctx, w_, ut, max_spread_rad_)) return false;
	const Eigen::MatrixXd S = ut.Pzz + m.R;
	const Eigen::LLT<Eigen::MatrixXd> llt(S);
	if (llt.info() != Eigen::Success) return false;
	Eigen::VectorXd nu(m.z.size());
	model.residual(m.z, ut.z_mean, nu);
	const Eigen::MatrixXd K = llt.solve(ut.Pxz.transpose()).transpose();  // K = Pxz S⁻¹
	x_ = x_.boxplus(K * nu);
	const Covariance Pn = P_ - K * S * K.transpose();
	P_ = 0.5 * (Pn + Pn.transpose());
	return true;
}

}  // namespace auvnav::reference
