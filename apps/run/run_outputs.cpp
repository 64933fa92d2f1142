#include "run_outputs.h"

#include <auvnav/io/decimal.h>
#include <auvnav/io/json.h>
#include <auvnav/state.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace auvnav::run
{
namespace
{
constexpr double kRad2Deg = 180.0 / M_PI;

std::string num(double v)
{
	if (!std::isfinite(v)) return "null";
	char b[64];
	std::snprintf(b, sizeof b, "%.10g", v);
	return b;
}

/** A reason as one CSV field's text: a plugin's message may hold newlines. */
std::string oneLine(std::string text)
{
	std::replace(text.begin(), text.end(), '\n', ' ');
	std::replace(text.begin(), text.end(), '\r', ' ');
	return text;
}
}  // namespace

RunOutputs::RunOutputs(const std::string& dir, double rate_hz, std::vector<std::string> tangent_names,
                       std::vector<std::string> stored_names, bool updates_csv)
    : dir_(dir),
      names_(std::move(tangent_names)),
      stored_names_(std::move(stored_names)),
      period_s_(1.0 / rate_hz)
{
	fs::create_directories(dir);
	const auto file = [&](const char* name) { return (fs::path(dir) / name).string(); };
	tum_ = io::LineFile(file("trajectory.tum"));
	csv_ = io::LineFile(file("states.csv"));
	fixes_ = io::LineFile(file("position_fixes.csv"));
	fixes_.line("time_s,label,north_m,east_m,status");
	tum_.line("# timestamp north_m east_m down_m qx qy qz qw  (body origin, NED tangent frame; auvnav-run)");
	csv_.line(statesCsvHeader(names_, stored_names_));
	nis_ = io::LineFile(file("nis.csv"));
	nis_.line("time_s,label,updates,nis_sum,dim_sum");
	health_ = io::LineFile(file("health.csv"));
	health_.line("time_s,status,reason");
	events_ = io::LineFile(file("events.csv"));
	events_.line("time_s,sensor,event");
	if (updates_csv)
	{
		updates_ = io::LineFile(file("updates.csv"));
		updates_.line("time_s,measurement_time_s,sensor,status,nis,dim,why");
	}
	flush();  // the headers: a run killed before its first row still names its columns
}

namespace
{
using io::appendFixed;
using io::appendGeneral;
/** Appends ",v" as "%.10g" would print v. */
void appendG10(std::string& s, double v)
{
	s.push_back(',');
	appendGeneral(s, v, 10);
}
}  // namespace

void RunOutputs::onAnyUpdate(const std::string& label, double t_filter_s, double t_measurement_s,
                             const UpdateResult& r)
{
	if (!updates_.isOpen()) return;
	const char* status = r.status == UpdateStatus::Accepted    ? "accepted"
	                     : r.status == UpdateStatus::Recovered ? "recovered"
	                     : r.status == UpdateStatus::Rejected  ? "rejected"
	                                                           : "invalid";
	const bool has_nis = r.status != UpdateStatus::Invalid || r.nis > 0;
	// One row per update of every sensor (~25 per IMU tick with an ADCP):
	// io::appendFixed / appendGeneral, as printf's "%.6f,%.6f,%s,%s,%.6g,%d" would write it.
	std::string& s = update_row_;
	s.clear();
	appendFixed(s, t_filter_s, 6);
	const std::size_t t_len = s.size();
	s.push_back(',');
	// Most updates are made when measured: the same text, copied (no second
	// formatting; a number's text is at most ~330 characters).
	char t_text[400];
	if (t_measurement_s == t_filter_s && t_len <= sizeof t_text)
	{
		std::memcpy(t_text, s.data(), t_len);
		s.append(t_text, t_len);
	}
	else
		appendFixed(s, t_measurement_s, 6);
	s.push_back(',');
	s += label;
	s.push_back(',');
	s += status;
	s.push_back(',');
	appendGeneral(s, has_nis ? r.nis : NAN, 6);
	s.push_back(',');
	char dim[16];
	s.append(dim, std::to_chars(dim, dim + sizeof dim, r.dim).ptr);
	s += ",\"";
	if (r.status != UpdateStatus::Accepted) s += oneLine(r.why ? r.why : "");
	s.push_back('"');
	updates_.line(s);
}

void RunOutputs::onPositionFix(const std::string& label, double t, const Measurement& m,
                               const UpdateResult& r)
{
	if (m.z.size() < 2) return;  // north, east (a USBL fix may add its depth)
	const char* status = r.status == UpdateStatus::Accepted    ? "accepted"
	                     : r.status == UpdateStatus::Recovered ? "recovered"
	                     : r.status == UpdateStatus::Rejected  ? "rejected"
	                                                           : "invalid";
	char line[256];
	std::snprintf(line, sizeof line, "%.3f,%s,%.3f,%.3f,%s", t, label.c_str(), m.z[0], m.z[1], status);
	fixes_.line(line);
	fixes_.flush();  // rare (GPS, USBL), and what a person watching a run reads
}

std::string statesCsvHeader(const std::vector<std::string>& tangent_names,
                            const std::vector<std::string>& stored_names)
{
	std::string header = "time_s,qw,qx,qy,qz,roll_deg,pitch_deg,yaw_deg";
	for (std::size_t i = 3; i < stored_names.size(); ++i) header += ',' + stored_names[i];
	header += ",body_n_m,body_e_m,body_d_m";
	for (const auto& n : tangent_names) header += ",sigma_" + n;
	// Off-diagonal covariances of position and attitude (for NEES in auvnav-eval).
	header += ",cov_pos_ne,cov_pos_nd,cov_pos_ed,cov_att_ne,cov_att_nd,cov_att_ed";
	return header;
}

void formatTumRow(std::string& s, double t, const NavState& x, const Eigen::Vector3d& p)
{
	const Eigen::Quaterniond q(x.R_nb);
	s.clear();
	appendFixed(s, t, 6);  // TUM: "%.6f" time and position, "%.9f" quaternion
	for (double v : {p.x(), p.y(), p.z()})
	{
		s.push_back(' ');
		appendFixed(s, v, 6);
	}
	for (double v : {q.x(), q.y(), q.z(), q.w()})
	{
		s.push_back(' ');
		appendFixed(s, v, 9);
	}
}

void formatStatesRow(std::string& s, double t, const NavState& x, const Eigen::Vector3d& p,
                     const double* sigma, const double* cov_offdiag)
{
	const Eigen::Quaterniond q(x.R_nb);
	const Eigen::Matrix3d& R = x.R_nb;
	const double roll = std::atan2(R(2, 1), R(2, 2)) * kRad2Deg;
	const double pitch = -std::asin(std::clamp(R(2, 0), -1.0, 1.0)) * kRad2Deg;
	const double yaw = std::atan2(R(1, 0), R(0, 0)) * kRad2Deg;
	// io::appendGeneral writes what "%.10g" (and an ostream at precision 10)
	// writes, at a fraction of the cost: this row is the run's biggest output.
	s.clear();
	appendFixed(s, t, 10);
	for (double v : {q.w(), q.x(), q.y(), q.z(), roll, pitch, yaw}) appendG10(s, v);
	const TangentVector e = x.euclidean();
	for (int i = 3; i < e.size(); ++i) appendG10(s, e[i]);
	for (double v : {p.x(), p.y(), p.z()}) appendG10(s, v);
	for (int i = 0; i < x.dim(); ++i) appendG10(s, sigma[i]);
	for (int i = 0; i < 6; ++i) appendG10(s, cov_offdiag[i]);
}

void sigmaAndOffDiagonals(const Covariance& P, double* sigma, double* cov_offdiag)
{
	for (int i = 0; i < P.rows(); ++i) sigma[i] = std::sqrt(std::max(P(i, i), 0.0));
	int k = 0;
	for (int b : {idx::pos, idx::att})
		for (double v : {P(b, b + 1), P(b, b + 2), P(b + 1, b + 2)}) cov_offdiag[k++] = v;
}

void RunOutputs::onState(const Navigator& nav)
{
	const double t = nav.time();
	if (t < last_t_) last_t_ = -1e300;  // the clock went back (a jump, clock.on_jump: reinitialize)
	if (t - last_t_ < period_s_ - 1e-9) return;
	last_t_ = t;
	const NavState& x = nav.filter().state();
	const Eigen::Vector3d p = nav.bodyPosition_n();
	formatTumRow(row_, t, x, p);
	tum_.line(row_);
	double sigma[idx::max_dim], cov[6];
	sigmaAndOffDiagonals(nav.filter().covariance(), sigma, cov);
	formatStatesRow(row_, t, x, p, sigma, cov);
	csv_.line(row_);
	++rows_;
}

void RunOutputs::onUpdate(const std::string& label, double t, const UpdateResult& r)
{
	if (r.status != UpdateStatus::Accepted && r.status != UpdateStatus::Recovered) return;
	if (t - nis_t0_ >= 1.0 || t < nis_t0_)  // a new second, or the clock went back (as in onState)
	{
		for (const auto& [l, a] : nis_acc_)
		{
			char line[256];
			std::snprintf(line, sizeof line, "%.3f,%s,%zu,%.6g,%zu", nis_t0_, l.c_str(), a.n, a.nis, a.dim);
			nis_.line(line);
		}
		nis_acc_.clear();
		nis_t0_ = std::floor(t);
	}
	auto& a = nis_acc_[label];
	++a.n;
	a.nis += r.nis;
	a.dim += static_cast<std::size_t>(r.dim);
}

void RunOutputs::flush()
{
	nis_.flush();
	if (updates_.isOpen()) updates_.flush();
	tum_.flush();
	csv_.flush();
	fixes_.flush();
	health_.flush();
	events_.flush();
}

void RunOutputs::onHealthChange(double t_s, NavStatus status, const std::string& reason)
{
	health_.line(num(t_s) + ',' + navStatusName(status) + ",\"" + oneLine(reason) + "\"");
	health_.flush();
}

void RunOutputs::onEvent(double t_s, const std::string& label, const std::string& what)
{
	events_.line(num(t_s) + ',' + label + ",\"" + oneLine(what) + "\"");
	events_.flush();  // rare, and what a person watching a run reads
}

void RunOutputs::writeSummary(const Navigator& nav, double wall_s, Phase phase, const std::string& rawlog,
                              const std::string& error) const
{
	const double data_s = nav.startTime() > 0 ? nav.time() - nav.startTime() : 0.0;
	io::Json j;
	j["rawlog"] = rawlog;
	j["completed"] = phase == Phase::Ended && error.empty();
	j["running"] = phase == Phase::Running;
	if (phase == Phase::Interrupted) j["interrupted"] = true;
	if (!error.empty()) j["error"] = error;
	j["initialized"] = nav.initialized();
	const auto& h = nav.health();
	j["status"] = navStatusName(h.status());
	j["status_reason"] = h.reason();
	j["worst_status"] = navStatusName(h.worst());
	j["worst_status_reason"] = h.worstReason();
	j["worst_status_since_s"] = h.worstSince_s();
	j["data_duration_s"] = data_s;
	j["wall_time_s"] = wall_s;
	j["real_time_factor"] = wall_s > 0 ? data_s / wall_s : 0;
	j["predictions"] = nav.predictions();
	j["imu_gaps"] = nav.imuGaps();
	j["clock_jumps"] = nav.clockJumps();
	j["replayed_predictions"] = nav.replayedPredictions();
	j["cholesky_repairs"] = nav.filter().choleskyRepairs();
	j["sigma_limit_hits"] = nav.filter().sigmaLimitHits();  // filter.sigma_limits (0 without)
	j["position_reinitializations"] = nav.positionReinitializations();
	j["sensors"] = io::Json::array();
	for (const auto& s : nav.stats())
		j["sensors"].push_back({{"label", s.label},
		                        {"plugin", s.plugin},
		                        {"accepted", s.accepted},
		                        {"recovered", s.recovered},
		                        {"rejected", s.rejected},
		                        {"invalid", s.invalid},
		                        {"skipped", s.skipped},
		                        {"denied", s.denied},
		                        {"late", s.late},
		                        {"delayed", s.delayed},
		                        {"before_init", s.before_init},
		                        {"position_reinitializations", s.reinitialized},
		                        {"mean_nis_per_dim", s.nis_dim_sum > 0 ? s.nis_sum / s.nis_dim_sum : NAN},
		                        {"last_problem", s.last_problem}});
	io::Json sigma = io::Json::object();
	const auto& P = nav.filter().covariance();
	for (int i = 0; i < static_cast<int>(names_.size()) && i < P.rows(); ++i)
		sigma[names_[i]] = nav.initialized() ? std::sqrt(std::max(P(i, i), 0.0)) : NAN;
	j["final_sigma"] = sigma;
	io::writeJsonAtomically(fs::path(dir_) / "summary.json", j);
}

}  // namespace auvnav::run
