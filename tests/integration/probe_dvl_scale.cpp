// Probe (not a test; EXCLUDE_FROM_ALL): the DVL scale-factor state on the square
// mission, as tests/integration/test_plugin_states.cpp runs it, with the
// simulator's DVL errors off unless given.
// usage: probe_dvl_scale SEED [s:KEY=VAL (sensor file)] [e:KEY=VAL (environment)]
//        [n:KEY=VAL (navigator, applied last)] [m:KEY=VAL (mission)] [nofilter] [nostates] [keep]
// Prints: the simulated DVL against the truth (least-squares scale of its
// velocity, surface / submerged) and the GPS fixes against the truth (mean
// error, error-vs-north slope); then, with the states on, the scale and
// misalignment estimates every 300 s, at the dive and at resurfacing, how much
// each sensor's updates moved the scale estimate (per phase), the mean DVL
// innovation along the measured velocity, the filter's horizontal velocity
// against the truth, and the update statistics. E.g. perfect GPS fixes:
//   probe_dvl_scale 1 s:gps.white_sigma_m=0 s:gps.correlated_sigma_m=0 s:gps.outlier_probability=0
#include <auvnav/config.h>
#include <auvnav/earth.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/navigator.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/so3.h>
#include <mrpt/obs/CObservationGPS.h>

#include <unistd.h>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>

#include "harness.h"
#include "mission.h"

namespace fs = std::filesystem;
using namespace auvnav;
using namespace auvnav::test;

namespace
{
constexpr double kDeg = M_PI / 180;
Eigen::Matrix3d yprDeg(const Eigen::Vector3d& ypr)
{
	return (Eigen::AngleAxisd(ypr[0] * kDeg, Eigen::Vector3d::UnitZ()) *
	        Eigen::AngleAxisd(ypr[1] * kDeg, Eigen::Vector3d::UnitY()) *
	        Eigen::AngleAxisd(ypr[2] * kDeg, Eigen::Vector3d::UnitX()))
	    .toRotationMatrix();
}
Eigen::Vector3d pointAt(const std::vector<TruthRow>& truth, double t, const Eigen::Vector3d& r_b)
{
	const auto tr = truthAt(truth, t);
	return tr.p_n + tr.q_nb.toRotationMatrix() * r_b;
}
struct Acc
{
	double vm = 0, vv = 0, mm = 0;
	int n = 0;
	void add(const Eigen::Vector3d& truth, const Eigen::Vector3d& meas)
	{
		vm += truth.dot(meas);
		vv += truth.dot(truth);
		mm += meas.dot(meas);
		++n;
	}
	double scale() const { return vm / vv - 1; }
};
}  // namespace

int main(int argc, char** argv)
{
	if (argc < 2) return 2;
	const unsigned seed = std::stoul(argv[1]);
	auto spec = sim::MissionSpec::load(std::string(AUVNAV_SOURCE_DIR) + "/config/missions/square_5x50m.yaml");
	auto cfg = config::Node::load(std::string(AUVNAV_SOURCE_DIR) + "/config/flatfish.yaml");
	bool filter = true, keep = false, nostates = false;
	Eigen::Vector3d mis(0, 0, 0);
	std::vector<std::pair<std::string, std::string>> nav_sets;
	spec.sensors.set("dvl.scale_factor_error", "0");
	for (int i = 0; i < 3; ++i) spec.sensors.set("dvl.misalignment_ypr_deg." + std::to_string(i), "0");
	for (int a = 2; a < argc; ++a)
	{
		const std::string s = argv[a];
		if (s == "nofilter")
		{
			filter = false;
			continue;
		}
		if (s == "keep")
		{
			keep = true;
			continue;
		}
		if (s == "nostates")
		{
			nostates = true;
			continue;
		}
		const auto eq = s.find('=');
		const std::string k = s.substr(2, eq - 2), v = s.substr(eq + 1);
		if (s[0] == 's') spec.sensors.set(k, v);
		if (s[0] == 'e') spec.environment.set(k, v);
		if (s[0] == 'n') nav_sets.emplace_back(k, v);
		if (s[0] == 'm') spec.mission.set(k, v);
		if (s[0] == 's' && k.rfind("dvl.misalignment_ypr_deg.", 0) == 0) mis[k.back() - '0'] = std::stod(v);
	}
	const fs::path dir =
	    fs::temp_directory_path() / ("probe_dvl_" + std::to_string(seed) + "_" + std::to_string(::getpid()));
	fs::remove_all(dir);
	sim::runMission(spec, seed, dir.string());
	const auto truth = readTruth(dir / "ground_truth.csv");
	const auto [dive, surf] = diveAndResurfacing(truth);
	const double t_dive = truth[dive].t_unix, t_surf = truth[surf].t_unix;
	const std::string rawlog = (dir / (spec.name + ".rawlog")).string();

	// ---- data: DVL against truth, GPS against truth
	const Eigen::Vector3d r_dvl = spec.sensors.child("dvl").vector3("position_m");
	const Eigen::Vector3d r_gps = spec.sensors.child("gps").vector3("position_m");
	const Eigen::Matrix3d R_bs =
	    yprDeg(spec.sensors.child("dvl").vector3("orientation_ypr_deg")) * yprDeg(mis);
	const earth::TangentFrame frame(
	    earth::Geodetic{cfg.child("navigation_frame").child("origin").number("latitude_deg") * kDeg,
	                    cfg.child("navigation_frame").child("origin").number("longitude_deg") * kDeg, 0});
	Acc surf_h, sub_h, sub_v, all_v;
	double gps_en = 0, gps_ee = 0, gps_nn = 0, gps_mean_n = 0, gps_mean_e = 0;
	int gps_n = 0;
	double gps_path_truth = 0, gps_path_fix = 0;
	Eigen::Vector3d prev_fix = Eigen::Vector3d::Zero(), prev_true = Eigen::Vector3d::Zero();
	bool have_prev = false;
	io::RawlogReader rd(rawlog);
	while (auto o = rd.next())
	{
		const double t = mrpt::Clock::toDouble(o->timestamp);
		if (auto d = std::dynamic_pointer_cast<obs::CObservationDVL>(o))
		{
			if (!d->bottom_lock || t < truth.front().t_unix + 1 || t > truth.back().t_unix - 1) continue;
			const double h = 0.05;
			const Eigen::Vector3d v_true =
			    (pointAt(truth, t + h, r_dvl) - pointAt(truth, t - h, r_dvl)) / (2 * h);
			const Eigen::Matrix3d R_nb = truthAt(truth, t).q_nb.toRotationMatrix();
			const Eigen::Vector3d v_meas =
			    R_nb * R_bs *
			    Eigen::Vector3d(d->velocity_s_mps[0], d->velocity_s_mps[1], d->velocity_s_mps[2]);
			const bool submerged = t > t_dive && t < t_surf;
			Eigen::Vector3d th = v_true, mh = v_meas;
			th.z() = 0;
			mh.z() = 0;
			(submerged ? sub_h : surf_h).add(th, mh);
			Eigen::Vector3d tv(0, 0, v_true.z()), mv(0, 0, v_meas.z());
			if (submerged) sub_v.add(tv, mv);
			all_v.add(tv, mv);
		}
		else if (auto g = std::dynamic_pointer_cast<mrpt::obs::CObservationGPS>(o))
		{
			if (!g->has_GGA_datum()) continue;
			const auto& f = g->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>().fields;
			const Eigen::Vector3d p =
			    frame.toNed(earth::Geodetic{f.latitude_degrees * kDeg, f.longitude_degrees * kDeg,
			                                f.altitude_meters + f.geoidal_distance});
			const Eigen::Vector3d tr = pointAt(truth, t, r_gps);
			const Eigen::Vector3d e = p - tr;
			if (e.head<2>().norm() > 8) continue;  // outliers
			gps_mean_n += e.x();
			gps_mean_e += e.y();
			gps_nn += tr.x() * tr.x();
			gps_en += e.x() * tr.x();
			gps_ee += e.y() * tr.y();
			++gps_n;
			if (have_prev)
			{
				gps_path_fix += (p - prev_fix).head<2>().norm();
				gps_path_truth += (tr - prev_true).head<2>().norm();
			}
			prev_fix = p;
			prev_true = tr;
			have_prev = true;
		}
	}
	std::printf(
	    "DATA seed %u: DVL horiz scale-1: surface %+.4f %% (%d), submerged %+.4f %% (%d); vertical submerged "
	    "%+.4f %%, all %+.4f %%\n",
	    seed, 100 * surf_h.scale(), surf_h.n, 100 * sub_h.scale(), sub_h.n, 100 * sub_v.scale(),
	    100 * all_v.scale());
	std::printf(
	    "DATA GPS: %d fixes, mean error N %.3f E %.3f m, error-vs-north slope %+.4f %%, path fix/truth-1 "
	    "%+.4f %%\n",
	    gps_n, gps_mean_n / std::max(gps_n, 1), gps_mean_e / std::max(gps_n, 1), 100 * gps_en / gps_nn,
	    100 * (gps_path_fix / gps_path_truth - 1));
	if (!filter)
	{
		if (!keep) fs::remove_all(dir);
		return 0;
	}

	// ---- filter with the states on
	const double t0 = truth.front().t_unix;
	cfg.set("filter.initial.heading_deg",
	        std::to_string(yawOf(truth.front().q_nb.toRotationMatrix()) / kDeg + 10));
	cfg.set("filter.initial.heading_sigma_deg", "30");
	if (!nostates)
	{
		cfg.set("sensors.DVL.config.states.scale_factor.sigma", "0.01");
		cfg.set("sensors.DVL.config.states.misalignment.sigma_deg", "2");
	}
	for (const auto& [k, v] : nav_sets) cfg.set(k, v);
	PluginHost host;
	Navigator nav(cfg, host);
	nav.addDenial({{"GPS"}, t_dive - t0, 1e9});
	nav.addDenial({{"ADCP", "THRUSTERS"}, 0.0, 1e9});
	double next_print = 0;
	bool at_dive = false, at_surf = false;
	auto print = [&](const Navigator& n, const char* tag)
	{
		const auto& x = n.filter().state();
		if (x.extra.size() == 0)
		{
			std::printf("  %-6s t=%6.0f s  err %.2f m\n", tag, n.time() - t0,
			            (n.bodyPosition_n() - truthAt(truth, n.time()).p_n).head<2>().norm());
			return;
		}
		const auto& C = n.filter().covariance();
		const auto tr = truthAt(truth, n.time());
		const double err = (n.bodyPosition_n() - tr.p_n).head<2>().norm();
		std::printf(
		    "  %-6s t=%6.0f s  scale %+.3f %% (%.3f)  mis %.2f %.2f %.2f deg  err %.2f m  sig_v %.4f %.4f "
		    "corr_sv %.3f\n",
		    tag, n.time() - t0, 100 * x.extra[0], 100 * std::sqrt(C(idx::extra, idx::extra)),
		    x.extra[1] / kDeg, x.extra[2] / kDeg, x.extra[3] / kDeg, err, std::sqrt(C(idx::vel, idx::vel)),
		    std::sqrt(C(idx::vel + 1, idx::vel + 1)),
		    C(idx::vel, idx::extra) / std::sqrt(C(idx::vel, idx::vel) * C(idx::extra, idx::extra)));
	};
	RunCallbacks cb;
	double last_scale = 0;
	std::map<std::string, double> moved;  // phase/label -> sum of scale changes
	auto phase = [&](double t) { return t < t_dive ? "surface" : t < t_surf ? "submerged" : "after"; };
	std::map<std::string, std::pair<double, int>> innov;  // phase/label -> sum of innovation along z
	cb.on_update = [&](const std::string& label, double t_obs, const Measurement& m, const UpdateResult& r)
	{
		if (label == "DVL" && r.innovation.size() == 3 && m.z.size() == 3 && m.z.norm() > 0.1)
		{
			auto& a = innov[std::string(phase(t_obs)) + "/along"];
			a.first += r.innovation.dot(m.z.normalized());
			++a.second;
			auto& b = innov[std::string(phase(t_obs)) + "/along_rel"];
			b.first += r.innovation.dot(m.z) / m.z.squaredNorm();
			++b.second;
		}
		if (nav.filter().state().extra.size() == 0) return;
		const double s = nav.filter().state().extra[0];
		moved[std::string(phase(t_obs)) + "/" + label] += s - last_scale;
		last_scale = s;
	};
	const Eigen::Vector3d r_imu = cfg.child("imu").vector3("position_m");
	Acc fv_surf, fv_sub;
	double verr2 = 0, vvar = 0;
	int nverr = 0;
	double next_v = 0;
	cb.on_predict = [&](const Navigator& n)
	{
		if (n.time() >= next_v && n.time() > truth.front().t_unix + 5 && n.time() < truth.back().t_unix - 1)
		{
			next_v = n.time() + 0.5;
			const double h = 0.05, t = n.time();
			Eigen::Vector3d v_true = (pointAt(truth, t + h, r_imu) - pointAt(truth, t - h, r_imu)) / (2 * h);
			Eigen::Vector3d v_f = n.filter().state().v_n;
			v_true.z() = 0;
			v_f.z() = 0;
			(t < t_dive ? fv_surf : fv_sub).add(v_true, v_f);
			if (t > t0 + 600)
			{
				const auto& C = n.filter().covariance();
				verr2 += (v_f - v_true).squaredNorm() / 2;
				vvar += (C(idx::vel, idx::vel) + C(idx::vel + 1, idx::vel + 1)) / 2;
				++nverr;
			}
		}
		if (n.filter().state().extra.size() == 0) return;
		const double s = n.filter().state().extra[0];
		moved[std::string(phase(n.time())) + "/(predict)"] += s - last_scale;
		last_scale = s;
		if (n.time() >= next_print)
		{
			next_print = std::floor(n.time() / 300) * 300 + 300;
			print(n, "");
		}
		if (!at_dive && n.time() >= t_dive)
		{
			at_dive = true;
			print(n, "DIVE");
		}
		if (!at_surf && n.time() >= t_surf)
		{
			at_surf = true;
			print(n, "SURF");
		}
	};
	const auto run = runRawlog(nav, rawlog, cb);
	run.rethrow();
	for (const auto& st : run.stats)
		std::printf(
		    "  stats %-10s acc %zu rec %zu rej %zu inv %zu skip %zu late %zu delayed %zu NIS/dim %.3f\n",
		    st.label.c_str(), st.accepted, st.recovered, st.rejected, st.invalid, st.skipped, st.late,
		    st.delayed, st.nis_sum / std::max(st.nis_dim_sum, 1.0));
	std::printf("  filter horizontal velocity / truth - 1: surface %+.4f %% (%d), submerged %+.4f %% (%d)\n",
	            100 * fv_surf.scale(), fv_surf.n, 100 * fv_sub.scale(), fv_sub.n);
	std::printf("  horizontal velocity error rms %.4f m/s, filter sigma rms %.4f m/s\n",
	            std::sqrt(verr2 / nverr), std::sqrt(vvar / nverr));
	for (const auto& [k, v] : innov)
		std::printf("  DVL innovation %-18s mean %+.6f (%d)\n", k.c_str(), v.first / std::max(v.second, 1),
		            v.second);
	for (const auto& [k, v] : moved) std::printf("  moved %-22s %+.3f %%\n", k.c_str(), 100 * v);
	if (!keep)
		fs::remove_all(dir);
	else
		std::printf("kept %s\n", dir.c_str());
	return 0;
}
