#include <auvnav/enum_names.h>
#include <auvnav/health.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>

namespace auvnav
{
namespace
{
std::string format(const char* fmt, double a, double b = 0, double c = 0, double d = 0)
{
	char buf[256];
	std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
	return buf;
}
}  // namespace

const char* navStatusName(NavStatus s)
{
	static constexpr const char* kNames[] = {"ok", "degraded", "not_initialized", "diverged"};
	static_assert(namesEveryValue(kNames, NavStatus::Diverged));
	return nameOf(kNames, s, "unknown");
}

HealthLimits HealthLimits::fromConfig(const config::Node& h)
{
	h.allowOnly({"max_heading_sigma_deg", "max_horizontal_sigma_m", "window_s", "min_updates",
	             "inconsistent_probability", "inconsistent_nis_ratio", "rejected_fraction",
	             "diverged_rejected_fraction", "diverged_after_s"});
	HealthLimits l;
	l.max_heading_sigma_deg = h.inRange("max_heading_sigma_deg", 0.01, 360, l.max_heading_sigma_deg);
	l.max_horizontal_sigma_m = h.positive("max_horizontal_sigma_m", l.max_horizontal_sigma_m);
	l.window_s = h.positive("window_s", l.window_s);
	l.min_updates = h.inRange("min_updates", 1, 1e6, l.min_updates);
	l.inconsistent_probability =
	    h.inRange("inconsistent_probability", 0.5, 1.0 - 1e-12, l.inconsistent_probability);
	l.inconsistent_nis_ratio = h.inRange("inconsistent_nis_ratio", 1.0, 1e6, l.inconsistent_nis_ratio);
	l.rejected_fraction = h.inRange("rejected_fraction", 0.0, 1.0, l.rejected_fraction);
	l.diverged_rejected_fraction =
	    h.inRange("diverged_rejected_fraction", 0.0, 1.0, l.diverged_rejected_fraction);
	l.diverged_after_s = h.positive("diverged_after_s", l.diverged_after_s);
	return l;
}

void HealthMonitor::onUpdate(const std::string& label, double t_s, const UpdateResult& r)
{
	if (r.status == UpdateStatus::Invalid) return;  // bad input, counted elsewhere; says nothing of the state
	SensorWindow& w = sensors_[label];
	const bool rejected = r.status != UpdateStatus::Accepted;
	w.entries.push_back({t_s, rejected ? 0.0 : r.nis, rejected ? 0 : r.dim, rejected});
	w.nis_sum += w.entries.back().nis;
	w.dim_sum += w.entries.back().dim;
	w.rejected += rejected;
	while (!w.entries.empty() && w.entries.front().t_s < t_s - limits_.window_s)
	{
		const Entry& e = w.entries.front();
		w.nis_sum -= e.nis;
		w.dim_sum -= e.dim;
		w.rejected -= e.rejected;
		w.entries.pop_front();
	}
	judge(label, w, t_s);
	refresh(t_s);
}

void HealthMonitor::judge(const std::string& label, SensorWindow& w, double t_s) const
{
	const double n = static_cast<double>(w.entries.size());
	if (n < limits_.min_updates)
	{
		w.verdict = NavStatus::Ok;
		w.bad_since_s = -1;
		return;
	}
	const double rejected_fraction = w.rejected / n;
	const double span_s = t_s - w.entries.front().t_s;
	if (rejected_fraction > limits_.diverged_rejected_fraction)
	{
		if (w.bad_since_s < 0)
			for (const Entry& e : w.entries)  // the streak starts at its window's first rejection
				if (e.rejected)
				{
					w.bad_since_s = e.t_s;
					break;
				}
	}
	else
		w.bad_since_s = -1;
	// Significant (χ² quantile) and large enough to matter: a 100 Hz aid
	// makes a 5 % excess significant within seconds. The cheap ratio first:
	// the quantile of a window's every new dim_sum is a root search, needed
	// only when the ratio is exceeded.
	const bool nis_high =
	    w.dim_sum > 0 && w.nis_sum > limits_.inconsistent_nis_ratio * w.dim_sum &&
	    w.nis_sum > ManifoldUkf::chiSquareQuantile(w.dim_sum, limits_.inconsistent_probability);
	if (w.bad_since_s >= 0 && t_s - w.bad_since_s >= limits_.diverged_after_s)
	{
		w.verdict = NavStatus::Diverged;
		w.why = label + format(": %.0f of %.0f updates rejected in %.0f s, for %.0f s", w.rejected, n, span_s,
		                       t_s - w.bad_since_s);
	}
	else if (rejected_fraction > limits_.rejected_fraction)
	{
		w.verdict = NavStatus::Degraded;
		w.why = label + format(": %.0f of %.0f updates rejected in %.0f s", w.rejected, n, span_s);
	}
	else if (nis_high)
	{
		w.verdict = NavStatus::Degraded;
		w.why = label + format(": NIS %.2f per dimension over %.0f s (inconsistent with the state)",
		                       w.nis_sum / w.dim_sum, span_s);
	}
	else
		w.verdict = NavStatus::Ok;
}

void HealthMonitor::onState(double t_s, const NavState& x, const Covariance& P)
{
	// Forget sensors that fell silent (dropouts, denial): their last verdict
	// is about a state that has moved on.
	for (auto& [label, w] : sensors_)
		if (!w.entries.empty() && w.entries.back().t_s < t_s - limits_.window_s)
		{
			w = SensorWindow{};
		}
	const double heading_sigma_deg = std::sqrt(std::max(P(idx::att + 2, idx::att + 2), 0.0)) * 180 / M_PI;
	const Eigen::Matrix2d P_ne = P.block<2, 2>(idx::pos, idx::pos);
	const double horizontal_sigma_m =
	    std::sqrt(std::max(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(P_ne).eigenvalues()(1), 0.0));
	if (!x.allFinite() || !P.allFinite())
	{
		state_verdict_ = NavStatus::Diverged;
		state_why_ = "non-finite state or covariance";
	}
	else if (heading_sigma_deg > limits_.max_heading_sigma_deg)
	{
		state_verdict_ = NavStatus::Degraded;
		state_why_ = format("heading not aligned (sigma %.1f deg > %.1f)", heading_sigma_deg,
		                    limits_.max_heading_sigma_deg);
	}
	else if (horizontal_sigma_m > limits_.max_horizontal_sigma_m)
	{
		state_verdict_ = NavStatus::Degraded;
		state_why_ = format("horizontal position sigma %.1f m > %.1f m", horizontal_sigma_m,
		                    limits_.max_horizontal_sigma_m);
	}
	else
	{
		state_verdict_ = NavStatus::Ok;
		state_why_.clear();
	}
	refresh(t_s);
}

void HealthMonitor::setNotInitialized(const std::string& what)
{
	status_ = worst_ = NavStatus::NotInitialized;
	reason_ = worst_reason_ = "not initialised: " + what;
	if (on_change) on_change(0, status_, reason_);
}

void HealthMonitor::refresh(double t_s)
{
	NavStatus s = state_verdict_;
	std::string why = state_why_;
	for (const auto& [label, w] : sensors_)
		if (w.verdict > s)
		{
			s = w.verdict;
			why = w.why;
		}
	if (s == NavStatus::Ok && worst_ == NavStatus::Diverged)
	{
		// Once diverged, "ok" is not earned back by quiet aids alone.
		s = NavStatus::Degraded;
		why = format("diverged at %.0f s (", worst_t_s_) + worst_reason_ + "), consistent since";
	}
	if (s > worst_)
	{
		worst_ = s;
		worst_reason_ = why;
		worst_t_s_ = t_s;
	}
	// Reason text changes (figures) without a status change are not news.
	const bool changed = s != status_;
	status_ = s;
	reason_ = why;
	if (changed && on_change) on_change(t_s, status_, reason_);
}

}  // namespace auvnav
