#pragma once
/** @file smooth_outputs.h
 *  The smoother's outputs for a run directory, from its stretch file
 *  (smoother_stream.h), in the filter's formats:
 *   - smoothed_trajectory.tum: as trajectory.tum, one row per kept tick;
 *   - smoothed_states.csv: as states.csv (mean, σ of every state, the
 *     position/attitude covariances), plus a last column `smoother`:
 *     smoothed, segment_end (the estimate before a reset or at the end:
 *     the filtered one) or filtered_kept (a broken stretch or failed step);
 *   - smoother.json: what the backward pass did (counts, disk use, time).
 *  The backward pass yields the estimates newest first; they go to a
 *  scratch file of fixed-size rows that is then read from the end, so the
 *  memory used does not grow with the run's length.
 */
#include <string>

namespace auvnav::run
{
struct SmoothRunResult
{
	std::size_t rows = 0, smoothed = 0, segment_ends = 0, kept = 0, repairs = 0, limit_hits = 0;
	bool partial_tail = false;
	double wall_s = 0;
	unsigned long long stretch_bytes = 0;
};

/** Smooths the run in `run_dir` (its smoother/stretches.bin) and writes the
 *  outputs there. Throws std::runtime_error with the file and the reason. */
SmoothRunResult smoothRun(const std::string& run_dir);

/** The stretch file of a run directory. */
std::string stretchFileOf(const std::string& run_dir);
}  // namespace auvnav::run
