#pragma once
/** @file health.h
 *  The navigator's divergence monitor: whether the estimate can be trusted.
 *
 *  Status, worst first: `diverged` (the aids have disagreed with the state
 *  for longer than `diverged_after_s` while the gate rejected most of them,
 *  or the state is not finite), `not_initialized` (set by the navigator when
 *  the run ends before the filter started), `degraded` (an aid's windowed NIS
 *  is inconsistent, most of its recent updates were rejected, the heading σ
 *  or the horizontal position σ is above its limit: the filter says it does
 *  not know), `ok`.
 *
 *  Per sensor, over the last `window_s` of updates: the NIS sum of the
 *  accepted updates against the χ² quantile of their summed dimensions at
 *  `inconsistent_probability` (a consistent filter exceeds it with
 *  probability 1 − p) and above `inconsistent_nis_ratio` per dimension, and the fraction rejected or only
 * accepted by the recovery rule. A single outlier rejected by the gate does not count as inconsistency (it
 * never enters the NIS sum), a streak of rejections does. Conditions are evaluated at every update and state
 * check; the reason names the condition and its figures, e.g. "DVL: 46 of 50 updates rejected in 30 s for 61
 * s".
 */
#include <auvnav/config.h>
#include <auvnav/state.h>
#include <auvnav/ukf.h>

#include <deque>
#include <functional>
#include <map>
#include <string>

namespace auvnav
{
enum class NavStatus
{
	Ok = 0,
	Degraded = 1,
	NotInitialized = 2,
	Diverged = 3
};
const char* navStatusName(NavStatus s);

struct HealthLimits
{
	double max_heading_sigma_deg = 5.0;    //!< heading σ above this: not aligned (degraded)
	double max_horizontal_sigma_m = 50.0;  //!< horizontal position σ (larger axis) above this: degraded
	double window_s = 30.0;                //!< per-sensor window of updates
	double min_updates = 5;                //!< fewer updates in the window: no verdict
	double inconsistent_probability = 0.9999;
	double inconsistent_nis_ratio = 1.5;      //!< and NIS per dimension above this
	double rejected_fraction = 0.5;           //!< above: degraded
	double diverged_rejected_fraction = 0.8;  //!< above for diverged_after_s: diverged
	double diverged_after_s = 60.0;
	/** From the navigator's `health:` section (every key optional). */
	static HealthLimits fromConfig(const config::Node& health);
};

class HealthMonitor
{
 public:
	explicit HealthMonitor(const HealthLimits& limits = {}) : limits_(limits) {}

	/** One measurement update of sensor `label` at time t [s]. */
	void onUpdate(const std::string& label, double t_s, const UpdateResult& r);
	/** The state and covariance at time t (call at about 1 Hz or more). */
	void onState(double t_s, const NavState& x, const Covariance& P);
	/** The run ended before initialisation; `what` says what it waited for. */
	void setNotInitialized(const std::string& what);

	NavStatus status() const { return status_; }
	const std::string& reason() const { return reason_; }  //!< empty when ok
	NavStatus worst() const { return worst_; }
	const std::string& worstReason() const { return worst_reason_; }
	double worstSince_s() const { return worst_t_s_; }
	const HealthLimits& limits() const { return limits_; }

	/** Called on every change of status (time, new status, reason). */
	std::function<void(double t_s, NavStatus, const std::string& reason)> on_change;

 private:
	struct Entry
	{
		double t_s, nis;
		int dim;
		bool rejected;
	};
	struct SensorWindow
	{
		std::deque<Entry> entries;
		double nis_sum = 0;
		int dim_sum = 0, rejected = 0;
		double bad_since_s = -1;  //!< start of the current rejected streak (diverged clock)
		NavStatus verdict = NavStatus::Ok;
		std::string why;
	};
	void judge(const std::string& label, SensorWindow& w, double t_s) const;
	void refresh(double t_s);

	HealthLimits limits_;
	std::map<std::string, SensorWindow> sensors_;
	NavStatus state_verdict_ = NavStatus::Ok;
	std::string state_why_;
	NavStatus status_ = NavStatus::Ok, worst_ = NavStatus::Ok;
	std::string reason_, worst_reason_;
	double worst_t_s_ = 0;
};

}  // namespace auvnav
