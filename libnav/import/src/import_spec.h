#pragma once
// Internal to the importer: the spec as read, one SensorRun per sensor (its
// source, converter and reading state), and what fills it: parseSpec
// (import_spec.cpp); openSensor, checkConverter and stampOf (import_sensor.cpp).
#include <auvnav/config.h>
#include <auvnav/import/record.h>
#include <auvnav/import/time_format.h>
#include <mrpt/obs/CObservation.h>

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "converters.h"
#include "field_spec.h"

namespace auvnav::import::detail
{
constexpr TimeNs kNoTime = std::numeric_limits<TimeNs>::min();

struct TimeSpec
{
	bool from_record = false;
	std::string field;
	TimeFormat format = TimeFormat::Seconds;
	bool format_given = false;
	TimeNs offset_ns = 0;
};

struct SensorRun
{
	std::string label, cls;
	config::Node node;
	std::string source_kind;  // csv, ros1, ros2
	std::string source_pattern, topic;
	char delimiter = ',';
	bool optional = false;
	std::string absent_why;  // an optional sensor's reason for having no source
	TimeSpec time;

	std::string path;  // resolved
	std::unique_ptr<RecordSource> source;
	std::unique_ptr<Converter> converter;
	std::size_t report_index = 0;

	bool done = false;
	TimeNs frontier = kNoTime;  // stamp of the last record placed (where this sensor's reading stands)
	TimeNs newest = kNoTime;    // newest stamp placed
	TimeNs previous = kNoTime;  // stamp of the previous accepted record
	std::vector<std::pair<TimeNs, TimeNs>> steps;  // (start, step) of positive steps
	Record record;

	// A record more than clock_jump_s from the last one placed (or the first
	// record) waits for the next record of its sensor, which says whether it
	// was a clock jump (the next one follows it) or one bad stamp (the next one
	// is back where the sensor's clock was).
	struct Held
	{
		TimeNs t;
		mrpt::obs::CObservation::Ptr obs;
		std::string where;
	};
	std::optional<Held> suspect;
	bool has_placed = false, first_rejected = false;
	TimeNs placed_prev = 0;  // stamp of the last record placed (valid with has_placed)
};

struct Spec
{
	double reorder_window_s = 1.0;
	double clock_jump_s = 10.0;
	double gap_factor = 5.0;
	std::vector<SensorRun> sensors;
};

/** The import spec in `root` (common keys and sources; the quantities are
 *  the converters'). Throws ConfigError. */
Spec parseSpec(const config::Node& root);

/** Builds the converter of a sensor from its spec alone (units, required
 *  keys, ...), to check it without its input; a bag topic relying on a preset
 *  needs the topic's message type, so it is checked only once opened. */
void checkConverter(const SensorRun& run);

/** Opens the source and builds the converter; false (and run.absent_why) if
 *  an optional sensor has no input or its bag lacks the topic. */
bool openSensor(SensorRun& run, const std::vector<std::string>& inputs);

/** The stamp of `r` per the time spec, or false and `why`. */
bool stampOf(const SensorRun& run, const Record& r, detail::Columns& cols, TimeNs& out, std::string& why);

}  // namespace auvnav::import::detail
