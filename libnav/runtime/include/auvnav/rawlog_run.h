#pragma once
/** @file rawlog_run.h
 *  The one rawlog-run loop of the programs and tests (auvnav-run,
 *  auvnav-experiment, auvnav-bench, the integration harness): streams a
 *  rawlog into a Navigator in file order, calls back per prediction, per
 *  update and per observation, and ends with Navigator::finish() and the
 *  run's figures.
 *
 *  A rawlog or navigator error does not escape the loop: it ends the run
 *  (the navigator is finished and the figures cover what was processed) and
 *  is reported in RunSummary::error, so that a program can still write its
 *  outputs; RunSummary::rethrow() raises it for callers that just fail.
 *
 *  A log the navigator can do nothing with is an error too, not a silent
 *  empty run (io::RawlogError, naming the file): one without any observation
 *  (an empty file), and one without a single observation on the IMU's label
 *  (imu.label), listing the labels it has. A run stopped by
 *  RunCallbacks::stop is not judged.
 */
#include <auvnav/navigator.h>

#include <exception>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace auvnav
{
struct RunCallbacks
{
	/** Installed as Navigator::on_predict / on_update for the run (when set). */
	std::function<void(const Navigator&)> on_predict;
	std::function<void(const std::string& label, double t_obs, const Measurement&, const UpdateResult&)>
	    on_update;
	/** After every observation fed (progress displays). */
	std::function<void(const Navigator&)> on_observation;
	/** Polled before every observation; true ends the run early (interrupted). */
	std::function<bool()> stop;
};

struct RunSummary
{
	std::size_t observations = 0;               //!< fed to the navigator
	double data_s = 0;                          //!< navigator time span (0 if nothing was read)
	double wall_s = 0;                          //!< of the loop alone
	bool interrupted = false;                   //!< RunCallbacks::stop said so
	std::string error;                          //!< what ended the run early (empty: the end of the file)
	std::exception_ptr failure;                 //!< the same, as thrown
	std::vector<SensorStats> stats;             //!< Navigator::stats() at the end
	std::map<std::string, std::size_t> labels;  //!< observations fed, per sensor label

	bool completed() const { return !interrupted && error.empty(); }
	/** Rethrows the error that ended the run, if any. */
	void rethrow() const
	{
		if (failure) std::rethrow_exception(failure);
	}
};

/** Runs `nav` over the rawlog at `path` (see the file comment). */
RunSummary runRawlog(Navigator& nav, const std::string& path, const RunCallbacks& callbacks = {});

}  // namespace auvnav
