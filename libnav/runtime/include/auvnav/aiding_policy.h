#pragma once
/** @file aiding_policy.h
 *  What the navigator does with an update the χ² gate rejected (`gates`):
 *
 *  - Re-acquisition: a sensor whose last `consistent_rejections` rejections
 *    agree with each other (a drifting bias of the state,
 *    rejection_streak.h) is applied at once with the innovation covariance
 *    inflated onto the gate, or, for an absolute reference of what the
 *    filter integrates without bound (attitude, position, depth), with the
 *    state's covariance widened along the correction.
 *  - Recovery: as a backstop, a sensor rejected for `recovery_after_s` is
 *    applied on the gate boundary (it cannot lock itself out, e.g. the DVL
 *    after a long dropout).
 *  - Position re-initialisation (`position_reinit`): when the last
 *    `rejected_fixes` fixes of a position sensor (reportsPositionFix: GPS,
 *    USBL, …) all failed the gate and agree with each other (RejectedFixRun,
 *    fix_consensus.h), the horizontal position moves onto the newest —
 *    provided most of the sensor's fixes over that run, also those its plugin
 *    skipped, lie within `max_spread_m` of that offset: outliers the plugin
 *    happened to pick at the same phase agree with each other, the good fixes
 *    between them do not.
 */
#include <auvnav/fix_consensus.h>
#include <auvnav/navigator_config.h>
#include <auvnav/rejection_streak.h>
#include <auvnav/ukf.h>

#include <deque>
#include <utility>

namespace auvnav
{
/** One sensor's gate history: what a filter checkpoint must restore. */
struct GateState
{
	double rejecting_since_s = -1;  //!< start of the current run of rejections
	RejectionStreak streak;         //!< its innovations (rejection_streak.h)
	RejectedFixRun fix_run;         //!< a position sensor's gate-failing fixes
	void clear()
	{
		rejecting_since_s = -1;
		streak.clear();
		fix_run.clear();
	}
};

/** One sensor's aiding state. */
struct SensorAiding
{
	GateState gate;
	//! Every fix of a position sensor since its run of rejections began
	//! (initialFix: also those the plugin skips): arrival time, fix − the
	//! state's sensor point [m].
	std::deque<std::pair<double, Eigen::Vector2d>> fix_offsets;
	double last_reinit_t_obs = -1;  //!< counted once, though re-filtering may redo it
};

/** What to do after a gated update. */
enum class AidingAction
{
	Keep,                  //!< its result stands (accepted, or rejected for now)
	ReinitializePosition,  //!< move the position onto this fix (its innovation's first two components)
	RecoverNoise,          //!< apply it again with Recovery::Noise
	RecoverState,          //!< apply it again with Recovery::State
};

class AidingPolicy
{
 public:
	explicit AidingPolicy(const AidingParams& p = {}) : p_(p) {}
	const AidingParams& params() const { return p_; }

	/** Decides on the gated update r of measurement m at t_obs of a sensor
	 *  whose model reads `uses` (state.h) and, if `position_fix`, gives
	 *  position fixes; records the rejection in `s`. */
	AidingAction decide(SensorAiding& s, const Measurement& m, const UpdateResult& r, double t_obs,
	                    bool position_fix, uint32_t uses) const;
	/** Updates the gate history with the status the update finally had. */
	static void settle(GateState& g, UpdateStatus status, double t_obs);

	/** Records a position sensor's fix (every one) as fix − predicted sensor
	 *  point [m, NE] at arrival time t. */
	static void recordFixOffset(SensorAiding& s, double t_s, const Eigen::Vector2d& offset_m);
	/** After a position re-initialisation at t_obs: the run's mean offset
	 *  [m, NE] and whether it is the first time this fix did it (re-filtering
	 *  repeats it). Call when decide() said ReinitializePosition (the mean
	 *  is NaN without a run of fixes). Clears the sensor's gate history. */
	std::pair<Eigen::Vector2d, bool> reinitialized(SensorAiding& s, double t_obs) const;

 private:
	/** More than half of the fixes recorded over the run lie within
	 *  reinit_spread_m of `offset_m`. */
	bool mostFixesAgreeWith(const SensorAiding& s, const Eigen::Vector2d& offset_m) const;

	AidingParams p_;
};

}  // namespace auvnav
