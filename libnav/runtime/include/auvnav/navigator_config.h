#pragma once
/** @file navigator_config.h
 *  Everything the navigator's YAML configuration says, read and checked in
 *  one place (NavigatorConfig::fromNode) with file, line and key in every
 *  message. config/flatfish.yaml lists and explains every key.
 */
#include <auvnav/config.h>
#include <auvnav/earth.h>
#include <auvnav/fix_consensus.h>
#include <auvnav/health.h>
#include <auvnav/process_model.h>
#include <auvnav/ukf.h>

#include <optional>
#include <string>
#include <vector>

namespace auvnav
{
/** `imu`: the sensor whose samples drive the prediction. */
struct ImuConfig
{
	std::string label;
	Eigen::Vector3d position_b = Eigen::Vector3d::Zero();  //!< IMU origin in the body frame [m]
	double leveling_s = 1.0;                               //!< accelerometer averaging for roll and pitch
	double max_gap_s = 0.5;  //!< longer steps are predicted in 0.01 s sub-steps and counted as gaps
	double angular_acceleration_tau_s = 0.2;  //!< low-pass of the gyro's derivative (FilterContext::alpha_b)
};

/** `filter.initial`: where the filter starts. */
struct InitialStateConfig
{
	//! `position: gps`: from the fix consensus of sensor `fix_label`; else north_m, east_m.
	bool position_from_fix = false;
	std::string fix_label = "GPS";
	FixConsensusParams fix_consensus;
	double heading_rad = 0, north_m = 0, east_m = 0, depth_m = 0;
};

/** `filter.delayed_measurements`: measurements older than the filter. */
struct DelayedFusionParams
{
	double apply_now_within_s = 0.05;  //!< closer to the filter time: applied as if current
	double max_delay_s = 10;           //!< older: counted late (0: never re-filter)
	double checkpoint_every_s = 0.25;  //!< filter snapshots to re-filter from
};

/** `clock`: jumps of the IMU's clock, not predicted through. */
struct ClockParams
{
	double max_forward_jump_s = 10, max_backward_jump_s = 1;
	bool stop_on_jump = true;  //!< `on_jump: stop`; false: `reinitialize`
};

/** `gates`: what happens to updates the χ² gate rejects (aiding_policy.h). */
struct AidingParams
{
	double recovery_after_s = 30;           //!< a sensor rejected this long is applied against the gate
	int consistent_rejections = 5;          //!< rejections that agree re-acquire the aid (0: off)
	double consistency_probability = 0.99;  //!< their agreement test
	int reinit_fixes = 3;                   //!< position_reinit.rejected_fixes (0: off)
	double reinit_probability = 0.99;       //!< position_reinit.probability
	double reinit_spread_m = 10;            //!< position_reinit.max_spread_m
};

/** `smoother`: what the navigator records for the RTS smoother. */
struct SmootherParams
{
	double keep_every_s = 1.0;       //!< one stretch per this much filter time
	bool across_recoveries = false;  //!< false: a segment ends before every recovery update
};

struct DenialWindow
{
	std::vector<std::string> labels;
	double from_s = 0, to_s = 0;  //!< seconds from the first observation
};

/** A denial window written "LABEL:FROM:TO" (auvnav-run --deny): FROM and TO
 *  numbers of seconds, 0 <= FROM < TO. Throws config::ConfigError saying
 *  what is wrong with it; whether LABEL is a sensor is for the
 *  navigator to say (Navigator::addDenial). */
DenialWindow parseDenial(const std::string& text);

/** One `sensors:` entry: the plugin to load for observations with `label`. */
struct SensorEntry
{
	std::string label, plugin;
	double latency_s = 0;       //!< measurement time = observation stamp − latency
	std::string config_yaml;    //!< what the plugin is created with (pluginConfigText)
	std::string config_origin;  //!< file:line of that configuration, for the plugin's errors
};

struct NavigatorConfig
{
	earth::Geodetic origin;  //!< navigation_frame.origin
	ImuConfig imu;
	//! The paper's 43 states' process (filter.process_noise); plugin blocks are appended later.
	ProcessModel process;
	UtParams unscented;
	bool earth_rate = true;  //!< filter.earth_rate: false only for studies (no gyrocompassing)
	//! Prior mean of the 43 states: zero biases and currents, the vehicle model's parameters.
	TangentVector prior_mean = TangentVector::Zero(idx::core_dim);
	//! Initial covariance of the 43 states (diagonal, tangent order).
	Covariance P0;
	InitialStateConfig initial;
	DelayedFusionParams delayed;
	ClockParams clock;
	HealthLimits health;
	SmootherParams smoother;
	AidingParams gates;
	std::vector<DenialWindow> denial;
	std::vector<SensorEntry> sensors;
	//! filter.sigma_limits, read once the plugins' states are known (state_layout.h).
	std::optional<config::Node> sigma_limits;

	/** Reads and checks the whole navigator configuration: every key must be
	 *  known (`plugin_paths` and `outputs` belong to the program). Throws
	 *  ConfigError naming file, line and key. */
	static NavigatorConfig fromNode(const config::Node& cfg);
};

/** The configuration text the navigator hands the plugin of one `sensors:`
 *  entry: its inline `config`, or the file `config_file` (relative to the
 *  navigator's file), plus `config_dir` (plugin_api.h). */
std::string pluginConfigText(const config::Node& sensor_entry);

}  // namespace auvnav
