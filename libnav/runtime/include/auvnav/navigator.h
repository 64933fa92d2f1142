#pragma once
/** @file navigator.h
 *  The navigator: a ManifoldUkf fed with observations in time order, made of
 *  named pieces — its configuration (navigator_config.h), the start
 *  (initializer.h), the gate policy (aiding_policy.h), delayed fusion
 *  (filter_history.h), the divergence monitor (health.h) and per-sensor
 *  statistics (sensor_stats.h).
 *
 *  - The IMU (`imu.label`) drives prediction: each sample predicts from the
 *    previous sample's time with its gyro reading; the same observation then
 *    goes to the sensors configured for that label (the accelerometer
 *    update). Other observations are applied at the filter's current time
 *    (the latest IMU sample, ≤ one IMU period earlier).
 *  - A measurement's time is its observation's stamp minus the sensor's
 *    `latency_s`, or what the plugin reads from the observation
 *    (MeasurementModel::measurementTime). One older than the filter by more
 *    than `apply_now_within_s` and less than `max_delay_s` is applied at its
 *    time by re-filtering (filter_history.h); older ones are counted late.
 *    Statistics, updates and outputs record each update once.
 *  - Bad input never reaches the state: non-finite or absent IMU data,
 *    duplicate or backward timestamps, NaN measurements are counted and
 *    dropped. An observation more than `clock.max_forward_jump_s` ahead of
 *    the filter is refused as invalid (a sensor on another clock).
 *  - Clock jumps: an IMU sample more than `clock.max_forward_jump_s` after
 *    the last one, or more than `clock.max_backward_jump_s` before it, is a
 *    jump of the log's clock, not a gap to predict through: `clock.on_jump:
 *    stop` (default) ends the run (process() throws std::runtime_error naming
 *    it); `reinitialize` starts the filter again from that sample on.
 *    Smaller backward steps drop the sample.
 */
#include <auvnav/aiding_policy.h>
#include <auvnav/config.h>
#include <auvnav/earth.h>
#include <auvnav/health.h>
#include <auvnav/initializer.h>
#include <auvnav/navigator_config.h>
#include <auvnav/plugin_host.h>
#include <auvnav/sensor_stats.h>
#include <auvnav/smoother_stream.h>
#include <auvnav/state_layout.h>
#include <auvnav/ukf.h>
#include <mrpt/obs/CObservation.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace auvnav
{
class FilterHistory;

/** A sensor's measurement model and where its observations are found. */
struct SensorSource
{
	std::string label;   //!< observations' sensorLabel
	std::string plugin;  //!< what made the model (statistics, messages)
	ModelPtr model;
	double latency_s = 0;  //!< measurement time = stamp − latency (before measurementTime)
};

/** The models of the configuration's `sensors:` entries, created by their
 *  plugins (loaded by `host`). Throws PluginError naming the entry. */
std::vector<SensorSource> loadSensorModels(const NavigatorConfig& cfg, PluginHost& host);

class Navigator
{
 public:
	/** Builds the filter over `sensors` (their plugin states appended in
	 *  order; cfg.sensors is not read). Throws PluginError / ConfigError, or
	 *  std::invalid_argument if the start's fix sensor is not among them. */
	Navigator(const NavigatorConfig& cfg, std::vector<SensorSource> sensors);
	/** Loads cfg.sensors' plugins through `host` (loadSensorModels). */
	Navigator(const NavigatorConfig& cfg, PluginHost& host) : Navigator(cfg, loadSensorModels(cfg, host)) {}
	/** Reads `cfg` (NavigatorConfig::fromNode) and loads its plugins. */
	Navigator(const config::Node& cfg, PluginHost& host) : Navigator(NavigatorConfig::fromNode(cfg), host) {}
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
	const Eigen::Vector3d& imuPosition_b() const { return cfg_.imu.position_b; }
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
	const std::vector<std::string>& stateNames() const { return layout_.tangent_names; }
	/** The same for NavState::euclidean()'s stored values (storedNames). */
	const std::vector<std::string>& storedStateNames() const { return layout_.stored_names; }
	const std::vector<PluginStateBlock>& pluginStates() const { return layout_.plugin_blocks; }
	/** Labels of the sensors whose measurements are position fixes
	 *  (MeasurementModel::reportsPositionFix: GPS, USBL, …). */
	std::vector<std::string> positionFixLabels() const;

	/** Position of the body origin (CG) and attitude, from the IMU state. */
	Eigen::Vector3d bodyPosition_n() const;

	/** Records the run for the RTS smoother (smoother_stream.h): one
	 *  stretch per `smoother.keep_every_s` of filter time (default 1 s) to
	 *  the stretch file at `path`. Segments end at position
	 *  re-initialisations, clock-jump restarts and (unless
	 *  `smoother.across_recoveries: true`) before every recovery update.
	 *  Call before the first observation; the file is complete after
	 *  finish(). Throws std::runtime_error if the file cannot be created. */
	void enableSmoothing(const std::string& path);
	const SmoothingRecorder* smoothingRecorder() const { return smoother_.get(); }
	double smootherKeepEvery_s() const { return cfg_.smoother.keep_every_s; }
	//! Why the smoother's file could not be finished in finish() (empty: it was).
	const std::string& smootherError() const { return smoother_error_; }

	/** Adds a data-denial window (as the config's `denial` list does).
	 *  Throws std::invalid_argument for a label that is none of the sensors'
	 *  (labels are case-sensitive), naming the sensors. */
	void addDenial(const DenialWindow& w);

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
	/** Called when a sensor's observation starts (true) and stops (false)
	 *  being prepared and applied, re-filtering included: a profiler can
	 *  attribute the work to the sensor (bench/instructions.sh). */
	std::function<void(const std::string& label, bool begin)> on_sensor_work;

 private:
	struct Slot;
	class SensorWork;

	// Observations in (navigator.cpp).
	bool handleImu(const mrpt::obs::CObservation& obs);  // false: sample dropped
	void dispatch(const mrpt::obs::CObservation& obs, double stamp_s);
	bool denied(const std::string& label, double t_obs) const;
	void checkDenialLabels(const DenialWindow& w) const;
	/** The measurement time of `obs` for a slot (NaN: the plugin says invalid). */
	double measurementTime(const Slot& slot, const mrpt::obs::CObservation& obs, double stamp_s) const;
	/** What a plugin sees besides the state, for an observation at t_obs. */
	FilterContext context(double t_obs) const;
	/** Records a position sensor's fix (every one, initialFix) against the state. */
	void recordFixOffset(const mrpt::obs::CObservation& obs, double t);
	void initialize();
	/** A jump of the IMU clock by dt at t: throws (stop) or restarts initialisation. */
	void clockJump(double t, double dt);

	// The filter's steps (navigator_updates.cpp).
	/** The state-changing part of an IMU sample: predict to t with gyro w. */
	void propagate(const Eigen::Vector3d& w, double t);
	/** Prepares `obs` for slot `slot_index` at measurement time t_m on the
	 *  current state and applies it, counting a Skip or Invalid; true when
	 *  measurements were applied. With a history, they are moved into the
	 *  event inserted at absolute index `at` (the end for in-order ones). */
	bool prepareAndApply(std::size_t slot_index, const mrpt::obs::CObservation& obs, double t_m,
	                     std::size_t at);
	/** Applies one observation's prepared measurements (gates, recovery);
	 *  `record`: count them and report them (false when re-filtering). */
	void applyMeasurements(Slot& slot, const std::vector<Measurement>& ms, const FilterContext& ctx,
	                       double t_obs, bool record);
	/** Moves the horizontal position onto a rejected fix (aiding_policy.h). */
	void reinitializePosition(Slot& slot, const Measurement& m, const UpdateResult& r, double t_obs);

	// Delayed fusion and the smoother's feed (navigator_replay.cpp).
	/** Takes a checkpoint before IMU event `event` if one is due. */
	void checkpointIfDue(std::size_t event);
	/** Applies an observation at its past time t_m by re-filtering. False: no
	 *  checkpoint old enough (the caller counts it late). */
	bool applyDelayed(std::size_t slot_index, const mrpt::obs::CObservation& obs, double t_m);
	void restoreLastCheckpoint();
	/** Re-applies a recorded event (an IMU prediction or measurements). */
	void replayEvent(std::size_t event);
	/** Writes the smoother's records no re-filtering can rewind any more. */
	void commitSmoother();
	/** A stretch-file write failed: the run goes on without smoothing. */
	void stopSmoothing(const std::string& why);

	NavigatorConfig cfg_;
	std::unique_ptr<earth::TangentFrame> frame_;
	std::vector<std::unique_ptr<Slot>> slots_;
	StateLayout layout_;
	Covariance P0_;  // with the plugin states
	std::unique_ptr<ManifoldUkf> ukf_;
	Initializer init_;
	AidingPolicy policy_;
	std::unique_ptr<FilterHistory> history_;       // null: delayed measurements are counted late
	std::unique_ptr<SmoothingRecorder> smoother_;  // enableSmoothing
	std::string smoother_error_;
	HealthMonitor health_;

	bool initialized_ = false;
	double t_s_ = 0, t0_s_ = -1, t_latest_s_ = 0;
	Eigen::Vector3d omega_ib_b_ = Eigen::Vector3d::Zero();
	Eigen::Vector3d alpha_b_ = Eigen::Vector3d::Zero();  // low-pass filtered gyro derivative
	double alpha_delay_s_ = 0;                           // FilterContext::alpha_delay_s
	SensorStats imu_stats_;
	std::size_t predictions_ = 0, imu_gaps_ = 0, clock_jumps_ = 0, replayed_predictions_ = 0;
	double next_health_check_s_ = 0;
};

}  // namespace auvnav
