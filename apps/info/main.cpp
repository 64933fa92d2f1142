// auvnav-info: summarises a rawlog per sensor label without loading it: the
// file is streamed one observation at a time, and only one small record per
// (sensor label, class) is kept, so memory does not grow with the file length.
//
// Exit codes: 0 success, 1 usage or output error, 2 unreadable/corrupt rawlog
// (the summary of what was read before the error is still printed).
#include <auvnav/cli.h>
#include <auvnav/io/json.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/system/datetime.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace
{
using auvnav::cli::kExitOk;
using auvnav::cli::kExitUsage;
constexpr int kExitBadRawlog = auvnav::cli::kExitBadInput;

// Depth from absolute pressure with a fixed sea-water model; good enough for a
// summary (the navigator uses its configured density and atmosphere).
constexpr double kAtmosphere_pa = 101325.0;
constexpr double kSeawaterDensity_kgpm3 = 1025.0;
constexpr double kGravity_mps2 = 9.80665;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double depthFromPressure_m(double pressure_pa)
{
	return (pressure_pa - kAtmosphere_pa) / (kSeawaterDensity_kgpm3 * kGravity_mps2);
}

// ------------------------------------------------------------------ summary

struct SensorSummary
{
	std::string label;
	std::string class_name;
	std::size_t count = 0;
	mrpt::Clock::time_point earliest{}, latest{}, previous{};
	std::size_t backwards = 0;   //!< timestamp earlier than this sensor's previous one
	std::size_t duplicates = 0;  //!< timestamp equal to this sensor's previous one

	// Per-class facts; only those of `class_name` are ever updated.
	std::size_t dvl_bottom_locked = 0;
	std::size_t adcp_valid_cells = 0;
	double depth_min_m = std::numeric_limits<double>::infinity();
	double depth_max_m = -std::numeric_limits<double>::infinity();
	std::size_t gps_fixes = 0;
	std::size_t thrusters_min = std::numeric_limits<std::size_t>::max();
	std::size_t thrusters_max = 0;
};

struct LogSummary
{
	std::string path;
	std::vector<SensorSummary> sensors;  // in order of first appearance
	std::map<std::pair<std::string, std::string>, std::size_t> sensor_index;
	std::size_t observations = 0;
	std::size_t actions_skipped = 0;
	std::optional<mrpt::Clock::time_point> t0;  // first observation in file order
	std::string error;                          // empty when the whole file was read
};

SensorSummary& sensorFor(LogSummary& log, const std::string& label, const std::string& cls)
{
	const auto key = std::make_pair(label, cls);
	const auto it = log.sensor_index.find(key);
	if (it != log.sensor_index.end()) return log.sensors[it->second];
	log.sensor_index.emplace(key, log.sensors.size());
	log.sensors.push_back(SensorSummary{});
	log.sensors.back().label = label;
	log.sensors.back().class_name = cls;
	return log.sensors.back();
}

void updateTiming(SensorSummary& s, const mrpt::Clock::time_point& t)
{
	if (s.count == 0)
	{
		s.earliest = s.latest = t;
	}
	else
	{
		if (t < s.previous) ++s.backwards;
		if (t == s.previous) ++s.duplicates;
		s.earliest = std::min(s.earliest, t);
		s.latest = std::max(s.latest, t);
	}
	s.previous = t;
	++s.count;
}

bool isGpsFix(const mrpt::obs::CObservationGPS& gps)
{
	using namespace mrpt::obs::gnss;
	if (gps.hasMsgClass<Message_NMEA_GGA>() && gps.getMsgByClass<Message_NMEA_GGA>().fields.fix_quality > 0)
		return true;
	return gps.hasMsgClass<Message_NMEA_RMC>() &&
	       gps.getMsgByClass<Message_NMEA_RMC>().fields.validity_char == 'A';
}

void updateTypeFacts(SensorSummary& s, const mrpt::obs::CObservation& obs)
{
	if (const auto* dvl = dynamic_cast<const auvnav::obs::CObservationDVL*>(&obs))
	{
		if (dvl->bottom_lock) ++s.dvl_bottom_locked;
	}
	else if (const auto* adcp = dynamic_cast<const auvnav::obs::CObservationADCP*>(&obs))
	{
		for (const auto& c : adcp->cells) s.adcp_valid_cells += c.valid ? 1 : 0;
	}
	else if (const auto* p = dynamic_cast<const auvnav::obs::CObservationPressure*>(&obs))
	{
		const double depth_m = depthFromPressure_m(p->pressure_pa);
		s.depth_min_m = std::min(s.depth_min_m, depth_m);
		s.depth_max_m = std::max(s.depth_max_m, depth_m);
	}
	else if (const auto* gps = dynamic_cast<const mrpt::obs::CObservationGPS*>(&obs))
	{
		if (isGpsFix(*gps)) ++s.gps_fixes;
	}
	else if (const auto* thr = dynamic_cast<const auvnav::obs::CObservationThrusters*>(&obs))
	{
		s.thrusters_min = std::min(s.thrusters_min, thr->thrusterCount());
		s.thrusters_max = std::max(s.thrusters_max, thr->thrusterCount());
	}
}

void addObservation(LogSummary& log, const mrpt::obs::CObservation& obs)
{
	if (!log.t0) log.t0 = obs.timestamp;
	auto& s = sensorFor(log, obs.sensorLabel, obs.GetRuntimeClass()->className);
	updateTiming(s, obs.timestamp);
	updateTypeFacts(s, obs);
	++log.observations;
}

// Reads the whole file; a RawlogError ends the reading and is recorded in
// `log.error` so that what was read so far can still be reported.
void summarise(LogSummary& log)
{
	try
	{
		auvnav::io::RawlogReader reader(log.path);
		while (const auto obs = reader.next())
		{
			addObservation(log, *obs);
			log.actions_skipped = reader.actionsSkipped();
		}
		log.actions_skipped = reader.actionsSkipped();
	}
	catch (const auvnav::io::RawlogError& e)
	{
		log.error = auvnav::oneLineReason(e.what());
	}
}

// ------------------------------------------------------------ derived values

double secondsSinceStart(const LogSummary& log, const mrpt::Clock::time_point& t)
{
	return log.t0 ? mrpt::system::timeDifference(*log.t0, t) : kNaN;
}

double span_s(const SensorSummary& s)
{
	return mrpt::system::timeDifference(s.earliest, s.latest);
}

// Mean rate over the sensor's own time span; undefined for fewer than two
// observations or a zero span.
double meanRate_hz(const SensorSummary& s)
{
	const double dt_s = span_s(s);
	return (s.count >= 2 && dt_s > 0) ? static_cast<double>(s.count - 1) / dt_s : kNaN;
}

double bottomLockFraction(const SensorSummary& s)
{
	return s.count ? static_cast<double>(s.dvl_bottom_locked) / static_cast<double>(s.count) : kNaN;
}

double meanValidCells(const SensorSummary& s)
{
	return s.count ? static_cast<double>(s.adcp_valid_cells) / static_cast<double>(s.count) : kNaN;
}

bool isClass(const SensorSummary& s, const char* cls)
{
	return s.class_name == cls;
}

std::string fixed(double v, int decimals)
{
	if (std::isnan(v)) return "-";
	std::ostringstream o;
	o << std::fixed << std::setprecision(decimals) << v;
	return o.str();
}

std::string thrusterCountText(const SensorSummary& s)
{
	if (s.thrusters_min == s.thrusters_max) return std::to_string(s.thrusters_max);
	return std::to_string(s.thrusters_min) + ".." + std::to_string(s.thrusters_max);
}

// The per-class fact column of the table.
std::string facts(const SensorSummary& s)
{
	if (isClass(s, "auvnav::obs::CObservationDVL"))
		return "bottom lock " + fixed(100.0 * bottomLockFraction(s), 1) + "%";
	if (isClass(s, "auvnav::obs::CObservationADCP"))
		return "mean valid cells/profile " + fixed(meanValidCells(s), 2);
	if (isClass(s, "auvnav::obs::CObservationPressure"))
		return "depth " + fixed(s.depth_min_m, 2) + " .. " + fixed(s.depth_max_m, 2) + " m";
	if (isClass(s, "mrpt::obs::CObservationGPS")) return "fixes " + std::to_string(s.gps_fixes);
	if (isClass(s, "auvnav::obs::CObservationThrusters")) return "thrusters " + thrusterCountText(s);
	return "";
}

// ------------------------------------------------------------------- table

using Row = std::vector<std::string>;

Row tableRow(const LogSummary& log, const SensorSummary& s)
{
	return {s.label.empty() ? "(no label)" : s.label,
	        s.class_name,
	        std::to_string(s.count),
	        fixed(secondsSinceStart(log, s.earliest), 3),
	        fixed(secondsSinceStart(log, s.latest), 3),
	        fixed(meanRate_hz(s), 2),
	        std::to_string(s.backwards),
	        std::to_string(s.duplicates),
	        facts(s)};
}

void printTable(const std::vector<Row>& rows, std::ostream& out)
{
	std::vector<std::size_t> width;
	for (const auto& r : rows)
	{
		width.resize(std::max(width.size(), r.size()), 0);
		for (std::size_t c = 0; c < r.size(); ++c) width[c] = std::max(width[c], r[c].size());
	}
	for (const auto& r : rows)
	{
		std::string line;
		for (std::size_t c = 0; c < r.size(); ++c)
		{
			line += r[c];
			if (c + 1 < r.size()) line += std::string(width[c] - r[c].size() + 2, ' ');
		}
		out << line << "\n";
	}
}

void printSummary(const LogSummary& log, std::ostream& out)
{
	out << "File: " << log.path << "\n";
	out << "Observations: " << log.observations << " (actions skipped: " << log.actions_skipped << ")\n";
	if (!log.error.empty()) out << "INCOMPLETE: reading stopped at an error (see stderr)\n";
	if (log.sensors.empty()) return;
	out << "Times are seconds from the first observation; BACK/DUP count timestamps going\n"
	    << "backwards / repeated relative to the same sensor's previous observation.\n\n";
	std::vector<Row> rows{
	    {"LABEL", "CLASS", "COUNT", "FIRST[s]", "LAST[s]", "RATE[Hz]", "BACK", "DUP", "DETAILS"}};
	for (const auto& s : log.sensors) rows.push_back(tableRow(log, s));
	printTable(rows, out);
}

// -------------------------------------------------------------------- JSON

// Per-class facts as extra members of the sensor's object.
void addFacts(const SensorSummary& s, auvnav::io::Json& j)
{
	if (isClass(s, "auvnav::obs::CObservationDVL")) j["bottom_lock_fraction"] = bottomLockFraction(s);
	if (isClass(s, "auvnav::obs::CObservationADCP")) j["mean_valid_cells_per_profile"] = meanValidCells(s);
	if (isClass(s, "auvnav::obs::CObservationPressure"))
	{
		j["depth_min_m"] = s.depth_min_m;
		j["depth_max_m"] = s.depth_max_m;
	}
	if (isClass(s, "mrpt::obs::CObservationGPS")) j["gps_fixes"] = s.gps_fixes;
	if (isClass(s, "auvnav::obs::CObservationThrusters"))
	{
		j["thruster_count_min"] = s.thrusters_min;
		j["thruster_count_max"] = s.thrusters_max;
	}
}

auvnav::io::Json sensorJson(const LogSummary& log, const SensorSummary& s)
{
	auvnav::io::Json j;
	j["label"] = s.label;
	j["class"] = s.class_name;
	j["count"] = s.count;
	j["first_s"] = secondsSinceStart(log, s.earliest);
	j["last_s"] = secondsSinceStart(log, s.latest);
	j["mean_rate_hz"] = meanRate_hz(s);
	j["timestamps_backwards"] = s.backwards;
	j["timestamps_duplicated"] = s.duplicates;
	addFacts(s, j);
	return j;
}

void writeJson(const LogSummary& log, std::ostream& out)
{
	auvnav::io::Json j;
	j["file"] = log.path;
	j["complete"] = log.error.empty();
	j["error"] = log.error.empty() ? auvnav::io::Json() : auvnav::io::Json(log.error);
	j["observations"] = log.observations;
	j["actions_skipped"] = log.actions_skipped;
	j["sensors"] = auvnav::io::Json::array();
	for (const auto& s : log.sensors) j["sensors"].push_back(sensorJson(log, s));
	out << auvnav::io::jsonText(j);
}

// Returns false (after telling stderr why) if the file cannot be written.
bool writeJsonFile(const LogSummary& log, const std::string& path)
{
	if (path == "-")
	{
		writeJson(log, std::cout);
		return true;
	}
	std::ofstream f(path);
	if (f) writeJson(log, f);
	if (!f)
	{
		std::cerr << "auvnav-info: error: cannot write JSON summary to '" << path << "'\n";
		return false;
	}
	return true;
}

// ------------------------------------------------------------ command line

struct Options
{
	std::string rawlog;
	std::string json;  // empty: no JSON
};

// `exit_code`: set when the program should stop (after --help, or a bad command line).
std::optional<Options> parseCommandLine(int argc, char** argv, int& exit_code)
{
	TCLAP::CmdLine cmd(
	    "Summarises a rawlog per sensor label: class, count, first/last time, mean rate, "
	    "timestamps going backwards or repeated, and per-sensor facts (DVL bottom-lock "
	    "fraction, ADCP valid cells, depth range from pressure, GPS fixes, thruster count). "
	    "The file is streamed, so any size works. Exit code: 0 ok, 1 usage error, "
	    "2 unreadable or corrupt rawlog (what was read before the error is still reported).",
	    ' ', AUVNAV_VERSION);
	TCLAP::UnlabeledValueArg<std::string> rawlog("RAWLOG", "Rawlog to summarise (gzip-compressed or plain).",
	                                             true, "", "RAWLOG", cmd);
	TCLAP::ValueArg<std::string> json(
	    "", "json", "Also write the summary as JSON to FILE; '-' writes only the JSON, to stdout.", false, "",
	    "FILE", cmd);
	const auvnav::cli::ObsLibOption obs_libs(cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-info"))
	{
		exit_code = *code;
		return std::nullopt;
	}
	// Before the rawlog is opened: its classes must be registered to be read.
	if (const auto code = obs_libs.load("auvnav-info"))
	{
		exit_code = *code;
		return std::nullopt;
	}
	return Options{rawlog.getValue(), json.getValue()};
}
}  // namespace

int main(int argc, char** argv)
{
	int exit_code = kExitOk;
	const auto options = parseCommandLine(argc, argv, exit_code);
	if (!options) return exit_code;

	LogSummary log;
	log.path = options->rawlog;
	summarise(log);

	// With the JSON on stdout, the table would make stdout unparseable.
	if (options->json != "-") printSummary(log, std::cout);
	const bool json_ok = options->json.empty() || writeJsonFile(log, options->json);
	std::cout.flush();  // the error line must come after the summary

	if (!log.error.empty()) return auvnav::cli::fail("auvnav-info", log.error, kExitBadRawlog);
	// An empty file reads as a clean empty log (rawlog.h), but it is no dataset.
	if (log.observations == 0 && log.actions_skipped == 0)
		return auvnav::cli::fail("auvnav-info", log.path + ": no observations (an empty rawlog)",
		                         kExitBadRawlog);
	return json_ok ? kExitOk : kExitUsage;
}
