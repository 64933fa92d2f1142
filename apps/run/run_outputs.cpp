#include "run_outputs.h"

#include <auvnav/io/json.h>
#include <auvnav/state.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
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
}  // namespace

RunOutputs::RunOutputs(const std::string& dir, double rate_hz, std::vector<std::string> tangent_names,
					   std::vector<std::string> stored_names, bool updates_csv)
	: dir_(dir), names_(std::move(tangent_names)), stored_names_(std::move(stored_names)), period_s_(1.0 / rate_hz)
{
	fs::create_directories(dir);
	tum_.open(fs::path(dir) / "trajectory.tum");
	csv_.open(fs::path(dir) / "states.csv");
	fixes_.open(fs::path(dir) / "position_fixes.csv");
	if (!tum_ || !csv_ || !fixes_) throw std::runtime_error("cannot write outputs in " + dir);
	fixes_ << "time_s,label,north_m,east_m,status\n";
	tum_ << "# timestamp north_m east_m down_m qx qy qz qw  (body origin, NED tangent frame; auvnav-run)\n";
	const auto& names = names_;
	const auto& stored = stored_names_;
	csv_ << "time_s,qw,qx,qy,qz,roll_deg,pitch_deg,yaw_deg";
	for (std::size_t i = 3; i < stored.size(); ++i) csv_ << ',' << stored[i];
	csv_ << ",body_n_m,body_e_m,body_d_m";
	for (const auto& n : names) csv_ << ",sigma_" << n;
	// Off-diagonal covariances of position and attitude (for NEES in auvnav-eval).
	csv_ << ",cov_pos_ne,cov_pos_nd,cov_pos_ed,cov_att_ne,cov_att_nd,cov_att_ed";
	csv_ << '\n';
	nis_.open(fs::path(dir) / "nis.csv");
	if (!nis_) throw std::runtime_error("cannot write outputs in " + dir);
	nis_ << "time_s,label,updates,nis_sum,dim_sum\n";
	health_.open(fs::path(dir) / "health.csv");
	if (!health_) throw std::runtime_error("cannot write outputs in " + dir);
	health_ << "time_s,status,reason\n";
	health_.flush();
	if (updates_csv)
	{
		updates_.open(fs::path(dir) / "updates.csv");
		if (!updates_) throw std::runtime_error("cannot write outputs in " + dir);
		updates_ << "time_s,measurement_time_s,sensor,status,nis,dim,why\n";
	}
}

void RunOutputs::onAnyUpdate(const std::string& label, double t_filter_s, double t_measurement_s,
							 const UpdateResult& r)
{
	if (!updates_.is_open()) return;
	const char* status = r.status == UpdateStatus::Accepted	   ? "accepted"
						 : r.status == UpdateStatus::Recovered ? "recovered"
						 : r.status == UpdateStatus::Rejected  ? "rejected"
															   : "invalid";
	const bool has_nis = r.status != UpdateStatus::Invalid || r.nis > 0;
	char line[320];
	std::snprintf(line, sizeof line, "%.6f,%.6f,%s,%s,%.6g,%d,\"%s\"\n", t_filter_s, t_measurement_s, label.c_str(), status,
				  has_nis ? r.nis : NAN, r.dim, r.status == UpdateStatus::Accepted ? "" : r.why);
	updates_ << line;
	if (++update_rows_ % 500 == 0) updates_.flush();
}

void RunOutputs::onPositionFix(const std::string& label, double t, const Measurement& m, const UpdateResult& r)
{
	if (m.z.size() < 2) return;	// north, east (a USBL fix may add its depth)
	const char* status = r.status == UpdateStatus::Accepted	   ? "accepted"
						 : r.status == UpdateStatus::Recovered ? "recovered"
						 : r.status == UpdateStatus::Rejected  ? "rejected"
															   : "invalid";
	char line[256];
	std::snprintf(line, sizeof line, "%.3f,%s,%.3f,%.3f,%s\n", t, label.c_str(), m.z[0], m.z[1], status);
	fixes_ << line;
	fixes_.flush();
}

void RunOutputs::onState(const Navigator& nav)
{
	const double t = nav.time();
	if (t - last_t_ < period_s_ - 1e-9) return;
	last_t_ = t;
	const NavState& x = nav.filter().state();
	const Eigen::Quaterniond q(x.R_nb);
	const Eigen::Vector3d p = nav.bodyPosition_n();
	char line[256];
	std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", t, p.x(), p.y(), p.z(), q.x(), q.y(),
				  q.z(), q.w());
	tum_ << line;
	const Eigen::Matrix3d& R = x.R_nb;
	const double roll = std::atan2(R(2, 1), R(2, 2)) * kRad2Deg;
	const double pitch = -std::asin(std::clamp(R(2, 0), -1.0, 1.0)) * kRad2Deg;
	const double yaw = std::atan2(R(1, 0), R(0, 0)) * kRad2Deg;
	std::ostringstream s;
	s.precision(10);
	s << std::fixed << t;
	s.unsetf(std::ios::fixed);
	s << ',' << q.w() << ',' << q.x() << ',' << q.y() << ',' << q.z() << ',' << roll << ',' << pitch << ',' << yaw;
	const TangentVector e = x.euclidean();
	for (int i = 3; i < e.size(); ++i) s << ',' << e[i];
	s << ',' << p.x() << ',' << p.y() << ',' << p.z();
	const auto& P = nav.filter().covariance();
	for (int i = 0; i < P.rows(); ++i) s << ',' << std::sqrt(std::max(P(i, i), 0.0));
	for (int b : {idx::pos, idx::att}) s << ',' << P(b, b + 1) << ',' << P(b, b + 2) << ',' << P(b + 1, b + 2);
	csv_ << s.str() << '\n';
	if (++rows_ % 50 == 0) flush();
}

void RunOutputs::onUpdate(const std::string& label, double t, const UpdateResult& r)
{
	if (r.status != UpdateStatus::Accepted && r.status != UpdateStatus::Recovered) return;
	if (t - nis_t0_ >= 1.0)
	{
		for (const auto& [l, a] : nis_acc_)
		{
			char line[256];
			std::snprintf(line, sizeof line, "%.3f,%s,%zu,%.6g,%zu\n", nis_t0_, l.c_str(), a.n, a.nis, a.dim);
			nis_ << line;
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
	if (updates_.is_open()) updates_.flush();
	tum_.flush();
	csv_.flush();
}

void RunOutputs::onHealthChange(double t_s, NavStatus status, const std::string& reason)
{
	health_ << num(t_s) << ',' << navStatusName(status) << ",\"" << reason << "\"\n";
	health_.flush();
}

void RunOutputs::writeSummary(const Navigator& nav, double wall_s, bool interrupted, const std::string& rawlog,
							  const std::string& error) const
{
	const double data_s = nav.startTime() > 0 ? nav.time() - nav.startTime() : 0.0;
	io::Json j;
	j["rawlog"] = rawlog;
	j["completed"] = !interrupted && error.empty();
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
	j["replayed_predictions"] = nav.replayedPredictions();
	j["cholesky_repairs"] = nav.filter().choleskyRepairs();
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
