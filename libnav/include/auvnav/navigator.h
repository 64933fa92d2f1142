#pragma once
/** @file navigator.h
 *  The navigator: a ManifoldUkf fed with observations in time order.
 *
 *  - The IMU (label from `imu.label`) drives prediction: each sample
 *    predicts from the previous sample's time with its gyro reading; the same
 *    observation then goes to the plugins configured for that label (the
 *    accelerometer update). Other observations are applied at the filter's
 *    current time (the latest IMU sample, ≤ one IMU period earlier).
 *  - Delayed measurements (an acoustic fix arrives seconds after it was
 *    taken): a measurement's time is its observation's timestamp, minus the
 *    sensor entry's `latency_s`, or what the plugin reads from the
 *    observation (MeasurementModel::measurementTime). One older than the
 *    filter by more than `filter.delayed_measurements.apply_now_within_s` and
 *    less than `max_delay_s` is applied AT its time by re-filtering: the
 *    navigator keeps checkpoints of the filter (mean, covariance, gate state)
 *    every `checkpoint_every_s` and the IMU samples and prepared measurements
 *    since the oldest; it restores the last checkpoint before the
 *    measurement, re-predicts and re-applies everything up to it, applies it,
 *    and re-applies the rest. Plugins prepare each observation once (a
 *    replay re-applies the prepared measurements), so the result equals
 *    in-order processing exactly for plugins whose prepare does not read the
 *    filter's mean or covariance. Statistics, updates.csv and the outputs
 *    record each update once, when it was first applied. Older ones are
 *    counted as late.
 *  - Start-up: the first `imu.leveling_s` of accelerometer data give roll and
 *    pitch; heading comes from `filter.initial.heading_deg`; position from
 *    the fix sensor `filter.initial.gps_label` (`filter.initial.position:
 *    gps`): the newest of `fix_consensus.min_fixes` fixes that agree with the
 *    median of the recent ones and are a majority of them (fix_consensus.h),
 *    so one wild fix cannot be the start; or from `north_m`, `east_m`
 *    (`position: config`); depth from `depth_m`.
 *  - Position re-initialisation (`gates.position_reinit`): when the last
 *    `rejected_fixes` fixes of any position sensor (its plugin's
 *    reportsPositionFix(): GPS, USBL, …) all failed the χ² gate and agree
 *    with each other (RejectedFixRun, fix_consensus.h), the horizontal
 *    position is moved onto the newest of them, its covariance reset to the
 *    start's (`filter.initial.position_sigma_m`, or the fix's σ if larger)
 *    and decorrelated from the rest of the state — provided most of the
 *    sensor's fixes over that run, also those its plugin skipped (read with
 *    initialFix, where the plugin gives it), lie within `max_spread_m` of
 *    that offset: outliers the plugin happened to pick at the same phase
 *    agree with each other, the good fixes between them do not. Counted per
 *    sensor (SensorStats::reinitialized) and reported through on_event.
 *  - Every update is counted per sensor: accepted, recovered, rejected by the
 *    gate, invalid, skipped, denied (data denial windows), late. A sensor
 *    whose last `gates.consistent_rejections` rejections agree with each other
 *    (a drifting bias of the state, rejection_streak.h) is re-acquired at once:
 *    that update is applied with the innovation covariance inflated onto the
 *    gate; as a backstop, so is one rejected for `gates.recovery_after_s` (it
 *    cannot lock itself out, e.g. the DVL after a long dropout).
 *  - A divergence monitor (health.h) judges every update and, once a second,
 *    the covariance: ok, degraded, diverged, or not_initialized (finish()).
 *  - Bad input never reaches the state: non-finite or absent IMU data,
 *    duplicate or backward timestamps, NaN measurements are counted and dropped.
 *  - Clock jumps: an IMU sample more than `clock.max_forward_jump_s` after
 *    the last one, or more than `clock.max_backward_jump_s` before it, is a
 *    jump of the log's clock, not a gap to predict through: `clock.on_jump:
 *    stop` (default) ends the run with an error naming it (process() throws
 *    std::runtime_error); `reinitialize` starts the filter again (levelling,
 *    first fix) from that sample on. Smaller backward steps drop the sample.
 *    Any other observation more than max_forward_jump_s ahead of the filter
 *    is refused as invalid (a sensor on another clock).
 */
#include <auvnav/config.h>
#include <auvnav/earth.h>
#include <auvnav/fix_consensus.h>
#include <auvnav/health.h>
#include <auvnav/plugin_host.h>
#include <auvnav/smoother_stream.h>
#include <auvnav/ukf.h>
#include <mrpt/obs/CObservation.h>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace auvnav
{
struct SensorStats
{
	std::string label, plugin;
	std::size_t accepted = 0, recovered = 0, rejected = 0, invalid = 0, skipped = 0, denied = 0, late = 0,
	            before_init = 0;
	//! Observations applied at their measurement time by re-filtering (also
	//! counted by their update status).
	std::size_t delayed = 0;
	//! Position re-initialisations from this sensor's fixes (gates.position_reinit).
	std::size_t reinitialized = 0;
	double nis_sum = 0;      //!< over accepted updates
	double nis_dim_sum = 0;  //!< Σ dimensions of those updates (E[NIS] = dim)
	std::string last_problem;
};

/** A block of plugin-owned states in the filter's state (tangent index). */
struct PluginStateBlock
{
	std::string sensor, name;
	int offset = 0, dim = 0;
};

struct DenialWindow
{
	std::vector<std::string> labels;
	double from_s = 0, to_s = 0;  //!< seconds from the first observation
};

/** The configuration text the navigator hands the plugin of one `sensors:`
 *  entry: its inline `config`, or the file `config_file` (relative to the
 *  navigator's file), plus `config_dir` (plugin_api.h). */
std::string pluginConfigText(const config::Node& sensor_entry);

class Navigator
{
 public:
	/** Builds the filter and loads the plugins named in `cfg`. Throws
	 *  ConfigError / PluginError with a clear message. */
	Navigator(const config::Node& cfg, PluginHost& host);
	~Navigator();

	/** Feeds one observation (must come in file order). */
	void process(const mrpt::obs::CObservation& obs);

	bool initialized() const { return initialized_; }
	const ManifoldUkf& filter() const { return *ukf_; }
	double time() const { return t_s_; }  //!< filter time [s, Unix]
	//! The latest IMU sample's time [s, Unix]: time() except while
	//! re-filtering for a delayed measurement (callbacks then see the past).
	double latestTime() const { return t_latest_s_; }
	double startTime() const { return t0_s_; }  //!< first observation [s, Unix]
	const earth::TangentFrame& frame() const { return *frame_; }
	const Eigen::Vector3d& imuPosition_b() const { return imu_position_b_; }
	std::vector<SensorStats> stats() const;
	const SensorStats& imuStats() const { return imu_stats_; }
	std::size_t predictions() const { return predictions_; }
	/** The divergence monitor (health.h); its times are seconds from startTime(). */
	const HealthMonitor& health() const { return health_; }
	HealthMonitor& health() { return health_; }
	/** Call once after the last observation: a filter that never started
	 *  becomes not_initialized, with what it waited for. */
	void finish();
	/** What initialisation still waits for (empty once initialised). */
	std::string waitingFor() const;
	std::size_t imuGaps() const { return imu_gaps_; }
	/** IMU clock jumps handled by re-initialising (clock.on_jump: reinitialize). */
	std::size_t clockJumps() const { return clock_jumps_; }
	/** IMU steps re-predicted while re-filtering for delayed measurements
	 *  (the cost of delays: compare with predictions()). */
	std::size_t replayedPredictions() const { return replayed_predictions_; }
	/** Position re-initialisations of the run, all sensors (gates.position_reinit). */
	std::size_t positionReinitializations() const;

	/** Names of the state's tangent coordinates: the paper's 43
	 *  (tangentNames) and "<label>.<block>_<component>" per plugin state. */
	const std::vector<std::string>& stateNames() const { return state_names_; }
	/** The same for NavState::euclidean()'s stored values (storedNames). */
	const std::vector<std::string>& storedStateNames() const { return stored_names_; }
	const std::vector<PluginStateBlock>& pluginStates() const { return plugin_blocks_; }
	/** Labels of the sensors whose measurements are position fixes
	 *  (MeasurementModel::reportsPositionFix: GPS, USBL, …). */
	std::vector<std::string> positionFixLabels() const;

	/** Position of the body origin (CG) and attitude, from the IMU state. */
	Eigen::Vector3d bodyPosition_n() const;

	/** Records the run for the RTS smoother (smoother_stream.h): one
	 *  stretch per `smoother.keep_every_s` of filter time (default 1 s) to
	 *  the stretch file at `path`. Segments end at position
	 *  re-initialisations, clock-jump restarts and (unless
	 *  `smoother.across_recoveries: true`) before every recovery update. Call before the first observation;
	 * the file is complete after finish(). Throws std::runtime_error if the file cannot be created. */
	void enableSmoothing(const std::string& path);
	const SmoothingRecorder* smoothingRecorder() const { return smoother_.get(); }
	double smootherKeepEvery_s() const { return smoother_keep_every_s_; }
	//! Why the smoother's file could not be finished in finish() (empty: it was).
	const std::string& smootherError() const { return smoother_error_; }

	/** Adds a data-denial window (as the config's `denial` list does). */
	void addDenial(const DenialWindow& w) { denial_.push_back(w); }

	/** Called after every prediction (i.e. at IMU rate) once initialised. */
	std::function<void(const Navigator&)> on_predict;
	/** Called after every measurement update with the sensor label, the
	 *  observation time, the measurement and its result (any status). */
	std::function<void(const std::string& label, double t_obs, const Measurement&, const UpdateResult&)>
	    on_update;
	/** Called on an event worth a line in a log: the start from a fix
	 *  consensus, a position re-initialisation (time from startTime() [s],
	 *  sensor label, what happened). */
	std::function<void(double t_s, const std::string& label, const std::string& what)> on_event;

 private:
	struct Slot;
	struct History;
	bool handleImu(const mrpt::obs::CObservation& obs);  // false: sample dropped
	/** The state-changing part of an IMU sample: predict to t with gyro w. */
	void propagate(const Eigen::Vector3d& w, double t);
	/** Applies one observation's prepared measurements (gates, recovery);
	 *  `record`: count them and report them (false when re-filtering). */
	void applyMeasurements(Slot& slot, const std::vector<Measurement>& ms, const FilterContext& ctx,
	                       double t_obs, bool record);
	/** Applies an observation at its past time t_m by re-filtering. False: no
	 *  checkpoint old enough (the caller counts it late). */
	bool applyDelayed(std::size_t slot_index, const mrpt::obs::CObservation& obs, double t_m);
	/** Prepares `obs` for slot `slot_index` at measurement time t_m on the
	 *  current state and applies it, counting a Skip or Invalid; true when
	 *  measurements were applied. With a history, they are moved into the
	 *  event inserted at absolute index `at` (the end for in-order ones). */
	bool prepareAndApply(std::size_t slot_index, const mrpt::obs::CObservation& obs, double t_m,
	                     std::size_t at);
	/** Takes a checkpoint before IMU event `event` if checkpoint_every_s has
	 *  passed since the last one. */
	void checkpointIfDue(std::size_t event);
	/** Drops checkpoints and events no delay up to max_delay_s can need. */
	void trimHistory();
	/** Restores the filter to the last checkpoint. */
	void restoreLastCheckpoint();
	/** Re-applies a recorded event (an IMU prediction or measurements). */
	void replayEvent(std::size_t event);
	/** The measurement time of `obs` for a slot (NaN: the plugin says invalid). */
	double measurementTime(const Slot& slot, const mrpt::obs::CObservation& obs, double stamp_s) const;
	void initialize();
	/** A fix of a position sensor failed the gate (r rejected): adds it to
	 *  the slot's run and, if the run agrees, re-initialises the horizontal
	 *  position onto it. True: re-initialised. */
	bool reinitializeFromRejectedFix(Slot& slot, const Measurement& m, const UpdateResult& r, double t_obs);
	/** Records a position sensor's fix (every one, initialFix) against the state. */
	void recordFixOffset(const mrpt::obs::CObservation& obs, double t);
	/** More than half of the fixes recorded over the slot's run of rejections
	 *  lie within reinit_spread_m_ of `offset_m` (fix − state) [m]. */
	bool mostFixesAgreeWith(const Slot& slot, const Eigen::Vector2d& offset_m) const;
	void dispatch(const mrpt::obs::CObservation& obs, double stamp_s);
	/** What a plugin sees besides the state, for an observation at t_obs. */
	FilterContext context(double t_obs) const;
	bool denied(const std::string& label, double t_obs) const;
	/** Appends the plugins' state blocks to `pm` and P0 (plugin SDK v2). */
	void appendPluginStates(ProcessModel& pm);
	/** filter.sigma_limits: {<block or state>: {min, max}} [the state's units]
	 *  → ManifoldUkf::setSigmaLimits (after appendPluginStates: plugin
	 *  blocks may be named). */
	void readSigmaLimits(const config::Node& limits);

	std::unique_ptr<earth::TangentFrame> frame_;
	std::unique_ptr<ManifoldUkf> ukf_;
	std::vector<std::unique_ptr<Slot>> slots_;
	std::vector<DenialWindow> denial_;
	config::Node initial_;
	std::string imu_label_;
	Eigen::Vector3d imu_position_b_ = Eigen::Vector3d::Zero();
	double leveling_s_ = 1.0, max_gap_s_ = 0.5, recovery_after_s_ = 30;
	// filter.delayed_measurements: applied now within apply_now_within_s,
	// re-filtered up to max_delay_s (0: never), checkpoints every checkpoint_every_s.
	double apply_now_within_s_ = 0.05, max_delay_s_ = 10, checkpoint_every_s_ = 0.25;
	std::unique_ptr<History> history_;
	std::size_t replayed_predictions_ = 0;
	std::unique_ptr<SmoothingRecorder> smoother_;  // enableSmoothing
	double smoother_keep_every_s_ = 1.0;           // smoother.keep_every_s
	// smoother.across_recoveries: false ends a smoothing segment before every
	// recovery update (an aid applied against the gate: the filter's
	// covariance was just contradicted, so its gains are not trusted across it).
	bool smooth_across_recoveries_ = false;
	std::string smoother_error_;
	/** Writes the smoother's records no re-filtering can rewind any more. */
	void commitSmoother();
	/** A stretch-file write failed: the run goes on without smoothing. */
	void stopSmoothing(const std::string& why);
	// clock: jumps of the IMU's time beyond these are not predicted through.
	double max_forward_jump_s_ = 10, max_backward_jump_s_ = 1;
	bool stop_on_jump_ = true;
	std::size_t clock_jumps_ = 0;
	/** A jump of the IMU clock by dt at t: throws (stop) or restarts initialisation. */
	void clockJump(double t, double dt);
	int consistent_rejections_ = 5;          // gates.consistent_rejections (0: off)
	double consistency_probability_ = 0.99;  // gates.consistency_probability
	// gates.position_reinit: this many agreeing gate-rejected fixes reset the position (0: off).
	int reinit_fixes_ = 3;
	double reinit_probability_ = 0.99;
	double reinit_spread_m_ = 10;  // [m] a recorded fix agrees with the run's offset within this
	bool position_from_gps_ = false;
	bool earth_rate_ = true;  // filter.earth_rate: false only for studies (no gyrocompassing)
	std::string gps_label_;
	TangentVector prior_mean_ = TangentVector::Zero(idx::core_dim);
	Covariance P0_;
	std::vector<std::string> state_names_, stored_names_;
	std::vector<PluginStateBlock> plugin_blocks_;

	bool initialized_ = false;
	double t_s_ = 0, t0_s_ = -1, t_latest_s_ = 0;
	Eigen::Vector3d omega_ib_b_ = Eigen::Vector3d::Zero();
	Eigen::Vector3d alpha_b_ = Eigen::Vector3d::Zero();  // low-pass filtered gyro derivative
	double alpha_tau_s_ = 0.2;
	Eigen::Vector3d f_sum_ = Eigen::Vector3d::Zero(), w_sum_ = Eigen::Vector3d::Zero();
	std::size_t leveling_samples_ = 0;
	double leveling_start_s_ = -1;
	InitialFixConsensus fix_consensus_;  // the fix sensor's fixes before the start (initialFix)
	std::optional<InitialFix> gps_fix_;  // the agreed one, once there is a consensus
	SensorStats imu_stats_;
	std::size_t predictions_ = 0, imu_gaps_ = 0;
	HealthMonitor health_;
	double next_health_check_s_ = 0;
};

}  // namespace auvnav
