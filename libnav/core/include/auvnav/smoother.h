#pragma once
/** @file smoother.h
 *  Unscented Rauch–Tung–Striebel smoothing (Särkkä 2008, "Unscented
 *  Rauch–Tung–Striebel smoother", IEEE Trans. Automatic Control 53(3)) on
 *  the filter's manifold state: the backward pass over what a forward
 *  ManifoldUkf recorded.
 *
 *  One RtsStep per prediction k → k+1 holds the filtered mean and covariance
 *  at k (after every update applied at tick k), the predicted ones at k+1
 *  (before its updates) and the prediction's cross covariance
 *  C = Cov(x_k, x_k+1) (ManifoldUkf::predict's P_cross). The updates between
 *  two predictions need nothing more: they are part of "filtered at k+1".
 *
 *  The backward step, in the tangent spaces of the filter's retraction
 *  (state.h: attitude on SO(3), never angles):
 *      G  = C (P⁻_k+1)⁻¹                 (a Cholesky solve, no inverse)
 *      x̂_k = x_k ⊞ G (x̂_k+1 ⊟ x⁻_k+1)
 *      P̂_k = P_k + G (P̂_k+1 − P⁻_k+1) Gᵀ
 *  P̂_k is taken in the tangent space at x_k, as the filter itself keeps P
 *  across an update (its small re-centring is neglected there too).
 *
 *  A step whose P⁻_k+1 is not positive definite, or whose result is not
 *  finite or has a variance that is not positive, keeps the filtered
 *  estimate at k (`smoothed` false) and the pass continues from it.
 *
 *  Memory: a step holds three n × n matrices (n = 43: 44 KB) per tick, so
 *  this form is for short runs and tests; RtsStretch (below) keeps one
 *  record per kept tick, streamed to disk by smoother_stream.h.
 */
#include <auvnav/state.h>
#include <auvnav/ukf.h>

#include <Eigen/Core>
#include <array>
#include <vector>

namespace auvnav
{
struct RtsStep
{
	double t_s = 0;          //!< time of the filtered estimate (tick k)
	NavState x_filtered;     //!< x_k
	Covariance P_filtered;   //!< P_k
	NavState x_predicted;    //!< x⁻_k+1
	Covariance P_predicted;  //!< P⁻_k+1 (process noise included)
	Covariance P_cross;      //!< Cov(x_k, x_k+1)
};

/** ukf.predict(omega_ib_b, omega_ie_n, dt_s) that also returns the step;
 *  `t_s` is the time of the state before the prediction. */
RtsStep predictRecorded(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b,
                        const Eigen::Vector3d& omega_ie_n, double dt_s, double t_s);

struct SmoothedEstimate
{
	double t_s = 0;
	NavState x;
	Covariance P;
	bool smoothed = true;  //!< false: the filtered estimate kept (failed step, see above)
};

/** One backward step from the smoothed estimate at k+1. False (and x_out,
 *  P_out = the filtered ones) if the step failed (see above). */
bool rtsBackwardStep(const RtsStep& step, const NavState& x_next, const Covariance& P_next, NavState& x_out,
                     Covariance& P_out);

/** The backward pass over a whole recorded run: one estimate per step (at
 *  steps[k].t_s) and, last, the end state (x_end, P_end at t_end_s: the
 *  filter's estimate after the last step's updates, which smoothing leaves
 *  as it is). */
std::vector<SmoothedEstimate> smoothRts(const std::vector<RtsStep>& steps, const NavState& x_end,
                                        const Covariance& P_end, double t_end_s);

/** What the backward pass needs of one stretch between kept ticks k and k′
 *  (docs/smoother.md): the per-tick recursion telescoped,
 *      x̂_k = x_k ⊞ (sum_dx + M (x̂_k′ ⊟ x_k′)),
 *      P̂_k = P_k − sum_dP + M (P̂_k′ − P_k′) Mᵀ,
 *  with M = G_k ⋯ G_k′−1 and the sums over the ticks t in (k, k′] of
 *  M_t (x_t ⊟ x⁻_t) and M_t (P⁻_t − P_t) M_tᵀ. The covariance is the per-tick
 *  pass's exactly. The mean is where a vector space would have it: this
 *  state's retraction turns velocity, acceleration and currents with the
 *  attitude (state.h), so the per-tick pass's x̂_t ⊟ x⁻_t is not
 *  (x̂_t ⊟ x_t) + (x_t ⊟ x⁻_t) but (x_t ⊟ x⁻_t) + T_t (x̂_t ⊟ x_t) + O(2) with
 *  T_t = ∂/∂b [(x_t ⊞ b) ⊟ x⁻_t] at b = 0 (identity but for the attitude and
 *  accelerometer-bias columns, taken by central differences): the mean uses
 *  M_mean, the product of G_t T_t+1, and agrees with the per-tick pass to
 *  second order in the smoothing corrections. */
struct RtsStretch
{
	double t_s = 0;       //!< time of tick k
	NavState x_filtered;  //!< x_k
	Covariance P_filtered;
	Covariance M;       //!< G_k ⋯ G_k′−1 (the covariance's)
	Covariance M_mean;  //!< the same with each tick's correction transport (below)
	TangentVector sum_dx;
	Covariance sum_dP;
	std::size_t ticks = 0;  //!< predictions in the stretch
	bool broken = false;    //!< a tick's P⁻ was not positive definite: smoothing keeps x_k
};

/** Forward bookkeeping for RtsStretch: call predict() in place of the
 *  filter's, and close() at a kept tick (after its updates).
 *
 *  It keeps, as the filter runs, X = M P (the cross covariance of x_k with
 *  the current state: a clone of x_k carried through the filter by
 *  statistical linearisation, whose regression on the current state is M)
 *  and X_mean = M_mean P, from the factors the filter already has
 *  (StepObserver): a prediction moves X's first k columns by L11⁻ᵀ Dᵀ and
 *  scales the rest; an update is X −= (M W) Wᵀ with M W = X_{:,1:k} B,
 *  Σ M dx += (M_mean W) u and Σ M ΔP Mᵀ += (M W)(M W)ᵀ. The X −= part of a
 *  tick's updates is made once, as one rank-r product before the next
 *  prediction (a later update of the tick corrects its M W for the earlier
 *  ones), and the Σ M ΔP Mᵀ part every 32 columns. The correction
 *  transports of kTransportEveryTicks ticks are applied together, from
 *  their summed corrections (E is first order in them): only those ticks
 *  need the rest of P's Cholesky factor. M = X P⁻¹ is solved once per kept
 *  tick. Per tick that is O(n k²) for the prediction and O(n² m) per
 *  update instead of the O(n³) gain products of the per-tick recursion;
 *  the covariance is the same and the mean agrees to second order (tested
 *  against it, SmootherStretches.*). Sigma limits hit in an update (onOtherChange)
 *  cost an n³ solve; hit in a prediction, and a recovery's widening, they
 *  are process noise to it (not reported). A stretch during which the filter repaired its covariance,
 *  or whose P is not positive definite when it closes, is `broken`.
 *
 *  The recorder registers itself as the filter's StepObserver in
 *  predict(); it must stay at the same address while the filter runs. */
class RtsStretchRecorder : public StepObserver
{
 public:
	/** Opens the first stretch at the filter's current estimate. */
	void begin(const ManifoldUkf& ukf, double t_s);
	bool open() const { return open_; }
	/** ukf.predict(...), with the tick's updates folded in. False if the
	 *  stretch is broken (it keeps the filtered estimate when smoothed). */
	bool predict(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n,
	             double dt_s);
	/** Ends the stretch at the filter's current estimate (tick k′, after its
	 *  updates), returns it and opens the next one there. */
	RtsStretch close(const ManifoldUkf& ukf, double t_s);
	/** Marks the stretch broken if the filter repaired its covariance since
	 *  the last look, and looks now; after a rewind (re-filtering), call it
	 *  with `reset` true so that the discarded pass's repairs do not count. */
	void checkRepairs(const ManifoldUkf& ukf, bool reset = false);

	void onPredict(const Covariance& L, bool full, const Eigen::Ref<const Eigen::MatrixXd>& D,
	               const ProcessModel& model, const StepDecay& step) override;
	void onUpdate(const Eigen::Ref<const Eigen::MatrixXd>& B, const Eigen::Ref<const Eigen::VectorXd>& u,
	              const Eigen::Ref<const Eigen::MatrixXd>& W) override;
	void onOtherChange(const Covariance& P_before, const Covariance& P_after,
	                   const TangentVector& dx) override;
	bool wantsFullFactor() const override { return transport_pending_; }

 private:
	//! Update columns deferred to one pass over X (flushUpdates).
	static constexpr int kMaxPending = 16;
	//! Columns of Σ M ΔP Mᵀ's rank update gathered before it is made.
	static constexpr int kMaxDpPending = 32;
	//! Ticks whose correction transports are applied together (and the
	//! only ticks that need P's whole factor): on the sample, 5 against 1
	//! moves the smoothed position by 6e-4 σ and the velocity by 0.03 σ.
	static constexpr int kTransportEveryTicks = 5;
	using Stacked = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * idx::max_dim, idx::max_dim>;
	using SixColumns = Eigen::Matrix<double, Eigen::Dynamic, 6, 0, idx::max_dim, 6>;
	using StackedPending =
	    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 2 * idx::max_dim, kMaxPending>;
	using Pending = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, idx::max_dim, kMaxPending>;
	/** Adds the tick's update correction (after its updates) to the sum
	 *  since the last transport; every kTransportEveryTicks ticks, or with
	 *  `now` (close()), takes the transport T = I + E (six columns) for
	 *  M_mean from that sum, applied by the next prediction (which then
	 *  asks for P's whole factor) or by close(). */
	void takeTransport(const ManifoldUkf& ukf, bool now = false);
	/** Applies the deferred updates to X, X_mean and Σ M ΔP Mᵀ: one
	 *  rank-r product instead of one pass over X per update. */
	void flushUpdates();
	/** Adds the gathered M W columns to Σ M ΔP Mᵀ (before close reads it). */
	void flushDp();
	/** An update too wide to defer: applied to X at once (heap scratch; no
	 *  built-in sensor is this wide). */
	void applyWideUpdate(const Eigen::Ref<const Eigen::MatrixXd>& B,
	                     const Eigen::Ref<const Eigen::VectorXd>& u,
	                     const Eigen::Ref<const Eigen::MatrixXd>& W);
	RtsStretch current_;
	NavState x_predicted_;
	Stacked XX_;  // [X; X_mean], 2n × n, without the pending updates
	// The updates since the last flush: X_now = X − MW Wᵀ (for X and X_mean
	// at once), with MW = [M W_1 … M W_r] (2n × r) and W = [W_1 … W_r].
	StackedPending MW_pending_;
	Pending W_pending_;
	int pending_ = 0;
	Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, idx::max_dim, kMaxDpPending>
	    MW_dP_;  // M W columns not yet in Σ M ΔP Mᵀ
	int dP_pending_ = 0;
	SixColumns E_, ME_;
	Covariance scratch_;
	std::size_t repairs_seen_ = 0;
	TangentVector dx_since_transport_;  // Σ x_t ⊟ x⁻_t since the last transport
	int ticks_since_transport_ = 0;
	bool open_ = false, predicted_ = false, transport_pending_ = false;
};

/** One backward step over a stretch, from the filtered and smoothed
 *  estimates at its end (tick k′). False (outputs = the filtered estimate at
 *  k) if the stretch is broken or the result is not finite or has a
 *  variance that is not positive. */
bool rtsStretchBackward(const RtsStretch& s, const NavState& x_end_filtered, const Covariance& P_end_filtered,
                        const NavState& x_end_smoothed, const Covariance& P_end_smoothed, NavState& x_out,
                        Covariance& P_out);

}  // namespace auvnav
