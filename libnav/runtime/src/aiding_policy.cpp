#include <auvnav/aiding_policy.h>

#include <algorithm>
#include <cmath>

namespace auvnav
{
AidingAction AidingPolicy::decide(SensorAiding& s, const Measurement& m, const UpdateResult& r, double t_obs,
                                  bool position_fix, uint32_t uses) const
{
	if (r.status != UpdateStatus::Rejected) return AidingAction::Keep;
	GateState& g = s.gate;
	if (position_fix && p_.reinit_fixes >= 2 && r.innovation.size() >= 2 && m.R.rows() >= 2)
	{
		const Eigen::Vector2d nu = r.innovation.head<2>();
		g.fix_run.add(t_obs, nu, m.R.topLeftCorner<2, 2>());
		if (g.fix_run.agree(p_.reinit_fixes, p_.reinit_probability) && mostFixesAgreeWith(s, nu))
			return AidingAction::ReinitializePosition;
	}
	if (g.rejecting_since_s >= 0 && t_obs - g.rejecting_since_s > p_.recovery_after_s)
		return AidingAction::RecoverNoise;
	if (p_.consistent_rejections == 0) return AidingAction::Keep;
	// Rejected but agreeing with the aid's previous rejections: the state is
	// off, not the aid. An absolute reference of what the filter integrates
	// without bound (attitude, position, depth: magnetometer, AHRS, GPS,
	// pressure) pulls the state back by widening its covariance; a velocity
	// aid only on the gate boundary, since a consistent velocity disagreement
	// is as often the aid's (a wrong mounting or scale), and widening let a
	// DVL mounted 157° off turn the heading and end far off as 'degraded'.
	g.streak.add(t_obs, r.innovation, m.R);
	if (!g.streak.consistentBias(p_.consistent_rejections, p_.consistency_probability))
		return AidingAction::Keep;
	// (Plugin states such as a heading bias widen with the state.)
	constexpr uint32_t kAbsolute = kAttitude | kPosition | kGravity | kPluginStates;
	return (uses & ~kAbsolute) == 0 ? AidingAction::RecoverState : AidingAction::RecoverNoise;
}

void AidingPolicy::settle(GateState& g, UpdateStatus status, double t_obs)
{
	const bool applied = status == UpdateStatus::Accepted || status == UpdateStatus::Recovered;
	if (applied)
	{
		g.streak.clear();
		g.rejecting_since_s = -1;
	}
	// A fix inside the gate ends a run of rejected ones (a recovery on the
	// gate boundary does not: the fix still failed it).
	if (status == UpdateStatus::Accepted) g.fix_run.clear();
	if (status == UpdateStatus::Rejected && g.rejecting_since_s < 0) g.rejecting_since_s = t_obs;
}

void AidingPolicy::recordFixOffset(SensorAiding& s, double t_s, const Eigen::Vector2d& offset_m)
{
	auto& offsets = s.fix_offsets;
	offsets.emplace_back(t_s, offset_m);
	// Only those since the current run of rejections began are needed.
	const double keep_from = s.gate.fix_run.size() > 0 ? s.gate.fix_run.firstTime_s() : t_s;
	while (offsets.size() > 1 && offsets.front().first < keep_from) offsets.pop_front();
}

std::pair<Eigen::Vector2d, bool> AidingPolicy::reinitialized(SensorAiding& s, double t_obs) const
{
	const bool have_run = s.gate.fix_run.size() >= std::max(p_.reinit_fixes, 1);
	const Eigen::Vector2d mean =
	    have_run ? s.gate.fix_run.meanOffset_m(p_.reinit_fixes) : Eigen::Vector2d::Constant(NAN);
	s.gate.clear();
	s.fix_offsets.clear();
	const bool first = t_obs > s.last_reinit_t_obs;
	if (first) s.last_reinit_t_obs = t_obs;
	return {mean, first};
}

bool AidingPolicy::mostFixesAgreeWith(const SensorAiding& s, const Eigen::Vector2d& offset_m) const
{
	const double from = s.gate.fix_run.firstTime_s(p_.reinit_fixes);
	int all = 0, agreeing = 0;
	for (const auto& [t, d] : s.fix_offsets)
		if (t >= from)
		{
			++all;
			agreeing += (d - offset_m).norm() <= p_.reinit_spread_m;
		}
	return all == 0 || 2 * agreeing > all;  // no record (a plugin without initialFix): the run decides
}

}  // namespace auvnav
