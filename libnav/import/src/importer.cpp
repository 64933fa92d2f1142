// runImport and validateSpec (importer.h): every sensor's records read in
// time order, converted, checked for stamp defects, merged through the
// reorder buffer and written to the rawlog. The spec and its sensors:
// import_spec.h; the report's formats: import_report.cpp.
#include <auvnav/config.h>
#include <auvnav/import/importer.h>
#include <auvnav/io/rawlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <queue>

#include "converters.h"
#include "import_spec.h"

namespace auvnav::import
{
namespace
{
using detail::checkConverter;
using detail::kNoTime;
using detail::openSensor;
using detail::parseSpec;
using detail::SensorRun;
using detail::Spec;
using detail::stampOf;

constexpr std::size_t kMaxNotes = 5;
constexpr std::size_t kMaxPending = 2000000;  // ~1.5 GB at worst; 5.5 h of a 100 Hz IMU
constexpr std::size_t kMaxReasons = 20;       // distinct rejection reasons kept per sensor

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
				rep.source = run.source_pattern + " (optional, " + run.absent_why + ")";
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

	// Written under a temporary name and renamed once complete: a killed or
	// failed import never leaves a partial rawlog that passes for the log.
	const std::string partial = opt.out_rawlog + ".partial";
	io::RawlogWriter writer(partial);
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
		writer.close();
		std::error_code ec;
		std::filesystem::rename(partial, opt.out_rawlog, ec);
		if (ec) throw ImportError(opt.out_rawlog + ": cannot rename " + partial + " to it: " + ec.message());
		report.output_created = true;
	}
	catch (const ImportError& e)
	{
		report.error = e.what();
		std::remove(partial.c_str());
		throw;
	}
	catch (const std::exception& e)
	{
		report.error = e.what();
		std::remove(partial.c_str());
		throw ImportError(e.what());
	}
	for (auto& run : spec.sensors) finishSteps(run, report.sensors[run.report_index], spec.gap_factor);
	report.completed = true;
}

}  // namespace auvnav::import
