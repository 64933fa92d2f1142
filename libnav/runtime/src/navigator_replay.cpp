// Delayed fusion (filter_history.h) and the smoother's feed: what lets the
// navigator rewind the filter and what must follow it when it does.
#include "navigator_slot.h"

#include <limits>

namespace auvnav
{
void Navigator::checkpointIfDue(std::size_t event)
{
	if (!history_->checkpointDue(t_s_)) return;
	FilterCheckpoint c;
	c.event = event;
	c.t_s = t_s_;
	c.x = ukf_->state();
	c.P = ukf_->covariance();
	c.omega_ib_b = omega_ib_b_;
	c.alpha_b = alpha_b_;
	c.alpha_delay_s = alpha_delay_s_;
	c.gates.reserve(slots_.size());
	for (const auto& slot : slots_) c.gates.push_back(slot->aiding.gate);
	if (smoother_) c.smoother = smoother_->snapshot(*ukf_);
	history_->addCheckpoint(std::move(c));
}

void Navigator::restoreLastCheckpoint()
{
	const FilterCheckpoint& c = history_->lastCheckpoint();
	ukf_->restore(c.x, c.P);
	t_s_ = c.t_s;
	omega_ib_b_ = c.omega_ib_b;
	alpha_b_ = c.alpha_b;
	alpha_delay_s_ = c.alpha_delay_s;
	if (smoother_ && c.smoother) smoother_->restore(*c.smoother, *ukf_);
	for (std::size_t i = 0; i < slots_.size(); ++i) slots_[i]->aiding.gate = c.gates[i];
}

void Navigator::replayEvent(std::size_t event)
{
	FilterEvent& e = history_->at(event);
	if (e.imu)
	{
		checkpointIfDue(event);
		propagate(e.w, e.t);
		++replayed_predictions_;
		return;
	}
	FilterContext ctx = e.ctx;
	ctx.t_s = t_s_;
	ctx.mean = &ukf_->state();
	ctx.covariance = &ukf_->covariance();
	Slot& slot = *slots_[e.sensor];
	const SensorWork work(*this, slot.stats.label);
	applyMeasurements(slot, e.ms, ctx, e.t_obs, false);
}

bool Navigator::applyDelayed(std::size_t slot_index, const mrpt::obs::CObservation& obs, double t_m)
{
	const std::optional<std::size_t> ins = history_->rewindFor(t_m);
	if (!ins) return false;
	restoreLastCheckpoint();
	for (std::size_t k = history_->lastCheckpoint().event; k < *ins; ++k) replayEvent(k);
	std::size_t resume = *ins;
	if (prepareAndApply(slot_index, obs, t_m, *ins))
	{
		++slots_[slot_index]->stats.delayed;
		resume = *ins + 1;
	}
	for (std::size_t k = resume; k < history_->end(); ++k) replayEvent(k);
	return true;
}

void Navigator::commitSmoother()
{
	if (!smoother_) return;
	try
	{
		smoother_->commit(history_ ? history_->settledSmootherRecords()
		                           : std::numeric_limits<std::size_t>::max());
	}
	catch (const std::exception& e)
	{
		stopSmoothing(e.what());
	}
}

void Navigator::stopSmoothing(const std::string& why)
{
	// The filter's run goes on; the stretch file ends where writing failed
	// (its partial last record is ignored by the reader).
	smoother_error_ = why;
	ukf_->setStepObserver(nullptr);
	smoother_.reset();
	if (history_) history_->dropSmootherSnapshots();
}

void Navigator::enableSmoothing(const std::string& path)
{
	StretchFileHeader h;
	h.n = ukf_->dim();
	h.imu_position_b = cfg_.imu.position_b;
	h.tangent_names = layout_.tangent_names;
	h.stored_names = layout_.stored_names;
	smoother_ = std::make_unique<SmoothingRecorder>(path, h, cfg_.smoother.keep_every_s);
}

}  // namespace auvnav
