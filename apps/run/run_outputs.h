#pragma once
/** @file run_outputs.h
 *  auvnav-run's output files, written incrementally so that a run killed
 *  half way (kill -9 included) leaves valid files up to that point: the text
 *  files are written in whole lines (io::LineFile; the caller flushes them at
 *  an interval, flush()), summary.json is replaced atomically (writeSummary).
 *  A SIGKILL can still stop the kernel's write() of a buffer at a page
 *  boundary: a last line without its newline is such a cut one (drop it);
 *  every line before it is whole.
 *   - trajectory.tum: `t x y z qx qy qz qw`, body-origin position (NED tangent
 *     frame, metres) and body-to-NED attitude: the simulator's ground-truth
 *     convention;
 *   - states.csv: header row; time, the full state mean (attitude as
 *     quaternion and roll/pitch/yaw in degrees for reading), the body-origin
 *     position, and the standard deviation of every tangent coordinate;
 *   - nis.csv: per sensor and second of data, the accepted updates' summed
 *     NIS and dimension (consistency over time, auvnav-eval);
 *   - states.csv also carries the position and attitude covariances'
 *     off-diagonal terms (cov_pos_*, cov_att_*) for NEES;
 *   - position_fixes.csv: every position fix (GPS, USBL: reportsPositionFix)
 *     offered to the filter: time, label,
 *     north/east [m] and whether the χ² gate accepted it (for auvnav-view);
 *   - health.csv: every change of the divergence monitor's status (health.h):
 *     seconds from the first observation, status, reason;
 *   - events.csv: the navigator's events (Navigator::on_event: the start
 *     from a fix consensus, position re-initialisations): seconds from the
 *     first observation, sensor, what;
 *   - summary.json: status (ok, degraded, diverged, not_initialized) with its
 *     reason and the worst status of the run, per-sensor counts, consistency (mean NIS per dimension),
 *     final standard deviations, run time and real-time factor; `completed`
 *     true only in the final rewrite of a run that read its whole rawlog.
 */
#include <auvnav/io/line_file.h>
#include <auvnav/navigator.h>

#include <map>
#include <string>
#include <vector>

namespace auvnav::run
{
/** states.csv's header row (also smoothed_states.csv's). */
std::string statesCsvHeader(const std::vector<std::string>& tangent_names,
                            const std::vector<std::string>& stored_names);
/** A trajectory.tum row (no newline) for time t, attitude of x and body-origin position p [m, NED]. */
void formatTumRow(std::string& row, double t, const NavState& x, const Eigen::Vector3d& p);
/** A states.csv row: x, body position p, x.dim() σ and the six off-diagonal
 *  position/attitude covariances (sigmaAndOffDiagonals). */
void formatStatesRow(std::string& row, double t, const NavState& x, const Eigen::Vector3d& p,
                     const double* sigma, const double* cov_offdiag);
void sigmaAndOffDiagonals(const Covariance& P, double* sigma, double* cov_offdiag);

class RunOutputs
{
 public:
	/** `tangent_names` / `stored_names`: Navigator::stateNames() and
	 *  storedStateNames() (the 43 and the plugin states), for the headers. */
	RunOutputs(const std::string& dir, double rate_hz, std::vector<std::string> tangent_names,
	           std::vector<std::string> stored_names, bool updates_csv = true);
	/** One updates.csv row per update of any sensor and any status: filter
	 *  time, measurement time, sensor, status, NIS, dimension, why (for
	 *  invalid and rejected ones). */
	void onAnyUpdate(const std::string& label, double t_filter_s, double t_measurement_s,
	                 const UpdateResult& r);
	/** Appends a row if at least 1/rate since the last one. */
	void onState(const Navigator& nav);
	/** Appends a GPS-like 2-D position update (label "…GPS…" or any update
	 *  whose measurement is a north/east position) to position_fixes.csv. */
	/** Accumulates accepted updates' NIS per sensor; one nis.csv row per
	 *  sensor and second of data: time, label, updates, ΣNIS, Σdim. */
	void onUpdate(const std::string& label, double t, const UpdateResult& r);
	void onPositionFix(const std::string& label, double t, const Measurement& m, const UpdateResult& r);
	void onHealthChange(double t_s, NavStatus status, const std::string& reason);
	void onEvent(double t_s, const std::string& label, const std::string& what);
	/** Hands every file's buffered lines to the kernel (whole lines only). */
	void flush();
	/** Where the run is when summary.json is written. */
	enum class Phase
	{
		Running,      //!< at the start and at the interval: completed false, running true
		Interrupted,  //!< stopped by a signal: completed false
		Ended,        //!< the end of the rawlog, or an error: completed = no error
	};
	/** Writes summary.json (complete rewrite: SUMMARY.tmp renamed over it, so
	 *  a reader or a kill never sees half a file). `error` (one line) is
	 *  written when not empty. `clock_jumps`: the jumps re-initialised
	 *  through (Navigator::clockJumps(), clock.on_jump: reinitialize). */
	void writeSummary(const Navigator& nav, double wall_s, Phase phase, const std::string& rawlog,
	                  const std::string& error) const;
	std::size_t rows() const { return rows_; }

 private:
	std::string dir_;
	std::vector<std::string> names_, stored_names_;
	double period_s_;
	double last_t_ = -1e300;
	io::LineFile tum_, csv_, fixes_, nis_, health_, events_, updates_;
	struct NisAcc
	{
		std::size_t n = 0, dim = 0;
		double nis = 0;
	};
	std::map<std::string, NisAcc> nis_acc_;
	double nis_t0_ = -1e300;
	std::size_t rows_ = 0;
	std::string row_;         // states.csv and trajectory.tum row buffer (reused: no allocation per row)
	std::string update_row_;  // updates.csv row buffer
};
}  // namespace auvnav::run
