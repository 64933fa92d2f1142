// Reading the import spec (import_spec.h): the common keys, each sensor's
// class, source and time. The quantities are left to the converters.
#include <algorithm>
#include <cmath>

#include "import_spec.h"

namespace auvnav::import::detail
{
namespace
{
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
}  // namespace

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

}  // namespace auvnav::import::detail
