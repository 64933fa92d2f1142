#include "navigator_slot.h"

#include <auvnav/filter_history.h>
#include <mrpt/obs/CObservationIMU.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace auvnav
{
std::vector<SensorSource> loadSensorModels(const NavigatorConfig& cfg, PluginHost& host)
{
	std::vector<SensorSource> out;
	for (const SensorEntry& s : cfg.sensors)
	{
		host.load(s.plugin);  // a plugin that does not load is no config error
		SensorSource src{s.label, s.plugin, nullptr, s.latency_s};
		try
		{
			src.model = host.create(s.plugin, s.config_yaml, s.label);
		}
		catch (const PluginError& e)
		{
			// Name the file the plugin's configuration came from.
			throw PluginError(s.config_origin + ": " + e.what());
		}
		out.push_back(std::move(src));
	}
	return out;
}

Navigator::~Navigator() = default;

Navigator::Navigator(const NavigatorConfig& cfg, std::vector<SensorSource> sensors)
    : cfg_(cfg),
      frame_(std::make_unique<earth::TangentFrame>(cfg.origin)),
      P0_(cfg.P0),
      init_(cfg.initial, cfg.imu),
      policy_(cfg.gates),
      health_(cfg.health)
{
	imu_stats_.label = cfg_.imu.label;
	imu_stats_.plugin = "(prediction)";
	std::vector<LabelledModel> models;
	for (SensorSource& s : sensors)
	{
		if (!s.model) throw std::invalid_argument("sensor '" + s.label + "' has no model");
		auto slot = std::make_unique<Slot>();
		slot->stats.label = s.label;
		slot->stats.plugin = s.plugin;
		slot->model = std::move(s.model);
		slot->latency_s = s.latency_s;
		models.push_back({slot->stats.label, slot->stats.plugin, *slot->model});
		slots_.push_back(std::move(slot));
	}
	if (cfg_.initial.position_from_fix &&
	    !std::any_of(slots_.begin(), slots_.end(),
	                 [&](const auto& s) { return s->stats.label == cfg_.initial.fix_label; }))
		throw std::invalid_argument("filter.initial.gps_label: no sensor '" + cfg_.initial.fix_label +
		                            "' gives the first fix");
	for (const auto& w : cfg_.denial) checkDenialLabels(w);
	ProcessModel pm = cfg_.process;
	layout_ = appendPluginStates(models, pm, P0_);
	ukf_ = std::make_unique<ManifoldUkf>(pm, cfg_.unscented);
	if (cfg_.sigma_limits)
	{
		const auto [lo, hi] = sigmaLimitsFromConfig(*cfg_.sigma_limits, layout_, P0_);
		ukf_->setSigmaLimits(lo, hi);
	}
	if (cfg_.delayed.max_delay_s > 0) history_ = std::make_unique<FilterHistory>(cfg_.delayed);
}

void Navigator::addDenial(const DenialWindow& w)
{
	checkDenialLabels(w);
	cfg_.denial.push_back(w);
}

void Navigator::checkDenialLabels(const DenialWindow& w) const
{
	for (const auto& label : w.labels)
	{
		if (std::any_of(slots_.begin(), slots_.end(), [&](const auto& s) { return s->stats.label == label; }))
			continue;
		std::string known;
		for (const auto& s : slots_) known += (known.empty() ? "" : ", ") + s->stats.label;
		throw std::invalid_argument("denial of an unknown sensor '" + label + "' (the sensors: " + known +
		                            ")");
	}
}

bool Navigator::denied(const std::string& label, double t_obs) const
{
	const double rel = t_obs - t0_s_;
	for (const auto& w : cfg_.denial)
		if (rel >= w.from_s && rel < w.to_s)
			for (const auto& l : w.labels)
				if (l == label) return true;
	return false;
}

std::vector<SensorStats> Navigator::stats() const
{
	std::vector<SensorStats> out{imu_stats_};
	for (const auto& s : slots_) out.push_back(s->stats);
	return out;
}

std::size_t Navigator::positionReinitializations() const
{
	std::size_t n = 0;
	for (const auto& s : slots_) n += s->stats.reinitialized;
	return n;
}

std::vector<std::string> Navigator::positionFixLabels() const
{
	std::vector<std::string> out;
	for (const auto& s : slots_)
		if (s->model->reportsPositionFix()) out.push_back(s->stats.label);
	return out;
}

Eigen::Vector3d Navigator::bodyPosition_n() const
{
	const NavState& x = ukf_->state();
	return x.p_n - x.R_nb * cfg_.imu.position_b;
}

void Navigator::process(const mrpt::obs::CObservation& obs)
{
	const double t = mrpt::Clock::toDouble(obs.timestamp);
	if (!std::isfinite(t) || t <= 0)
	{
		++imu_stats_.invalid;  // counted with the IMU: there is no valid time to place it
		imu_stats_.last_problem = "observation '" + obs.sensorLabel + "' with an invalid timestamp";
		return;
	}
	if (t0_s_ < 0) t0_s_ = t;
	if (obs.sensorLabel == cfg_.imu.label)
	{
		if (denied(obs.sensorLabel, t))
		{
			++imu_stats_.denied;
			return;
		}
		// A sample unfit for prediction (NaN, duplicate, backwards) is dropped
		// whole: its accelerometer part must not update the state either.
		if (!handleImu(obs)) return;
	}
	// The fixes for initialisation come from the fix sensor's plugin
	// (MeasurementModel::initialFix: the GPS decodes its GGA, a USBL its own);
	// the start waits for enough of them to agree (fix_consensus.h).
	if (!initialized_ && init_.wantsFixFrom(obs.sensorLabel) && !denied(obs.sensorLabel, t))
		for (auto& slot : slots_)
			if (slot->stats.label == obs.sensorLabel)
			{
				InitialFix fix;
				if (slot->model->initialFix(obs, context(t), fix)) init_.addFix(t, fix);
			}
	if (initialized_ && !denied(obs.sensorLabel, t)) recordFixOffset(obs, t);
	dispatch(obs, t);
}

void Navigator::recordFixOffset(const mrpt::obs::CObservation& obs, double t)
{
	for (auto& slot : slots_)
	{
		if (slot->stats.label != obs.sensorLabel || !slot->model->reportsPositionFix()) continue;
		InitialFix fix;
		if (!slot->model->initialFix(obs, context(t), fix) || !fix.p_n.allFinite() || !fix.r_b.allFinite())
			continue;
		const NavState& x = ukf_->state();
		const Eigen::Vector3d predicted_n = x.p_n + x.R_nb * (fix.r_b - cfg_.imu.position_b);
		AidingPolicy::recordFixOffset(slot->aiding, t, (fix.p_n - predicted_n).head<2>());
	}
}

bool Navigator::handleImu(const mrpt::obs::CObservation& obs)
{
	const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(&obs);
	const double t = mrpt::Clock::toDouble(obs.timestamp);
	using namespace mrpt::obs;
	if (!imu || !imu->has(IMU_WX) || !imu->has(IMU_WY) || !imu->has(IMU_WZ) || !imu->has(IMU_X_ACC))
	{
		++imu_stats_.invalid;
		imu_stats_.last_problem = "IMU observation without gyro/accelerometer data";
		return false;
	}
	const Eigen::Vector3d w(imu->get(IMU_WX), imu->get(IMU_WY), imu->get(IMU_WZ));
	const Eigen::Vector3d f(imu->get(IMU_X_ACC), imu->get(IMU_Y_ACC), imu->get(IMU_Z_ACC));
	if (!w.allFinite() || !f.allFinite())
	{
		++imu_stats_.invalid;
		imu_stats_.last_problem = "non-finite IMU sample";
		return false;
	}
	if (!initialized_)
	{
		init_.addImu(t, f);
		t_s_ = t;
		omega_ib_b_ = w;
		++imu_stats_.before_init;
		if (init_.ready(t)) initialize();
		return true;
	}
	const double dt = t - t_s_;
	if (dt > cfg_.clock.max_forward_jump_s || dt < -cfg_.clock.max_backward_jump_s)
	{
		clockJump(t, dt);
		return handleImu(obs);  // the first sample of the new initialisation
	}
	if (dt <= 0)
	{
		++imu_stats_.invalid;
		imu_stats_.last_problem = dt == 0 ? "duplicate IMU timestamp" : "IMU timestamp going backwards";
		return false;
	}
	if (history_)
	{
		checkpointIfDue(history_->end());
		history_->trim(t_s_);
		commitSmoother();
		history_->pushImu(t, w);
	}
	if (dt > cfg_.imu.max_gap_s) ++imu_gaps_;
	propagate(w, t);
	if (!history_) commitSmoother();  // nothing can rewind: write as it comes
	t_latest_s_ = t;
	++predictions_;
	++imu_stats_.accepted;
	if (t_s_ >= next_health_check_s_)
	{
		next_health_check_s_ = t_s_ + 1.0;
		health_.onState(t_s_ - t0_s_, ukf_->state(), ukf_->covariance());
	}
	if (on_predict) on_predict(*this);
	return true;
}

void Navigator::clockJump(double t, double dt)
{
	char what[256];
	std::snprintf(what, sizeof what,
	              "IMU '%s' clock jumped by %+.3f s at %.3f s from the start (%.3f -> %.3f s)",
	              cfg_.imu.label.c_str(), dt, t_s_ - t0_s_, t_s_, t);
	if (cfg_.clock.stop_on_jump)
		throw std::runtime_error(
		    std::string(what) + "; not predicted through (clock.on_jump: stop; 'reinitialize' starts again)");
	// Start again from this sample: levelling, then the first fix, as at the start.
	++clock_jumps_;
	imu_stats_.last_problem = std::string(what) + "; re-initialised";
	if (smoother_ && initialized_)
	{
		smoother_->endSegment(*ukf_, t_s_);
		// After the history is reset below nothing rewinds: write all.
		try
		{
			smoother_->commit(std::numeric_limits<std::size_t>::max());
		}
		catch (const std::exception& e)
		{
			stopSmoothing(e.what());
		}
	}
	initialized_ = false;
	init_.clear();
	if (history_) history_ = std::make_unique<FilterHistory>(cfg_.delayed);
	for (auto& slot : slots_) slot->aiding.gate.clear();
	t_s_ = t_latest_s_ = t;
}

void Navigator::initialize()
{
	NavState x0 = init_.initialState(*frame_);
	// Plugin states start at their declared means, the model parameters at
	// their prior (the process model's prior mean).
	const TangentVector& prior = ukf_->processModel().prior_mean;
	x0.extra = prior.tail(prior.size() - idx::core_dim);
	TangentVector e = x0.euclidean();
	e.segment<18>(idx::inertia) = cfg_.prior_mean.segment<18>(idx::inertia);
	x0.setEuclidean(e);
	ukf_->initialize(x0, P0_);
	initialized_ = true;
	t_latest_s_ = t_s_;
	const std::string event = init_.startEvent(x0);
	if (!event.empty() && on_event) on_event(t_s_ - t0_s_, cfg_.initial.fix_label, event);
}

std::string Navigator::waitingFor() const
{
	return initialized_ ? "" : init_.waitingFor(t_s_, t0_s_ >= 0);
}

void Navigator::finish()
{
	if (!initialized_) health_.setNotInitialized(waitingFor());
	if (smoother_ && initialized_) try
		{
			smoother_->finish(*ukf_, t_s_);
		}
		catch (const std::exception& e)  // a full disk: the filter's run stands, the smoothing cannot
		{
			stopSmoothing(e.what());
		}
}

FilterContext Navigator::context(double t_obs) const
{
	FilterContext ctx;
	ctx.t_s = t_s_;
	ctx.t_measurement_s = t_obs;
	ctx.omega_ib_b = omega_ib_b_;
	ctx.omega_ie_n = frame_->earthRate();
	ctx.imu_position_b = cfg_.imu.position_b;
	ctx.frame = frame_.get();
	ctx.alpha_b = alpha_b_;
	ctx.alpha_delay_s = alpha_delay_s_;
	ctx.mean = initialized_ ? &ukf_->state() : nullptr;
	ctx.current_far_distance_m = ukf_ ? ukf_->processModel().current_far_distance_m : 0.0;
	ctx.covariance = initialized_ ? &ukf_->covariance() : nullptr;
	return ctx;
}

double Navigator::measurementTime(const Slot& slot, const mrpt::obs::CObservation& obs, double stamp_s) const
{
	const double t = slot.model->measurementTime(obs, stamp_s - slot.latency_s);
	return std::isfinite(t) && t > 0 ? t : std::numeric_limits<double>::quiet_NaN();
}

void Navigator::dispatch(const mrpt::obs::CObservation& obs, double stamp_s)
{
	for (std::size_t i = 0; i < slots_.size(); ++i)
	{
		Slot& slot = *slots_[i];
		SensorStats& st = slot.stats;
		if (st.label != obs.sensorLabel) continue;
		const double t_m = measurementTime(slot, obs, stamp_s);
		if (std::isnan(t_m))
		{
			++st.invalid;
			st.last_problem = "no valid measurement time";
			continue;
		}
		if (denied(st.label, t_m))
		{
			++st.denied;
			continue;
		}
		if (!initialized_)
		{
			++st.before_init;
			continue;
		}
		if (t_m > t_s_ + cfg_.clock.max_forward_jump_s)
		{
			// Not a measurement to apply now: a sensor on another clock, or a jump.
			++st.invalid;
			st.last_problem =
			    "timestamp " + std::to_string(t_m - t_s_) + " s ahead of the IMU (clock.max_forward_jump_s)";
			continue;
		}
		if (t_m < t_s_ - cfg_.delayed.apply_now_within_s)
		{
			// Re-filtered at its time if the history reaches back that far.
			if (history_ && t_m >= t_s_ - cfg_.delayed.max_delay_s && applyDelayed(i, obs, t_m)) continue;
			++st.late;
			st.last_problem = "observation older than filter.delayed_measurements.max_delay_s";
			continue;
		}
		prepareAndApply(i, obs, t_m, history_ ? history_->end() : 0);
	}
}

}  // namespace auvnav
