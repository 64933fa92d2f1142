#include <auvnav/so3.h>
#include <auvnav/ukf.h>

#include "covariance_kernels.h"

#include <boost/math/distributions/chi_squared.hpp>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace auvnav
{
namespace
{
// The inertial block and the currents (attitude … position, the two currents)
// predict nonlinearly under the retraction of state.h; the ADCP bias and the
// model parameters are affine and independent of them.
constexpr int kNonlinear = idx::adcp_bias;
// Their blocks (the first kNonlinear coordinates).
constexpr uint32_t kInertialBlocks = kAttitude | kGyroBias | kAcceleration | kGravity | kAccelBias |
                                     kVelocity | kPosition | kCurrentVehicle | kCurrentFar;
// Of those, attitude and gyro bias turn the attitude; along every other
// direction the retraction is a plain difference (InertialStepMap).
constexpr int kTurning = idx::acc;

/** P ← ½(P + Pᵀ), in place over one triangle (the same sums as the
 *  expression, without its temporary: this runs after every step). */
void symmetrize(Covariance& P)
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
bool choleskyColumns(const Covariance& P, int from, int to, Covariance& L, int rows = -1)
{
	return kernels::choleskyColumns(P, from, to, L, rows < 0 ? P.rows() : rows);
}

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

/** r = a ⊟ b for an update's m-vectors: formed here when the model's
 *  residual is the plain difference (residualIsDifference(): the same
 *  subtractions, without a virtual call and three Refs per sigma point,
 *  which cost more than the arithmetic at m ≤ 3), else the model's own. */
class Residuals
{
 public:
	Residuals(const MeasurementFunction& model, int m)
	    : model_(model), plain_(model.residualIsDifference()), m_(m)
	{
	}
	__attribute__((always_inline)) void into(const double* a, const double* b, double* out) const
	{
		if (plain_)
			for (int q = 0; q < m_; ++q) out[q] = a[q] - b[q];
		else
			modelResidual(a, b, out);
	}

 private:
	void modelResidual(const double* a, const double* b, double* out) const
	{
		using ConstMapV = Eigen::Map<const Eigen::VectorXd>;
		model_.residual(ConstMapV(a, m_), ConstMapV(b, m_), Eigen::Map<Eigen::VectorXd>(out, m_));
	}

	const MeasurementFunction& model_;
	const bool plain_;
	const int m_;
};

/** Aᵀ ((k − kn) × m): h's slope along tangent coordinates kn..k−1 of x, the
 *  model's own (MeasurementFunction::affineSlopes) or else by a difference at
 *  the sigma points' step γσᵢ (exact for h affine there), zero for
 *  coordinates of blocks h does not read. z0 = h(x); z_scratch and dz are
 *  overwritten. False, with `why`, if h fails or is not finite. */
bool affineSlopes(const MeasurementFunction& model, const Residuals& residuals, const Measurement& meas,
                  const FilterContext& ctx, const NavState& x, const Covariance& P, double gamma, int kn,
                  int k, const Eigen::Ref<const Eigen::VectorXd>& z0, Eigen::Ref<Eigen::VectorXd> z_scratch,
                  Eigen::Ref<Eigen::VectorXd> dz, Eigen::Ref<Eigen::MatrixXd> At, const char*& why)
{
	const int n = static_cast<int>(P.rows());
	At.setZero();
	if (model.affineSlopes(x, meas, ctx, kn, k, At))
	{
		bool finite = true;
		for (Eigen::Index c = 0; c < At.cols(); ++c)
			finite = finite && allFiniteEntries(At.col(c).data(), At.rows());
		if (finite) return true;
		why = "model returned non-finite affine slopes";
		return false;
	}
	At.setZero();  // a model that declined may have written some
	for (int i = kn; i < k; ++i)
	{
		if (!(blockOfCoordinate(i, n) & model.uses())) continue;
		const double root = gamma * std::sqrt(std::max(P(i, i), 0.0));
		const double h = root > 0 ? root : 1.0;
		const bool ok = model.predict(x.boxplusCoordinate(i, h), meas, ctx, z_scratch);
		if (!ok || !allFiniteEntries(z_scratch.data(), z_scratch.size()))
		{
			why = ok ? "model returned a non-finite h" : "model could not evaluate h";
			return false;
		}
		residuals.into(z_scratch.data(), z0.data(), dz.data());
		At.row(i - kn) = dz.transpose() / h;
	}
	return true;
}

}  // namespace

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
	// the state's units: rad, m/s, m, …): the second step is the sums'
	// rounding, ~1e-13 on the benchmark cut, and a bound of 1e-13 took a
	// third round for it in 2 ticks of 3. The price, measured on the bench's
	// 20 s replay: means 1.3e-8 σ from the dense reference's, not 2.9e-9 σ
	// (a bound relative to each σ was tried: it stopped earlier where σ is
	// large, 1.7e-7 σ).
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

namespace
{
/** Variance β ≥ 0 to add along the normal correction dx = K ν so that the
 *  innovation lands on the gate, or a negative value if no β can (the state
 *  cannot explain ν: blame the aid). With u = H dx = S_x S⁻¹ ν, the innovation
 *  covariance becomes S + β u uᵀ, and by Sherman–Morrison its NIS is
 *  q − β a²/(1 + β b) with q = νᵀS⁻¹ν, a = νᵀS⁻¹u, b = uᵀS⁻¹u. Only S⁻¹ is
 *  needed (never S_x⁻¹, which is near singular when the state hardly moves
 *  the measurement), and the added covariance is bounded by the innovation. */
double inflationAlongCorrection(const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>>& llt_S,
                                const Eigen::Ref<const Eigen::VectorXd>& nu,
                                const Eigen::Ref<const Eigen::VectorXd>& Si_nu,
                                const Eigen::Ref<const Eigen::VectorXd>& u, double gate)
{
	const Eigen::VectorXd Si_u = llt_S.solve(u);
	const double q = nu.dot(Si_nu), a = nu.dot(Si_u), b = u.dot(Si_u);
	const double excess = q - gate;  // > 0: the update failed the gate
	const double denom = a * a - excess * b;
	if (!(b > 0) || !(denom > 1e-12 * a * a)) return -1;  // q − a²/b ≥ gate: out of reach
	return excess / denom;
}
}  // namespace

UpdateResult ManifoldUkf::update(const MeasurementFunction& model, const Measurement& meas,
                                 const FilterContext& ctx, Recovery recovery)
{
	UpdateResult res;
	const int m = static_cast<int>(meas.z.size());
	res.dim = m;
	if (m == 0 || meas.R.rows() != m || meas.R.cols() != m)
	{
		res.why = "measurement and noise sizes disagree";
		return res;
	}
	if (!allFiniteEntries(meas.z) || !allFiniteEntries(meas.R))
	{
		res.why = "non-finite measurement or noise";
		return res;
	}
	const int n = n_;
	const int k = tangentPrefix(model.uses(), n);
	if (k == 0)
	{
		res.why = "model declares no state dependence";
		return res;
	}
	// Blocks h is affine in (measurement_function.h): sigma points only along
	// the first kn Cholesky columns (those that move a non-affine block);
	// the pairs along columns kn..k−1 are ±γ A L_j about z₀, taken from P.
	const uint32_t affine = model.affineIn() & model.uses() & ~static_cast<uint32_t>(kAttitude);
	const int kn = affine ? tangentPrefix(model.uses() & ~affine, n) : k;
	leadingCholeskyColumns(kn);
	const double g = w_.gamma;
	const int count = 2 * kn + 1;
	// Temporaries as Maps into one grow-only buffer (sizes below).
	using MapM = Eigen::Map<Eigen::MatrixXd>;
	using MapV = Eigen::Map<Eigen::VectorXd>;
	const std::size_t scratch_size =
	    static_cast<std::size_t>(m) * (16 + 3 * count + 2 * m + k + 2 * kn + 2 * n + 2 * (k - kn) + kn);
	if (update_scratch_.size() < scratch_size) update_scratch_.resize(scratch_size);
	double* cursor = update_scratch_.data();
	auto takeM = [&](int rows, int cols)
	{
		MapM out(cursor, rows, cols);
		cursor += static_cast<std::ptrdiff_t>(rows) * cols;
		return out;
	};
	auto takeV = [&](int rows)
	{
		MapV out(cursor, rows);
		cursor += rows;
		return out;
	};
	MapM z_sigma = takeM(m, count + 1);  // h at the sigma points; the last column h's scratch
	// Sigma points that move the first k coordinates; the rest evaluate like the centre.
	if (!model.predict(x_, meas, ctx, z_sigma.col(0)))
	{
		res.why = "model could not evaluate h";
		return res;
	}
	// Attitude-heavy columns are evaluated at a shorter step (ukf.h).
	std::array<double, 3> scale{1.0, 1.0, 1.0};
	// Only the blocks h reads are perturbed (its contract, measurement_function.h);
	// the rest of both points holds x's values.
	const uint32_t read_blocks = model.uses();
	if (kn > 0)
	{
		pair_scratch_[0] = x_;
		pair_scratch_[1] = x_;
	}
	for (int j = 0; j < kn; ++j)
	{
		if (j < 3) scale[j] = attitudeTurnScale(g * L_.col(j).head<3>(), ut_.max_attitude_spread_rad);
		const double step = j < 3 ? g * scale[j] : g;
		// (−step)·L_j is −(step·L_j) exactly: the pair is x ⊞ ±step·L_j.
		x_.boxplusPairBlocks(L_.col(j), step, read_blocks, pair_scratch_[0], pair_scratch_[1]);
		for (int s = 0; s < 2; ++s)
			if (!model.predict(pair_scratch_[s], meas, ctx, z_sigma.col(1 + 2 * j + s)))
			{
				res.why = "model could not evaluate h";
				return res;
			}
	}
	if (!allFiniteEntries(z_sigma.data(), static_cast<Eigen::Index>(m) * count))  // columns 0..count−1
	{
		res.why = "model returned a non-finite h";
		return res;
	}
	// Mean in the measurement space, via residuals about the centre (wraps
	// angles): z̄ = z₀ + Σ W_i (z_i ⊟ z₀), the weights summing to one. A
	// scaled pair enters as deviations ±a/s + m from z₀ (no point of its own).
	const double w_center_c = w_.wc0 + 2 * (n - kn) * w_.wi;
	const Residuals residuals(model, m);
	const double* z0 = z_sigma.col(0).data();
	MapV r = takeV(m), z_mean = takeV(m), acc = takeV(m);
	z_mean = z_sigma.col(0);
	acc.setZero();
	// ŷ± of the scaled pairs, about z₀: every update while the heading is
	// unknown (a vehicle without a heading source), so from the arena too.
	MapM D_scaled = takeM(m, 6);
	MapV rm = takeV(m);
	for (int j = 0; j < std::min(kn, 3); ++j)
		if (scale[j] < 1.0)
		{
			residuals.into(z_sigma.col(1 + 2 * j).data(), z0, r.data());
			residuals.into(z_sigma.col(2 + 2 * j).data(), z0, rm.data());
			const double s = scale[j];
			D_scaled.col(2 * j) = 0.5 * (r + rm) + 0.5 * (r - rm) / s;
			D_scaled.col(2 * j + 1) = 0.5 * (r + rm) - 0.5 * (r - rm) / s;
		}
	auto isScaled = [&](int i) { return i >= 1 && i <= 6 && i <= 2 * kn && scale[(i - 1) / 2] < 1.0; };
	for (int i = 1; i < count; ++i)
	{
		if (isScaled(i))
			acc += w_.wi * D_scaled.col(i - 1);
		else
		{
			residuals.into(z_sigma.col(i).data(), z0, r.data());
			for (int q = 0; q < m; ++q) acc[q] += w_.wi * r[q];  // acc += W r, entry by entry
		}
	}
	z_mean += acc;  // centre residual is zero; its weight does not matter
	MapM E = takeM(m, count);
	for (int i = 0; i < count; ++i)
	{
		if (isScaled(i))
			E.col(i) = D_scaled.col(i - 1) - acc;
		else
			residuals.into(z_sigma.col(i).data(), z_mean.data(), E.col(i).data());  // straight into E
	}
	// S = Σ W_i e_i e_iᵀ + R and Pxz = Σ_j W γ L_j (e₊ⱼ − e₋ⱼ)ᵀ, each as one
	// product (not 2k+1 small outer products).
	MapM EW = takeM(m, count);
	EW.col(0) = w_center_c * E.col(0);
	EW.rightCols(count - 1) = w_.wi * E.rightCols(count - 1);
	MapM S = takeM(m, m);
	S = meas.R;
	S.noalias() += EW.lazyProduct(E.transpose());
	MapM D = takeM(m, kn);
	const double wg = w_.wi * g;
	for (int j = 0; j < kn; ++j)  // D_j = W γ (e₊ⱼ − e₋ⱼ), entry by entry (m is small)
		for (int q = 0; q < m; ++q) D(q, j) = wg * (E(q, 1 + 2 * j) - E(q, 2 + 2 * j));
	// Pxz = L_{:,0:kn} Mᵀ (+ the affine pairs' P_{:,kn:k} part below), with M
	// the sigma points' D less, for affine pairs, their share through L_{:,0:kn}.
	MapM M = takeM(m, kn);
	M = D;
	MapM Pxz = takeM(n, m);
	const double c_lin = 2 * w_.wi * g * g;  // 1 up to rounding
	const double* At_data = nullptr;         // Aᵀ below (k − kn × m), for a smoother's B
	if (kn < k)
	{
		// The affine pairs (j ≥ kn): e± = e₀ ± γ A L_{kn:k,j}, so they add
		// 2W γ² A G Aᵀ to S and 2W γ² C Aᵀ to Pxz, with C = Σ_{j≥kn} L_j L_{kn:k,j}ᵀ
		// = P_{:,kn:k} − L_{:,0:kn} L_{kn:k,0:kn}ᵀ and G its rows kn..k−1
		// (C is never formed). A is h's slope along each read coordinate (a
		// difference: exact for an affine h), at the sigma points' own step.
		const int nk = k - kn;
		MapM At = takeM(nk, m);  // Aᵀ: columns contiguous for the dot products
		At_data = At.data();
		if (!affineSlopes(model, residuals, meas, ctx, x_, P_, g, kn, k, z_sigma.col(0), z_sigma.col(count),
		                  takeV(m), At, res.why))
			return res;
		// P_{:,kn:k} Aᵀ as axpys of P's contiguous columns (short dot
		// products per entry cost more in set-up than in arithmetic).
		// Runs of coordinates h reads, up to four of P's columns per pass.
		Pxz.setZero();
		for (int i = 0; i < m; ++i)
		{
			const double* a = At.col(i).data();
			for (int l = 0; l < nk;)
			{
				if (a[l] == 0)
				{
					++l;
					continue;
				}
				int end = l;
				while (end < nk && a[end] != 0) ++end;
				kernels::subtractCombination(Pxz.col(i), P_.middleCols(kn + l, end - l),
				                             (-c_lin) * Eigen::Map<const Eigen::VectorXd>(a + l, end - l));
				l = end;
			}
		}
		// G Aᵀ = P_{kn:k,kn:k} Aᵀ − L_{kn:k,0:kn} (A L_{kn:k,0:kn})ᵀ, for S.
		MapM GAt = takeM(nk, m);
		GAt = Pxz.middleRows(kn, nk);
		if (kn > 0)
		{
			MapM AL = takeM(m, kn);
			AL.noalias() = At.transpose().lazyProduct(L_.block(kn, 0, nk, kn));  // m × kn
			M.noalias() -= c_lin * AL;
			GAt.noalias() -= c_lin * L_.block(kn, 0, nk, kn).lazyProduct(AL.transpose());
		}
		S.noalias() += At.transpose().lazyProduct(GAt);
	}
	else
		Pxz.setZero();
	// n × kn × m, small: a matrix-vector product per measurement coordinate.
	// (kn = 0: h affine in all it reads, no sigma point; M has no storage.)
	if (kn > 0)
		for (int i = 0; i < m; ++i)  // axpys of L's columns (a gemv's set-up costs more at these sizes)
			kernels::subtractCombination(Pxz.col(i), L_.leftCols(kn), -M.row(i).transpose());

	MapV nu = takeV(m);
	residuals.into(meas.z.data(), z_mean.data(), nu.data());
	MapM S_factor = takeM(m, m);  // the LLT's storage (S itself is read again on a recovery)
	S_factor = S;
	Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(S_factor);
	if (llt.info() != Eigen::Success || !allFiniteEntries(nu))
	{
		res.why = "innovation covariance not positive definite";
		return res;
	}
	{
		MapV Si_nu = takeV(m);
		Si_nu = nu;
		llt.solveInPlace(Si_nu);
		res.nis = nu.dot(Si_nu);
	}
	res.innovation = nu;
	const double gate = chiSquareQuantile(m, model.gateProbability());
	if (res.nis > gate)
	{
		if (recovery == Recovery::None)
		{
			res.status = UpdateStatus::Rejected;
			res.why = "chi-square gate";
			return res;
		}
		res.status = UpdateStatus::Recovered;
		bool widened = false;
		if (recovery == Recovery::State)
		{
			// The normal correction dx = Pxz S⁻¹ ν and what it does to z,
			// u = H dx = S_x S⁻¹ ν (S_x = S − R, the state's share of S).
			const Eigen::VectorXd Si_nu = llt.solve(nu);
			const TangentVector dx0 = Pxz * Si_nu;
			const Eigen::VectorXd u = (S - meas.R) * Si_nu;
			const double beta = inflationAlongCorrection(llt, nu, Si_nu, u, gate);
			if (beta > 0 && std::isfinite(beta) && dx0.allFinite())
			{
				// P' = P + β dx dxᵀ; then Pxz' = Pxz + β dx uᵀ, S' = S + β u uᵀ.
				const TangentVector v = std::sqrt(beta) * dx0;  // v vᵀ: exactly symmetric
				P_.noalias() += v * v.transpose();
				Pxz.noalias() += beta * dx0 * u.transpose();
				S.noalias() += beta * u * u.transpose();
				widened = true;
			}
		}
		if (!widened) S *= res.nis / gate;  // the aid blamed: the innovation on the gate boundary
		llt.compute(S);
		if (llt.info() != Eigen::Success)
		{
			res.status = UpdateStatus::Invalid;
			res.why = "innovation covariance not positive definite";
			return res;
		}
	}
	else
		res.status = UpdateStatus::Accepted;
	// With S = L Lᵀ and W = Pxz L⁻ᵀ: dx = K ν = W (L⁻¹ ν) and
	// P −= K S Kᵀ = W Wᵀ, a rank-m downdate (P
	// stays exactly symmetric: no symmetrize pass).
	MapM W = takeM(n, m);
	W = Pxz;
	// W Lᵀ = Pxz column by column (forward substitution as axpys: the
	// blocked triangular solver packs its operands, costly for m ≤ 6).
	const auto& L_S = llt.matrixLLT();  // L in its lower triangle
	kernels::solveRightLowerTransposed(kernels::columns(W.data(), n, m, n), L_S);
	MapV u = takeV(m);
	u = nu;
	llt.matrixL().solveInPlace(u);
	TangentVector dx = TangentVector::Zero(n);
	kernels::subtractCombination(dx, W, -u);
	x_ = x_.boxplus(dx);
	x_.R_nb = so3::normalized(x_.R_nb);
	kernels::downdateSymmetric(P_, W);
	if (observer_)
	{
		// P⁻¹ W = P⁻¹ Pxz L_S⁻ᵀ with Pxz = L_{:,0:kn} Mᵀ + c P_{:,kn:k} Aᵀ
		// (above) and P_{:,0:kn} = L_{:,0:kn} L11ᵀ (L11: L's leading kn × kn
		// block), so P⁻¹ Pxz = [L11⁻ᵀ Mᵀ; c Aᵀ; 0]. That needs only the
		// columns the filter factored anyway: none past kn, and P B = W holds
		// even where P is not positive definite past them.
		// A recovery's widening P += β dx dxᵀ is reported as nothing: to a
		// smoother it is process noise added at this tick (it leaves the
		// cross covariance with past states as it is). With P, Pxz and S
		// widened together, B is the same expression: exactly so for an h
		// linear over the spread (u = H dx then), else to first order.
		// In the update's arena, by the same solve as W (B L_Sᵀ = that), then
		// L11ᵀ B_top = that by back substitution.
		MapM B = takeM(k, m);
		B.topRows(kn) = M.transpose();
		if (kn < k) B.bottomRows(k - kn) = c_lin * Eigen::Map<const Eigen::MatrixXd>(At_data, k - kn, m);
		kernels::solveRightLowerTransposed(kernels::columns(B.data(), k, m, k), L_S);
		kernels::solveLeftLowerTransposed(kernels::columns(B.data(), kn, m, k),
		                                  kernels::columns(L_.data(), kn, kn, L_.outerStride()));
		observer_->onUpdate(B, u, W);
	}
	applySigmaLimits();
	return res;
}

}  // namespace auvnav
