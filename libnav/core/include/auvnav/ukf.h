#pragma once
/** @file ukf.h
 *  The manifold Unscented Kalman Filter on SO(3) × R⁴⁰ × R^e (state.h; e
 *  plugin-owned states, fixed at initialize()).
 *
 *  Scaled unscented transform (Wan & van der Merwe): λ = α²(n+κ) − n, sigma
 *  points x̄ ⊞ ±√(n+λ)·L_j with L the lower Cholesky factor of P (state order
 *  of state.h), W_m0 = λ/(n+λ), W_c0 = W_m0 + 1 − α² + β, W_i = 1/(2(n+λ)).
 *  Means on the manifold are iterated; the innovation covariance is solved by
 *  LLT, never inverted; P is kept symmetric.
 *
 *  Speed without approximation. Sigma points along Cholesky columns j ≥ k
 *  leave the first k tangent coordinates unchanged. So
 *   - prediction: only the inertial block and the currents (k = 23: attitude,
 *     biases, acceleration, gravity, velocity, position, currents) propagate
 *     nonlinearly; the remaining 20 coordinates (ADCP bias, model parameters)
 *     are affine and independent, whose unscented transform is exactly
 *     A P Aᵀ. Within the 23, a pair along a column past the gyro bias's
 *     keeps the centre's turn, and there the step is J δ + q(δ) exactly (J
 *     linear, q the current transport's second-order part), so those pairs'
 *     sums enter in closed form: 13 sigma points are propagated instead of
 *     87;
 *   - update: a model whose h reads only the first k coordinates (from its
 *     `uses()` mask) needs 2k+1 evaluations and the first k Cholesky columns.
 *  Both give the same numbers as the dense 87-point UKF (auvnav::core_testing keeps
 *  a plain dense implementation as the oracle).
 *
 *  Large attitude uncertainty. A sigma point turned by π or more about any
 *  axis is the same rotation as one turned by less (a heading σ of 180° at
 *  γ ≈ 2 puts the pair at ±354°, i.e. at ∓6°), so the spread recovered by ⊟
 *  collapsed: a heading σ of 180° became 3° in one prediction, information
 *  the filter never had. So a sigma-point pair whose attitude step γ‖L_j,att‖
 *  exceeds `max_attitude_spread_rad` is evaluated at the step scaled down to
 *  that angle (s_j < 1), and its first-order (antisymmetric) part is scaled
 *  back up by 1/s_j; the second-order (symmetric) part is kept as measured at
 *  the shorter step. For a function linear in the state this is exact; below
 *  the limit nothing changes. The default limit, 30° (reached at an attitude
 *  σ of 15° with α = 0.3), is where the pair's secant slope is still 95 % of
 *  the tangent's (sin 30°/(π/6)): gyrocompassing from a heading 180° off with
 *  σ 180° converged from all of 0, ±45, ±90, ±135, 180° with it (< 0.3° after
 *  15 min, heading mission, seed 1), while at 90° (secant 64 %, a large
 *  symmetric part) the σ fell to 6° at 139° of error within 10 s. Only the
 *  first three Cholesky columns have attitude rows, so at most three pairs
 *  are ever scaled.
 *
 *  A Cholesky failure is repaired (symmetrise, clip eigenvalues) and counted.
 */
#include <auvnav/measurement_function.h>
#include <auvnav/process_model.h>
#include <auvnav/state.h>

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace auvnav
{
struct UtParams
{
	double alpha = 0.3, beta = 2.0, kappa = 0.0;
	double max_attitude_spread_rad = 0.5235987755982988;  //!< largest sigma-point turn, 30° (see above)
};

/** Scale s ∈ (0, 1] of a sigma-point step `c` (tangent order of state.h) so
 *  that its attitude part turns by at most `max_rad`. */
double attitudeSpreadScale(const Eigen::Ref<const TangentVector>& c, double max_rad);
/** The same from the step's attitude part alone (no full step formed). */
double attitudeTurnScale(const Eigen::Vector3d& turn_rad, double max_rad);

/** Sigma-point weights for dimension n. */
struct UtWeights
{
	double gamma = 0;  //!< √(n+λ)
	double wm0 = 0, wc0 = 0, wi = 0;
	static UtWeights make(int dim, const UtParams& p);
};

enum class UpdateStatus
{
	Accepted,
	Recovered,  //!< accepted on the gate boundary after a run of rejections (see Recovery)
	Rejected,   //!< failed the χ² gate
	Invalid     //!< non-finite z/R/h, wrong size, or singular innovation covariance
};

/** How an update that fails the χ² gate is applied anyway (re-acquisition).
 *  Both put the innovation on the gate boundary; they differ in whom they
 *  blame. */
enum class Recovery
{
	None,  //!< gate as usual
	//! The aid may be off: the whole innovation covariance is scaled up, so
	//! the state moves by at most what the gate allows (a small step when the
	//! state's σ is small). For a long run of rejections of unknown cause.
	Noise,
	//! The state is off: its covariance is widened along the normal
	//! correction dx = K ν (P += β dx dxᵀ, β the smallest that puts the
	//! innovation on the gate; closed form, ukf.cpp), then a normal update.
	//! For rejections of an absolute attitude/position aid that agree with
	//! each other (rejection_streak.h, aiding_policy.h): an over-confident
	//! heading is pulled to the magnetometer however small its σ had become. Falls back to Noise when no β
	//! can (the state cannot explain the innovation).
	State
};

struct UpdateResult
{
	UpdateStatus status = UpdateStatus::Invalid;
	double nis = 0;  //!< normalised innovation squared
	int dim = 0;     //!< measurement dimension
	const char* why = "";
	Eigen::VectorXd innovation;  //!< ν = z ⊟ z̄, once the innovation covariance was formed
};

/** Makes a symmetric P positive definite without changing any state's
 *  variance: eigenvalue clipping of the correlation matrix D⁻¹PD⁻¹
 *  (D = diag(σ), floor 1e-9) renormalised to unit diagonal, so a repair
 *  changes correlations only and a large variance (position, m²) cannot
 *  inflate a small one (a gyro bias). A variance that is not positive and
 *  finite is first set to variance_floor(i) (> 0). */
void repairCovariance(Covariance& P, const TangentVector& variance_floor);

/** Keeps every state's σ within [min_sigma(i), max_sigma(i)] (0 and +∞: no
 *  bound) by scaling its row and column of P: P ← D P D with D diagonal and
 *  positive, so correlations are kept and P stays positive definite. A floor
 *  keeps a state from becoming over-confident (a bias the data can never pin
 *  to nanoradians); a ceiling keeps an unobservable one from growing without
 *  meaning. Returns how many states were moved. */
int limitSigmas(Covariance& P, const TangentVector& min_sigma, const TangentVector& max_sigma);

/** What an RTS smoother's forward bookkeeping needs of each filter step
 *  (smoother.h, RtsStretchRecorder): the statistical linearisation the
 *  filter used, in the factored form it already has, so that the
 *  bookkeeping costs O(n² m) per update instead of O(n³). Each call comes at
 *  the end of the step it describes. */
class StepObserver
{
 public:
	virtual ~StepObserver() = default;
	/** predict(): L is the prior P's lower Cholesky factor (n × n; only its
	 *  first k columns unless `full`, P not positive definite past them) and
	 *  D the k × k inertial pair differences, so that the cross covariance's
	 *  first k columns are L_{:,1:k} Dᵀ (the prediction's effective
	 *  transition on the first k states is D L11⁻¹, L11 = L's leading k × k
	 *  block); the rows k… of the transition only scale (diagonal), as
	 *  model.applyLinearRows(·, step) does. */
	virtual void onPredict(const Covariance& L, bool full, const Eigen::Ref<const Eigen::MatrixXd>& D,
	                       const ProcessModel& model, const StepDecay& step) = 0;
	/** update(): the correction dx = W u and P ← P − W Wᵀ, with
	 *  P [B; 0] = W (B: k × m, P the covariance before the update; so
	 *  P⁻¹ W = [B; 0] where P is invertible). B is formed from the Cholesky
	 *  columns the filter factored for its sigma points only. */
	virtual void onUpdate(const Eigen::Ref<const Eigen::MatrixXd>& B,
	                      const Eigen::Ref<const Eigen::VectorXd>& u,
	                      const Eigen::Ref<const Eigen::MatrixXd>& W) = 0;
	/** Any other change of P (sigma limits) and of the mean by dx (tangent
	 *  at the mean before). A recovery's widening of P along its correction
	 *  (Recovery::State) is not reported: to a smoother it is process noise
	 *  added at that tick, which leaves Cov(past states, x) as it is. */
	virtual void onOtherChange(const Covariance& P_before, const Covariance& P_after,
	                           const TangentVector& dx) = 0;
	/** Whether the next predict() should pass all n columns of L (`full`),
	 *  at the cost of the factor's remaining columns. */
	virtual bool wantsFullFactor() const { return true; }
};

class ManifoldUkf
{
 public:
	ManifoldUkf(const ProcessModel& model, const UtParams& ut);

	/** Sets the state; P0 is x0.dim() square (std::invalid_argument
	 *  otherwise), and the process model has the same dimension. */
	void initialize(const NavState& x0, const Covariance& P0);
	/** Sets mean and covariance of the current dimension, unchanged (a
	 *  checkpoint taken from state()/covariance(): re-filtering). */
	void restore(const NavState& x, const Covariance& P);
	int dim() const { return n_; }
	const NavState& state() const { return x_; }
	const Covariance& covariance() const { return P_; }

	/** Propagates by dt_s with the raw gyro sample (IMU axes) and the Earth
	 *  rate. `P_cross`, if given, receives the prediction's cross covariance
	 *  Cov(x_k, x_k+1) = Σ W_i (X_i ⊟ x̄_k)(Y_i ⊟ x̄_k+1)ᵀ (n × n; rows in the
	 *  tangent space at the prior mean, columns at the predicted one): what
	 *  a Rauch–Tung–Striebel smoother's gain needs (smoother.h). It costs an
	 *  n × k × k product and a copy, nothing when not asked for. */
	void predict(const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n, double dt_s,
	             Covariance* P_cross = nullptr);

	/** One measurement update; `recovery` says how one failing the gate is
	 *  applied anyway (see Recovery). */
	UpdateResult update(const MeasurementFunction& model, const Measurement& m, const FilterContext& ctx,
	                    Recovery recovery = Recovery::None);
	//! `true`: Recovery::Noise (the older form).
	UpdateResult update(const MeasurementFunction& model, const Measurement& m, const FilterContext& ctx,
	                    bool recovery)
	{
		return update(model, m, ctx, recovery ? Recovery::Noise : Recovery::None);
	}

	/** Bounds applied after every prediction and update (limitSigmas);
	 *  dim() long each. Empty vectors: none (the default). */
	void setSigmaLimits(const TangentVector& min_sigma, const TangentVector& max_sigma);
	/** How many times a state's σ was moved onto one of its bounds. */
	std::size_t sigmaLimitHits() const { return sigma_limit_hits_; }

	std::size_t choleskyRepairs() const { return repairs_; }
	/** Reports every predict and update from now on (nullptr: none, the
	 *  default); restore() is not reported. Not owned; a copy of the filter
	 *  reports to the same observer. */
	void setStepObserver(StepObserver* observer) { observer_ = observer; }
	const UtWeights& weights() const { return w_; }
	const ProcessModel& processModel() const { return model_; }
	const UtParams& utParams() const { return ut_; }

	/** χ² quantile for dimension `dof` at probability `p` (cached). */
	static double chiSquareQuantile(int dof, double p);

 private:
	/** First k columns of the lower Cholesky factor of P (repairs P if
	 *  needed): the first `whole_columns` (all k if negative) over all rows,
	 *  the others over the first k rows only. */
	void leadingCholeskyColumns(int k, int whole_columns = -1);
	void repairCovariance();

	ProcessModel model_;
	UtParams ut_;
	UtWeights w_;
	NavState x_;
	int n_ = idx::core_dim;  // state dimension (43 + plugin states)
	Covariance P_ = Covariance::Identity(idx::core_dim, idx::core_dim);
	Covariance L_;  // scratch: leading Cholesky columns
	// Update temporaries (grow-only: no heap allocation once the largest
	// measurement has been seen), carved into Eigen::Maps per update.
	std::vector<double> update_scratch_;
	std::array<NavState, 2 * idx::acc + 1>
	    sigma_scratch_;                     // prediction sigma points (along attitude and gyro bias)
	std::array<NavState, 2> pair_scratch_;  // a sigma-point pair before propagation / h (boxplusPair)
	std::size_t repairs_ = 0;
	TangentVector min_sigma_, max_sigma_;  // setSigmaLimits (empty: none)
	std::size_t sigma_limit_hits_ = 0;
	/** `report`: tell the observer (an update's limits; a prediction's are
	 *  part of its P⁻, like process noise). */
	void applySigmaLimits(bool report = true);
	TangentVector variance_floor_;  // 1e-12 × the initial variances (repairCovariance)
	StepObserver* observer_ = nullptr;
	Covariance P_before_;  // scratch: P before a change reported as onOtherChange
};

}  // namespace auvnav
