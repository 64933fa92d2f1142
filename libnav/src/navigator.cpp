#include <auvnav/navigator.h>
#include <auvnav/process_model_config.h>
#include <auvnav/rejection_streak.h>
#include <auvnav/so3.h>
#include <mrpt/obs/CObservationIMU.h>
#if AUVNAV_HAVE_CALLGRIND_H
#include <valgrind/callgrind.h>
#endif

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace auvnav
{
namespace
{
constexpr double kDeg = M_PI / 180;

/** Rows x, y; columns x, y, ψ of the 6x6 diagonal matrix given by its
 *  diagonal, in the state's stored form (logarithms on the diagonal). */
Eigen::Matrix<double, 2, 3> subMatrix(const config::Node& n, const std::string& key)
{
	const auto d = n.numbers(key);
	if (d.size() != 6) n.fail(key, "expected 6 diagonal values");
	if (!(d[0] > 0) || !(d[1] > 0)) n.fail(key, "surge and sway entries must be positive");
	Eigen::Matrix<double, 2, 3> m = Eigen::Matrix<double, 2, 3>::Zero();
	m(0, 0) = d[0];
	m(1, 1) = d[1];
	return storedSub(m);
}

void put23(TangentVector& t, int at, const Eigen::Matrix<double, 2, 3>& m)
{
	for (int r = 0; r < 2; ++r)
		for (int c = 0; c < 3; ++c) t[at + 3 * r + c] = m(r, c);
}
}  // namespace

struct Navigator::Slot
{
	SensorStats stats;
	ModelPtr model;
	double latency_s = 0;           // sensors[].latency_s: measurement time = stamp − latency
	double rejecting_since_s = -1;  // start of the current run of rejections
	RejectionStreak streak;         // its innovations (rejection_streak.h)
	RejectedFixRun fix_run;         // a position sensor's gate-failing fixes (fix_consensus.h)
	double last_reinit_t_obs = -1;  // counted once, though re-filtering may redo it
	// Every fix of a position sensor since its run of rejections began (initialFix:
	// also those the plugin skips): arrival time, fix − the state's sensor point [m].
	std::deque<std::pair<double, Eigen::Vector2d>> fix_offsets;
	std::vector<Measurement> buffer;
	bool profiled = false;  // AUVNAV_CALLGRIND_SENSOR names it (CallgrindStage)
};

namespace
{
/** bench/instructions.sh counts one sensor's instructions: run under
 *  `valgrind --tool=callgrind --collect-atstart=no` with
 *  AUVNAV_CALLGRIND_SENSOR=<label>, collection is on only while that sensor's
 *  observations are prepared and applied. Outside valgrind the toggle is a few
 *  no-op instructions, and it only runs for the named sensor. */
class CallgrindStage
{
 public:
	explicit CallgrindStage(bool on) : on_(on) { toggle(); }
	~CallgrindStage() { toggle(); }
	CallgrindStage(const CallgrindStage&) = delete;
	CallgrindStage& operator=(const CallgrindStage&) = delete;

 private:
	void toggle() const
	{
#if AUVNAV_HAVE_CALLGRIND_H
		if (on_) CALLGRIND_TOGGLE_COLLECT;
#endif
	}
	bool on_;
};

bool profiledSensor(const std::string& label)
{
	const char* name = std::getenv("AUVNAV_CALLGRIND_SENSOR");
	return name && label == name;
}
}  // namespace

/** What re-filtering for delayed measurements needs (navigator.h): the
 *  filter's inputs since the oldest checkpoint, in the order applied, and
 *  checkpoints of everything that decides how they are applied. */
struct Navigator::History
{
	struct Event
	{
		bool imu = false;  // an IMU sample to predict to, or one observation's prepared measurements
		double t = 0;      // IMU: its time; else the filter time it was applied at
		Eigen::Vector3d w = Eigen::Vector3d::Zero();  // IMU: gyro sample
		std::size_t slot = 0;
		double t_obs = 0;   // measurement time
		FilterContext ctx;  // as prepared (mean and covariance pointers are re-set)
		std::vector<Measurement> ms;
	};
	struct Gate
	{
		double rejecting_since_s = -1;
		RejectionStreak streak;
		RejectedFixRun fix_run;
	};
	struct Checkpoint
	{
		std::size_t event = 0;  // absolute index of the IMU event it precedes
		double t_s = 0;
		NavState x;
		Covariance P;
		Eigen::Vector3d omega_ib_b, alpha_b;
		std::vector<Gate> gates;
		std::optional<SmoothingRecorder::Snapshot> smoother;
	};
	std::deque<Event> events;
	std::size_t first = 0;  // absolute index of events.front()
	std::deque<Checkpoint> checkpoints;

	Event& at(std::size_t abs) { return events[abs - first]; }
	std::size_t end() const { return first + events.size(); }
};

Navigator::~Navigator() = default;

Navigator::Navigator(const config::Node& cfg, PluginHost& host)
{
	const auto nf = cfg.child("navigation_frame").child("origin");
	frame_ = std::make_unique<earth::TangentFrame>(
	    earth::Geodetic{nf.inRange("latitude_deg", -85, 85) * kDeg,
	                    nf.inRange("longitude_deg", -180, 180) * kDeg, nf.number("height_m", 0.0)});
	const auto imu = cfg.child("imu");
	imu_label_ = imu.string("label");
	imu_position_b_ = imu.vector3("position_m");
	leveling_s_ = imu.inRange("leveling_s", 0.01, 600, 1.0);
	max_gap_s_ = imu.inRange("max_gap_s", 0.01, 10, 0.5);
	alpha_tau_s_ = imu.inRange("angular_acceleration_tau_s", 0.01, 10, 0.2);
	imu_stats_.label = imu_label_;
	imu_stats_.plugin = "(prediction)";

	const auto f = cfg.child("filter");
	initial_ = f.child("initial");
	// Prior means of the Gauss–Markov states: zero biases and currents,
	// model parameters from the system identification.
	// The parameter prior: inline `vehicle_model`, or `vehicle_model_file`
	// (relative to this config file) shared with the model-aiding plugin.
	const auto vm = f.has("vehicle_model_file") ? config::Node::load(f.filePath("vehicle_model_file"))
	                                            : f.child("vehicle_model");
	put23(prior_mean_, idx::inertia, subMatrix(vm, "inertia_diag"));
	put23(prior_mean_, idx::damping_lin, subMatrix(vm, "linear_damping_diag"));
	put23(prior_mean_, idx::damping_quad, subMatrix(vm, "quadratic_damping_diag"));
	ProcessModel pm = processModelFromConfig(f.child("process_noise"), prior_mean_);
	UtParams ut;
	if (f.has("unscented"))
	{
		const auto u = f.child("unscented");
		ut.alpha = u.inRange("alpha", 1e-4, 1.0, ut.alpha);
		ut.beta = u.nonNegative("beta", ut.beta);
		ut.kappa = u.number("kappa", ut.kappa);
		ut.max_attitude_spread_rad = u.inRange("max_attitude_spread_deg", 1, 170, 30) * kDeg;
	}
	earth_rate_ = f.boolean("earth_rate", true);
	if (f.has("delayed_measurements"))
	{
		const auto d = f.child("delayed_measurements");
		max_delay_s_ = d.inRange("max_delay_s", 0, 600, max_delay_s_);
		apply_now_within_s_ = d.inRange("apply_now_within_s", 0, 1, apply_now_within_s_);
		checkpoint_every_s_ = d.inRange("checkpoint_every_s", 0.001, 10, checkpoint_every_s_);
	}
	if (max_delay_s_ > 0) history_ = std::make_unique<History>();

	// Initial covariance (diagonal, tangent order).
	const auto& in = initial_;
	P0_.setZero(idx::core_dim, idx::core_dim);
	auto set3 = [&](int at, double sigma) { P0_.block<3, 3>(at, at).diagonal().setConstant(sigma * sigma); };
	const double rp = in.positive("roll_pitch_sigma_deg") * kDeg;
	P0_(0, 0) = P0_(1, 1) = rp * rp;
	P0_(2, 2) = std::pow(in.positive("heading_sigma_deg") * kDeg, 2);
	set3(idx::gyro_bias, in.positive("gyro_bias_sigma_deg_per_h") * kDeg / 3600);
	set3(idx::acc, in.positive("acceleration_sigma_mps2"));
	P0_(idx::gravity, idx::gravity) = std::pow(in.positive("gravity_sigma_mps2"), 2);
	set3(idx::acc_bias, in.positive("accel_bias_sigma_mg") * 1e-3 * 9.80665);
	set3(idx::vel, in.positive("velocity_sigma_mps"));
	set3(idx::pos, in.positive("position_sigma_m"));
	const double sc = in.positive("current_sigma_mps");
	P0_.block<4, 4>(idx::current_vehicle, idx::current_vehicle).diagonal().setConstant(sc * sc);
	const double sb = in.positive("adcp_bias_sigma_mps");
	P0_.block<2, 2>(idx::adcp_bias, idx::adcp_bias).diagonal().setConstant(sb * sb);
	for (int i = 0; i < 18; ++i)
		P0_(idx::inertia + i, idx::inertia + i) = std::pow(std::max(pm.noise.parameter_sigma[i], 1e-6), 2);
	const std::string position_source = in.string("position", "config");
	if (position_source == "gps")
	{
		position_from_gps_ = true;
		gps_label_ = in.string("gps_label", "GPS");
	}
	else if (position_source != "config")
		in.fail("position", "expected 'gps' or 'config', got '" + position_source + "'");
	if (in.has("fix_consensus"))
	{
		const auto c = in.child("fix_consensus");
		FixConsensusParams p;
		p.min_fixes = static_cast<int>(c.inRange("min_fixes", 1, 100, p.min_fixes));
		p.max_spread_m = c.positive("max_spread_m", p.max_spread_m);
		p.window_s = c.positive("window_s", p.window_s);
		fix_consensus_ = InitialFixConsensus(p);
	}
	// Used at initialisation (or with the other position source); checked now so
	// that a bad or misspelled key fails at start.
	(void)in.string("gps_label", "GPS");
	(void)in.inRange("heading_deg", -360, 360);
	(void)in.number("north_m", 0.0), (void)in.number("east_m", 0.0), (void)in.number("depth_m", 0.0);

	if (cfg.has("clock"))
	{
		const auto c = cfg.child("clock");
		max_forward_jump_s_ = c.inRange("max_forward_jump_s", 0.02, 3600, max_forward_jump_s_);
		max_backward_jump_s_ = c.inRange("max_backward_jump_s", 0.0, 3600, max_backward_jump_s_);
		const std::string action = c.string("on_jump", "stop");
		if (action != "stop" && action != "reinitialize")
			c.fail("on_jump", "expected stop or reinitialize, got '" + action + "'");
		stop_on_jump_ = action == "stop";
	}
	if (max_gap_s_ > max_forward_jump_s_)
		imu.fail("max_gap_s", "must not exceed clock.max_forward_jump_s (" +
		                          std::to_string(max_forward_jump_s_) +
		                          " s): longer steps are clock jumps, not gaps");
	if (cfg.has("health")) health_ = HealthMonitor(HealthLimits::fromConfig(cfg.child("health")));
	if (cfg.has("smoother"))
	{
		const auto sm = cfg.child("smoother");
		sm.allowOnly({"keep_every_s", "across_recoveries"});
		smoother_keep_every_s_ = sm.inRange("keep_every_s", 0.005, 3600, smoother_keep_every_s_);
		smooth_across_recoveries_ = sm.boolean("across_recoveries", smooth_across_recoveries_);
	}
	if (cfg.has("gates"))
	{
		const auto g = cfg.child("gates");
		g.allowOnly(
		    {"recovery_after_s", "consistent_rejections", "consistency_probability", "position_reinit"});
		recovery_after_s_ = g.positive("recovery_after_s", recovery_after_s_);
		consistent_rejections_ =
		    static_cast<int>(g.inRange("consistent_rejections", 0, 8, consistent_rejections_));
		if (consistent_rejections_ > 0 && consistent_rejections_ < 3)
			g.fail("consistent_rejections", "needs at least 3 rejections to fit a drift (0 switches it off)");
		consistency_probability_ =
		    g.inRange("consistency_probability", 0.5, 1.0 - 1e-9, consistency_probability_);
		if (g.has("position_reinit"))
		{
			const auto r = g.child("position_reinit");
			reinit_fixes_ = static_cast<int>(r.inRange("rejected_fixes", 0, 16, reinit_fixes_));
			if (reinit_fixes_ == 1)
				r.fail("rejected_fixes", "needs at least 2 fixes to agree (0 switches it off)");
			reinit_probability_ = r.inRange("probability", 0.5, 1.0 - 1e-9, reinit_probability_);
			reinit_spread_m_ = r.positive("max_spread_m", reinit_spread_m_);
		}
	}
	if (cfg.has("denial"))
		for (const auto& d : cfg.sequence("denial"))
		{
			DenialWindow w;
			w.from_s = d.nonNegative("from_s");
			w.to_s = d.positive("to_s");
			if (w.to_s <= w.from_s) d.fail("to_s", "must be after from_s");
			for (const auto& l : d.strings("labels")) w.labels.push_back(l);
			denial_.push_back(w);
		}

	for (const auto& s : cfg.sequence("sensors"))
	{
		auto slot = std::make_unique<Slot>();
		slot->stats.label = s.string("label");
		slot->stats.plugin = s.string("plugin");
		slot->profiled = profiledSensor(slot->stats.label);
		slot->latency_s = s.inRange("latency_s", 0, 600, 0.0);
		s.markFreeForm("config");  // the plugin checks its own keys
		// Observation libraries the entry declares are the program's to load
		// before the rawlog is opened (obs_libraries.h); accepted here.
		if (s.has("obs_libs"))
			(void)(s.isSequence("obs_libs") ? s.strings("obs_libs").size() : s.string("obs_libs").size());
		host.load(slot->stats.plugin);  // a plugin that does not load is no config error
		try
		{
			slot->model = host.create(slot->stats.plugin, pluginConfigText(s), slot->stats.label);
		}
		catch (const PluginError& e)
		{
			// Name the file the plugin's configuration came from.
			throw PluginError((s.has("config_file") ? s.filePath("config_file") : s.where("config")) + ": " +
			                  e.what());
		}
		slots_.push_back(std::move(slot));
	}
	if (position_from_gps_)
	{
		bool found = false;
		for (const auto& slot : slots_) found = found || slot->stats.label == gps_label_;
		if (!found)
			initial_.fail("gps_label", "'" + gps_label_ +
			                               "' is not the label of any entry in sensors: (the first fix comes "
			                               "from that sensor's plugin)");
	}
	// Every key must have been read: a misspelled one is an error, not a default.
	// plugin_paths and outputs belong to the program (auvnav-run checks them).
	appendPluginStates(pm);
	ukf_ = std::make_unique<ManifoldUkf>(pm, ut);
	if (f.has("sigma_limits")) readSigmaLimits(f.child("sigma_limits"));
	cfg.checkAllKeysUsed({"plugin_paths", "outputs"});
}

void Navigator::readSigmaLimits(const config::Node& limits)
{
	// What a key may name: a block of the paper's state, a plugin's block
	// ("<label>.<block>") or one state (stateNames()), each [first, count).
	std::map<std::string, std::pair<int, int>> targets = {{"att", {idx::att, 3}},
	                                                      {"gyro_bias", {idx::gyro_bias, 3}},
	                                                      {"acc", {idx::acc, 3}},
	                                                      {"gravity", {idx::gravity, 1}},
	                                                      {"acc_bias", {idx::acc_bias, 3}},
	                                                      {"vel", {idx::vel, 3}},
	                                                      {"pos", {idx::pos, 3}},
	                                                      {"current", {idx::current_vehicle, 2}},
	                                                      {"current_far", {idx::current_far, 2}},
	                                                      {"adcp_bias", {idx::adcp_bias, 2}},
	                                                      {"M", {idx::inertia, 6}},
	                                                      {"Dl", {idx::damping_lin, 6}},
	                                                      {"Dq", {idx::damping_quad, 6}}};
	for (const auto& b : plugin_blocks_) targets[b.sensor + "." + b.name] = {b.offset, b.dim};
	for (int i = 0; i < static_cast<int>(state_names_.size()); ++i)
		targets.emplace(state_names_[i], std::make_pair(i, 1));
	std::vector<std::string> names;
	for (const auto& [name, range] : targets) names.push_back(name);
	limits.allowOnly(names);
	const int n = static_cast<int>(state_names_.size());
	TangentVector lo = TangentVector::Zero(n), hi = TangentVector::Constant(n, INFINITY);
	// Blocks first, then single states, so that a state's own entry wins.
	for (const bool single : {false, true})
		for (const auto& key : limits.keys())
		{
			const auto [first, count] = targets.at(key);
			if ((count == 1 && first < n && state_names_[first] == key) != single) continue;
			const auto l = limits.child(key);
			l.allowOnly({"min", "max"});
			const double min_sigma = l.nonNegative("min", 0.0);
			const double max_sigma = l.has("max") ? l.positive("max") : INFINITY;
			if (max_sigma < min_sigma) l.fail("max", "is below min");
			lo.segment(first, count).setConstant(min_sigma);
			hi.segment(first, count).setConstant(max_sigma);
		}
	for (int i = 0; i < n; ++i)
		if (std::sqrt(P0_(i, i)) < lo[i] || std::sqrt(P0_(i, i)) > hi[i])
			limits.fail(state_names_[i], "its initial sigma " + std::to_string(std::sqrt(P0_(i, i))) +
			                                 " (filter.initial) is outside its limits [" +
			                                 std::to_string(lo[i]) + ", " + std::to_string(hi[i]) + "]");
	ukf_->setSigmaLimits(lo, hi);
}

void Navigator::appendPluginStates(ProcessModel& pm)
{
	state_names_ = tangentNames();
	stored_names_ = storedNames();
	for (auto& slot : slots_)
	{
		const std::string& label = slot->stats.label;
		std::vector<StateBlockSpec> blocks;
		try
		{
			blocks = slot->model->stateBlocks();
		}
		catch (const std::exception& e)
		{
			throw PluginError("sensor '" + label + "' (plugin " + slot->stats.plugin +
			                  "): stateBlocks() failed: " + e.what());
		}
		if (blocks.empty()) continue;
		const int first_extra = pm.dim() - idx::core_dim;
		for (const StateBlockSpec& b : blocks)
		{
			const int at = pm.dim();
			try
			{
				pm.appendBlock(b);
			}
			catch (const std::exception& e)
			{
				throw PluginError("sensor '" + label + "' (plugin " + slot->stats.plugin + "): " + e.what());
			}
			P0_.conservativeResize(pm.dim(), pm.dim());
			P0_.rightCols(b.dimension()).setZero();
			P0_.bottomRows(b.dimension()).setZero();
			for (int i = 0; i < b.dimension(); ++i)
			{
				const double sigma = b.sigma.size() == 1 ? b.sigma[0] : b.sigma[i];
				P0_(at + i, at + i) = sigma * sigma;
				const std::string name =
				    label + "." + b.name + (b.components[i].empty() ? "" : "_" + b.components[i]);
				state_names_.push_back(name);
				stored_names_.push_back(name);
			}
			plugin_blocks_.push_back({label, b.name, at, b.dimension()});
		}
		slot->model->bindStates(first_extra);
	}
}

std::string pluginConfigText(const config::Node& s)
{
	// Inline `config`, or `config_file` relative to the navigator's file.
	if (s.has("config") && s.has("config_file")) s.fail("config_file", "give either config or config_file");
	config::Node plugin_cfg = s.has("config")        ? s.child("config")
	                          : s.has("config_file") ? config::Node::load(s.filePath("config_file"))
	                                                 : config::Node::fromText("{}", s.file());
	// Plugins receive YAML text: tell them where relative paths in it start.
	const std::string origin = s.has("config_file") ? s.filePath("config_file") : s.file();
	if (!plugin_cfg.has("config_dir"))
		plugin_cfg.set("config_dir", fs::absolute(fs::path(origin)).parent_path().string());
	return plugin_cfg.toYaml();
}

bool Navigator::denied(const std::string& label, double t_obs) const
{
	const double rel = t_obs - t0_s_;
	for (const auto& w : denial_)
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
	return x.p_n - x.R_nb * imu_position_b_;
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
	if (obs.sensorLabel == imu_label_)
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
	if (!initialized_ && position_from_gps_ && obs.sensorLabel == gps_label_ && !denied(obs.sensorLabel, t))
		for (auto& slot : slots_)
			if (slot->stats.label == gps_label_)
			{
				InitialFix fix;
				if (slot->model->initialFix(obs, context(t), fix) && fix.p_n.allFinite() &&
				    fix.r_b.allFinite())
				{
					fix_consensus_.add(t, fix);
					gps_fix_ = fix_consensus_.agreed();
				}
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
		const Eigen::Vector3d predicted_n = x.p_n + x.R_nb * (fix.r_b - imu_position_b_);
		auto& offsets = slot->fix_offsets;
		offsets.emplace_back(t, (fix.p_n - predicted_n).head<2>());
		// Only those since the current run of rejections began are needed.
		const double keep_from = slot->fix_run.size() > 0 ? slot->fix_run.firstTime_s() : t;
		while (offsets.size() > 1 && offsets.front().first < keep_from) offsets.pop_front();
	}
}

bool Navigator::mostFixesAgreeWith(const Slot& slot, const Eigen::Vector2d& offset_m) const
{
	const double from = slot.fix_run.firstTime_s(reinit_fixes_);
	int all = 0, agreeing = 0;
	for (const auto& [t, d] : slot.fix_offsets)
		if (t >= from)
		{
			++all;
			agreeing += (d - offset_m).norm() <= reinit_spread_m_;
		}
	return all == 0 || 2 * agreeing > all;  // no record (a plugin without initialFix): the run decides
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
		if (leveling_start_s_ < 0) leveling_start_s_ = t;
		f_sum_ += f;
		w_sum_ += w;
		++leveling_samples_;
		t_s_ = t;
		omega_ib_b_ = w;
		++imu_stats_.before_init;
		if (t - leveling_start_s_ >= leveling_s_ && (!position_from_gps_ || gps_fix_)) initialize();
		return true;
	}
	const double dt = t - t_s_;
	if (dt > max_forward_jump_s_ || dt < -max_backward_jump_s_)
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
		trimHistory();
		History::Event e;
		e.imu = true;
		e.t = t;
		e.w = w;
		history_->events.push_back(std::move(e));
	}
	if (dt > max_gap_s_) ++imu_gaps_;
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
	              imu_label_.c_str(), dt, t_s_ - t0_s_, t_s_, t);
	if (stop_on_jump_)
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
	leveling_samples_ = 0;
	leveling_start_s_ = -1;
	f_sum_.setZero();
	w_sum_.setZero();
	gps_fix_.reset();
	fix_consensus_.clear();
	if (history_) history_ = std::make_unique<History>();
	for (auto& slot : slots_)
	{
		slot->rejecting_since_s = -1;
		slot->streak.clear();
		slot->fix_run.clear();
	}
	t_s_ = t_latest_s_ = t;
}

void Navigator::propagate(const Eigen::Vector3d& w, double t)
{
	const double dt = t - t_s_;
	// A gap: predict in steps no longer than the nominal limit with the new rate.
	const int steps = dt > max_gap_s_ ? static_cast<int>(std::ceil(dt / 0.01)) : 1;
	const Eigen::Vector3d omega_ie_n = earth_rate_ ? frame_->earthRate() : Eigen::Vector3d::Zero();
	for (int i = 0; i < steps; ++i)
	{
		if (smoother_)
			smoother_->predict(*ukf_, w, omega_ie_n, dt / steps, t_s_ + i * (dt / steps));
		else
			ukf_->predict(w, omega_ie_n, dt / steps);
	}
	// Angular acceleration: first-order low-pass of the gyro's derivative.
	alpha_b_ += ((w - omega_ib_b_) / dt - alpha_b_) * (dt / (alpha_tau_s_ + dt));
	t_s_ = t;
	omega_ib_b_ = w;
}

void Navigator::checkpointIfDue(std::size_t event)
{
	auto& cps = history_->checkpoints;
	if (!cps.empty() && t_s_ - cps.back().t_s < checkpoint_every_s_) return;
	History::Checkpoint c;
	c.event = event;
	c.t_s = t_s_;
	c.x = ukf_->state();
	c.P = ukf_->covariance();
	c.omega_ib_b = omega_ib_b_;
	c.alpha_b = alpha_b_;
	c.gates.reserve(slots_.size());
	for (const auto& slot : slots_) c.gates.push_back({slot->rejecting_since_s, slot->streak, slot->fix_run});
	if (smoother_) c.smoother = smoother_->snapshot(*ukf_);
	cps.push_back(std::move(c));
}

void Navigator::trimHistory()
{
	// Keep the newest checkpoint at or before t − max_delay and all after it:
	// a measurement up to max_delay_s old finds one before it.
	auto& H = *history_;
	while (H.checkpoints.size() >= 2 && H.checkpoints[1].t_s <= t_s_ - max_delay_s_)
		H.checkpoints.pop_front();
	const std::size_t keep_from = H.checkpoints.empty() ? H.end() : H.checkpoints.front().event;
	while (H.first < keep_from && !H.events.empty())
	{
		H.events.pop_front();
		++H.first;
	}
	commitSmoother();
}

void Navigator::commitSmoother()
{
	if (!smoother_) return;
	// Records from before the oldest checkpoint can no longer be rewound.
	const bool can_rewind =
	    history_ && !history_->checkpoints.empty() && history_->checkpoints.front().smoother;
	try
	{
		smoother_->commit(can_rewind ? history_->checkpoints.front().smoother->emitted
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
	if (history_)
		for (auto& c : history_->checkpoints) c.smoother.reset();
}

void Navigator::enableSmoothing(const std::string& path)
{
	StretchFileHeader h;
	h.n = ukf_->dim();
	h.imu_position_b = imu_position_b_;
	h.tangent_names = state_names_;
	h.stored_names = stored_names_;
	smoother_ = std::make_unique<SmoothingRecorder>(path, h, smoother_keep_every_s_);
}

void Navigator::restoreLastCheckpoint()
{
	const History::Checkpoint& c = history_->checkpoints.back();
	ukf_->restore(c.x, c.P);
	t_s_ = c.t_s;
	omega_ib_b_ = c.omega_ib_b;
	alpha_b_ = c.alpha_b;
	if (smoother_ && c.smoother) smoother_->restore(*c.smoother, *ukf_);
	for (std::size_t i = 0; i < slots_.size(); ++i)
	{
		slots_[i]->rejecting_since_s = c.gates[i].rejecting_since_s;
		slots_[i]->streak = c.gates[i].streak;
		slots_[i]->fix_run = c.gates[i].fix_run;
	}
}

void Navigator::replayEvent(std::size_t event)
{
	History::Event& e = history_->at(event);
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
	const CallgrindStage profile(slots_[e.slot]->profiled);
	applyMeasurements(*slots_[e.slot], e.ms, ctx, e.t_obs, false);
}

bool Navigator::applyDelayed(std::size_t slot_index, const mrpt::obs::CObservation& obs, double t_m)
{
	History& H = *history_;
	// In-order processing would have applied it after the last IMU sample at
	// or before t_m and the measurements taken up to t_m applied with it.
	std::size_t ins = H.end();
	while (ins > H.first && !(H.at(ins - 1).imu && H.at(ins - 1).t <= t_m)) --ins;
	if (ins == H.first) return false;  // older than everything kept
	while (ins < H.end() && !H.at(ins).imu && H.at(ins).t_obs <= t_m) ++ins;
	// The last checkpoint before that point; later ones are re-taken.
	std::size_t keep = H.checkpoints.size();
	while (keep > 0 && H.checkpoints[keep - 1].event > ins) --keep;
	if (keep == 0) return false;
	H.checkpoints.resize(keep);
	restoreLastCheckpoint();
	for (std::size_t k = H.checkpoints.back().event; k < ins; ++k) replayEvent(k);

	std::size_t resume = ins;
	if (prepareAndApply(slot_index, obs, t_m, ins))
	{
		++slots_[slot_index]->stats.delayed;
		resume = ins + 1;
	}
	for (std::size_t k = resume; k < H.end(); ++k) replayEvent(k);
	return true;
}

double Navigator::measurementTime(const Slot& slot, const mrpt::obs::CObservation& obs, double stamp_s) const
{
	const double t = slot.model->measurementTime(obs, stamp_s - slot.latency_s);
	return std::isfinite(t) && t > 0 ? t : std::numeric_limits<double>::quiet_NaN();
}

void Navigator::initialize()
{
	// Level from the mean specific force: f_b = R_nbᵀ (0, 0, −g).
	const Eigen::Vector3d fm = f_sum_ / static_cast<double>(leveling_samples_);
	const double roll = std::atan2(-fm.y(), -fm.z());
	const double pitch = std::atan2(fm.x(), std::hypot(fm.y(), fm.z()));
	const double heading = initial_.inRange("heading_deg", -360, 360) * kDeg;
	NavState x0;
	x0.R_nb = (Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()) *
	           Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
	           Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
	              .toRotationMatrix();
	x0.g = earth::normalGravity(frame_->origin().lat_rad, frame_->origin().h_m);
	Eigen::Vector3d p_body(initial_.number("north_m", 0.0), initial_.number("east_m", 0.0), 0.0);
	// A fix is of its sensor point (e.g. the antenna): the body origin is
	// r_b behind it along the initial attitude.
	if (position_from_gps_ && gps_fix_) p_body = gps_fix_->p_n - x0.R_nb * gps_fix_->r_b;
	p_body.z() = initial_.number("depth_m", 0.0);
	x0.p_n = p_body + x0.R_nb * imu_position_b_;
	// Plugin states start at their declared means (the process model's prior).
	const TangentVector& prior = ukf_->processModel().prior_mean;
	x0.extra = prior.tail(prior.size() - idx::core_dim);
	TangentVector e = x0.euclidean();
	e.segment<18>(idx::inertia) = prior_mean_.segment<18>(idx::inertia);
	x0.setEuclidean(e);
	ukf_->initialize(x0, P0_);
	initialized_ = true;
	t_latest_s_ = t_s_;
	if (position_from_gps_ && gps_fix_ && on_event)
	{
		const int n = fix_consensus_.fixes(), agree = fix_consensus_.agreeing();
		char what[200];
		std::snprintf(
		    what, sizeof what,
		    "initialised at N %.2f E %.2f m from the newest of %d agreeing fixes (%d in the last %.0f s, "
		    "%d outliers)",
		    p_body.x(), p_body.y(), agree, n, fix_consensus_.params().window_s, n - agree);
		on_event(t_s_ - t0_s_, gps_label_, what);
	}
}

bool Navigator::reinitializeFromRejectedFix(Slot& slot, const Measurement& m, const UpdateResult& r,
                                            double t_obs)
{
	if (reinit_fixes_ < 2 || r.innovation.size() < 2 || m.R.rows() < 2) return false;
	const Eigen::Vector2d nu = r.innovation.head<2>();
	const Eigen::Matrix2d R = m.R.topLeftCorner<2, 2>();
	slot.fix_run.add(t_obs, nu, R);
	if (!slot.fix_run.agree(reinit_fixes_, reinit_probability_)) return false;
	// Outliers the plugin happened to pick (one fix used per interval, the
	// wild ones at the same phase) agree too, but the fixes in between do not.
	if (!mostFixesAgreeWith(slot, nu)) return false;
	// Every recent fix says the same: the state is off by ν, not the sensor.
	// Move onto the newest (the older innovations were taken against a state
	// recovery steps have moved since) and forget what the position was
	// correlated with, as at the start.
	// The smoother does not carry information across the reset (smoother_stream.h).
	if (smoother_) smoother_->endSegment(*ukf_, t_s_);
	NavState x = ukf_->state();
	Covariance P = ukf_->covariance();
	x.p_n.head<2>() += nu;
	P.middleRows<2>(idx::pos).setZero();
	P.middleCols<2>(idx::pos).setZero();
	for (int i = 0; i < 2; ++i)
		P(idx::pos + i, idx::pos + i) = std::max(P0_(idx::pos + i, idx::pos + i), R(i, i));
	ukf_->restore(x, P);
	const Eigen::Vector2d mean = slot.fix_run.meanOffset_m(reinit_fixes_);
	slot.fix_run.clear();
	slot.fix_offsets.clear();
	slot.streak.clear();
	slot.rejecting_since_s = -1;
	// A re-filtering pass (delayed measurements) redoes it: count it once.
	if (t_obs > slot.last_reinit_t_obs)
	{
		slot.last_reinit_t_obs = t_obs;
		++slot.stats.reinitialized;
		if (on_event)
		{
			char what[220];
			std::snprintf(
			    what, sizeof what,
			    "position re-initialised: moved N %+.2f E %+.2f m onto the newest of %d agreeing fixes "
			    "rejected by the gate (their mean offset N %+.2f E %+.2f m)",
			    nu.x(), nu.y(), reinit_fixes_, mean.x(), mean.y());
			on_event(t_obs - t0_s_, slot.stats.label, what);
		}
	}
	return true;
}

std::string Navigator::waitingFor() const
{
	if (initialized_) return "";
	if (leveling_samples_ == 0)
		return t0_s_ < 0 ? "no observations at all"
		                 : "no valid IMU sample with label '" + imu_label_ + "' (imu.label)";
	if (t_s_ - leveling_start_s_ < leveling_s_)
		return "IMU data for levelling: " + std::to_string(t_s_ - leveling_start_s_) + " s of " +
		       std::to_string(leveling_s_) + " s (imu.leveling_s)";
	if (position_from_gps_ && !gps_fix_)
		return std::to_string(fix_consensus_.params().min_fixes) + " agreeing GPS fixes on label '" +
		       gps_label_ + "' (filter.initial.position: gps, filter.initial.fix_consensus): " +
		       std::to_string(fix_consensus_.agreeing()) + " of " + std::to_string(fix_consensus_.fixes()) +
		       " agree; set filter.initial.position: config to start without them";
	return "initialisation";
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
	ctx.imu_position_b = imu_position_b_;
	ctx.frame = frame_.get();
	ctx.alpha_b = alpha_b_;
	ctx.mean = initialized_ ? &ukf_->state() : nullptr;
	ctx.current_far_distance_m = ukf_ ? ukf_->processModel().current_far_distance_m : 0.0;
	ctx.covariance = initialized_ ? &ukf_->covariance() : nullptr;
	return ctx;
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
		if (t_m > t_s_ + max_forward_jump_s_)
		{
			// Not a measurement to apply now: a sensor on another clock, or a jump.
			++st.invalid;
			st.last_problem =
			    "timestamp " + std::to_string(t_m - t_s_) + " s ahead of the IMU (clock.max_forward_jump_s)";
			continue;
		}
		if (t_m < t_s_ - apply_now_within_s_)
		{
			// Re-filtered at its time if the history reaches back that far.
			if (history_ && t_m >= t_s_ - max_delay_s_ && applyDelayed(i, obs, t_m)) continue;
			++st.late;
			st.last_problem = "observation older than filter.delayed_measurements.max_delay_s";
			continue;
		}
		prepareAndApply(i, obs, t_m, history_ ? history_->end() : 0);
	}
}

bool Navigator::prepareAndApply(std::size_t slot_index, const mrpt::obs::CObservation& obs, double t_m,
                                std::size_t at)
{
	Slot& slot = *slots_[slot_index];
	const CallgrindStage profile(slot.profiled);
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
	History::Event e;
	e.t = t_s_;
	e.slot = slot_index;
	e.t_obs = t_m;
	e.ctx = ctx;
	e.ms = std::move(slot.buffer);
	auto& events = history_->events;
	events.insert(events.begin() + static_cast<std::ptrdiff_t>(at - history_->first), std::move(e));
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
		const bool recovery =
		    slot.rejecting_since_s >= 0 && t_obs - slot.rejecting_since_s > recovery_after_s_;
		// Gated as usual first: a position fix that fails the gate may be one
		// of a run that re-initialises the position (reinitializeFromRejectedFix).
		UpdateResult r = ukf_->update(*slot.model, m, ctx, Recovery::None);
		const bool position_fix = slot.model->reportsPositionFix();
		bool reinitialized = false;
		if (r.status == UpdateStatus::Rejected && position_fix)
			reinitialized = reinitializeFromRejectedFix(slot, m, r, t_obs);
		if (reinitialized)
		{
			// The position now sits on this fix with its start covariance; the
			// fix itself has been used (applying it again would count it twice).
			r.status = UpdateStatus::Recovered;
			r.why = "position re-initialised onto agreeing rejected fixes";
		}
		else if (r.status == UpdateStatus::Rejected && recovery)
		{
			if (smoother_ && !smooth_across_recoveries_) smoother_->endSegment(*ukf_, t_s_);
			r = ukf_->update(*slot.model, m, ctx, Recovery::Noise);
		}
		else if (r.status == UpdateStatus::Rejected && consistent_rejections_ > 0)
		{
			// Rejected but agreeing with the aid's previous rejections: the
			// state is off, not the aid. Re-acquire now (rejection_streak.h).
			// An absolute reference of what the filter integrates without
			// bound (attitude, position, depth: magnetometer, AHRS, GPS,
			// pressure) pulls the state back by widening its covariance; a
			// velocity aid only on the gate boundary, since a consistent
			// velocity disagreement is as often the aid's (a wrong mounting
			// or scale), and widening let a DVL mounted 157° off turn the
			// heading 52° and end 400 m off as 'degraded'.
			slot.streak.add(t_obs, r.innovation, m.R);
			if (slot.streak.consistentBias(consistent_rejections_, consistency_probability_))
			{
				// (Plugin states such as a heading bias widen with the state.)
				constexpr uint32_t kAbsolute = kAttitude | kPosition | kGravity | kPluginStates;
				const bool absolute = (slot.model->uses() & ~kAbsolute) == 0;
				if (smoother_ && !smooth_across_recoveries_) smoother_->endSegment(*ukf_, t_s_);
				r = ukf_->update(*slot.model, m, ctx, absolute ? Recovery::State : Recovery::Noise);
			}
		}
		if (r.status == UpdateStatus::Accepted || r.status == UpdateStatus::Recovered) slot.streak.clear();
		// A fix inside the gate ends a run of rejected ones (a recovery on
		// the gate boundary does not: the fix still failed it).
		if (r.status == UpdateStatus::Accepted) slot.fix_run.clear();
		if (r.status == UpdateStatus::Accepted || r.status == UpdateStatus::Recovered)
			slot.rejecting_since_s = -1;
		else if (r.status == UpdateStatus::Rejected && slot.rejecting_since_s < 0)
			slot.rejecting_since_s = t_obs;
		if (!record) continue;
		if (on_update) on_update(st.label, t_obs, m, r);
		health_.onUpdate(st.label, t_obs - t0_s_, r);
		switch (r.status)
		{
			case UpdateStatus::Accepted:
			case UpdateStatus::Recovered:
				(r.status == UpdateStatus::Accepted ? st.accepted : st.recovered)++;
				st.nis_sum += r.nis;
				st.nis_dim_sum += r.dim;
				break;
			case UpdateStatus::Rejected:
				++st.rejected;
				break;
			case UpdateStatus::Invalid:
				++st.invalid;
				st.last_problem = r.why;
				break;
		}
	}
}

}  // namespace auvnav
