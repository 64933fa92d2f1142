#pragma once
/** @file importer.h
 *  Vehicle logs (CSV files, ROS 1 and ROS 2 bags) to an MRPT rawlog, driven
 *  by an import spec (YAML; schema in docs/import.md, examples in
 *  config/import/). Used by `auvnav-import` and the tests.
 *
 *  Contract:
 *  - Every sensor of the spec is read from its source, each record converted
 *    to the observation class the spec names (units to SI, axes to the sensor
 *    frame, mounting, time format and offset), and the observations of all
 *    sensors are written in time order. Sources may interleave and jitter: a
 *    record up to `reorder_window_s` older than the newest of its sensor is
 *    put in place; one older than what is already written is rejected and
 *    counted ("behind the reorder window"). Observations with equal stamps
 *    are written in the order of their sensors in the spec.
 *  - Spec errors (unknown key, unit or class; a unit of the wrong kind; a
 *    column the file does not have; a topic the bag does not have) throw
 *    ImportError before anything is written.
 *  - A record that cannot be converted (malformed row, non-numeric or
 *    non-finite value) throws ImportError naming file, line/message and field,
 *    unless `lenient`: then it is rejected and counted by reason.
 *  - Repeated and backward stamps, gaps and clock jumps are counted per sensor
 *    in the report; nothing is silently dropped.
 */
#include <auvnav/import/record.h>

#include <map>
#include <string>
#include <vector>

namespace auvnav::import
{
struct ImportOptions
{
	std::string spec_path;
	std::vector<std::string> inputs;  //!< files or folders the spec's sources are looked up in
	std::string out_rawlog;
	bool lenient = false;
	/** Called every ~1 s of input with the rows read so far (progress line). */
	void (*progress)(std::size_t rows, void* user) = nullptr;
	void* progress_user = nullptr;
};

/** What happened to one sensor's records. */
struct SensorReport
{
	std::string label;
	std::string observation_class;
	std::string source;  //!< file or "bag topic"
	std::size_t rows_read = 0;
	std::size_t written = 0;
	std::size_t rejected = 0;
	std::map<std::string, std::size_t> rejected_by_reason;
	std::map<std::string, std::string> first_rejected_where;  //!< reason → first "file:line"
	std::size_t repeated_stamps = 0;                          //!< same stamp as the previous record
	std::size_t backward_stamps = 0;  //!< older than the previous record (reordered or rejected)
	std::size_t reordered = 0;        //!< written in place thanks to the reorder buffer
	std::size_t gaps = 0;             //!< steps longer than gap_factor × median step
	double largest_gap_s = 0;
	double largest_gap_at_s = 0;  //!< UNIX time where it starts
	std::size_t clock_jumps = 0;  //!< forward steps > clock_jump_s, backward steps beyond the window
	std::vector<std::string> clock_jump_notes;  //!< first few, "at 1453606150.8: +3600.0 s"
	bool has_span = false;
	TimeNs first_ns = 0, last_ns = 0;
	double median_rate_hz = 0;
	std::vector<std::string> notes;  //!< mapping facts worth reviewing (e.g. a left-handed axis map)
};

struct ImportReport
{
	std::string spec_path;
	std::string out_rawlog;
	std::vector<SensorReport> sensors;
	std::size_t written = 0;
	std::size_t buffer_overflows = 0;  //!< records written early because the reorder buffer was full
	double reorder_window_s = 0;
	bool completed = false;
	bool output_created = false;  //!< runImport wrote out_rawlog (OUT.partial until complete)
	std::string error;            //!< why the import stopped, if it did

	std::string toJson() const;
	std::string toMarkdown() const;
	/** Fixed-width table for the terminal. */
	std::string toTable() const;
};

/** Runs the import. Throws ImportError (spec errors, strict-mode record
 *  errors, unreadable input); `report` holds what was done until then. */
void runImport(const ImportOptions& options, ImportReport& report);

/** Checks a spec (keys, classes, units, time formats) without reading any
 *  input; throws ImportError. */
void validateSpec(const std::string& spec_path);

}  // namespace auvnav::import
