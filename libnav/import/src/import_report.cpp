// The import report (importer.h): JSON, Markdown and a terminal table.
#include <auvnav/import/importer.h>
#include <auvnav/io/json.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace auvnav::import
{
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

double seconds(TimeNs t)
{
	return static_cast<double>(t) * 1e-9;
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
		                        {"first_time_s", s.has_span ? Json(seconds(s.first_ns)) : no_time},
		                        {"last_time_s", s.has_span ? Json(seconds(s.last_ns)) : no_time},
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
