#pragma once
/** @file mission.h
 *  A simulated mission: loads the mission YAML (which names the vehicle and
 *  sensor files and holds the environment and the plan), runs the vehicle,
 *  the autopilot and the sensors on a fixed time grid, and writes
 *  DIR/<name>.rawlog, DIR/ground_truth.tum and DIR/ground_truth.csv.
 *  The same seed gives byte-identical outputs.
 *
 *  Sensors: imu, dvl, pressure and thrusters are required in the sensors
 *  file; adcp, gps, magnetometer and sonar are optional (absent, or
 *  `enabled: false`). A magnetometer needs environment.magnetic_field.
 *  The rawlog is written in the time order of the recorded stamps (jittered,
 *  logger_clock.h); without jitter that is the simulation order, as before.
 */
#include <auvnav/config.h>
#include <auvnav/earth.h>
#include <auvnav/sonar/landmarks.h>

#include <map>
#include <string>

#include "environment.h"
#include "guidance.h"
#include "vehicle.h"

namespace auvnav::sim
{
struct MissionSpec
{
	std::string name;
	std::string file;
	earth::Geodetic origin;
	double start_unix_s = 0;
	Eigen::Vector2d start_ne{0, 0};
	double start_heading_rad = 0;
	double start_depth_m = 0.25;  //!< CG depth at the start (start.depth_m, default 0.25 m)
	double dt_s = 0.01;
	double ground_truth_rate_hz = 10;
	double max_duration_s = 6 * 3600;
	int rawlog_compression = 6;
	config::Node vehicle;
	config::Node sensors;
	config::Node environment;
	config::Node mission;
	/** Surveyed poles (environment.pole_map), empty if none: the truth the
	 *  imaging sonar sees. */
	sonar::PoleMap poles;

	static MissionSpec load(const std::string& mission_file);
};

struct MissionSummary
{
	double duration_s = 0;
	double distance_m = 0;
	double submerged_distance_m = 0;
	double max_depth_m = 0;
	std::map<std::string, std::size_t> observations;  // per sensor label
	std::size_t dvl_locked = 0, dvl_total = 0;
	std::size_t adcp_valid_cells = 0, adcp_profiles = 0;
	std::size_t gps_outliers = 0;
	std::size_t stamp_duplicates = 0, stamp_out_of_order = 0;  //!< logger-clock anomalies injected
	std::size_t sonar_frames = 0, sonar_poles_in_view = 0;
	bool plan_completed = false;
	std::string rawlog_path;
};

/** Runs the mission and writes its outputs into `out_dir` (created). */
MissionSummary runMission(const MissionSpec& spec, uint32_t seed, const std::string& out_dir);

}  // namespace auvnav::sim
