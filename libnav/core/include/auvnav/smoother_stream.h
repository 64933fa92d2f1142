#pragma once
/** @file smoother_stream.h
 *  A whole run smoothed in bounded memory (issue 17, docs/smoother.md): the
 *  forward pass streams one RtsStretch per kept tick to a file; the backward
 *  pass reads it from the end.
 *
 *  The stretch file (`<run>/smoother/stretches.bin`, host byte order: a
 *  run's scratch file, read back on the machine that wrote it):
 *   - a header: magic "AUVNVRTS", format version, state dimension n, the
 *     IMU lever arm, the tangent and stored state names;
 *   - fixed-size records, one per kept tick in time order: the filtered
 *     estimate there (time, attitude, euclidean part, P's lower triangle)
 *     and the stretch from it to the next record (M, M_mean, Σ M dx, the
 *     lower triangle of Σ M ΔP Mᵀ, its tick count and flags).
 *  A record is written only when the stretch it opens is closed, so a run
 *  killed half way leaves whole records and at most a partial last one,
 *  which the reader ignores: the last whole record is then the end of what
 *  is smoothed ("interrupted runs smooth what was completed").
 *
 *  Segments: smoothing never carries information across a state reset. A
 *  position re-initialisation, a clock-jump restart or a recovery update (an
 *  aid applied though it failed the gate: the filter's covariance was just
 *  contradicted; Navigator, smoother.across_recoveries) ends the segment with
 *  a record flagged `ends_segment` (the estimate just before the reset);
 *  the backward pass starts again there from the filtered estimate, and
 *  says so in its output. A stretch in which the filter repaired its
 *  covariance (ManifoldUkf::choleskyRepairs: a non-PD P replaced) or whose
 *  P⁻ was not positive definite is `broken`: the smoothed estimate at its
 *  start is the filtered one (reported), and the pass goes on from it.
 *  Sigma-limit hits (filter.sigma_limits) are counted per stretch and
 *  smoothed through: in a prediction as process noise, in an update as a
 *  change of the filtered covariance (RtsStretchRecorder).
 */
#include <auvnav/io/c_file.h>
#include <auvnav/smoother.h>

#include <cstdint>
#include <cstdio>
#include <deque>
#include <functional>
#include <string>
#include <vector>

namespace auvnav
{
/** What the stretch file says besides its records. */
struct StretchFileHeader
{
	int n = 0;                                                 //!< tangent dimension
	Eigen::Vector3d imu_position_b = Eigen::Vector3d::Zero();  //!< body origin → IMU [m], body axes
	std::vector<std::string> tangent_names, stored_names;
};

/** One kept tick's record. */
struct StretchRecord
{
	RtsStretch stretch;            //!< ticks 0 (and the matrices unset) in an ends_segment record
	bool ends_segment = false;     //!< the estimate just before a reset, or the run's end
	std::uint32_t repairs = 0;     //!< covariance repairs inside the stretch (makes it broken)
	std::uint32_t limit_hits = 0;  //!< sigma-limit hits inside the stretch
};

/** Appends records to a stretch file (created or truncated). Throws
 *  std::runtime_error naming the file on any I/O failure. */
class StretchWriter
{
 public:
	StretchWriter(const std::string& path, const StretchFileHeader& header);
	StretchWriter(const StretchWriter&) = delete;  // and no move: a moved-from writer has no file
	StretchWriter& operator=(const StretchWriter&) = delete;
	void write(const StretchRecord& r);
	void flush();
	std::size_t records() const { return records_; }
	std::uint64_t bytes() const;

 private:
	void writeHeader(const StretchFileHeader& h);
	std::string path_;
	io::CFile f_;
	int n_ = 0;
	std::size_t records_ = 0;
	std::vector<double> buf_;
};

/** Reads a stretch file's header and its whole records by index. Throws
 *  std::runtime_error naming the file if it is not one or is unreadable. */
class StretchReader
{
 public:
	explicit StretchReader(const std::string& path);
	StretchReader(const StretchReader&) = delete;
	StretchReader& operator=(const StretchReader&) = delete;
	const StretchFileHeader& header() const { return header_; }
	std::size_t records() const { return records_; }    //!< whole ones
	bool partialTail() const { return partial_tail_; }  //!< bytes of an unfinished record after them
	StretchRecord read(std::size_t i);

 private:
	void readHeader();
	std::string path_;
	io::CFile f_;
	StretchFileHeader header_;
	std::uint64_t data_offset_ = 0, record_bytes_ = 0;
	std::size_t records_ = 0;
	bool partial_tail_ = false;
	std::vector<double> buf_;
};

/** Bytes of one record for tangent dimension n (for the documented disk use). */
std::uint64_t stretchRecordBytes(int n);

/** The navigator's forward-pass side: RtsStretchRecorder driven at IMU
 *  rate, a stretch closed at the first tick `keep_every_s` after the last
 *  kept one, records held back while a re-filtering pass (delayed
 *  measurements) could still rewind them and written once it cannot. */
class SmoothingRecorder
{
 public:
	SmoothingRecorder(const std::string& path, const StretchFileHeader& header, double keep_every_s);
	/** Instead of ukf.predict: closes the stretch first if a kept tick is
	 *  due (t_s: the time of the state before the prediction). */
	void predict(ManifoldUkf& ukf, const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& omega_ie_n,
	             double dt_s, double t_s);
	/** Before a reset of the state at t_s (position re-initialisation, clock
	 *  jump): ends the segment at the filter's current estimate. */
	void endSegment(const ManifoldUkf& ukf, double t_s);
	/** At the end of the run: ends the segment and writes everything. */
	void finish(const ManifoldUkf& ukf, double t_s);

	/** Everything a re-filtering pass rewinds (Navigator checkpoints). */
	struct Snapshot
	{
		RtsStretchRecorder recorder;
		double next_keep_s = -1e300;
		std::size_t emitted = 0;
		std::size_t repairs_seen = 0, limit_hits_seen = 0;
		std::uint32_t repairs = 0, limit_hits = 0;
	};
	/** The state to rewind to (looks for covariance repairs first). */
	const Snapshot& snapshot(const ManifoldUkf& ukf);
	/** Back to a snapshot: records emitted after it are dropped; repairs the
	 *  discarded pass made are not this stretch's. */
	void restore(const Snapshot& s, const ManifoldUkf& ukf);
	/** Writes the held records emitted before `emitted` (no checkpoint can
	 *  rewind past them any more); SIZE_MAX: all. */
	void commit(std::size_t emitted);
	std::size_t segments() const { return segments_; }
	std::size_t written() const { return writer_.records(); }

 private:
	void emit(StretchRecord r);
	void noteFilterCounters(const ManifoldUkf& ukf);
	StretchWriter writer_;
	double keep_every_s_;
	Snapshot s_;
	std::deque<StretchRecord> held_;  // emitted but not yet written; held_.front() is number first_held_
	std::size_t first_held_ = 0;
	std::size_t segments_ = 0;
};

/** What the backward pass did at one record. */
enum class SmoothedKind
{
	Smoothed,    //!< the RTS step over the stretch
	SegmentEnd,  //!< the estimate before a reset or the run's end: the filtered one (nothing later to use)
	Kept,        //!< a broken stretch or a failed step: the filtered estimate kept
};
const char* smoothedKindName(SmoothedKind k);

struct BackwardPassSummary
{
	std::size_t records = 0, smoothed = 0, segment_ends = 0, kept = 0, repairs = 0, limit_hits = 0;
	bool partial_tail = false;
};

/** The backward pass over a stretch file: calls `out` once per record, from
 *  the last to the first, with its time, the smoothed (or kept) estimate
 *  and what was done. Memory: two records. */
BackwardPassSummary smoothStretchFile(
    const std::string& path,
    const std::function<void(double t_s, const NavState& x, const Covariance& P, SmoothedKind kind)>& out);

}  // namespace auvnav
