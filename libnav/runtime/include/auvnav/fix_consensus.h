#pragma once
/** @file fix_consensus.h
 *  Position fixes that agree with each other: where the filter starts, and
 *  when a position every good fix disagrees with is reset.
 *
 *  InitialFixConsensus — the start (`filter.initial.fix_consensus`). One
 *  unchecked fix must not decide the first position: a wild one (a GPS
 *  multipath jump, a USBL false detection) starts the filter far away with a
 *  small σ, and the gate then rejects every good fix after it. The fixes of
 *  the last `window_s` are kept; their median per axis (north, east) is the
 *  robust centre, and the fixes within `max_spread_m` (horizontal distance)
 *  of it agree. Once at least `min_fixes` agree and they are more than half of
 *  the window's fixes, the filter starts from the newest agreeing fix (the
 *  newest, not their mean: the vehicle moves while they are collected).
 *  Invariants: no consensus with fewer than `min_fixes` fixes; outliers
 *  (beyond max_spread_m from the median) never are the start; min_fixes = 1
 *  is the old behaviour (the first valid fix).
 *
 *  RejectedFixRun — later (`gates.position_reinit`). If a fix sensor's last
 *  `rejected_fixes` fixes were all rejected by the χ² gate and they agree with
 *  one another — their horizontal innovations ν_k = fix_k − h(x̂_k) (the
 *  vehicle's motion taken out by the filter's own dead reckoning) scatter
 *  about their R⁻¹-weighted mean ν̄ within the χ² quantile of 2(n − 1)
 *  degrees of freedom, each whitened by its own noise R_k — then the state,
 *  not the sensor, is wrong by ν̄, and the navigator resets the horizontal
 *  position to the fixes (aiding_policy.h). Scattered outliers do not agree; a
 *  sensor whose fixes are accepted in between never builds a run.
 */
#include <auvnav/measurement_model.h>
#include <auvnav/recent_rejections.h>

#include <Eigen/Core>
#include <algorithm>
#include <deque>
#include <optional>

namespace auvnav
{
struct FixConsensusParams
{
	int min_fixes = 5;         //!< agreeing fixes needed before the filter starts (1: the first fix)
	double max_spread_m = 10;  //!< [m] horizontal distance from the median within which a fix agrees
	double window_s = 60;      //!< [s] fixes older than this before the newest are forgotten
};

class InitialFixConsensus
{
 public:
	explicit InitialFixConsensus(const FixConsensusParams& params = {}) : params_(params) {}

	/** One valid fix taken at t_s [s] (its p_n's down is ignored). */
	void add(double t_s, const InitialFix& fix);
	void clear() { fixes_.clear(); }

	/** The newest fix that agrees with the window's median, once at least
	 *  min_fixes agree and they are a strict majority; nullopt before. */
	std::optional<InitialFix> agreed() const;
	/** Fixes in the window, and how many of them agree with the median. */
	int fixes() const { return static_cast<int>(fixes_.size()); }
	int agreeing() const;
	const FixConsensusParams& params() const { return params_; }

 private:
	struct Entry
	{
		double t_s;
		InitialFix fix;
	};
	Eigen::Vector2d median_ne() const;
	bool agrees(const Entry& e, const Eigen::Vector2d& centre_ne) const;

	FixConsensusParams params_;
	std::deque<Entry> fixes_;
};

/** One gate-failing fix: its time [s], horizontal innovation ν [m] (north,
 *  east) and the fix's noise R [m²] with its inverse. */
struct RejectedFix
{
	double t_s;
	Eigen::Vector2d nu;
	Eigen::Matrix2d R, R_inv;
};

class RejectedFixRun : public RecentRejections<RejectedFix>
{
 public:
	explicit RejectedFixRun(int capacity = 16) : RecentRejections(capacity) {}

	/** One more gate rejection: time [s], horizontal innovation ν = fix − h(x̂)
	 *  [m] (north, east), and the fix's noise R [m²]. A non-positive-definite R
	 *  starts a new run (nothing to judge it by). */
	void add(double t_s, const Eigen::Vector2d& nu_ne_m, const Eigen::Matrix2d& R_m2);

	/** True when the last `count` (≥ 2) rejections agree with one offset
	 *  (the χ² test above, at `probability`). */
	bool agree(int count, double probability) const;
	/** Of the last `count`: the R⁻¹-weighted mean innovation ν̄ [m] (the
	 *  state's horizontal error, fix minus state) and their mean noise [m²]. */
	Eigen::Vector2d meanOffset_m(int count) const;
	Eigen::Matrix2d meanNoise_m2(int count) const;
	/** Time [s] of the oldest of the last `count` rejections (of all kept by
	 *  default); 0 when there are none. */
	double firstTime_s(int count = 1 << 30) const
	{
		return size() == 0 ? 0.0 : entry(std::max(0, size() - count)).t_s;
	}
};

}  // namespace auvnav
