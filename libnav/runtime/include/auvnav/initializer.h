#pragma once
/** @file initializer.h
 *  The filter's start: roll and pitch from the first `imu.leveling_s` of
 *  accelerometer data, heading from `filter.initial.heading_deg`, position
 *  from the fix sensor `filter.initial.gps_label` (`position: gps`) — the
 *  newest of `fix_consensus.min_fixes` fixes that agree with the median of
 *  the recent ones and are a majority of them (fix_consensus.h), so one wild
 *  fix cannot be the start — or from `north_m`, `east_m` (`position:
 *  config`); depth from `depth_m`.
 */
#include <auvnav/earth.h>
#include <auvnav/fix_consensus.h>
#include <auvnav/navigator_config.h>
#include <auvnav/state.h>

#include <optional>
#include <string>

namespace auvnav
{
class Initializer
{
 public:
	Initializer(const InitialStateConfig& initial, const ImuConfig& imu) : initial_(initial), imu_(imu)
	{
		consensus_ = InitialFixConsensus(initial.fix_consensus);
	}

	/** Adds a valid IMU sample's specific force [m/s²] at t [s]. */
	void addImu(double t_s, const Eigen::Vector3d& f_b);
	/** True when observations labelled `label` give the start position. */
	bool wantsFixFrom(const std::string& label) const
	{
		return initial_.position_from_fix && label == initial_.fix_label;
	}
	/** Adds a fix of the fix sensor (its plugin's initialFix) at t [s]. */
	void addFix(double t_s, const InitialFix& fix);
	/** Levelled (and, with position: gps, a consensus of fixes) at IMU time t. */
	bool ready(double t_s) const
	{
		return samples_ > 0 && t_s - start_s_ >= imu_.leveling_s && (!initial_.position_from_fix || fix_);
	}
	/** The core part of the initial state (attitude, gravity, position; the
	 *  rest zero): the body origin at the start position, the IMU at
	 *  imu.position_m from it. Call when ready(). */
	NavState initialState(const earth::TangentFrame& frame) const;
	/** One line on where the start position came from, for the run's log
	 *  (empty without a fix consensus). */
	std::string startEvent(const NavState& x0) const;
	/** What the start still waits for at IMU time t ("" when ready). */
	std::string waitingFor(double t_s, bool any_observation) const;
	/** Forgets everything (a clock jump restarts the filter). */
	void clear();

 private:
	InitialStateConfig initial_;
	ImuConfig imu_;
	Eigen::Vector3d f_sum_b_ = Eigen::Vector3d::Zero();
	std::size_t samples_ = 0;
	double start_s_ = -1;
	InitialFixConsensus consensus_;
	std::optional<InitialFix> fix_;  // the agreed one, once there is a consensus
};

}  // namespace auvnav
