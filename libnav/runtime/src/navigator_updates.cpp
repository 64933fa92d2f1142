// The navigator's filter steps: prediction, a sensor's update through the
// aiding policy, and the position re-initialisation it may decide.
#include "navigator_slot.h"

#include <cmath>
#include <cstdio>

namespace auvnav
{
void Navigator::propagate(const Eigen::Vector3d& w, double t)
{
	const double dt = t - t_s_;
	// A gap: predict in steps no longer than the nominal limit with the new rate.
	const int steps = dt > cfg_.imu.max_gap_s ? static_cast<int>(std::ceil(dt / 0.01)) : 1;
	const Eigen::Vector3d omega_ie_n = cfg_.earth_rate ? frame_->earthRate() : Eigen::Vector3d::Zero();
	for (int i = 0; i < steps; ++i)
	{
		if (smoother_)
			smoother_->predict(*ukf_, w, omega_ie_n, dt / steps, t_s_ + i * (dt / steps));
		else
			ukf_->predict(w, omega_ie_n, dt / steps);
	}
	// Angular acceleration: first-order low-pass of the gyro's derivative.
	alpha_b_ += ((w - omega_ib_b_) / dt - alpha_b_) * (dt / (cfg_.imu.angular_acceleration_tau_s + dt));
	alpha_delay_s_ = cfg_.imu.angular_acceleration_tau_s + 0.5 * dt;
	t_s_ = t;
	omega_ib_b_ = w;
}

bool Navigator::prepareAndApply(std::size_t slot_index, const mrpt::obs::CObservation& obs, double t_m,
                                std::size_t at)
{
	Slot& slot = *slots_[slot_index];
	const SensorWork work(*this, slot.stats.label);
	SensorStats& st = slot.stats;
	const FilterContext ctx = context(t_m);
	std::string why;
	slot.buffer.clear();
	const PrepareStatus ps = slot.model->prepare(obs, ctx, slot.buffer, why);
	if (ps == PrepareStatus::Skip)
	{
		++st.skipped;
		return false;
	}
	if (ps == PrepareStatus::Invalid)
	{
		++st.invalid;
		st.last_problem = why;
		return false;
	}
	applyMeasurements(slot, slot.buffer, ctx, t_m, true);
	if (!history_) return true;
	FilterEvent e;
	e.t = t_s_;
	e.sensor = slot_index;
	e.t_obs = t_m;
	e.ctx = ctx;
	e.ms = std::move(slot.buffer);
	history_->insert(at, std::move(e));
	return true;
}

void Navigator::applyMeasurements(Slot& slot, const std::vector<Measurement>& ms, const FilterContext& ctx,
                                  double t_obs, bool record)
{
	SensorStats& st = slot.stats;
	for (const Measurement& m : ms)
	{
		if (m.skipped)
		{
			if (record) ++st.skipped;
			continue;
		}
		// Gated as usual first; the policy decides what a rejection means.
		UpdateResult r = ukf_->update(*slot.model, m, ctx, Recovery::None);
		const AidingAction action =
		    policy_.decide(slot.aiding, m, r, t_obs, slot.model->reportsPositionFix(), slot.model->uses());
		if (action == AidingAction::ReinitializePosition)
		{
			reinitializePosition(slot, m, r, t_obs);
			// The position now sits on this fix with its start covariance;
			// the fix itself has been used (applying it again would count it twice).
			r.status = UpdateStatus::Recovered;
			r.why = "position re-initialised onto agreeing rejected fixes";
		}
		else if (action == AidingAction::RecoverNoise || action == AidingAction::RecoverState)
		{
			// The filter's covariance was just contradicted: unless told
			// otherwise, the smoother does not trust its gains across it.
			if (smoother_ && !cfg_.smoother.across_recoveries) smoother_->endSegment(*ukf_, t_s_);
			r = ukf_->update(*slot.model, m, ctx,
			                 action == AidingAction::RecoverState ? Recovery::State : Recovery::Noise);
		}
		AidingPolicy::settle(slot.aiding.gate, r.status, t_obs);
		if (!record) continue;
		if (on_update) on_update(st.label, t_obs, m, r);
		health_.onUpdate(st.label, t_obs - t0_s_, r);
		st.count(r);
	}
}

void Navigator::reinitializePosition(Slot& slot, const Measurement& m, const UpdateResult& r, double t_obs)
{
	// Every recent fix says the same: the state is off by ν, not the sensor.
	// Move onto the newest (the older innovations were taken against a state
	// recovery steps have moved since) and forget what the position was
	// correlated with, as at the start. The smoother does not carry
	// information across the reset (smoother_stream.h).
	if (smoother_) smoother_->endSegment(*ukf_, t_s_);
	const Eigen::Vector2d nu = r.innovation.head<2>();
	NavState x = ukf_->state();
	Covariance P = ukf_->covariance();
	x.p_n.head<2>() += nu;
	P.middleRows<2>(idx::pos).setZero();
	P.middleCols<2>(idx::pos).setZero();
	for (int i = 0; i < 2; ++i)
		P(idx::pos + i, idx::pos + i) = std::max(P0_(idx::pos + i, idx::pos + i), m.R(i, i));
	ukf_->restore(x, P);
	const auto [mean, first_time] = policy_.reinitialized(slot.aiding, t_obs);
	if (!first_time) return;  // a re-filtering pass (delayed measurements) redoes it: count it once
	++slot.stats.reinitialized;
	if (!on_event) return;
	char what[220];
	std::snprintf(what, sizeof what,
	              "position re-initialised: moved N %+.2f E %+.2f m onto the newest of %d agreeing fixes "
	              "rejected by the gate (their mean offset N %+.2f E %+.2f m)",
	              nu.x(), nu.y(), policy_.params().reinit_fixes, mean.x(), mean.y());
	on_event(t_obs - t0_s_, slot.stats.label, what);
}

}  // namespace auvnav
