#include <auvnav/config.h>
#include <auvnav/import/csv_source.h>
#include <auvnav/import/importer.h>
#include <auvnav/import/time_format.h>
#include <auvnav/io/json.h>
#include <auvnav/io/rawlog.h>
#include <mrpt/system/filesystem.h>

#include <fnmatch.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <queue>
#include <sstream>

#include "converters.h"
#include "field_spec.h"

namespace auvnav::import
{
namespace
{
using detail::Converter;

constexpr TimeNs kNoTime = std::numeric_limits<TimeNs>::min();
constexpr std::size_t kMaxNotes = 5;
constexpr std::size_t kMaxPending = 2000000;  // ~1.5 GB at worst; 5.5 h of a 100 Hz IMU
constexpr std::size_t kMaxReasons = 20;       // distinct rejection reasons kept per sensor

bool isDirectory(const std::string& p)
{
	std::error_code ec;
	return std::filesystem::is_directory(p, ec);
}
bool isFile(const std::string& p)
{
	std::error_code ec;
	return std::filesystem::is_regular_file(p, ec);
}

std::string baseName(const std::string& p)
{
	const auto s = p.find_last_of('/');
	return s == std::string::npos ? p : p.substr(s + 1);
}

/** The input a source names: an INPUT whose file name matches `pattern`, or
 *  a file matching it inside an INPUT folder (also a rosbag2 folder, for
 *  `allow_dirs`). Exactly one match, else ImportError listing what was seen. */
std::string resolveInput(const std::string& pattern, const std::vector<std::string>& inputs, bool allow_dirs,
                         const std::string& what)
{
	std::vector<std::string> matches;
	auto consider = [&](const std::string& path, const std::string& name)
	{
		if (::fnmatch(pattern.c_str(), name.c_str(), 0) != 0) return;
		if (isFile(path) || (allow_dirs && isDirectory(path))) matches.push_back(path);
	};
	const bool has_slash = pattern.find('/') != std::string::npos;
	for (const auto& in : inputs)
	{
		if (has_slash)
		{
			// A path relative to an input folder ("run1/imu.csv").
			const std::string p = isDirectory(in) ? in + "/" + pattern : pattern;
			if (isFile(p) || (allow_dirs && isDirectory(p))) matches.push_back(p);
			continue;
		}
		consider(in, baseName(in));
		if (isDirectory(in))
		{
			std::error_code ec;
			for (const auto& e : std::filesystem::directory_iterator(in, ec))
				consider(e.path().string(), e.path().filename().string());
		}
	}
	std::sort(matches.begin(), matches.end());
	matches.erase(std::unique(matches.begin(), matches.end()), matches.end());
	if (matches.size() == 1) return matches[0];
	std::string list;
	for (const auto& in : inputs) list += (list.empty() ? "" : ", ") + in;
	if (matches.empty())
		throw ImportError(what + ": no input matches '" + pattern +
		                  "' (inputs: " + (list.empty() ? "none" : list) + ")");
	std::string m;
	for (const auto& x : matches) m += (m.empty() ? "" : ", ") + x;
	throw ImportError(what + ": '" + pattern + "' matches several inputs (" + m + "); name one");
}

struct TimeSpec
{
	bool from_record = false;
	std::string field;
	TimeFormat format = TimeFormat::Seconds;
	bool format_given = false;
	TimeNs offset_ns = 0;
};

/** Keys that say what the quantities are; without any, a bag topic of a
 *  standard type gets the preset mapping. */
bool hasQuantityKeys(const config::Node& s)
{
	for (const char* k :
	     {"angular_velocity", "linear_acceleration", "magnetic_field", "orientation", "velocity", "pressure",
	      "depth", "latitude", "longitude", "effort", "cells", "file", "beams"})
		if (s.has(k)) return true;
	return false;
}

struct SensorRun
{
	std::string label, cls;
	config::Node node;
	std::string source_kind;  // csv, ros1, ros2
	std::string source_pattern, topic;
	char delimiter = ',';
	bool optional = false;
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

TimeSpec parseTimeSpec(const config::Node& s, bool bag)
{
	if (!s.has("time"))
		s.fail("time", bag ? "required: {field: header.stamp} or {source: record} (the bag's record time)"
		                   : "required: {field: COLUMN, format: s|ms|us|ns|iso8601}");
	const config::Node t = s.child("time");
	t.allowOnly({"source", "field", "format", "offset_s"});
	TimeSpec ts;
	const std::string src = t.string("source", "field");
	if (src != "field" && src != "record") t.fail("source", "expected field or record");
	ts.from_record = src == "record";
	if (ts.from_record && !bag)
		t.fail("source", "record times exist only in bags; a CSV names its time column");
	if (ts.from_record && t.has("field")) t.fail("field", "not used with source: record");
	if (!ts.from_record) ts.field = t.string("field");
	if (t.has("format"))
	{
		ts.format = timeFormatFromName(t.string("format"), t.where("format"));
		ts.format_given = true;
	}
	else if (!bag && !ts.from_record)
		t.fail("format", "required for a CSV time column: s, ms, us, ns or iso8601");
	const double off = t.number("offset_s", 0.0);
	if (std::abs(off) > 1e9) t.fail("offset_s", "more than 30 years");
	ts.offset_ns = static_cast<TimeNs>(std::llround(off * 1e9));
	return ts;
}

Spec parseSpec(const config::Node& root)
{
	root.allowOnly(
	    {"format_version", "description", "reorder_window_s", "clock_jump_s", "gap_factor", "sensors"});
	if (root.has("format_version") && root.integer("format_version") != 1)
		root.fail("format_version", "this auvnav-import reads format_version 1");
	Spec spec;
	spec.reorder_window_s = root.inRange("reorder_window_s", 0, 600, 1.0);
	spec.clock_jump_s = root.inRange("clock_jump_s", 1e-6, 1e9, 10.0);  // 1e9 s: ~30 years, in int64 ns
	spec.gap_factor = root.inRange("gap_factor", 1.5, 1e6, 5.0);
	for (const auto& s : root.sequence("sensors"))
	{
		SensorRun run;
		run.node = s;
		run.label = s.string("label");
		if (run.label.empty() || run.label.find_first_of(" \t,") != std::string::npos)
			s.fail("label", "expected a non-empty label without spaces or commas");
		for (const auto& other : spec.sensors)
			if (other.label == run.label) s.fail("label", "label '" + run.label + "' used twice");
		run.cls = s.string("class");
		const auto& names = detail::observationClassNames();
		if (std::find(names.begin(), names.end(), run.cls) == names.end())
		{
			std::string list;
			for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
			s.fail("class", "unknown observation class '" + run.cls + "' (" + list + ")");
		}
		s.allowOnly(detail::classKeys(run.cls));
		run.optional = s.boolean("optional", false);
		const config::Node src = s.child("source");
		src.allowOnly({"csv", "ros1", "ros2", "topic", "delimiter"});
		int kinds = 0;
		for (const char* k : {"csv", "ros1", "ros2"})
			if (src.has(k))
			{
				run.source_kind = k;
				run.source_pattern = src.string(k);
				++kinds;
			}
		if (kinds != 1) s.fail("source", "give exactly one of csv: FILE, ros1: BAG, ros2: BAG");
		if (run.source_kind == "csv")
		{
			if (src.has("topic")) src.fail("topic", "a CSV source has no topic");
			const std::string d = src.string("delimiter", ",");
			if (d != "," && d != ";" && d != "\\t" && d != "tab" && d != " ")
				src.fail("delimiter", "expected ',', ';', ' ' or tab");
			run.delimiter = (d == "\\t" || d == "tab") ? '\t' : d[0];
		}
		else
		{
			run.topic = src.string("topic");
			if (src.has("delimiter")) src.fail("delimiter", "only for CSV sources");
		}
		run.time = parseTimeSpec(s, run.source_kind != "csv");
		spec.sensors.push_back(std::move(run));
	}
	if (spec.sensors.empty()) root.fail("sensors", "no sensors");
	return spec;
}

/** Builds the converter of a sensor from its spec alone (units, required
 *  keys, ...), to check it without its input; a bag topic relying on a preset
 *  needs the topic's message type, so it is checked only once opened. */
void checkConverter(const SensorRun& run)
{
	if (run.source_kind != "csv" && !hasQuantityKeys(run.node)) return;
	(void)detail::makeConverter(run.cls, run.node, run.node, run.label, ".");
}

/** Opens the source and builds the converter; false if an optional sensor has no input. */
bool openSensor(SensorRun& run, const std::vector<std::string>& inputs)
{
	const std::string what = run.node.where("source");
	try
	{
		run.path = resolveInput(run.source_pattern, inputs, run.source_kind == "ros2", what);
	}
	catch (const ImportError&)
	{
		// No input is fine for an optional sensor, a wrong spec is not.
		if (run.optional)
		{
			checkConverter(run);
			return false;
		}
		throw;
	}
	if (run.source_kind == "csv")
		run.source = std::make_unique<CsvSource>(run.path, run.delimiter);
	else if (run.source_kind == "ros1")
		run.source = openRos1Bag(run.path, run.topic);
	else
		run.source = openRos2Bag(run.path, run.topic);

	config::Node quantities = run.node;
	if (run.source_kind != "csv" && !hasQuantityKeys(run.node))
	{
		const std::string preset = detail::presetFor(run.source->messageType(), run.cls);
		if (preset.empty())
			run.node.fail("class", "topic " + run.topic + " has type '" + run.source->messageType() +
			                           "', which has no preset for class " + run.cls + ": name its fields");
		quantities = config::Node::fromText(preset, "preset for " + run.source->messageType());
	}
	const std::string dir = mrpt::system::extractFileDirectory(run.path);
	run.converter = detail::makeConverter(run.cls, quantities, run.node, run.label, dir.empty() ? "." : dir);
	return true;
}

/** The stamp of `r` per the time spec, or false and `why`. */
bool stampOf(const SensorRun& run, const Record& r, detail::Columns& cols, TimeNs& out, std::string& why)
{
	if (run.time.from_record)
	{
		if (!r.has_record_time)
		{
			why = "no record time";
			return false;
		}
		if (__builtin_add_overflow(r.record_time_ns, run.time.offset_ns, &out))
		{
			why = "record time plus offset_s is out of range";
			return false;
		}
		return true;
	}
	const int i = cols.index(r, run.time.field);
	if (i < 0)
	{
		why = "no field '" + run.time.field + "'";
		return false;
	}
	const Value& v = r.values[static_cast<std::size_t>(i)];
	switch (v.kind)
	{
		case Value::Kind::Time:
			out = v.time_ns;
			break;
		case Value::Kind::Text:
		{
			std::string err;
			const auto t = parseTime(v.text, run.time.format, err);
			if (!t)
			{
				why = "time field '" + run.time.field + "': '" + v.text.substr(0, 40) + "' " + err;
				return false;
			}
			out = *t;
			break;
		}
		case Value::Kind::Number:
		{
			// A bag's numeric time field has no unit of its own: s assumed for a
			// field in ms or ns would be a silent factor 1e3..1e9.
			if (!run.time.format_given)
			{
				why = "spec: time field '" + run.time.field +
				      "' is a number: give time.format (s, ms, us or ns)";
				return false;
			}
			const double scale = run.time.format == TimeFormat::Seconds        ? 1e9
			                     : run.time.format == TimeFormat::Milliseconds ? 1e6
			                     : run.time.format == TimeFormat::Microseconds ? 1e3
			                                                                   : 1.0;
			const double ns = v.number * scale;
			if (!std::isfinite(ns) || std::abs(ns) > 9e18 || run.time.format == TimeFormat::Iso8601)
			{
				why = "time field '" + run.time.field + "' is not a usable time";
				return false;
			}
			out = static_cast<TimeNs>(std::llround(ns));
			break;
		}
		case Value::Kind::Missing:
			why = "time field '" + run.time.field + "' is empty";
			return false;
	}
	if (__builtin_add_overflow(out, run.time.offset_ns, &out))
	{
		why = "time field '" + run.time.field + "' plus offset_s is out of range";
		return false;
	}
	return true;
}

struct Pending
{
	TimeNs t;
	uint64_t seq;
	std::size_t sensor;
	mrpt::obs::CObservation::Ptr obs;
	// Equal stamps: in the order of the sensors in the spec (the user's
	// choice, e.g. thrusters, IMU, then aiding sensors), then in row order.
	bool operator>(const Pending& o) const
	{
		if (t != o.t) return t > o.t;
		if (sensor != o.sensor) return sensor > o.sensor;
		return seq > o.seq;
	}
};

std::string secondsText(TimeNs t)
{
	char buf[40];
	std::snprintf(buf, sizeof buf, "%.3f", static_cast<double>(t) * 1e-9);
	return buf;
}

void finishSteps(SensorRun& run, SensorReport& rep, double gap_factor)
{
	if (run.steps.empty()) return;
	std::vector<TimeNs> d;
	d.reserve(run.steps.size());
	for (const auto& s : run.steps) d.push_back(s.second);
	std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
	const double median_s = static_cast<double>(d[d.size() / 2]) * 1e-9;
	rep.median_rate_hz = median_s > 0 ? 1.0 / median_s : 0;
	for (const auto& [start, step] : run.steps)
	{
		const double s = static_cast<double>(step) * 1e-9;
		if (s <= gap_factor * median_s) continue;
		++rep.gaps;
		if (s > rep.largest_gap_s)
		{
			rep.largest_gap_s = s;
			rep.largest_gap_at_s = static_cast<double>(start) * 1e-9;
		}
	}
	run.steps.clear();
	run.steps.shrink_to_fit();
}

}  // namespace

void validateSpec(const std::string& spec_path)
{
	try
	{
		// --check: the converters too (units, frame/sign, ...), not only the common keys.
		const Spec spec = parseSpec(config::Node::load(spec_path));
		for (const auto& run : spec.sensors) checkConverter(run);
	}
	catch (const config::ConfigError& e)
	{
		throw ImportError(e.what());
	}
}

void runImport(const ImportOptions& opt, ImportReport& report)
{
	report = ImportReport{};
	report.spec_path = opt.spec_path;
	report.out_rawlog = opt.out_rawlog;
	Spec spec;
	try
	{
		spec = parseSpec(config::Node::load(opt.spec_path));
		for (auto& run : spec.sensors)
		{
			SensorReport rep;
			rep.label = run.label;
			rep.observation_class = detail::mrptClassOf(run.cls);
			if (!openSensor(run, opt.inputs))
			{
				rep.source = run.source_pattern + " (optional, no input)";
				run.done = true;
			}
			else
			{
				rep.source = run.source->describe();
				rep.notes = run.converter->notes();
			}
			run.report_index = report.sensors.size();
			report.sensors.push_back(rep);
		}
	}
	catch (const config::ConfigError& e)
	{
		throw ImportError(e.what());
	}
	// Writing the rawlog over one of the inputs would destroy the data being read.
	{
		std::error_code ec;
		const auto out_abs = std::filesystem::weakly_canonical(opt.out_rawlog, ec);
		for (const auto& run : spec.sensors)
			if (!run.path.empty() && std::filesystem::weakly_canonical(run.path, ec) == out_abs)
				throw ImportError(opt.out_rawlog + ": the output is one of the inputs (" + run.label +
				                  " reads it)");
	}
	report.reorder_window_s = spec.reorder_window_s;
	const TimeNs window_ns = static_cast<TimeNs>(spec.reorder_window_s * 1e9);
	const TimeNs jump_ns = static_cast<TimeNs>(spec.clock_jump_s * 1e9);

	io::RawlogWriter writer(opt.out_rawlog);
	report.output_created = true;
	std::priority_queue<Pending, std::vector<Pending>, std::greater<Pending>> heap;
	TimeNs written_upto = kNoTime;
	uint64_t seq = 0;
	std::vector<detail::Columns> time_cols(spec.sensors.size());

	auto writeUpTo = [&](TimeNs limit)
	{
		// Strictly older than the limit: a record with the limit's stamp may still
		// come from a sensor listed earlier in the spec.
		while (!heap.empty() && (heap.top().t < limit || limit == std::numeric_limits<TimeNs>::max()))
		{
			const Pending& p = heap.top();
			writer.write(*p.obs);
			written_upto = p.t;
			report.sensors[spec.sensors[p.sensor].report_index].written++;
			report.written++;
			heap.pop();
		}
	};
	auto reject = [&](SensorRun& run, const std::string& reason, const std::string& where, bool always_fatal)
	{
		if (!opt.lenient || always_fatal)
			throw ImportError(
			    where + ": " + reason +
			    (always_fatal || opt.lenient ? "" : " (--lenient counts such records and goes on)"));
		SensorReport& rep = report.sensors[run.report_index];
		rep.rejected++;
		// Reasons quote the bad value: bound how many distinct ones are kept.
		const std::string key =
		    rep.rejected_by_reason.count(reason) || rep.rejected_by_reason.size() < kMaxReasons
		        ? reason
		        : std::string("other reasons");
		rep.rejected_by_reason[key]++;
		rep.first_rejected_where.emplace(key, where);
	};

	// Puts an accepted record in the reorder buffer (or counts it behind the window).
	auto place = [&](SensorRun& run, std::size_t idx, SensorRun::Held h)
	{
		SensorReport& rep = report.sensors[run.report_index];
		const TimeNs t = h.t;
		if (written_upto != kNoTime && t < written_upto)
		{
			// Not fatal in strict mode either: a stamp that went back
			// is the log's fact, reported, not a conversion error.
			const std::string reason = "behind the reorder window (older than data already written)";
			rep.rejected++;
			rep.rejected_by_reason[reason]++;
			rep.first_rejected_where.emplace(reason, h.where);
		}
		else
		{
			if (run.newest != kNoTime && t < run.newest) rep.reordered++;
			heap.push({t, seq++, idx, std::move(h.obs)});
			if (!rep.has_span)
			{
				rep.has_span = true;
				rep.first_ns = rep.last_ns = t;
			}
			rep.first_ns = std::min(rep.first_ns, t);
			rep.last_ns = std::max(rep.last_ns, t);
			run.newest = std::max(run.newest == kNoTime ? t : run.newest, t);
		}
		// The read position follows the placed stamps; a jump is placed only once
		// the next record confirmed it, so one stamp a year ahead cannot hold its
		// sensor back until every other sensor is read.
		if (written_upto == kNoTime || t >= written_upto) run.frontier = t;
		run.has_placed = true;
		run.placed_prev = t;
	};
	auto far = [&](TimeNs a, TimeNs b)
	{
		return std::abs(static_cast<long double>(a) - static_cast<long double>(b)) >
		       static_cast<long double>(jump_ns);
	};
	// A converted record: placed, or held as a suspect (see SensorRun::Held).
	auto arrive = [&](SensorRun& run, std::size_t idx, SensorRun::Held h)
	{
		if (run.suspect)
		{
			SensorRun::Held s = std::move(*run.suspect);
			run.suspect.reset();
			// The first record is a bad stamp when the next goes back more than
			// clock_jump_s (a later one, when its neighbours agree without it).
			// Only the very first record is judged so: a log stepping back more
			// than clock_jump_s at every record must not lose all but its last.
			const bool isolated =
			    !run.has_placed ? !run.first_rejected && far(h.t, s.t) && h.t < s.t
			                    : far(s.t, run.placed_prev) && far(h.t, s.t) && !far(h.t, run.placed_prev);
			if (isolated && !run.has_placed) run.first_rejected = true;
			if (isolated)
			{
				// Like "behind the reorder window": the log's fact, counted, not fatal.
				SensorReport& rep = report.sensors[run.report_index];
				const std::string reason =
				    "isolated time stamp (more than clock_jump_s from both neighbouring records, which "
				    "agree)";
				rep.rejected++;
				rep.rejected_by_reason[reason]++;
				rep.first_rejected_where.emplace(reason, s.where);
			}
			else
				place(run, idx, std::move(s));
		}
		if (!run.has_placed || far(h.t, run.placed_prev))
			run.suspect = std::move(h);
		else
			place(run, idx, std::move(h));
	};
	std::size_t rows_total = 0;
	try
	{
		for (;;)
		{
			// Read from the sensor that is furthest behind, so that the
			// buffer holds about one reorder window of every sensor.
			std::size_t pick = spec.sensors.size();
			for (std::size_t i = 0; i < spec.sensors.size(); ++i)
				if (!spec.sensors[i].done &&
				    (pick == spec.sensors.size() || spec.sensors[i].frontier < spec.sensors[pick].frontier))
					pick = i;
			if (pick == spec.sensors.size()) break;
			SensorRun& run = spec.sensors[pick];
			SensorReport& rep = report.sensors[run.report_index];
			if (!run.source->next(run.record))
			{
				run.done = true;
				// The last record has no next one to judge it by: kept.
				if (run.suspect)
				{
					SensorRun::Held h = std::move(*run.suspect);
					run.suspect.reset();
					place(run, pick, std::move(h));
				}
			}
			else
			{
				++rows_total;
				rep.rows_read++;
				if (opt.progress && rows_total % 100000 == 0) opt.progress(rows_total, opt.progress_user);
				const Record& r = run.record;
				TimeNs t = 0;
				std::string why;
				if (!r.defect.empty())
					reject(run, r.defect, r.where, false);
				else if (!stampOf(run, r, time_cols[pick], t, why))
					reject(run, why, r.where, why.rfind("no field", 0) == 0 || why.rfind("spec: ", 0) == 0);
				else if (auto obs = run.converter->convert(r, why); !obs)
					reject(run, why, r.where, why.rfind("no field", 0) == 0);
				else
				{
					obs->timestamp = toMrptTime(t);
					detail::finishObservation(*obs);
					if (run.previous != kNoTime)
					{
						// Steps in long double: two valid stamps can be 1.8e19 ns apart.
						const long double step =
						    static_cast<long double>(t) - static_cast<long double>(run.previous);
						if (t == run.previous) rep.repeated_stamps++;
						if (t < run.previous) rep.backward_stamps++;
						if (t > run.previous && step < 9e18L)
							run.steps.emplace_back(run.previous, t - run.previous);
						if (step > static_cast<long double>(jump_ns) ||
						    -step > static_cast<long double>(jump_ns))
						{
							rep.clock_jumps++;
							if (rep.clock_jump_notes.size() < kMaxNotes)
							{
								char buf[64];
								std::snprintf(buf, sizeof buf, "%+.3Lf", step * 1e-9L);
								rep.clock_jump_notes.push_back("at " + secondsText(run.previous) +
								                               " s: " + buf + " s");
							}
						}
					}
					arrive(run, pick, {t, std::move(obs), r.where});
					run.previous = t;
				}
			}
			// Everything older than the slowest sensor's newest stamp minus
			// the window can no longer be overtaken.
			TimeNs watermark = std::numeric_limits<TimeNs>::max();
			bool all_done = true;
			for (const auto& s : spec.sensors)
				if (!s.done)
				{
					all_done = false;
					watermark = std::min(
					    watermark,
					    s.frontier == kNoTime
					        ? kNoTime
					        : (s.frontier < kNoTime + window_ns + 1 ? kNoTime + 1 : s.frontier - window_ns));
				}
			if (all_done) break;
			if (watermark != kNoTime) writeUpTo(watermark);
			// A sensor whose clock jumped far ahead must not make the buffer hold
			// every other record: past kMaxPending the oldest are written anyway.
			while (heap.size() > kMaxPending)
			{
				const Pending& p = heap.top();
				writer.write(*p.obs);
				written_upto = p.t;
				report.sensors[spec.sensors[p.sensor].report_index].written++;
				report.written++;
				++report.buffer_overflows;
				heap.pop();
			}
		}
		writeUpTo(std::numeric_limits<TimeNs>::max());
	}
	catch (const ImportError& e)
	{
		report.error = e.what();
		throw;
	}
	catch (const std::exception& e)
	{
		report.error = e.what();
		throw ImportError(e.what());
	}
	for (auto& run : spec.sensors) finishSteps(run, report.sensors[run.report_index], spec.gap_factor);
	report.completed = true;
}

// ---------------------------------------------------------------- reports

namespace
{
std::string num(double v, int prec = 6)
{
	if (!std::isfinite(v)) return "null";
	std::ostringstream s;
	s.precision(prec);
	s << v;
	return s.str();
}

double spanSeconds(const SensorReport& s)
{
	return s.has_span ? static_cast<double>(s.last_ns - s.first_ns) * 1e-9 : 0;
}
}  // namespace

std::string ImportReport::toJson() const
{
	using io::Json;
	Json j;
	j["spec"] = spec_path;
	j["output"] = out_rawlog;
	j["completed"] = completed;
	j["error"] = error.empty() ? Json() : Json(error);
	j["written"] = written;
	j["reorder_window_s"] = reorder_window_s;
	j["sensors"] = Json::array();
	for (const auto& s : sensors)
	{
		Json by_reason = Json::object();
		for (const auto& [reason, n] : s.rejected_by_reason)
			by_reason[reason] = {{"count", n}, {"first", s.first_rejected_where.at(reason)}};
		const Json no_time;  // null: no observation written
		j["sensors"].push_back({{"label", s.label},
		                        {"class", s.observation_class},
		                        {"source", s.source},
		                        {"rows_read", s.rows_read},
		                        {"written", s.written},
		                        {"rejected", s.rejected},
		                        {"rejected_by_reason", by_reason},
		                        {"first_time_s", s.has_span ? Json(s.first_ns * 1e-9) : no_time},
		                        {"last_time_s", s.has_span ? Json(s.last_ns * 1e-9) : no_time},
		                        {"span_s", spanSeconds(s)},
		                        {"median_rate_hz", s.median_rate_hz},
		                        {"repeated_stamps", s.repeated_stamps},
		                        {"backward_stamps", s.backward_stamps},
		                        {"reordered", s.reordered},
		                        {"gaps", s.gaps},
		                        {"largest_gap_s", s.largest_gap_s},
		                        {"largest_gap_at_s", s.largest_gap_at_s},
		                        {"clock_jumps", s.clock_jumps},
		                        {"clock_jump_notes", s.clock_jump_notes},
		                        {"notes", s.notes}});
	}
	return io::jsonText(j);
}

std::string ImportReport::toMarkdown() const
{
	std::ostringstream o;
	o << "# Import report\n\n- spec: `" << spec_path << "`\n- output: `" << out_rawlog << "` (" << written
	  << " observations)\n- completed: " << (completed ? "yes" : "no") << "\n";
	if (!error.empty()) o << "- error: " << error << "\n";
	o << "- reorder window: " << reorder_window_s << " s\n\n";
	o << "| sensor | class | source | read | written | rejected | span [s] | rate [Hz] | repeated | backward "
	     "| "
	     "reordered | gaps (largest [s]) | clock jumps "
	     "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
	for (const auto& s : sensors)
		o << "| " << s.label << " | " << s.observation_class << " | " << s.source << " | " << s.rows_read
		  << " | " << s.written << " | " << s.rejected << " | " << num(spanSeconds(s), 4) << " | "
		  << num(s.median_rate_hz, 4) << " | " << s.repeated_stamps << " | " << s.backward_stamps << " | "
		  << s.reordered << " | " << s.gaps << " (" << num(s.largest_gap_s, 3) << ") | " << s.clock_jumps
		  << " |\n";
	for (const auto& s : sensors)
	{
		if (s.rejected_by_reason.empty() && s.clock_jump_notes.empty() && s.notes.empty()) continue;
		o << "\n## " << s.label << "\n\n";
		for (const auto& [reason, n] : s.rejected_by_reason)
			o << "- rejected " << n << " × " << reason << " (first: " << s.first_rejected_where.at(reason)
			  << ")\n";
		for (const auto& j : s.clock_jump_notes) o << "- clock jump " << j << "\n";
		for (const auto& n : s.notes) o << "- " << n << "\n";
	}
	return o.str();
}

std::string ImportReport::toTable() const
{
	std::ostringstream o;
	char line[256];
	std::snprintf(line, sizeof line, "  %-12s %-34s %9s %9s %9s %9s %8s %9s %7s\n", "sensor", "class", "read",
	              "written", "rejected", "span[s]", "rate[Hz]", "repeated", "gaps");
	o << line;
	for (const auto& s : sensors)
	{
		std::snprintf(line, sizeof line, "  %-12s %-34s %9zu %9zu %9zu %9.1f %8.2f %9zu %7zu\n",
		              s.label.c_str(), s.observation_class.c_str(), s.rows_read, s.written, s.rejected,
		              spanSeconds(s), s.median_rate_hz, s.repeated_stamps, s.gaps);
		o << line;
	}
	return o.str();
}

}  // namespace auvnav::import
