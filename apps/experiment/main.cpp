// auvnav-experiment: reproduces the paper's data-denial table on simulated
// missions (config/experiments/denial_table.yaml) and compares the drift
// during DVL dropouts with and without model aiding (dvl_dropout.yaml).
#include <auvnav/config.h>
#include <auvnav/io/trajectory.h>
#include <auvnav/obs_libraries.h>
#include <auvnav/navigator.h>
#include <auvnav/obs/register.h>
#include <auvnav/cli.h>
#include <auvnav/rawlog_run.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numeric>

#include "mission.h"

namespace fs = std::filesystem;
using namespace auvnav;

namespace
{
struct Configuration
{
	std::string name;
	std::vector<std::string> deny;
	double paper_sigma2 = NAN, paper_error = NAN;
};

struct Outcome
{
	double error_m = NAN, two_sigma_m = NAN;
	bool inside() const { return error_m <= two_sigma_m; }
};

/** Runs the navigator on `rawlog` with the denial and returns the error and
 *  2σ at the end of the denial window: at the first prediction at or after
 *  it, against the truth interpolated there (io::at, as auvnav-eval does). */
Outcome runOne(const config::Node& nav_cfg, PluginHost& host, const fs::path& rawlog,
			   const io::Trajectory& truth, const Configuration& c, double init_s, double denial_s)
{
	Navigator nav(nav_cfg, host);
	DenialWindow w;
	w.labels = c.deny;
	w.from_s = init_s;
	w.to_s = init_s + denial_s;
	nav.addDenial(w);
	const double t_eval = truth.front().t_unix + init_s + denial_s;
	Outcome o;
	nav.on_predict = [&](const Navigator& n) {
		if (!std::isnan(o.error_m) || n.time() < t_eval) return;
		const auto tr = io::at(truth, n.time());
		o.error_m = (n.bodyPosition_n() - tr.p_n).head<2>().norm();
		const auto& P = n.filter().covariance();
		// 2σ horizontal: twice the root of the summed north/east variances.
		o.two_sigma_m = 2 * std::sqrt(P(idx::pos, idx::pos) + P(idx::pos + 1, idx::pos + 1));
	};
	runRawlog(nav, rawlog.string()).rethrow();
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
	nav.on_predict = [&](const Navigator& n) {
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

/** The DVL-dropout comparison (config/experiments/dvl_dropout.yaml). */
int dropoutExperiment(const config::Node& ex, const std::string& out_dir, int max_seeds, bool keep_rawlogs)
{
	const auto spec = sim::MissionSpec::load(ex.filePath("mission"));
	const auto nav_cfg = config::Node::load(ex.filePath("navigator"));
	const double from_s = ex.nonNegative("gps_denied_from_s");
	const double min_gap_s = ex.positive("min_gap_s");
	const std::string dvl_label = ex.string("dvl_label", "DVL");
	std::vector<unsigned> seed_list;
	for (double s : ex.numbers("seeds")) seed_list.push_back(static_cast<unsigned>(s));
	if (max_seeds > 0 && static_cast<std::size_t>(max_seeds) < seed_list.size())
		seed_list.resize(static_cast<std::size_t>(max_seeds));
	std::vector<Configuration> configs;
	for (const auto& c : ex.sequence("configurations")) configs.push_back({c.string("name"), c.strings("deny")});
	ex.checkAllKeysUsed();
	PluginHost host;  // one for the experiment's runs: each plugin is loaded once
	loadObservationLibraries(declaredObservationLibraries(nav_cfg), host.searchPaths());
	{ const Navigator probe(nav_cfg, host); }  // refuses a bad navigator file before the first simulation
	fs::create_directories(out_dir);
	std::ofstream runs(fs::path(out_dir) / "dropout_runs.csv");
	runs << "seed,configuration,gaps,gap_time_s,drift_m,drift_rate_m_per_min\n";
	std::vector<DropoutDrift> total(configs.size());
	for (unsigned seed : seed_list)
	{
		const fs::path dir = fs::path(out_dir) / ("seed_" + std::to_string(seed));
		const auto summary = sim::runMission(spec, seed, dir.string());
		const auto truth = io::readGroundTruth(dir / "ground_truth.csv");
		for (std::size_t i = 0; i < configs.size(); ++i)
		{
			const DropoutDrift d =
				runDropouts(nav_cfg, host, summary.rawlog_path, truth, configs[i].deny, from_s, dvl_label, min_gap_s);
			total[i].drift_m += d.drift_m;
			total[i].gap_s += d.gap_s;
			total[i].gaps += d.gaps;
			runs << seed << ",\"" << configs[i].name << "\"," << d.gaps << "," << d.gap_s << "," << d.drift_m << ","
				 << 60 * d.rate() << "\n";
			runs.flush();
			std::printf("seed %2u  %-40s %3d gaps, %6.0f s, drift %6.2f m = %.3f m/min\n", seed,
						configs[i].name.c_str(), d.gaps, d.gap_s, d.drift_m, 60 * d.rate());
			std::fflush(stdout);
		}
		if (!keep_rawlogs) fs::remove(summary.rawlog_path);
	}
	std::ostringstream md;
	md << "| Filter measurements used | DVL gaps | time without DVL | drift during the gaps | drift rate |\n"
		  "|---|---|---|---|---|\n";
	for (std::size_t i = 0; i < configs.size(); ++i)
	{
		char line[512];
		std::snprintf(line, sizeof line, "| %s | %d | %.0f s | %.1f m | %.3f m/min |\n", configs[i].name.c_str(),
					  total[i].gaps, total[i].gap_s, total[i].drift_m, 60 * total[i].rate());
		md << line;
	}
	md << "\n" << seed_list.size() << " seeds of " << spec.name << "; GPS denied from " << from_s
	   << " s; a gap is a run of at least " << min_gap_s << " s without an accepted " << dvl_label
	   << " update; drift = length of the change of the horizontal error vector across each gap.\n";
	std::ofstream(fs::path(out_dir) / "dropout_table.md") << md.str();
	std::cout << "\n" << md.str();
	return 0;
}
}  // namespace

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
		"Reproduces the paper's data-denial table on simulated missions: for every seed, simulates the "
		"mission and runs the navigator under each configuration (sensors denied after the "
		"initialisation); writes DIR/denial_table.md and DIR/runs.csv. With 'kind: dvl_dropout' in the "
		"file: the position drift during DVL dropouts per configuration (DIR/dropout_table.md).",
		' ', "0.1.0");
	TCLAP::UnlabeledValueArg<std::string> exp_file("experiment", "Experiment YAML", true, "", "EXPERIMENT.yaml", cmd);
	TCLAP::ValueArg<std::string> out("o", "out", "Output directory", true, "", "DIR", cmd);
	TCLAP::ValueArg<int> seeds("n", "seeds", "Use only the first N seeds of the file", false, 0, "N", cmd);
	TCLAP::SwitchArg keep_rawlogs("", "keep-rawlogs", "Keep each seed's simulated rawlog in DIR/seed_N (to rerun or evaluate a run)", cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-experiment")) return *code;
	try
	{
		obs::registerAllClasses();
		const auto ex = config::Node::load(exp_file.getValue());
		const std::string kind = ex.string("kind", "denial_table");
		if (kind == "dvl_dropout")
			return dropoutExperiment(ex, out.getValue(), seeds.getValue(), keep_rawlogs.getValue());
		if (kind != "denial_table")
			throw std::runtime_error(exp_file.getValue() + ": kind '" + kind +
									 "' is neither 'denial_table' nor 'dvl_dropout'");
		const auto spec = sim::MissionSpec::load(ex.filePath("mission"));
		const auto nav_cfg = config::Node::load(ex.filePath("navigator"));
		const double init_s = ex.positive("initialization_s"), denial_s = ex.positive("denial_s");
		std::vector<unsigned> seed_list;
		for (double s : ex.numbers("seeds")) seed_list.push_back(static_cast<unsigned>(s));
		if (seeds.getValue() > 0 && static_cast<std::size_t>(seeds.getValue()) < seed_list.size())
			seed_list.resize(static_cast<std::size_t>(seeds.getValue()));
		std::vector<Configuration> configs;
		for (const auto& c : ex.sequence("configurations"))
			configs.push_back({c.string("name"), c.strings("deny"), c.number("paper_uncertainty_2sigma_m", NAN),
							   c.number("paper_error_m", NAN)});
		ex.checkAllKeysUsed();
		PluginHost host;  // one for the experiment's runs: each plugin is loaded once
		// The plugins' declared observation libraries (obs_libraries.h), also so
		// that their `obs_libs` keys count as read.
		loadObservationLibraries(declaredObservationLibraries(nav_cfg), host.searchPaths());
		{ const Navigator probe(nav_cfg, host); }  // refuses a bad navigator file before the first simulation
		fs::create_directories(out.getValue());
		std::ofstream runs(fs::path(out.getValue()) / "runs.csv");
		runs << "seed,configuration,error_m,two_sigma_m,inside_2sigma\n";
		std::vector<std::vector<Outcome>> results(configs.size());
		for (unsigned seed : seed_list)
		{
			const fs::path dir = fs::path(out.getValue()) / ("seed_" + std::to_string(seed));
			const auto summary = sim::runMission(spec, seed, dir.string());
			const auto truth = io::readGroundTruth(dir / "ground_truth.csv");
			for (std::size_t i = 0; i < configs.size(); ++i)
			{
				const Outcome o = runOne(nav_cfg, host, summary.rawlog_path, truth, configs[i], init_s, denial_s);
				results[i].push_back(o);
				runs << seed << ",\"" << configs[i].name << "\"," << o.error_m << "," << o.two_sigma_m << ","
					 << (o.inside() ? 1 : 0) << "\n";
				runs.flush();
				std::printf("seed %2u  %-26s error %6.2f m   2 sigma %6.2f m\n", seed, configs[i].name.c_str(),
							o.error_m, o.two_sigma_m);
				std::fflush(stdout);
			}
			if (!keep_rawlogs.getValue()) fs::remove(summary.rawlog_path);  // keep the truth, drop the bulky log
		}
		std::ostringstream md;
		md << "| Filter measurements used | 2σ uncertainty after " << denial_s << " s (mean) | error after "
		   << denial_s << " s: mean | worst | inside 2σ | paper: 2σ | paper: error |\n|---|---|---|---|---|---|---|\n";
		for (std::size_t i = 0; i < configs.size(); ++i)
		{
			const auto& r = results[i];
			double e_sum = 0, e_max = 0, s_sum = 0;
			int inside = 0;
			for (const auto& o : r)
			{
				e_sum += o.error_m;
				e_max = std::max(e_max, o.error_m);
				s_sum += o.two_sigma_m;
				inside += o.inside();
			}
			char line[512];
			std::snprintf(line, sizeof line, "| %s | %.1f m | %.1f m | %.1f m | %d/%zu | %.1f m | %.1f m |\n",
						  configs[i].name.c_str(), s_sum / r.size(), e_sum / r.size(), e_max, inside, r.size(),
						  configs[i].paper_sigma2, configs[i].paper_error);
			md << line;
		}
		md << "\n" << seed_list.size() << " seeds of " << spec.name << "; denial of the listed sensors from "
		   << init_s << " s to " << init_s + denial_s << " s; 2σ = 2·sqrt(σ_N² + σ_E²).\n";
		std::ofstream(fs::path(out.getValue()) / "denial_table.md") << md.str();
		std::cout << "\n" << md.str();
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-experiment", e.what());
	}
	return 0;
}
