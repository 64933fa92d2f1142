// auvnav-experiment: reproduces the paper's data-denial table on simulated
// missions (config/experiments/denial_table.yaml) and compares the drift
// during DVL dropouts with and without model aiding (dvl_dropout.yaml).
//
// A run is one seed: the mission is simulated once and every configuration
// runs the navigator on it (the configurations share the simulation, which
// costs about as much as one navigator run). Each run writes its numbers at
// full precision to DIR/runs/seed_N.result; the tables are always written
// from those files, whether the runs were done in this process (--jobs 1),
// by worker processes (--jobs N) or by the commands of --emit-jobs on other
// machines (--collect): the same files give the same tables, byte for byte.
#include <auvnav/cli.h>
#include <auvnav/config.h>
#include <auvnav/io/trajectory.h>
#include <auvnav/navigator.h>
#include <auvnav/obs/register.h>
#include <auvnav/obs_libraries.h>
#include <auvnav/rawlog_run.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>
#include <thread>

#include "mission.h"

extern char** environ;

namespace fs = std::filesystem;
using namespace auvnav;

namespace
{
const char* const kProgram = "auvnav-experiment";

struct Configuration
{
	std::string name;
	std::vector<std::string> deny;
	double paper_sigma2 = NAN, paper_error = NAN;
};

/** Everything an experiment file says, loaded and checked once. */
struct Experiment
{
	std::string file;  //!< absolute path
	std::string kind;  //!< denial_table or dvl_dropout
	sim::MissionSpec spec;
	config::Node nav_cfg;
	std::vector<unsigned> seeds;
	std::vector<Configuration> configs;
	double init_s = NAN, denial_s = NAN;  // denial_table
	//! denial_table `smooth: true`: each run also smoothed (auvnav-run
	//! --smooth's smoother); the error at mid-denial, filtered and smoothed.
	bool smooth = false;
	double from_s = NAN, min_gap_s = NAN;  // dvl_dropout
	std::string dvl_label;
};

/** Loads `file` keeping its first `max_seeds` seeds (0: all). */
Experiment loadExperiment(const std::string& file, int max_seeds)
{
	const auto ex = config::Node::load(file);
	Experiment e;
	e.file = fs::absolute(file).lexically_normal().string();
	e.kind = ex.string("kind", "denial_table");
	if (e.kind != "denial_table" && e.kind != "dvl_dropout")
		throw std::runtime_error(file + ": kind '" + e.kind +
		                         "' is neither 'denial_table' nor 'dvl_dropout'");
	e.spec = sim::MissionSpec::load(ex.filePath("mission"));
	e.nav_cfg = ex.loadFile("navigator");
	if (e.kind == "denial_table")
	{
		e.init_s = ex.positive("initialization_s");
		e.denial_s = ex.positive("denial_s");
		e.smooth = ex.boolean("smooth", false);
	}
	else
	{
		e.from_s = ex.nonNegative("gps_denied_from_s");
		e.min_gap_s = ex.positive("min_gap_s");
		e.dvl_label = ex.string("dvl_label", "DVL");
	}
	for (double s : ex.numbers("seeds")) e.seeds.push_back(static_cast<unsigned>(s));
	if (max_seeds > 0 && static_cast<std::size_t>(max_seeds) < e.seeds.size())
		e.seeds.resize(static_cast<std::size_t>(max_seeds));
	for (const auto& c : ex.sequence("configurations"))
		if (e.kind == "denial_table")
			e.configs.push_back({c.string("name"), c.strings("deny"),
			                     c.number("paper_uncertainty_2sigma_m", NAN),
			                     c.number("paper_error_m", NAN)});
		else
			e.configs.push_back({c.string("name"), c.strings("deny")});
	ex.checkAllKeysUsed();
	return e;
}

struct Outcome
{
	double error_m = NAN, two_sigma_m = NAN;
	//! smooth: at the first kept tick at or after mid-denial, the filter's
	//! and the smoother's horizontal error and the smoother's 2σ.
	double mid_filtered_m = NAN, mid_smoothed_m = NAN, mid_smoothed_two_sigma_m = NAN;
	bool inside() const { return error_m <= two_sigma_m; }
};

/** The kind line of a result: a smoothed denial table's numbers differ. */
std::string resultKind(const Experiment& e)
{
	return e.kind + (e.smooth ? " smoothed" : "");
}
/** Numbers per configuration in a denial_table result. */
std::size_t denialNumbers(const Experiment& e)
{
	return e.smooth ? 5 : 2;
}

/** Runs the navigator on `rawlog` with the denial and returns the error and
 *  2σ at the end of the denial window: at the first prediction at or after
 *  it, against the truth interpolated there (io::at, as auvnav-eval does). */
Outcome runDenial(const config::Node& nav_cfg, PluginHost& host, const fs::path& rawlog,
                  const io::Trajectory& truth, const Configuration& c, double init_s, double denial_s,
                  const fs::path& stretch_file = {})
{
	Navigator nav(nav_cfg, host);
	DenialWindow w;
	w.labels = c.deny;
	w.from_s = init_s;
	w.to_s = init_s + denial_s;
	nav.addDenial(w);
	if (!stretch_file.empty()) nav.enableSmoothing(stretch_file.string());
	const double t_eval = truth.front().t_unix + init_s + denial_s;
	const double t_mid = truth.front().t_unix + init_s + 0.5 * denial_s;
	Outcome o;
	// The filter's error at each prediction from mid-denial until the
	// smoother's next kept tick is certainly past (a kept tick is an IMU tick).
	std::map<double, double> filtered_after_mid;
	// The stretch file's estimate at a kept tick is the one after the tick's
	// updates: the filter's error is refreshed after each of them too.
	auto noteFiltered = [&](const Navigator& n)
	{
		if (!stretch_file.empty() && n.time() >= t_mid &&
		    n.time() <= t_mid + 2 * nav.smootherKeepEvery_s() + 1)
			filtered_after_mid[n.time()] =
			    (n.bodyPosition_n() - io::at(truth, n.time()).p_n).head<2>().norm();
	};
	if (!stretch_file.empty())
		nav.on_update = [&](const std::string&, double, const Measurement&, const UpdateResult&)
		{ noteFiltered(nav); };
	nav.on_predict = [&](const Navigator& n)
	{
		noteFiltered(n);
		if (!std::isnan(o.error_m) || n.time() < t_eval) return;
		const auto tr = io::at(truth, n.time());
		o.error_m = (n.bodyPosition_n() - tr.p_n).head<2>().norm();
		const auto& P = n.filter().covariance();
		// 2σ horizontal: twice the root of the summed north/east variances.
		o.two_sigma_m = 2 * std::sqrt(P(idx::pos, idx::pos) + P(idx::pos + 1, idx::pos + 1));
	};
	runRawlog(nav, rawlog.string()).rethrow();
	if (stretch_file.empty()) return o;
	if (!nav.smootherError().empty()) throw std::runtime_error(nav.smootherError());
	// The backward pass, newest first: the last kept tick at or after mid-denial is the first one.
	const Eigen::Vector3d lever_b = nav.imuPosition_b();
	double best_t = std::numeric_limits<double>::infinity();
	smoothStretchFile(stretch_file.string(),
	                  [&](double t, const NavState& x, const Covariance& P, SmoothedKind)
	                  {
		                  // Newest first: the earliest kept tick at or after mid-denial is the
		                  // last one seen; at a reset two share a time, the one after it first.
		                  if (t < t_mid || !(t < best_t)) return;
		                  const auto f = filtered_after_mid.find(t);
		                  if (f == filtered_after_mid.end()) return;
		                  const Eigen::Vector3d p_body = x.p_n - x.R_nb * lever_b;
		                  best_t = t;
		                  o.mid_smoothed_m = (p_body - io::at(truth, t).p_n).head<2>().norm();
		                  o.mid_filtered_m = f->second;
		                  o.mid_smoothed_two_sigma_m =
		                      2 * std::sqrt(P(idx::pos, idx::pos) + P(idx::pos + 1, idx::pos + 1));
	                  });
	fs::remove(stretch_file);
	return o;
}
/** Position drift during DVL dropouts of one run: the horizontal error vector
 *  accrued between the last accepted DVL update before a gap and the first
 *  after it, summed over gaps longer than `min_gap_s`. */
struct DropoutDrift
{
	double drift_m = 0, gap_s = 0;
	int gaps = 0;
	double rate() const { return gap_s > 0 ? drift_m / gap_s : NAN; }
};

DropoutDrift runDropouts(const config::Node& nav_cfg, PluginHost& host, const fs::path& rawlog,
                         const io::Trajectory& truth, const std::vector<std::string>& deny, double from_s,
                         const std::string& dvl_label, double min_gap_s)
{
	Navigator nav(nav_cfg, host);
	DenialWindow w;
	w.labels = deny;
	w.from_s = from_s;
	w.to_s = 1e12;
	nav.addDenial(w);
	const double t_from = truth.front().t_unix + from_s;
	DropoutDrift d;
	std::size_t last_accepted = 0;
	double t_last = NAN;
	Eigen::Vector2d e_last = Eigen::Vector2d::Zero();
	nav.on_predict = [&](const Navigator& n)
	{
		std::size_t accepted = 0;
		for (const auto& st : n.stats())
			if (st.label == dvl_label) accepted = st.accepted + st.recovered;
		if (accepted == last_accepted || n.time() < t_from) return;
		last_accepted = accepted;
		const Eigen::Vector2d e = (n.bodyPosition_n() - io::at(truth, n.time()).p_n).head<2>();
		if (!std::isnan(t_last) && n.time() - t_last >= min_gap_s)
		{
			d.drift_m += (e - e_last).norm();
			d.gap_s += n.time() - t_last;
			++d.gaps;
		}
		t_last = n.time();
		e_last = e;
	};
	runRawlog(nav, rawlog.string()).rethrow();
	return d;
}

// ---- One run (a seed) and its result file ----------------------------------

/** The numbers of one configuration in one run: denial_table {error_m,
 *  two_sigma_m}, dvl_dropout {drift_m, gap_s, gaps}. */
using Numbers = std::vector<double>;
/** A run's result: Numbers per configuration, in the file's order. */
using RunResult = std::vector<Numbers>;

fs::path resultPath(const fs::path& out_dir, unsigned seed)
{
	return out_dir / "runs" / ("seed_" + std::to_string(seed) + ".result");
}

/** Writes the run's result; through a temporary file and a rename, so that a
 *  run killed half-way leaves no result that --collect would take. Numbers
 *  are written with 17 significant digits: they read back exactly. */
void writeResult(const Experiment& e, const fs::path& out_dir, unsigned seed, const RunResult& r)
{
	const fs::path path = resultPath(out_dir, seed);
	fs::create_directories(path.parent_path());
	const fs::path tmp = path.string() + ".tmp" + std::to_string(getpid());
	{
		std::ofstream f(tmp);
		f << "auvnav-experiment result 1\nkind " << resultKind(e) << "\nseed " << seed << "\n";
		for (std::size_t i = 0; i < r.size(); ++i)
		{
			f << "configuration " << e.configs[i].name << "\n";
			char num[32];
			for (double v : r[i])
			{
				std::snprintf(num, sizeof num, "%.17g", v);
				f << num << "\n";
			}
		}
		f.flush();
		if (!f) throw std::runtime_error(tmp.string() + ": cannot write");
	}
	fs::rename(tmp, path);
}

/** Reads a result written by writeResult for this experiment; refuses one of
 *  another kind, seed or set of configurations (e.g. a stale directory). */
RunResult readResult(const Experiment& e, const fs::path& out_dir, unsigned seed)
{
	const fs::path path = resultPath(out_dir, seed);
	std::ifstream f(path);
	if (!f)
		throw std::runtime_error(path.string() + ": no result (did the run of seed " + std::to_string(seed) +
		                         " fail?)");
	const auto bad = [&](const std::string& why) { return std::runtime_error(path.string() + ": " + why); };
	std::string line;
	if (!std::getline(f, line) || line != "auvnav-experiment result 1")
		throw bad("not an auvnav-experiment result");
	if (!std::getline(f, line) || line != "kind " + resultKind(e))
		throw bad("not a " + resultKind(e) + " result");
	if (!std::getline(f, line) || line != "seed " + std::to_string(seed))
		throw bad("not the result of seed " + std::to_string(seed));
	const std::size_t per_config = e.kind == "denial_table" ? denialNumbers(e) : 3;
	RunResult r;
	for (const auto& c : e.configs)
	{
		if (!std::getline(f, line) || line != "configuration " + c.name)
			throw bad("configuration '" + c.name + "' missing or out of order (another experiment file?)");
		Numbers n;
		for (std::size_t k = 0; k < per_config; ++k)
		{
			if (!std::getline(f, line)) throw bad("truncated");
			n.push_back(std::strtod(line.c_str(), nullptr));
		}
		r.push_back(n);
	}
	return r;
}

/** Simulates the seed's mission into DIR/seed_N, runs every configuration
 *  on it and writes DIR/runs/seed_N.result. */
void runSeed(const Experiment& e, PluginHost& host, unsigned seed, const fs::path& out_dir, bool keep_rawlogs)
{
	fs::remove(resultPath(out_dir, seed));  // a failed rerun must not leave an older result for --collect
	const fs::path dir = out_dir / ("seed_" + std::to_string(seed));
	const auto summary = sim::runMission(e.spec, seed, dir.string());
	const auto truth = io::readGroundTruth(dir / "ground_truth.csv");
	RunResult r;
	for (const auto& c : e.configs)
	{
		if (e.kind == "denial_table")
		{
			const fs::path stretches =
			    e.smooth ? dir / ("stretches_" + std::to_string(r.size()) + ".bin") : fs::path();
			const Outcome o =
			    runDenial(e.nav_cfg, host, summary.rawlog_path, truth, c, e.init_s, e.denial_s, stretches);
			r.push_back({o.error_m, o.two_sigma_m});
			if (e.smooth)
				r.back().insert(r.back().end(),
				                {o.mid_filtered_m, o.mid_smoothed_m, o.mid_smoothed_two_sigma_m});
			std::printf("seed %2u  %-26s error %6.2f m   2 sigma %6.2f m", seed, c.name.c_str(), o.error_m,
			            o.two_sigma_m);
			if (e.smooth)
				std::printf("   mid-denial %6.2f m filtered, %6.2f m smoothed", o.mid_filtered_m,
				            o.mid_smoothed_m);
			std::printf("\n");
		}
		else
		{
			const DropoutDrift d = runDropouts(e.nav_cfg, host, summary.rawlog_path, truth, c.deny, e.from_s,
			                                   e.dvl_label, e.min_gap_s);
			r.push_back({d.drift_m, d.gap_s, static_cast<double>(d.gaps)});
			std::printf("seed %2u  %-40s %3d gaps, %6.0f s, drift %6.2f m = %.3f m/min\n", seed,
			            c.name.c_str(), d.gaps, d.gap_s, d.drift_m, 60 * d.rate());
		}
		std::fflush(stdout);  // one whole line at a time: parallel workers share stdout
	}
	if (!keep_rawlogs) fs::remove(summary.rawlog_path);  // keep the truth, drop the bulky log
	writeResult(e, out_dir, seed, r);
}

// ---- The tables, from the runs' results -------------------------------------

void writeDenialTables(const Experiment& e, const std::vector<RunResult>& runs, const fs::path& out_dir)
{
	std::ofstream csv(out_dir / "runs.csv");
	csv << "seed,configuration,error_m,two_sigma_m,inside_2sigma\n";
	for (std::size_t s = 0; s < e.seeds.size(); ++s)
		for (std::size_t i = 0; i < e.configs.size(); ++i)
		{
			const Outcome o{runs[s][i][0], runs[s][i][1]};
			csv << e.seeds[s] << ",\"" << e.configs[i].name << "\"," << o.error_m << "," << o.two_sigma_m
			    << "," << (o.inside() ? 1 : 0) << "\n";
		}
	std::ostringstream md;
	md << "| Filter measurements used | 2σ uncertainty after " << e.denial_s << " s (mean) | error after "
	   << e.denial_s
	   << " s: mean | worst | inside 2σ | paper: 2σ | paper: error |\n|---|---|---|---|---|---|---|\n";
	for (std::size_t i = 0; i < e.configs.size(); ++i)
	{
		double e_sum = 0, e_max = 0, s_sum = 0;
		int inside = 0;
		for (const auto& run : runs)
		{
			const Outcome o{run[i][0], run[i][1]};
			e_sum += o.error_m;
			e_max = std::max(e_max, o.error_m);
			s_sum += o.two_sigma_m;
			inside += o.inside();
		}
		const std::size_t n = runs.size();
		char line[512];
		std::snprintf(line, sizeof line, "| %s | %.1f m | %.1f m | %.1f m | %d/%zu | %.1f m | %.1f m |\n",
		              e.configs[i].name.c_str(), s_sum / n, e_sum / n, e_max, inside, n,
		              e.configs[i].paper_sigma2, e.configs[i].paper_error);
		md << line;
	}
	md << "\n"
	   << e.seeds.size() << " seeds of " << e.spec.name << "; denial of the listed sensors from " << e.init_s
	   << " s to " << e.init_s + e.denial_s << " s; 2σ = 2·sqrt(σ_N² + σ_E²).\n";
	if (e.smooth)
	{
		md << "\nSmoothed (`smooth: true`, the smoother of auvnav-run --smooth), at mid-denial ("
		   << e.init_s + 0.5 * e.denial_s << " s, the first kept tick at or after it):\n\n"
		   << "| Filter measurements used | filtered error (mean) | smoothed error (mean) | smoothed / "
		      "filtered (of the "
		      "means) | worst per-seed ratio | smoothed 2σ (mean) | smoothed inside 2σ "
		      "|\n|---|---|---|---|---|---|---|\n";
		for (std::size_t i = 0; i < e.configs.size(); ++i)
		{
			double f = 0, sm = 0, s2 = 0, worst = 0;
			int inside = 0;
			for (const auto& run : runs)
			{
				f += run[i][2], sm += run[i][3], s2 += run[i][4];
				worst = std::max(worst, run[i][3] / run[i][2]);
				inside += run[i][3] <= run[i][4];
			}
			const std::size_t n = runs.size();
			char line[512];
			std::snprintf(line, sizeof line, "| %s | %.2f m | %.2f m | %.2f | %.2f | %.2f m | %d/%zu |\n",
			              e.configs[i].name.c_str(), f / n, sm / n, sm / f, worst, s2 / n, inside, n);
			md << line;
		}
		md << "\nThe navigator's `smoother:` settings apply (across_recoveries: "
		   << (e.nav_cfg.has("smoother") && e.nav_cfg.child("smoother").boolean("across_recoveries", false)
		           ? "true"
		           : "false")
		   << "; false ends a segment before each recovery update).\n";
	}
	std::ofstream(out_dir / "denial_table.md") << md.str();
	std::cout << "\n" << md.str();
}

void writeDropoutTables(const Experiment& e, const std::vector<RunResult>& runs, const fs::path& out_dir)
{
	std::ofstream csv(out_dir / "dropout_runs.csv");
	csv << "seed,configuration,gaps,gap_time_s,drift_m,drift_rate_m_per_min\n";
	std::vector<DropoutDrift> total(e.configs.size());
	for (std::size_t s = 0; s < e.seeds.size(); ++s)
		for (std::size_t i = 0; i < e.configs.size(); ++i)
		{
			DropoutDrift d;
			d.drift_m = runs[s][i][0];
			d.gap_s = runs[s][i][1];
			d.gaps = static_cast<int>(runs[s][i][2]);
			total[i].drift_m += d.drift_m;
			total[i].gap_s += d.gap_s;
			total[i].gaps += d.gaps;
			csv << e.seeds[s] << ",\"" << e.configs[i].name << "\"," << d.gaps << "," << d.gap_s << ","
			    << d.drift_m << "," << 60 * d.rate() << "\n";
		}
	std::ostringstream md;
	md << "| Filter measurements used | DVL gaps | time without DVL | drift during the gaps | drift rate |\n"
	      "|---|---|---|---|---|\n";
	for (std::size_t i = 0; i < e.configs.size(); ++i)
	{
		char line[512];
		std::snprintf(line, sizeof line, "| %s | %d | %.0f s | %.1f m | %.3f m/min |\n",
		              e.configs[i].name.c_str(), total[i].gaps, total[i].gap_s, total[i].drift_m,
		              60 * total[i].rate());
		md << line;
	}
	md << "\n"
	   << e.seeds.size() << " seeds of " << e.spec.name << "; GPS denied from " << e.from_s
	   << " s; a gap is a run of at least " << e.min_gap_s << " s without an accepted " << e.dvl_label
	   << " update; drift = length of the change of the horizontal error vector across each gap.\n";
	std::ofstream(out_dir / "dropout_table.md") << md.str();
	std::cout << "\n" << md.str();
}

/** Reads every seed's result in DIR/runs and writes the tables into DIR.
 *  All missing seeds are named at once, so that they can be rerun together. */
void collect(const Experiment& e, const fs::path& out_dir)
{
	std::vector<RunResult> runs;
	std::string missing;
	for (unsigned seed : e.seeds)
		if (fs::exists(resultPath(out_dir, seed)))
			runs.push_back(readResult(e, out_dir, seed));
		else
			missing += (missing.empty() ? "" : " ") + std::to_string(seed);
	if (!missing.empty())
		throw std::runtime_error(out_dir.string() + ": no result for seed(s) " + missing +
		                         " (failed or not run: rerun them, e.g. with --seed)");
	if (e.kind == "denial_table")
		writeDenialTables(e, runs, out_dir);
	else
		writeDropoutTables(e, runs, out_dir);
}

// ---- Worker processes -------------------------------------------------------

/** This program's absolute path: workers and emitted commands run the same
 *  binary as the parent, wherever it was started from. */
std::string selfPath()
{
	return fs::canonical("/proc/self/exe").string();
}

/** The command line that runs one seed into `out_dir`. */
std::vector<std::string> seedCommand(const Experiment& e, unsigned seed, const fs::path& out_dir,
                                     bool keep_rawlogs)
{
	std::vector<std::string> argv = {selfPath(), e.file,
	                                 "--out",    fs::absolute(out_dir).lexically_normal().string(),
	                                 "--seed",   std::to_string(seed)};
	if (keep_rawlogs) argv.push_back("--keep-rawlogs");
	return argv;
}

std::string shellQuote(const std::string& s)
{
	std::string q = "'";
	for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
	return q + "'";
}

pid_t spawn(const std::vector<std::string>& args)
{
	std::vector<char*> argv;
	for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
	argv.push_back(nullptr);
	pid_t pid = 0;
	if (const int rc = posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ))
		throw std::runtime_error(std::string("cannot start a worker: ") + std::strerror(rc));
	return pid;
}

std::string exitText(int status)
{
	if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
	if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
	return "status " + std::to_string(status);
}

/** Runs every seed in this process, one after the other (--jobs 1, --seed).
 *  Returns the seeds that failed, each named on stderr as runWorkers does. */
std::vector<unsigned> runHere(const Experiment& e, PluginHost& host, const fs::path& out_dir,
                              bool keep_rawlogs)
{
	std::vector<unsigned> failed;
	for (unsigned seed : e.seeds) try
		{
			runSeed(e, host, seed, out_dir, keep_rawlogs);
		}
		catch (const std::exception& x)
		{
			std::cerr << kProgram << ": error: the run of seed " << seed
			          << " failed: " << oneLineReason(x.what()) << "\n";
			failed.push_back(seed);
		}
	return failed;
}

/** Runs every seed in a worker process (this program with --seed), at most
 *  `jobs` at a time. Returns the seeds that failed; the others' results are
 *  in DIR/runs whatever happens to the rest. */
std::vector<unsigned> runWorkers(const Experiment& e, const fs::path& out_dir, bool keep_rawlogs,
                                 unsigned jobs)
{
	std::map<pid_t, unsigned> running;
	std::vector<unsigned> failed;
	std::size_t next = 0;
	std::fflush(stdout);
	while (next < e.seeds.size() || !running.empty())
	{
		while (next < e.seeds.size() && running.size() < jobs)
		{
			const unsigned seed = e.seeds[next++];
			running[spawn(seedCommand(e, seed, out_dir, keep_rawlogs))] = seed;
		}
		int status = 0;
		const pid_t pid = waitpid(-1, &status, 0);
		if (pid < 0)
		{
			if (errno == EINTR) continue;
			throw std::runtime_error(std::string("waiting for the workers: ") + std::strerror(errno));
		}
		const auto it = running.find(pid);
		if (it == running.end()) continue;
		if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
		{
			std::cerr << kProgram << ": error: the run of seed " << it->second << " failed ("
			          << exitText(status) << ")\n";
			failed.push_back(it->second);
		}
		running.erase(it);
	}
	return failed;
}

/** Writes one self-contained command per seed into `jobs_file` (for GNU
 *  parallel, a Slurm array, ...), and removes those seeds' old results so
 *  that --collect cannot take a stale one for a run that did not happen. */
void emitJobs(const Experiment& e, const fs::path& out_dir, bool keep_rawlogs, const std::string& jobs_file)
{
	std::ofstream f(jobs_file);
	for (unsigned seed : e.seeds)
	{
		std::string line;
		for (const auto& a : seedCommand(e, seed, out_dir, keep_rawlogs))
			line += (line.empty() ? "" : " ") + shellQuote(a);
		f << line << "\n";
		fs::remove(resultPath(out_dir, seed));
	}
	f.flush();
	if (!f) throw std::runtime_error(jobs_file + ": cannot write");
	std::cout << "wrote " << e.seeds.size() << " commands (one per seed) to " << jobs_file
	          << "; when they are done: " << kProgram << " " << shellQuote(e.file) << " --collect "
	          << shellQuote(fs::absolute(out_dir).string())
	          << (e.seeds.size() ? " -n " + std::to_string(e.seeds.size()) : "") << "\n";
}

/** Loads the navigator's plugins and observation libraries once for all the
 *  runs of this process, and refuses a bad navigator file before the first
 *  (long) simulation. */
void prepareHost(const Experiment& e, PluginHost& host)
{
	// The plugins' declared observation libraries (obs_libraries.h), also so
	// that their `obs_libs` keys count as read.
	loadObservationLibraries(declaredObservationLibraries(e.nav_cfg), host.searchPaths());
	const Navigator probe(e.nav_cfg, host);
}
}  // namespace

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Reproduces the paper's data-denial table on simulated missions: for every seed, simulates the "
	    "mission and runs the navigator under each configuration (sensors denied after the "
	    "initialisation); writes DIR/denial_table.md and DIR/runs.csv. With 'kind: dvl_dropout' in the "
	    "file: the position drift during DVL dropouts per configuration (DIR/dropout_table.md). "
	    "Seeds run in parallel processes (--jobs), or as separate commands (--emit-jobs, then --collect).",
	    ' ', "0.1.0");
	TCLAP::UnlabeledValueArg<std::string> exp_file("experiment", "Experiment YAML", true, "",
	                                               "EXPERIMENT.yaml", cmd);
	TCLAP::ValueArg<std::string> out("o", "out", "Output directory (required unless --collect)", false, "",
	                                 "DIR", cmd);
	TCLAP::ValueArg<int> seeds("n", "seeds", "Use only the first N seeds of the file", false, 0, "N", cmd);
	TCLAP::SwitchArg keep_rawlogs(
	    "", "keep-rawlogs", "Keep each seed's simulated rawlog in DIR/seed_N (to rerun or evaluate a run)",
	    cmd);
	TCLAP::ValueArg<int> jobs(
	    "j", "jobs",
	    "Run up to N seeds at a time, each in its own process (0, the default: one per core); "
	    "the tables are the same for any N",
	    false, 0, "N", cmd);
	TCLAP::ValueArg<std::string> emit_jobs(
	    "", "emit-jobs",
	    "Run nothing: write one self-contained command per seed into FILE (for GNU parallel or a Slurm job "
	    "array), each writing its result into DIR/runs; then --collect DIR",
	    false, "", "FILE", cmd);
	TCLAP::ValueArg<std::string> collect_dir(
	    "", "collect",
	    "Run nothing: write the tables into DIR from the results in DIR/runs (of --emit-jobs' commands)",
	    false, "", "DIR", cmd);
	TCLAP::ValueArg<unsigned> only_seed(
	    "", "seed",
	    "Run only this seed of the file, writing DIR/runs/seed_S.result and no table "
	    "(what --jobs and --emit-jobs run)",
	    false, 0, "S", cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, kProgram)) return *code;
	if (out.isSet() == collect_dir.isSet())
		return cli::fail(kProgram, "give either --out DIR or --collect DIR", cli::kExitUsage);
	if (jobs.getValue() < 0)
		return cli::fail(kProgram,
		                 "--jobs " + std::to_string(jobs.getValue()) + ": must be 0 (one per core) or more",
		                 cli::kExitUsage);
	if (collect_dir.isSet() && (emit_jobs.isSet() || only_seed.isSet() || jobs.isSet()))
		return cli::fail(kProgram, "--collect runs nothing: it takes no --emit-jobs, --seed or --jobs",
		                 cli::kExitUsage);
	if (emit_jobs.isSet() && (only_seed.isSet() || jobs.isSet()))
		return cli::fail(kProgram, "--emit-jobs runs nothing: it takes no --seed or --jobs", cli::kExitUsage);
	try
	{
		obs::registerAllClasses();
		Experiment e = loadExperiment(exp_file.getValue(), seeds.getValue());
		if (collect_dir.isSet())
		{
			collect(e, collect_dir.getValue());
			return 0;
		}
		const fs::path out_dir = out.getValue();
		if (only_seed.isSet())
		{
			if (std::find(e.seeds.begin(), e.seeds.end(), only_seed.getValue()) == e.seeds.end())
				throw std::runtime_error(exp_file.getValue() + ": no seed " +
				                         std::to_string(only_seed.getValue()) + " in its seeds");
			e.seeds = {only_seed.getValue()};
		}
		PluginHost host;  // one for this process's runs: each plugin is loaded once
		prepareHost(e, host);
		fs::create_directories(out_dir);
		if (emit_jobs.isSet())
		{
			emitJobs(e, out_dir, keep_rawlogs.getValue(), emit_jobs.getValue());
			return 0;
		}
		unsigned n_jobs = jobs.getValue() > 0 ? static_cast<unsigned>(jobs.getValue())
		                                      : std::max(1u, std::thread::hardware_concurrency());
		n_jobs = std::min<unsigned>(n_jobs, static_cast<unsigned>(e.seeds.size()));
		const auto failed = n_jobs <= 1 ? runHere(e, host, out_dir, keep_rawlogs.getValue())
		                                : runWorkers(e, out_dir, keep_rawlogs.getValue(), n_jobs);
		if (only_seed.isSet() && !failed.empty()) return cli::kExitBadInput;  // named above
		if (!failed.empty())
		{
			std::string list;
			for (unsigned s : failed) list += (list.empty() ? "" : " ") + std::to_string(s);
			return cli::fail(kProgram,
			                 std::to_string(failed.size()) + " of " + std::to_string(e.seeds.size()) +
			                     " runs failed (seed " + list + "); the others' results are in " +
			                     (out_dir / "runs").string() +
			                     ": rerun the failed seeds with --seed, then --collect",
			                 cli::kExitBadInput);
		}
		if (!only_seed.isSet()) collect(e, out_dir);
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail(kProgram, e.what());
	}
	return 0;
}
