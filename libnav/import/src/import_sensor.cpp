// One sensor of the import spec at work (import_spec.h): its input found
// among the INPUTs, its source opened, its converter built (or a preset's),
// and the stamp of each record.
#include <auvnav/import/csv_source.h>
#include <mrpt/system/filesystem.h>

#include <fnmatch.h>
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "import_spec.h"

namespace auvnav::import::detail
{
namespace
{
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
}  // namespace

void checkConverter(const SensorRun& run)
{
	if (run.source_kind != "csv" && !hasQuantityKeys(run.node)) return;
	(void)detail::makeConverter(run.cls, run.node, run.node, run.label, ".");
}

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
			run.absent_why = "no input";
			return false;
		}
		throw;
	}
	try
	{
		if (run.source_kind == "csv")
			run.source = std::make_unique<CsvSource>(run.path, run.delimiter);
		else if (run.source_kind == "ros1")
			run.source = openRos1Bag(run.path, run.topic);
		else
			run.source = openRos2Bag(run.path, run.topic);
	}
	catch (const MissingTopicError&)
	{
		// A vehicle without that sensor: its bag lacks the topic.
		if (!run.optional) throw;
		checkConverter(run);
		run.absent_why = "topic " + run.topic + " not in " + run.path;
		return false;
	}

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

}  // namespace auvnav::import::detail
