// auvnav-bench: speed of the full navigator (Google Benchmark).
//
// Simulates a mission once (default config/missions/square_5x50m.yaml: ~70 min
// of data, every sensor), then times the navigator on it with the default
// configuration (config/flatfish.yaml, all configured sensor plugins):
//  - BM_NavigatorFromMemory: observations preloaded, the filter alone;
//  - BM_NavigatorFromRawlog: streaming the rawlog through libnav's run loop,
//    as auvnav-run does.
// The counter `real_time_factor` is seconds of data per second of wall time
// on one core. Environment: AUVNAV_BENCH_MISSION, AUVNAV_BENCH_CONFIG override
// the files; run from the repository root or set AUVNAV_SOURCE_DIR.
#include <auvnav/io/rawlog.h>
#include <auvnav/navigator.h>
#include <auvnav/rawlog_run.h>
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <vector>

#include "mission.h"

namespace fs = std::filesystem;

namespace
{
std::string sourceDir()
{
	const char* s = std::getenv("AUVNAV_SOURCE_DIR");
	return s ? s : AUVNAV_SOURCE_DIR_DEFAULT;
}
std::string envOr(const char* name, const std::string& def)
{
	const char* s = std::getenv(name);
	return s ? s : def;
}

struct Dataset
{
	fs::path dir, rawlog;
	std::vector<mrpt::obs::CObservation::Ptr> observations;
	double duration_s = 0;
	Dataset()
	{
		const auto spec = auvnav::sim::MissionSpec::load(
		    envOr("AUVNAV_BENCH_MISSION", sourceDir() + "/config/missions/square_5x50m.yaml"));
		dir = fs::temp_directory_path() / ("auvnav_bench_" + std::to_string(::getpid()));
		const auto summary = auvnav::sim::runMission(spec, 1, dir.string());
		rawlog = summary.rawlog_path;
		duration_s = summary.duration_s;
		auvnav::io::RawlogReader r(rawlog.string());
		while (auto o = r.next()) observations.push_back(o);
	}
	~Dataset() { fs::remove_all(dir); }
};

Dataset& dataset()
{
	static Dataset d;
	return d;
}

auvnav::config::Node navigatorConfig()
{
	return auvnav::config::Node::load(envOr("AUVNAV_BENCH_CONFIG", sourceDir() + "/config/flatfish.yaml"));
}

void BM_NavigatorFromMemory(benchmark::State& state)
{
	auto& d = dataset();
	const auto cfg = navigatorConfig();
	auvnav::PluginHost host;  // one per benchmark: each plugin is loaded once (milliseconds, first iteration)
	double data_s = 0;
	for (auto _ : state)
	{
		auvnav::Navigator nav(cfg, host);
		for (const auto& o : d.observations) nav.process(*o);
		data_s += nav.time() - nav.startTime();
		benchmark::DoNotOptimize(nav.filter().state());
	}
	state.counters["data_s_per_iteration"] = data_s / state.iterations();
	state.counters["real_time_factor"] = benchmark::Counter(data_s, benchmark::Counter::kIsRate);
}

void BM_NavigatorFromRawlog(benchmark::State& state)
{
	auto& d = dataset();
	const auto cfg = navigatorConfig();
	auvnav::PluginHost host;
	double data_s = 0;
	for (auto _ : state)
	{
		auvnav::Navigator nav(cfg, host);
		const auto run = auvnav::runRawlog(nav, d.rawlog.string());
		run.rethrow();
		data_s += run.data_s;
	}
	state.counters["real_time_factor"] = benchmark::Counter(data_s, benchmark::Counter::kIsRate);
}
}  // namespace

BENCHMARK(BM_NavigatorFromMemory)->Unit(benchmark::kSecond)->Iterations(2)->UseRealTime();
BENCHMARK(BM_NavigatorFromRawlog)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK_MAIN();
