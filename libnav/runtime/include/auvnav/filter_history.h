#pragma once
/** @file filter_history.h
 *  What applying a delayed measurement at its own time needs
 *  (`filter.delayed_measurements`): the filter's inputs since the oldest
 *  checkpoint, in the order applied, and checkpoints of everything that
 *  decides how they are applied, taken every `checkpoint_every_s` and kept
 *  for `max_delay_s`. The navigator restores the last checkpoint before the
 *  measurement, re-applies the events up to it, applies it and re-applies
 *  the rest; plugins prepare each observation once, so the result equals
 *  in-order processing for plugins whose prepare does not read the filter's
 *  mean or covariance.
 */
#include <auvnav/aiding_policy.h>
#include <auvnav/measurement_function.h>
#include <auvnav/navigator_config.h>
#include <auvnav/smoother_stream.h>
#include <auvnav/state.h>

#include <deque>
#include <optional>
#include <vector>

namespace auvnav
{
/** One input of the filter: an IMU sample, or one observation's prepared measurements. */
struct FilterEvent
{
	bool imu = false;
	double t = 0;                                 //!< IMU: its time; else the filter time it was applied at
	Eigen::Vector3d w = Eigen::Vector3d::Zero();  //!< IMU: gyro sample [rad/s]
	std::size_t sensor = 0;                       //!< index of the sensor in the navigator
	double t_obs = 0;                             //!< measurement time
	FilterContext ctx;                            //!< as prepared (mean and covariance are re-set)
	std::vector<Measurement> ms;
};

/** The filter and the navigator's gate state before one IMU event. */
struct FilterCheckpoint
{
	std::size_t event = 0;  //!< absolute index of the IMU event it precedes
	double t_s = 0;
	NavState x;
	Covariance P;
	Eigen::Vector3d omega_ib_b, alpha_b;
	double alpha_delay_s = 0;
	std::vector<GateState> gates;  //!< per sensor
	std::optional<SmoothingRecorder::Snapshot> smoother;
};

class FilterHistory
{
 public:
	explicit FilterHistory(const DelayedFusionParams& p) : p_(p) {}
	const DelayedFusionParams& params() const { return p_; }

	/** A checkpoint is due at filter time t (checkpoint_every_s since the last). */
	bool checkpointDue(double t_s) const
	{
		return checkpoints_.empty() || t_s - checkpoints_.back().t_s >= p_.checkpoint_every_s;
	}
	void addCheckpoint(FilterCheckpoint c) { checkpoints_.push_back(std::move(c)); }
	/** Drops checkpoints and events no measurement up to max_delay_s older
	 *  than t can need. */
	void trim(double t_s);
	void pushImu(double t_s, const Eigen::Vector3d& w);
	/** Inserts measurements at absolute event index `at` (end() in order). */
	void insert(std::size_t at, FilterEvent e);
	/** Where in-order processing would have applied a measurement taken at
	 *  t_m (an absolute event index: after the last IMU sample at or before
	 *  t_m and the measurements taken up to t_m), dropping the checkpoints
	 *  after it; nullopt when no checkpoint is that old. */
	std::optional<std::size_t> rewindFor(double t_m);
	const FilterCheckpoint& lastCheckpoint() const { return checkpoints_.back(); }

	FilterEvent& at(std::size_t abs) { return events_[abs - first_]; }
	std::size_t end() const { return first_ + events_.size(); }

	/** How many smoother records no rewind can reach any more (all of them
	 *  without a checkpoint that holds a smoother snapshot). */
	std::size_t settledSmootherRecords() const;
	/** The smoother stopped: its snapshots are not needed. */
	void dropSmootherSnapshots();

 private:
	DelayedFusionParams p_;
	std::deque<FilterEvent> events_;
	std::size_t first_ = 0;  // absolute index of events_.front()
	std::deque<FilterCheckpoint> checkpoints_;
};

}  // namespace auvnav
