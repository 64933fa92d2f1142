#include <auvnav/so3.h>
#include <auvnav/ukf.h>

#include "covariance_kernels.h"
#include "ukf_detail.h"

#include <boost/math/distributions/chi_squared.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace auvnav
{
using namespace ukf_detail;

double attitudeSpreadScale(const Eigen::Ref<const TangentVector>& c, double max_rad)
{
	return attitudeTurnScale(c.head<3>(), max_rad);
}

double attitudeTurnScale(const Eigen::Vector3d& turn_rad, double max_rad)
{
	const double turn = turn_rad.norm();
	return turn > max_rad ? max_rad / turn : 1.0;
}

UtWeights UtWeights::make(int dim, const UtParams& p)
{
	UtWeights w;
	const double lambda = p.alpha * p.alpha * (dim + p.kappa) - dim;
	w.gamma = std::sqrt(dim + lambda);
	w.wm0 = lambda / (dim + lambda);
	w.wc0 = w.wm0 + 1 - p.alpha * p.alpha + p.beta;
	w.wi = 1.0 / (2 * (dim + lambda));
	return w;
}

double ManifoldUkf::chiSquareQuantile(int dof, double p)
{
	static std::mutex mutex;
	static std::map<std::pair<int, double>, double> cache;
	std::lock_guard<std::mutex> lock(mutex);
	const auto key = std::make_pair(dof, p);
	auto it = cache.find(key);
	if (it != cache.end()) return it->second;
	const double q = p >= 1.0 ? INFINITY : boost::math::quantile(boost::math::chi_squared(dof), p);
	cache.emplace(key, q);
	return q;
}

ManifoldUkf::ManifoldUkf(const ProcessModel& model, const UtParams& ut)
    : model_(model), ut_(ut), w_(UtWeights::make(model.dim(), ut)), n_(model.dim())
{
}

void ManifoldUkf::initialize(const NavState& x0, const Covariance& P0)
{
	if (P0.rows() != x0.dim() || P0.cols() != x0.dim() || x0.dim() != model_.dim())
		throw std::invalid_argument("ManifoldUkf::initialize: state of " + std::to_string(x0.dim()) +
		                            " coordinates, covariance " + std::to_string(P0.rows()) + "x" +
		                            std::to_string(P0.cols()) + ", process model " +
		                            std::to_string(model_.dim()));
	n_ = x0.dim();
	w_ = UtWeights::make(n_, ut_);
	variance_floor_ = (1e-12 * P0.diagonal()).cwiseMax(1e-30);
	L_.setZero(n_, n_);
	x_ = x0;
	P_ = P0;
	symmetrize(P_);
}

void ManifoldUkf::restore(const NavState& x, const Covariance& P)
{
	if (x.dim() != n_ || P.rows() != n_ || P.cols() != n_)
		throw std::invalid_argument("ManifoldUkf::restore: a state of " + std::to_string(x.dim()) +
		                            " coordinates for a filter of " + std::to_string(n_));
	x_ = x;
	P_ = P;
	symmetrize(P_);  // the prediction relies on it (a checkpoint's P already is)
}

void repairCovariance(Covariance& P, const TangentVector& variance_floor)
{
	symmetrize(P);
	TangentVector sigma(P.rows());
	for (int i = 0; i < P.rows(); ++i)
	{
		if (!(std::isfinite(P(i, i)) && P(i, i) > 0))
		{
			// Nothing to keep: decorrelate the state and give it its floor.
			P.row(i).setZero();
			P.col(i).setZero();
			P(i, i) = variance_floor[i];
		}
		sigma[i] = std::sqrt(P(i, i));
	}
	Covariance C = sigma.cwiseInverse().asDiagonal() * P * sigma.cwiseInverse().asDiagonal();
	Eigen::SelfAdjointEigenSolver<Covariance> es(C);
	const TangentVector ev = es.eigenvalues().cwiseMax(1e-9);
	C = es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
	// Unit diagonal again: a congruence by a positive diagonal keeps C PD.
	const TangentVector scale = sigma.cwiseQuotient(C.diagonal().cwiseSqrt());
	P = scale.asDiagonal() * C * scale.asDiagonal();
	symmetrize(P);
}

namespace
{
/** The variance a positive, finite `var` is limited to by σ bounds [lo, hi]
 *  (var itself when inside them). */
double limitedVariance(double var, double lo, double hi)
{
	if (var < lo * lo) return lo * lo;
	if (var > hi * hi) return hi * hi;
	return var;
}
/** Whether limitSigmas would move any variance of P (a diagonal entry that
 *  is not positive and finite is repairCovariance's case, not a limit's). */
bool anySigmaLimitHit(const Covariance& P, const TangentVector& min_sigma, const TangentVector& max_sigma)
{
	for (int i = 0; i < P.rows(); ++i)
	{
		const double var = P(i, i);
		if (var > 0 && std::isfinite(var) && limitedVariance(var, min_sigma[i], max_sigma[i]) != var)
			return true;
	}
	return false;
}
}  // namespace

int limitSigmas(Covariance& P, const TangentVector& min_sigma, const TangentVector& max_sigma)
{
	int moved = 0;
	for (int i = 0; i < P.rows(); ++i)
	{
		const double var = P(i, i);
		if (!(var > 0) || !std::isfinite(var)) continue;  // repairCovariance's case
		const double target = limitedVariance(var, min_sigma[i], max_sigma[i]);
		if (target == var) continue;
		const double s = std::sqrt(target / var);
		P.row(i) *= s;
		P.col(i) *= s;  // P(i, i) scaled by s² in all: exactly the target (to rounding)
		P(i, i) = target;
		++moved;
	}
	return moved;
}

void ManifoldUkf::setSigmaLimits(const TangentVector& min_sigma, const TangentVector& max_sigma)
{
	if (min_sigma.size() == 0 && max_sigma.size() == 0)
	{
		min_sigma_.resize(0);
		max_sigma_.resize(0);
		return;
	}
	if (min_sigma.size() != n_ || max_sigma.size() != n_)
		throw std::invalid_argument(
		    "ManifoldUkf::setSigmaLimits: bounds of " + std::to_string(min_sigma.size()) + " and " +
		    std::to_string(max_sigma.size()) + " states for a filter of " + std::to_string(n_));
	for (int i = 0; i < n_; ++i)
		if (!(min_sigma[i] >= 0) || !(max_sigma[i] >= min_sigma[i]))
			throw std::invalid_argument("ManifoldUkf::setSigmaLimits: state " + std::to_string(i) +
			                            ": need 0 <= min_sigma <= max_sigma");
	min_sigma_ = min_sigma;
	max_sigma_ = max_sigma;
}

void ManifoldUkf::applySigmaLimits(bool report)
{
	if (min_sigma_.size() != n_) return;
	if (observer_ && report)
	{
		// The observer needs P before a change, and there is almost never
		// one: no copy of P (n² doubles) after every update for nothing.
		if (!anySigmaLimitHit(P_, min_sigma_, max_sigma_)) return;
		P_before_ = P_;
	}
	const int hits = limitSigmas(P_, min_sigma_, max_sigma_);
	sigma_limit_hits_ += static_cast<std::size_t>(hits);
	if (observer_ && report && hits) observer_->onOtherChange(P_before_, P_, TangentVector::Zero(n_));
}

void ManifoldUkf::repairCovariance()
{
	auvnav::repairCovariance(P_, variance_floor_);
	++repairs_;
}

void ManifoldUkf::leadingCholeskyColumns(int k, int whole_columns)
{
	const int n = n_;
	if (L_.rows() != n) L_.setZero(n, n);
	if (whole_columns < 0 || whole_columns > k) whole_columns = k;
	for (int attempt = 0; attempt < 2; ++attempt)
	{
		if (choleskyColumns(P_, 0, whole_columns, L_) && choleskyColumns(P_, whole_columns, k, L_, k)) return;
		repairCovariance();
	}
	// Still not PD after repair (pathological): fall back to the diagonal.
	L_.leftCols(k).setZero();
	for (int j = 0; j < k; ++j) L_(j, j) = std::sqrt(std::max(P_(j, j), 1e-15));
}

}  // namespace auvnav
