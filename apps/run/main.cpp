// auvnav-run: the navigator on an MRPT rawlog. See README.md.
#include <auvnav/cli.h>
#include <auvnav/navigator.h>
#include <auvnav/obs/register.h>
#include <auvnav/rawlog_run.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <set>

#include "live_view.h"
#include "run_outputs.h"
#include "smooth_outputs.h"

#if AUVNAV_HAVE_CALLGRIND_H
#include <valgrind/callgrind.h>
#endif

namespace
{
/** bench/instructions.sh counts one sensor's instructions: run under
 *  `valgrind --tool=callgrind --collect-atstart=no` with
 *  AUVNAV_CALLGRIND_SENSOR=<label>, collection is on only while that sensor's
 *  observations are prepared and applied. */
void profileSensorForBench(auvnav::Navigator& nav)
{
#if AUVNAV_HAVE_CALLGRIND_H
	const char* sensor = std::getenv("AUVNAV_CALLGRIND_SENSOR");
	if (!sensor) return;
	nav.on_sensor_work = [label = std::string(sensor)](const std::string& l, bool)
	{
		if (l == label) CALLGRIND_TOGGLE_COLLECT;
	};
#else
	(void)nav;
#endif
}
}  // namespace

namespace
{
volatile std::sig_atomic_t g_stop = 0;  // the signal that asked the run to stop, or 0
void onSignal(int signal)
{
	g_stop = signal;
}

// Output files go to the kernel at least this often (wall time): a killed run
// loses at most this much of its outputs, in whole lines (run_outputs.h).
constexpr double kFlushEvery_s = 1.0;
}  // namespace

namespace cli = auvnav::cli;

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Runs the auvnav navigator (manifold UKF with sensor plugins) on an MRPT rawlog and writes "
	    "DIR/trajectory.tum, DIR/states.csv and DIR/summary.json, incrementally.",
	    ' ', "0.1.0");
	TCLAP::UnlabeledValueArg<std::string> rawlog("rawlog", "Input rawlog", true, "", "RAWLOG", cmd);
	TCLAP::ValueArg<std::string> config("c", "config", "Navigator YAML (e.g. config/flatfish.yaml)", true, "",
	                                    "FILE", cmd);
	TCLAP::ValueArg<std::string> out("o", "out", "Output directory (created)", true, "", "DIR", cmd);
	TCLAP::MultiArg<std::string> set(
	    "s", "set", "Override a config value, e.g. filter.initial.heading_deg=25", false, "KEY=VALUE", cmd);
	TCLAP::MultiArg<std::string> deny(
	    "d", "deny",
	    "Data denial: ignore sensor LABEL from FROM to TO seconds after the first "
	    "observation, e.g. GPS:1200:1e9 (repeatable)",
	    false, "LABEL:FROM:TO", cmd);
	TCLAP::SwitchArg quiet("q", "quiet", "No progress display", cmd);
	TCLAP::SwitchArg view("", "view", "Live MRPT 3D window of the run (needs a display; xvfb-run works)",
	                      cmd);
	TCLAP::ValueArg<double> view_hold("", "view-hold",
	                                  "With --view: keep the window S seconds after the run (0: until a key)",
	                                  false, 0, "S", cmd);
	TCLAP::SwitchArg smooth(
	    "", "smooth",
	    "Also smooth the run (unscented RTS, backward over the whole run): DIR/smoothed_trajectory.tum, "
	    "DIR/smoothed_states.csv, DIR/smoother.json; the forward pass records DIR/smoother/stretches.bin "
	    "(smoother.keep_every_s)",
	    cmd);
	const auvnav::cli::ObsLibOption obs_libs(cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-run")) return *code;
	auvnav::obs::registerAllClasses();
	std::signal(SIGINT, onSignal);
	std::signal(SIGTERM, onSignal);
	const auto t0 = std::chrono::steady_clock::now();
	auto wall = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

	std::unique_ptr<auvnav::PluginHost> host;  // declared before nav: outlives the models
	std::unique_ptr<auvnav::Navigator> nav;
	std::unique_ptr<auvnav::run::RunOutputs> outputs;
	bool write_updates = true;
	double summary_every_s = 5.0;  // outputs.summary_every_s (README: summary.json)
	try
	{
		auto cfg = auvnav::config::Node::load(config.getValue());
		for (const auto& kv : set.getValue())
		{
			const auto eq = kv.find('=');
			if (eq == std::string::npos || eq == 0)
				throw auvnav::config::ConfigError("--set '" + kv + "': expected KEY=VALUE");
			cfg.set(kv.substr(0, eq), kv.substr(eq + 1));
		}
		std::vector<std::string> paths;
		if (cfg.has("plugin_paths"))
			for (const auto& p : cfg.strings("plugin_paths"))
				paths.push_back((std::filesystem::path(config.getValue()).parent_path() / p).string());
		host = std::make_unique<auvnav::PluginHost>(paths);
		// Observation libraries (--obs-lib, the sensors' obs_libs) before the
		// plugins, which may link them, and before the rawlog is opened.
		if (const auto code =
		        obs_libs.load("auvnav-run", auvnav::declaredObservationLibraries(cfg), host->searchPaths()))
			return *code;
		nav = std::make_unique<auvnav::Navigator>(cfg, *host);
		for (const auto& d : deny.getValue())
		{
			try
			{
				nav->addDenial(auvnav::parseDenial(d));
			}
			catch (const std::exception& e)
			{
				throw auvnav::config::ConfigError("--deny '" + d + "': " + e.what());
			}
		}
		const double rate = cfg.has("outputs") ? cfg.child("outputs").positive("rate_hz", 10.0) : 10.0;
		write_updates = cfg.has("outputs") ? cfg.child("outputs").boolean("updates_csv", true) : true;
		if (cfg.has("outputs"))
			summary_every_s = cfg.child("outputs").inRange("summary_every_s", 0.1, 3600, summary_every_s);
		cfg.checkAllKeysUsed();  // the navigator checked its sections; this adds plugin_paths and outputs
		outputs = std::make_unique<auvnav::run::RunOutputs>(out.getValue(), rate, nav->stateNames(),
		                                                    nav->storedStateNames(), write_updates);
		// An older run's smoothing in this folder would be read as this one's.
		for (const char* stale :
		     {"smoothed_trajectory.tum", "smoothed_states.csv", "smoother.json", "smoother"})
			std::filesystem::remove_all(std::filesystem::path(out.getValue()) / stale);
		if (smooth.getValue())
		{
			const std::string file = auvnav::run::stretchFileOf(out.getValue());
			std::filesystem::create_directories(std::filesystem::path(file).parent_path());
			nav->enableSmoothing(file);
		}
	}
	catch (const std::exception& e)
	{
		return cli::fail("auvnav-run", e.what());
	}
	// From here on summary.json exists: "completed": false until the last rewrite.
	try
	{
		outputs->writeSummary(*nav, wall(), auvnav::run::RunOutputs::Phase::Running, rawlog.getValue(), "");
	}
	catch (const std::exception& e)
	{
		return cli::fail("auvnav-run", e.what());
	}

	const bool progress = !quiet.getValue() && isatty(STDERR_FILENO);
	nav->on_predict = [&](const auvnav::Navigator& n) { outputs->onState(n); };
	profileSensorForBench(*nav);
	// Position fixes of any sensor (GPS, USBL, …), for position_fixes.csv and the view.
	std::set<std::string> fix_labels;
	for (const auto& label : nav->positionFixLabels()) fix_labels.insert(label);
	std::unique_ptr<auvnav::run::LiveView> live;
	if (view.getValue())
	{
		try
		{
			live = auvnav::run::openLiveView("auvnav-run: " + rawlog.getValue());
		}
		catch (const std::exception& e)
		{
			return cli::fail("auvnav-run", e.what());
		}
		nav->on_predict = [&](const auvnav::Navigator& n)
		{
			outputs->onState(n);
			live->onState(n);
		};
	}
	nav->health().on_change = [&](double t, auvnav::NavStatus st, const std::string& why)
	{
		outputs->onHealthChange(t, st, why);
		if (progress) std::fprintf(stderr, "\r%60s\r", "");
		if (!quiet.getValue())
			std::fprintf(stderr, "auvnav-run: %.1f s: %s%s%s\n", t, auvnav::navStatusName(st),
			             why.empty() ? "" : ": ", why.c_str());
	};
	nav->on_event = [&](double t, const std::string& label, const std::string& what)
	{
		outputs->onEvent(t, label, what);
		if (progress) std::fprintf(stderr, "\r%60s\r", "");
		if (!quiet.getValue())
			std::fprintf(stderr, "auvnav-run: %.1f s: %s: %s\n", t, label.c_str(), what.c_str());
	};
	nav->on_update =
	    [&](const std::string& label, double t, const auvnav::Measurement& m, const auvnav::UpdateResult& r)
	{
		outputs->onUpdate(label, t, r);
		// Filter time when made (a re-filtered delayed fix: its arrival) and measurement time.
		outputs->onAnyUpdate(label, nav->latestTime(), t, r);
		if (!fix_labels.count(label)) return;
		outputs->onPositionFix(label, t, m, r);
		if (live) live->onFix(label, t, m, r);
	};
	double next_progress = 0.5, next_flush = kFlushEvery_s, next_summary = summary_every_s;
	auvnav::RunCallbacks loop;
	loop.stop = [] { return g_stop != 0; };
	loop.on_observation = [&](const auvnav::Navigator& n)
	{
		const double now = wall();
		if (now >= next_flush)
		{
			outputs->flush();
			next_flush = now + kFlushEvery_s;
		}
		if (now >= next_summary)
		{
			outputs->flush();  // the summary never runs ahead of the files
			outputs->writeSummary(n, now, auvnav::run::RunOutputs::Phase::Running, rawlog.getValue(), "");
			next_summary = now + summary_every_s;
		}
		if (!progress || now <= next_progress) return;
		next_progress = wall() + 0.5;
		const double data_s = n.time() - n.startTime();
		std::fprintf(stderr, "\r  %8.1f s of data processed, %6.0fx real time   ", data_s, data_s / wall());
	};
	// A rawlog error (also: an empty or IMU-less log, a clock jump) ends the
	// run but not the outputs: reported below, exit 2.
	const std::string error = auvnav::oneLineReason(auvnav::runRawlog(*nav, rawlog.getValue(), loop).error);
	if (progress) std::fprintf(stderr, "\r%60s\r", "");
	try
	{
		outputs->flush();
		outputs->writeSummary(
		    *nav, wall(),
		    g_stop ? auvnav::run::RunOutputs::Phase::Interrupted : auvnav::run::RunOutputs::Phase::Ended,
		    rawlog.getValue(), error);
	}
	catch (const std::exception& e)  // a full disk, a folder removed under the run
	{
		return cli::fail("auvnav-run", e.what());
	}

	const double data_s = nav->time() - nav->startTime();
	const double forward_wall_s = wall();
	std::printf("auvnav-run: %.1f s of data in %.2f s (%.0fx real time)%s\n", data_s, forward_wall_s,
	            data_s / forward_wall_s, g_stop ? " [interrupted]" : "");
	std::string smooth_error = nav->smootherError();
	if (smooth.getValue() && smooth_error.empty())
	{
		if (g_stop)
			std::printf("  smoothing: not run (interrupted); auvnav-smooth %s smooths what was recorded\n",
			            out.getValue().c_str());
		else if (!nav->initialized())
			std::printf("  smoothing: nothing to smooth (the filter never started)\n");
		else
			try
			{
				const auto r = auvnav::run::smoothRun(out.getValue());
				std::printf(
				    "  smoothing: %zu estimates (%zu smoothed, %zu segment ends, %zu kept filtered) in %.2f "
				    "s; "
				    "stretch file %.1f MB\n",
				    r.rows, r.smoothed, r.segment_ends, r.kept, r.wall_s, r.stretch_bytes / 1e6);
			}
			catch (const std::exception& e)
			{
				smooth_error = e.what();
			}
	}
	std::printf("  %-10s %-14s %9s %9s %8s %8s %8s %8s  %s\n", "sensor", "plugin", "accepted", "rejected",
	            "invalid", "skipped", "denied", "recov.", "NIS/dim");
	for (const auto& s : nav->stats())
		std::printf("  %-10s %-14s %9zu %9zu %8zu %8zu %8zu %8zu  %.2f\n", s.label.c_str(), s.plugin.c_str(),
		            s.accepted, s.rejected, s.invalid, s.skipped, s.denied, s.recovered,
		            s.nis_dim_sum > 0 ? s.nis_sum / s.nis_dim_sum : NAN);
	if (nav->initialized())
	{
		const auto& P = nav->filter().covariance();
		const auto p = nav->bodyPosition_n();
		std::printf(
		    "  final position N %.2f E %.2f D %.2f m (1 sigma %.2f / %.2f / %.2f m), heading sigma %.3f "
		    "deg\n",
		    p.x(), p.y(), p.z(), std::sqrt(P(16, 16)), std::sqrt(P(17, 17)), std::sqrt(P(18, 18)),
		    std::sqrt(P(2, 2)) * 180 / M_PI);
	}
	std::printf("  outputs in %s: trajectory.tum, states.csv, position_fixes.csv, summary.json\n",
	            out.getValue().c_str());
	std::fflush(stdout);
	if (live && !g_stop)
	{
		std::printf("  3D view: %zu states shown\n", outputs->rows());
		live->hold(view_hold.getValue());
	}
	const auto& health = nav->health();
	std::printf("  status: %s%s%s\n", auvnav::navStatusName(health.status()),
	            health.reason().empty() ? "" : " (",
	            health.reason().empty() ? "" : (health.reason() + ")").c_str());
	std::fflush(stdout);
	if (!error.empty()) return cli::fail("auvnav-run", error);
	if (!smooth_error.empty()) return cli::fail("auvnav-run", "smoothing: " + smooth_error);
	// Exit codes (cli.h, README): a signal first (the outputs are partial
	// whatever the status), then the status: 0 ok or degraded, 3 never
	// initialised, 4 diverged.
	if (g_stop)
	{
		std::fprintf(stderr, "auvnav-run: interrupted by signal %d (summary.json: completed false)\n",
		             int(g_stop));
		return cli::kExitSignalBase + g_stop;
	}
	switch (health.status())
	{
		case auvnav::NavStatus::NotInitialized:
			std::fprintf(stderr, "auvnav-run: %s\n", health.reason().c_str());
			return cli::kExitNotInitialized;
		case auvnav::NavStatus::Diverged:
			std::fprintf(stderr, "auvnav-run: diverged: %s\n", health.reason().c_str());
			return cli::kExitDiverged;
		default:
			return cli::kExitOk;
	}
}
