// auvnav-eval: a run against the simulator's ground truth; figures and a table.
//   auvnav-eval --run RUN --truth SIM/ground_truth.csv --out DIR
//   auvnav-eval --run R1 --truth T1 --run R2 --truth T2 ... --out DIR   (Monte Carlo: averaged NEES)
#include <auvnav/cli.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "eval.h"
#include "plot.h"

namespace fs = std::filesystem;
using namespace auvnav::eval;

namespace
{
constexpr double kDeg = 180 / M_PI;
const cv::Scalar kBlue(200, 90, 30), kRed(40, 40, 220), kGreen(60, 160, 40), kGrey(150, 150, 150),
    kOrange(0, 140, 255), kPurple(160, 60, 140);

std::vector<double> minutes(const std::vector<Sample>& s)
{
	std::vector<double> m;
	for (const auto& x : s) m.push_back((x.t - s.front().t) / 60);
	return m;
}
template <typename F>
std::vector<double> col(const std::vector<Sample>& s, F f)
{
	std::vector<double> v;
	for (const auto& x : s) v.push_back(f(x));
	return v;
}

struct Fractions
{
	double pos = 0, att = 0;
};

/** Figures and table lines of one run. */
std::string singleRun(const Evaluation& ev, const fs::path& out, std::vector<std::string>& figures)
{
	const auto& s = ev.samples;
	const auto t = minutes(s);
	auto fig = [&](Plot& p, const std::string& name)
	{
		p.save((out / name).string());
		figures.push_back(name);
	};
	{
		Plot p("Horizontal position error with 1-sigma / 2-sigma", "time [min]", "[m]");
		const auto s1 = col(s, [](const Sample& x) { return std::sqrt(x.P_pos(0, 0) + x.P_pos(1, 1)); });
		std::vector<double> s2, zero(s.size(), 0.0);
		for (double v : s1) s2.push_back(2 * v);
		p.band(t, zero, s2, kGrey, "2 sigma");
		p.band(t, zero, s1, kBlue, "1 sigma");
		p.line(t, col(s, [](const Sample& x) { return x.pos_err_ned.head<2>().norm(); }), kRed, "error");
		fig(p, "position_error.png");
	}
	{
		Plot p("Heading error with +-1 / +-2 sigma", "time [min]", "[deg]");
		const auto sg = col(s, [](const Sample& x) { return x.heading_sigma_rad * kDeg; });
		std::vector<double> lo1, hi1, lo2, hi2;
		for (double v : sg) lo1.push_back(-v), hi1.push_back(v), lo2.push_back(-2 * v), hi2.push_back(2 * v);
		p.band(t, lo2, hi2, kGrey, "2 sigma");
		p.band(t, lo1, hi1, kBlue, "1 sigma");
		p.line(t, col(s, [](const Sample& x) { return x.heading_err_rad * kDeg; }), kRed, "error");
		const double lim = 3 * *std::max_element(sg.begin() + static_cast<long>(sg.size() / 10), sg.end());
		p.yRange(-std::max(lim, 0.5), std::max(lim, 0.5));
		fig(p, "heading_error.png");
	}
	for (int k = 0; k < 2; ++k)
	{
		Plot p(std::string("Water current ") + (k ? "east" : "north") + ": estimate with 2 sigma, truth",
		       "time [min]", "[m/s]");
		std::vector<double> lo, hi;
		for (const auto& x : s)
			lo.push_back(x.current_est[k] - 2 * x.current_sigma[k]),
			    hi.push_back(x.current_est[k] + 2 * x.current_sigma[k]);
		p.band(t, lo, hi, kGrey, "2 sigma");
		p.line(t, col(s, [k](const Sample& x) { return x.current_est[k]; }), kBlue, "estimate");
		p.line(t, col(s, [k](const Sample& x) { return x.current_true[k]; }), kGreen, "truth");
		fig(p, k ? "current_east.png" : "current_north.png");
	}
	const char* dnames[4] = {"linear damping surge D_l,xx [N/(m/s)]", "linear damping sway D_l,yy [N/(m/s)]",
	                         "quadratic damping surge D_q,xx [N/(m/s)^2]",
	                         "quadratic damping sway D_q,yy [N/(m/s)^2]"};
	const char* dfiles[4] = {"damping_l_xx.png", "damping_l_yy.png", "damping_q_xx.png", "damping_q_yy.png"};
	for (int k = 0; k < 4; ++k)
	{
		Plot p(std::string("Estimated ") + dnames[k] + " with 2 sigma", "time [min]", "");
		p.band(t, col(s, [k](const Sample& x) { return x.damping_lo[k]; }),
		       col(s, [k](const Sample& x) { return x.damping_hi[k]; }), kGrey, "2 sigma");
		p.line(t, col(s, [k](const Sample& x) { return x.damping[k]; }), kBlue, "estimate");
		fig(p, dfiles[k]);
	}
	const auto [lo, hi] = chi2MeanBounds(3, 1);
	Fractions in;
	double in_h = 0;
	const auto [lo2, hi2] = chi2MeanBounds(2, 1);
	{
		Plot p("NEES (3 dof) with the 95 % chi-square bounds", "time [min]", "NEES");
		p.line(t, col(s, [](const Sample& x) { return x.nees_pos; }), kBlue, "position", 1);
		p.line(t, col(s, [](const Sample& x) { return x.nees_att; }), kOrange, "attitude", 1);
		p.hline(lo, kRed, "95 % bounds");
		p.hline(hi, kRed, "");
		p.yRange(0, 3 * hi);
		fig(p, "nees.png");
		for (const auto& x : s)
		{
			in.pos += x.nees_pos >= lo && x.nees_pos <= hi, in.att += x.nees_att >= lo && x.nees_att <= hi;
			in_h += x.nees_hpos >= lo2 && x.nees_hpos <= hi2;
		}
	}
	// NIS per sensor: mean NIS/dim over 60 s windows.
	std::string nis_rows;
	{
		Plot p("NIS per dimension (60 s means) per sensor", "time [min]", "NIS / dim");
		const cv::Scalar colours[] = {kBlue, kOrange, kGreen, kPurple, kRed, kGrey};
		int ci = 0;
		for (const auto& [label, bins] : ev.nis)
		{
			std::vector<double> x, y;
			double w_nis = 0, w_dim = 0, t0 = bins.empty() ? 0 : bins.front().t;
			std::size_t inside = 0, windows = 0;
			double tot_nis = 0, tot_dim = 0;
			for (const auto& b : bins)
			{
				w_nis += b.nis, w_dim += static_cast<double>(b.dim);
				tot_nis += b.nis, tot_dim += static_cast<double>(b.dim);
				if (b.t - t0 >= 60 && w_dim > 0)
				{
					x.push_back((t0 - s.front().t) / 60);
					y.push_back(w_nis / w_dim);
					const auto [l, h] = chi2MeanBounds(static_cast<int>(w_dim), 1);
					inside += w_nis >= l && w_nis <= h;
					++windows;
					w_nis = w_dim = 0;
					t0 = b.t;
				}
			}
			p.line(x, y, colours[ci++ % 6], label, 1);
			char row[256];
			std::snprintf(row, sizeof row, "| %s | %.2f | %zu/%zu |\n", label.c_str(),
			              tot_dim > 0 ? tot_nis / tot_dim : NAN, inside, windows);
			nis_rows += row;
		}
		p.hline(1.0, kRed, "expected 1");
		p.yRange(0, 3);
		fig(p, "nis.png");
	}
	const auto& last = s.back();
	double max_err = 0, sq_head = 0;
	for (const auto& x : s)
		max_err = std::max(max_err, x.pos_err_ned.head<2>().norm()),
		sq_head += x.heading_err_rad * x.heading_err_rad;
	char buf[2048];
	std::snprintf(buf, sizeof buf,
	              "| final horizontal error | of distance travelled | worst | final 2σ | heading error RMS | "
	              "position NEES inside "
	              "95 %% | horizontal NEES inside 95 %% | attitude NEES inside 95 %% "
	              "|\n|---|---|---|---|---|---|---|---|\n"
	              "| %.2f m | %.3f %% (%.0f m) | %.2f m | %.2f m | %.3f° | %.1f %% | %.1f %% | %.1f %% |\n\n"
	              "| sensor | mean NIS/dim | 60 s windows inside 95 %% |\n|---|---|---|\n",
	              last.pos_err_ned.head<2>().norm(),
	              100 * last.pos_err_ned.head<2>().norm() / std::max(last.distance_m, 1e-9), last.distance_m,
	              max_err, 2 * std::sqrt(last.P_pos(0, 0) + last.P_pos(1, 1)),
	              std::sqrt(sq_head / s.size()) * kDeg, 100 * in.pos / s.size(), 100 * in_h / s.size(),
	              100 * in.att / s.size());
	return std::string(buf) + nis_rows;
}

/** Averaged NEES over runs (samples matched by index from each run's start). */
std::string monteCarlo(const std::vector<Evaluation>& evs, double settle_s, const fs::path& out,
                       std::vector<std::string>& figures)
{
	std::size_t n = evs.front().samples.size();
	for (const auto& e : evs) n = std::min(n, e.samples.size());
	const int M = static_cast<int>(evs.size());
	std::vector<double> t, pos(n, 0.0), att(n, 0.0), hpos(n, 0.0);
	for (std::size_t i = 0; i < n; ++i)
	{
		t.push_back((evs.front().samples[i].t - evs.front().samples.front().t) / 60);
		for (const auto& e : evs)
			pos[i] += e.samples[i].nees_pos / M, att[i] += e.samples[i].nees_att / M,
			    hpos[i] += e.samples[i].nees_hpos / M;
	}
	const auto [lo, hi] = chi2MeanBounds(3, M);
	Plot p("NEES averaged over " + std::to_string(M) + " runs, 95 % bounds", "time [min]", "mean NEES");
	p.line(t, pos, kBlue, "position", 1);
	p.line(t, att, kOrange, "attitude", 1);
	p.line(t, hpos, kGreen, "horizontal (2 dof)", 1);
	p.hline(lo, kRed, "95 % bounds (3 dof)");
	p.hline(hi, kRed, "");
	{
		const auto [l2, h2] = chi2MeanBounds(2, M);
		p.hline(l2, kGreen, "95 % bounds (2 dof)");
		p.hline(h2, kGreen, "");
	}
	p.yRange(0, 3 * hi);
	p.save((out / "nees_monte_carlo.png").string());
	figures.push_back("nees_monte_carlo.png");
	const auto [lo2, hi2] = chi2MeanBounds(2, M);
	// One row for the whole run and, with --settle, one from that time on
	// (after the initial alignment).
	// Structured bindings by init-capture: clang before 16 cannot capture them.
	auto row = [&, b3_lo = lo, b3_hi = hi, b2_lo = lo2, b2_hi = hi2](const char* from, std::size_t first)
	{
		std::size_t in_pos = 0, in_att = 0, above_pos = 0, above_att = 0, in_h = 0, above_h = 0;
		for (std::size_t i = first; i < n; ++i)
		{
			in_h += hpos[i] >= b2_lo && hpos[i] <= b2_hi, above_h += hpos[i] > b2_hi;
			in_pos += pos[i] >= b3_lo && pos[i] <= b3_hi, in_att += att[i] >= b3_lo && att[i] <= b3_hi;
			above_pos += pos[i] > b3_hi, above_att += att[i] > b3_hi;
		}
		const double k = std::max<double>(1.0, static_cast<double>(n - first));
		char buf[512];
		std::snprintf(buf, sizeof buf,
		              "| %d | %s | %zu | [%.3f, %.3f] / [%.3f, %.3f] | %.1f %% | %.1f %% | %.1f %% | %.1f %% "
		              "| %.1f %% | %.1f %% |\n",
		              M, from, n - first, b3_lo, b3_hi, b2_lo, b2_hi, 100.0 * in_pos / k,
		              100.0 * above_pos / k, 100.0 * in_h / k, 100.0 * above_h / k, 100.0 * in_att / k,
		              100.0 * above_att / k);
		return std::string(buf);
	};
	std::string buf =
	    "| runs | from | samples | bounds (3 dof / 2 dof) | position NEES inside | above | horizontal NEES "
	    "inside | above | "
	    "attitude NEES inside | above |\n|---|---|---|---|---|---|---|---|---|---|\n" +
	    row("start", 0);
	if (settle_s > 0)
	{
		std::size_t first = 0;
		while (first < n && t[first] * 60 < settle_s) ++first;
		char from[64];
		std::snprintf(from, sizeof from, "%.0f s", settle_s);
		buf += row(from, first);
	}
	return buf;
}
/** The --at line: the horizontal error at one instant. */
/** Filtered against smoothed (auvnav-run --smooth) for the runs that have
 *  smoothed_states.csv: horizontal RMS over the dive (truth deeper than
 *  0.5 m), the NEES fractions inside the 95 % bounds over the dive, and a
 *  figure of the first such run. Empty if no run has one. */
std::string smoothedComparison(const std::vector<std::string>& runs, const std::vector<std::string>& truths,
                               const std::vector<Evaluation>& filtered, double every_s, const fs::path& out,
                               std::vector<std::string>& figures)
{
	// Not a structured binding: a lambda below uses them (clang refuses to capture those in C++17).
	const std::pair<double, double> bounds = chi2MeanBounds(3, 1);
	const double lo = bounds.first, hi = bounds.second;
	struct Dive
	{
		double rms = 0, in_pos = 0, in_att = 0;
		std::size_t n = 0;
	};
	auto dive = [&](const Evaluation& e)
	{
		Dive d;
		double sq = 0;
		for (const auto& x : e.samples)
		{
			if (x.depth_true_m <= 0.5) continue;
			++d.n;
			sq += x.pos_err_ned.head<2>().squaredNorm();
			d.in_pos += x.nees_pos >= lo && x.nees_pos <= hi;
			d.in_att += x.nees_att >= lo && x.nees_att <= hi;
		}
		if (d.n) d.rms = std::sqrt(sq / d.n), d.in_pos /= d.n, d.in_att /= d.n;
		return d;
	};
	std::string md;
	double ratio_sum = 0, ratio_max = 0, in_pos = 0, in_att = 0;
	std::size_t n_runs = 0, samples = 0;
	for (std::size_t i = 0; i < runs.size(); ++i)
	{
		if (!fs::exists(fs::path(runs[i]) / "smoothed_states.csv")) continue;
		const Evaluation sm =
		    evaluate(runs[i], truths.size() == 1 ? truths[0] : truths[i], every_s, "smoothed_states.csv");
		const Dive f = dive(filtered[i]), s = dive(sm);
		if (!f.n || !s.n) continue;
		if (md.empty())
		{
			md = "| run | dive samples | filtered RMS [m] | smoothed RMS [m] | ratio | smoothed NEES pos / "
			     "att in 95 % | "
			     "filtered NEES pos / att in 95 % |\n|---|---|---|---|---|---|---|\n";
			const auto& ss = sm.samples;
			const auto& fs_ = filtered[i].samples;
			const double t0 = std::min(ss.front().t, fs_.front().t);
			std::vector<double> tf, ts;
			for (const auto& x : fs_) tf.push_back((x.t - t0) / 60);
			for (const auto& x : ss) ts.push_back((x.t - t0) / 60);
			Plot p("Horizontal position error: filtered, smoothed (2 sigma band: smoothed)", "time [min]",
			       "[m]");
			std::vector<double> zero(ss.size(), 0.0);
			p.band(ts, zero,
			       col(ss, [](const Sample& x) { return 2 * std::sqrt(x.P_pos(0, 0) + x.P_pos(1, 1)); }),
			       kGrey, "2 sigma smoothed");
			p.line(tf, col(fs_, [](const Sample& x) { return x.pos_err_ned.head<2>().norm(); }), kRed,
			       "filtered");
			p.line(ts, col(ss, [](const Sample& x) { return x.pos_err_ned.head<2>().norm(); }), kBlue,
			       "smoothed");
			p.save((out / "smoothed_vs_filtered.png").string());
			figures.push_back("smoothed_vs_filtered.png");
		}
		char row[400];
		std::snprintf(row, sizeof row,
		              "| %s | %zu | %.3f | %.3f | %.3f | %.1f / %.1f %% | %.1f / %.1f %% |\n",
		              runs[i].c_str(), s.n, f.rms, s.rms, s.rms / f.rms, 100 * s.in_pos, 100 * s.in_att,
		              100 * f.in_pos, 100 * f.in_att);
		md += row;
		ratio_sum += s.rms / f.rms;
		ratio_max = std::max(ratio_max, s.rms / f.rms);
		in_pos += s.in_pos * s.n, in_att += s.in_att * s.n;
		samples += s.n;
		++n_runs;
	}
	if (!n_runs) return "";
	char tail[300];
	std::snprintf(
	    tail, sizeof tail,
	    "\nSmoothed/filtered dive RMS: mean %.3f, worst %.3f over %zu run(s); smoothed NEES inside the 95 %% "
	    "bounds over the dive: position %.1f %%, attitude %.1f %%.\n",
	    ratio_sum / n_runs, ratio_max, n_runs, 100 * in_pos / samples, 100 * in_att / samples);
	return "## Filtered vs smoothed (auvnav-run --smooth)\n\n" + md + tail;
}

std::string errorAt(const std::string& run, const std::string& truth, double after_start_s,
                    const std::string& file)
{
	const auto s = sampleAt(run, truth, after_start_s, file);
	if (!s)
		throw std::runtime_error(run + "/" + file + ": no state with truth at or after " +
		                         std::to_string(after_start_s) + " s");
	char line[256];
	std::snprintf(line, sizeof line,
	              "Horizontal error at %.3f s after the truth's start: %.6f m (state at %.6f)\n",
	              after_start_s, s->pos_err_ned.head<2>().norm(), s->t);
	return line;
}
}  // namespace

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Evaluates auvnav-run outputs against auvnav-sim ground truth: PNG figures and DIR/eval.md.", ' ',
	    "0.1.0");
	TCLAP::MultiArg<std::string> runs("r", "run", "auvnav-run output folder (repeat for Monte Carlo)", true,
	                                  "DIR", cmd);
	TCLAP::MultiArg<std::string> truths("t", "truth", "ground_truth.csv, one per --run (or one for all)",
	                                    true, "FILE", cmd);
	TCLAP::ValueArg<std::string> out("o", "out", "Output folder", true, "", "DIR", cmd);
	TCLAP::ValueArg<double> every("", "every", "Seconds between evaluated samples", false, 1.0, "S", cmd);
	TCLAP::ValueArg<double> settle("", "settle",
	                               "Monte Carlo: also report the NEES fractions from S seconds after the "
	                               "start (after the initial alignment)",
	                               false, 0.0, "S", cmd);
	TCLAP::SwitchArg smoothed(
	    "", "smoothed",
	    "Evaluate the runs' smoothed_states.csv (auvnav-run --smooth) instead of states.csv; without it, a "
	    "run that has one also gets a filtered-vs-smoothed table and figure",
	    cmd);
	TCLAP::ValueArg<double> at(
	    "", "at",
	    "Also report the first run's horizontal error at the first state S seconds or more after the truth's "
	    "first row (as auvnav-experiment measures it: give it initialization_s + denial_s; needs a state per "
	    "prediction, e.g. auvnav-run --set outputs.rate_hz=1000)",
	    false, NAN, "S", cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-eval")) return *code;
	try
	{
		const auto& r = runs.getValue();
		const auto& tr = truths.getValue();
		if (tr.size() != r.size() && tr.size() != 1)
			throw std::runtime_error("give one --truth per --run, or one for all");
		if (!(every.getValue() > 0)) throw std::runtime_error("--every must be positive");
		if (!(settle.getValue() >= 0)) throw std::runtime_error("--settle must be zero or positive");
		fs::create_directories(out.getValue());
		std::vector<Evaluation> evs;
		for (std::size_t i = 0; i < r.size(); ++i)
			evs.push_back(evaluate(r[i], tr.size() == 1 ? tr[0] : tr[i], every.getValue(),
			                       smoothed.getValue() ? "smoothed_states.csv" : "states.csv"));
		std::vector<std::string> figures;
		std::string md =
		    "# Evaluation of " + r.front() + "\n\n" + singleRun(evs.front(), out.getValue(), figures);
		if (evs.size() > 1)
			md += "\n## Monte Carlo\n\n" + monteCarlo(evs, settle.getValue(), out.getValue(), figures);
		if (!smoothed.getValue())
			if (const std::string cmp =
			        smoothedComparison(r, tr, evs, every.getValue(), out.getValue(), figures);
			    !cmp.empty())
				md += "\n" + cmp;
		if (!std::isnan(at.getValue()))
			md += "\n" + errorAt(r.front(), tr.front(), at.getValue(),
			                     smoothed.getValue() ? "smoothed_states.csv" : "states.csv");
		md += "\nFigures:";
		for (const auto& f : figures) md += " " + f;
		md += "\n";
		std::ofstream(fs::path(out.getValue()) / "eval.md") << md;
		std::cout << md;
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-eval", e.what());
	}
	return auvnav::cli::kExitOk;
}
