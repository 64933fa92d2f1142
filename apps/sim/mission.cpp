#include "mission.h"

#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationThrusters.h>

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>

#include "compass.h"
#include "sensors.h"
#include "sonar.h"

namespace fs = std::filesystem;

namespace auvnav::sim
{
namespace
{
constexpr double kDeg = M_PI / 180;

config::Node loadRelative(const config::Node& mission, const std::string& key)
{
	const std::string p = mission.filePath(key);
	if (!fs::exists(p)) mission.fail(key, "file not found: " + p);
	return config::Node::load(p);
}

/** Number of simulation steps in `period_s`; the period must be a whole
 *  number of steps so that every sensor fires on the grid. */
long stepsOf(double period_s, double dt_s, const config::Node& owner, const std::string& key)
{
	const double n = period_s / dt_s;
	const long k = std::lround(n);
	if (k < 1 || std::abs(n - k) > 1e-6)
		owner.fail(key, "period " + std::to_string(period_s) +
		                    " s is not a whole multiple of the simulation step " + std::to_string(dt_s) +
		                    " s");
	return k;
}

struct Schedule
{
	long every = 1, offset = 0;
	bool due(long k) const { return k >= offset && (k - offset) % every == 0; }
};

/** Text output written line by line and flushed, so a killed run keeps what it made. */
class LineWriter
{
 public:
	explicit LineWriter(const std::string& path) : f_(path)
	{
		if (!f_) throw std::runtime_error("cannot write " + path);
	}
	void line(const std::string& s)
	{
		f_ << s << '\n';
		if (++n_ % 100 == 0) f_.flush();
	}

 private:
	std::ofstream f_;
	std::size_t n_ = 0;
};

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...)
{
	char buf[2048];
	va_list ap;
	va_start(ap, f);
	std::vsnprintf(buf, sizeof buf, f, ap);
	va_end(ap);
	return buf;
}

const char* kCsvHeader =
    "time_s,unix_time_s,north_m,east_m,down_m,latitude_deg,longitude_deg,qw,qx,qy,qz,"
    "roll_deg,pitch_deg,yaw_deg,vn_mps,ve_mps,vd_mps,u_mps,v_mps,w_mps,p_radps,q_radps,r_radps,"
    "current_n_mps,current_e_mps,current_far_n_mps,current_far_e_mps,"
    "gyro_bias_x_radps,gyro_bias_y_radps,gyro_bias_z_radps,"
    "accel_bias_x_mps2,accel_bias_y_mps2,accel_bias_z_mps2,adcp_bias_x_mps,adcp_bias_y_mps,"
    "seabed_depth_m,altitude_m,distance_m,submerged";
}  // namespace

MissionSpec MissionSpec::load(const std::string& mission_file)
{
	MissionSpec s;
	s.mission = config::Node::load(mission_file);
	const auto& m = s.mission;
	s.file = mission_file;
	s.name = m.string("name");
	for (char c : s.name)
		if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'))
			m.fail("name", "use letters, digits, '_' or '-' only (it names the rawlog file)");
	s.vehicle = loadRelative(m, "vehicle");
	s.sensors = loadRelative(m, "sensors");
	// Per-mission sensor settings on top of the shared sensors file, e.g.
	// sensor_overrides: ["sonar.enabled=true"].
	if (m.has("sensor_overrides"))
		for (const auto& kv : m.strings("sensor_overrides"))
		{
			const auto eq = kv.find('=');
			if (eq == std::string::npos || eq == 0)
				m.fail("sensor_overrides", "expected KEY=VALUE, got '" + kv + "'");
			s.sensors.set(kv.substr(0, eq), kv.substr(eq + 1));
		}
	s.environment = m.child("environment");
	if (s.environment.has("pole_map")) s.poles = sonar::PoleMap::load(s.environment.filePath("pole_map"));
	const auto o = s.environment.child("origin");
	s.origin.lat_rad = o.inRange("latitude_deg", -85, 85) * kDeg;
	s.origin.lon_rad = o.inRange("longitude_deg", -180, 180) * kDeg;
	s.origin.h_m = 0;
	const auto st = m.child("start");
	s.start_unix_s = st.nonNegative("unix_time_s");
	const auto ne = st.numbers("position_ne_m");
	if (ne.size() != 2) st.fail("position_ne_m", "expected [north_m, east_m]");
	s.start_ne = {ne[0], ne[1]};
	s.start_heading_rad = st.inRange("heading_deg", -360, 360) * kDeg;
	s.start_depth_m = st.inRange("depth_m", -1, 11000, s.start_depth_m);
	if (m.has("simulation"))
	{
		const auto sim = m.child("simulation");
		s.dt_s = sim.inRange("step_s", 1e-4, 0.1, s.dt_s);
		s.ground_truth_rate_hz = sim.positive("ground_truth_rate_hz", s.ground_truth_rate_hz);
		s.max_duration_s = sim.positive("max_duration_s", s.max_duration_s);
		s.rawlog_compression =
		    static_cast<int>(sim.inRange("rawlog_compression", 0, 9, s.rawlog_compression));
	}
	return s;
}

MissionSummary runMission(const MissionSpec& spec, uint32_t seed, const std::string& out_dir)
{
	fs::create_directories(out_dir);
	const earth::TangentFrame frame(spec.origin);
	Vehicle vehicle(VehicleParams::fromConfig(spec.vehicle));
	Environment env = Environment::fromConfig(spec.environment, seed * 31u + 17u);
	Controller controller(vehicle.params(),
	                      spec.vehicle.has("controller")
	                          ? ControllerGains::fromConfig(spec.vehicle.child("controller"))
	                          : ControllerGains{},
	                      planFromConfig(spec.mission));

	const auto& sc = spec.sensors;
	// Optional sensors: absent, or present with `enabled: false`.
	auto enabled = [&sc](const char* key, bool default_on)
	{ return sc.has(key) && sc.child(key).boolean("enabled", default_on); };
	ImuSim imu(sc.child("imu"), seed);
	DvlSim dvl(sc.child("dvl"), seed);
	// The ADCP object also defines the far-current column of the truth, so it
	// exists whenever it is configured, as before.
	std::unique_ptr<AdcpSim> adcp =
	    sc.has("adcp") ? std::make_unique<AdcpSim>(sc.child("adcp"), seed) : nullptr;
	PressureSim pressure(sc.child("pressure"), seed);
	std::unique_ptr<GpsSim> gps =
	    enabled("gps", true) ? std::make_unique<GpsSim>(sc.child("gps"), seed) : nullptr;
	std::unique_ptr<UsblSim> usbl =
	    enabled("usbl", true) ? std::make_unique<UsblSim>(sc.child("usbl"), seed) : nullptr;
	std::unique_ptr<MagnetometerSim> mag;
	if (enabled("magnetometer", true))
	{
		if (!spec.environment.has("magnetic_field"))
			spec.environment.fail("magnetic_field",
			                      "the sensors file has a magnetometer: give the Earth field "
			                      "{total_intensity_ut, declination_deg, inclination_deg}");
		mag = std::make_unique<MagnetometerSim>(
		    sc.child("magnetometer"), MagneticField::fromConfig(spec.environment.child("magnetic_field")),
		    vehicle.params().thrusters.size(), seed);
	}
	// A compass (compass.h), when the sensors file has one (flatfish_sensors.yaml: disabled).
	std::unique_ptr<CompassSim> compass;
	if (enabled("compass", true))
	{
		const double declination_rad =
		    spec.environment.has("magnetic_field")
		        ? MagneticField::fromConfig(spec.environment.child("magnetic_field")).declination_rad
		        : 0.0;
		compass = std::make_unique<CompassSim>(sc.child("compass"), declination_rad, seed);
	}
	const auto thr_cfg = sc.child("thrusters");
	const std::string thr_label = thr_cfg.string("label", "THRUSTERS");
	const double dt = spec.dt_s;

	const Schedule imu_s{stepsOf(imu.period_s(), dt, sc.child("imu"), "rate_hz"), 0};
	const Schedule dvl_s{stepsOf(dvl.period_s(), dt, sc.child("dvl"), "rate_hz"),
	                     std::lround(dvl.offset_s() / dt)};
	const Schedule adcp_s = adcp ? Schedule{stepsOf(adcp->period_s(), dt, sc.child("adcp"), "rate_hz"),
	                                        std::lround(adcp->offset_s() / dt)}
	                             : Schedule{};
	const Schedule pres_s{stepsOf(pressure.period_s(), dt, sc.child("pressure"), "rate_hz"),
	                      std::lround(pressure.offset_s() / dt)};
	const Schedule gps_s =
	    gps ? Schedule{stepsOf(gps->period_s(), dt, sc.child("gps"), "rate_hz"), 0} : Schedule{};
	const Schedule mag_s = mag ? Schedule{stepsOf(mag->period_s(), dt, sc.child("magnetometer"), "rate_hz"),
	                                      std::lround(mag->offset_s() / dt)}
	                           : Schedule{};
	const Schedule compass_s =
	    compass ? Schedule{stepsOf(compass->period_s(), dt, sc.child("compass"), "rate_hz"),
	                       std::lround(compass->offset_s() / dt)}
	            : Schedule{};
	const Schedule usbl_s =
	    usbl ? Schedule{stepsOf(usbl->period_s(), dt, sc.child("usbl"), "rate_hz"), 0} : Schedule{};
	const Schedule ctl_s{stepsOf(1.0 / thr_cfg.positive("rate_hz"), dt, thr_cfg, "rate_hz"), 0};
	const Schedule truth_s{
	    stepsOf(1.0 / spec.ground_truth_rate_hz, dt, spec.mission, "simulation.ground_truth_rate_hz"), 0};
	const bool use_adcp = adcp && sc.child("adcp").boolean("enabled", true);
	const bool use_sonar = sc.has("sonar") && sc.child("sonar").boolean("enabled", false);
	std::unique_ptr<SonarSim> sonar;
	Schedule sonar_s{1, 0};
	std::unique_ptr<LineWriter> sonar_frames, sonar_truth;
	if (use_sonar)
	{
		sonar = std::make_unique<SonarSim>(sc.child("sonar"), spec.poles, seed);
		sonar_s = {stepsOf(sonar->period_s(), dt, sc.child("sonar"), "rate_hz"),
		           std::lround(sonar->offset_s() / dt)};
		sonar_frames = std::make_unique<LineWriter>((fs::path(out_dir) / "sonar_frames.csv").string());
		sonar_truth = std::make_unique<LineWriter>((fs::path(out_dir) / "sonar_truth.csv").string());
		sonar_frames->line(
		    "unix_time_s,vehicle_north_m,vehicle_east_m,sonar_heading_deg,vehicle_yaw_deg,poles_in_view");
		sonar_truth->line("unix_time_s,pole_id,bearing_deg,range_m");
	}

	// Everything but the logger clocks is read; those are read next. A disabled
	// sensor's section is kept for when it is enabled again: not checked.
	if (!gps) sc.markFreeForm("gps");
	if (!mag) sc.markFreeForm("magnetometer");
	if (!compass) sc.markFreeForm("compass");
	if (!usbl) sc.markFreeForm("usbl");
	if (!use_sonar) sc.markFreeForm("sonar");

	// The logger's clock per sensor (logger_clock.h), each with its own stream.
	auto clockFor = [&](const char* key, long every_steps, uint32_t id)
	{
		if (!sc.has(key)) return LoggerClock{};
		const double period = every_steps * dt;
		return LoggerClock(StampParams::fromConfig(sc.child(key), period), period,
		                   seed * 7919u + id * 104729u + 1u);
	};
	LoggerClock imu_clk = clockFor("imu", imu_s.every, 31), dvl_clk = clockFor("dvl", dvl_s.every, 32),
	            adcp_clk = use_adcp ? clockFor("adcp", adcp_s.every, 33) : LoggerClock{},
	            pres_clk = clockFor("pressure", pres_s.every, 34),
	            gps_clk = gps ? clockFor("gps", gps_s.every, 35) : LoggerClock{},
	            thr_clk = clockFor("thrusters", ctl_s.every, 36),
	            sonar_clk = use_sonar ? clockFor("sonar", sonar_s.every, 37) : LoggerClock{},
	            mag_clk = mag ? clockFor("magnetometer", mag_s.every, 38) : LoggerClock{},
	            compass_clk = compass ? clockFor("compass", compass_s.every, 41) : LoggerClock{},
	            usbl_clk = usbl ? clockFor("usbl", usbl_s.every, 39) : LoggerClock{};
	// Every key of the mission, vehicle and sensors files must have been read.
	spec.mission.checkAllKeysUsed();
	spec.vehicle.checkAllKeysUsed();
	spec.sensors.checkAllKeysUsed();
	double max_jitter_s = 0;
	for (const LoggerClock* c : {&imu_clk, &dvl_clk, &adcp_clk, &pres_clk, &gps_clk, &thr_clk, &sonar_clk,
	                             &mag_clk, &compass_clk, &usbl_clk})
		max_jitter_s = std::max(max_jitter_s, c->maxEarly_s());

	MissionSummary sum;
	sum.rawlog_path = (fs::path(out_dir) / (spec.name + ".rawlog")).string();
	io::RawlogWriter rawlog(sum.rawlog_path, spec.rawlog_compression);
	LineWriter tum((fs::path(out_dir) / "ground_truth.tum").string());
	LineWriter csv((fs::path(out_dir) / "ground_truth.csv").string());
	tum.line(
	    "# timestamp north_m east_m down_m qx qy qz qw  (body FRD origin, NED tangent frame at the mission "
	    "origin)");
	csv.line(kCsvHeader);

	// Observations wait here until no later-sampled one can carry an earlier
	// stamp: keyed by (recorded stamp, sequence), so the rawlog stays in time
	// order, equal stamps keep the simulation order and, without jitter, the
	// rawlog is what it always was.
	std::map<std::pair<mrpt::Clock::rep, std::uint64_t>, mrpt::obs::CObservation::Ptr> pending;
	std::uint64_t sequence = 0;
	auto count = [&](mrpt::obs::CObservation::Ptr o, LoggerClock& clk)
	{
		const LoggerClock::Stamp st = clk.stamp(o->timestamp);
		o->timestamp = st.recorded;
		pending.emplace(std::make_pair(st.recorded.time_since_epoch().count(), sequence++), std::move(o));
	};
	auto flushBefore = [&](mrpt::Clock::rep horizon)
	{
		while (!pending.empty() && pending.begin()->first.first < horizon)
		{
			const auto& o = *pending.begin()->second;
			rawlog.write(o);
			++sum.observations[o.sensorLabel];
			pending.erase(pending.begin());
		}
	};
	const auto jitter_window =
	    std::chrono::duration_cast<mrpt::Clock::duration>(std::chrono::duration<double>(max_jitter_s))
	        .count();

	VehicleState x;
	x.p_n = {spec.start_ne.x(), spec.start_ne.y(), spec.start_depth_m};
	x.q_nb = Eigen::AngleAxisd(spec.start_heading_rad, Eigen::Vector3d::UnitZ());
	x.thrust_n = Eigen::VectorXd::Zero(vehicle.params().thrusters.size());
	Eigen::VectorXd cmd = x.thrust_n;

	for (long k = 0;; ++k)
	{
		const double t = k * dt;
		if (t > spec.max_duration_s) break;
		env.advanceTo(t);
		const Eigen::Vector3d current_n = env.current(x.p_n.z());
		Truth truth;
		truth.t_s = t;
		truth.stamp = mrpt::Clock::fromDouble(spec.start_unix_s + t);
		truth.x = &x;
		truth.current_n = current_n;
		truth.nu_dot_b = vehicle.rates(x, cmd, current_n).nu_dot_b;
		flushBefore(truth.stamp.time_since_epoch().count() - jitter_window);

		if (ctl_s.due(k))
		{
			if (controller.finished())
			{
				sum.plan_completed = true;
				break;
			}
			cmd = controller.command(x, t, ctl_s.every * dt);
			auto thr = auvnav::obs::CObservationThrusters::Create();
			thr->timestamp = truth.stamp;
			thr->sensorLabel = thr_label;
			thr->unit = auvnav::obs::EffortUnit::Force_N;
			thr->effort.assign(cmd.data(), cmd.data() + cmd.size());
			count(thr, thr_clk);
			truth.nu_dot_b = vehicle.rates(x, cmd, current_n).nu_dot_b;
		}
		if (imu_s.due(k)) count(imu.sample(truth, frame), imu_clk);
		if (dvl_s.due(k))
		{
			const auto o = dvl.sample(truth, env);
			sum.dvl_total++;
			sum.dvl_locked += o->bottom_lock;
			count(o, dvl_clk);
		}
		if (use_adcp && adcp_s.due(k))
		{
			const auto o = adcp->sample(truth, env);
			sum.adcp_profiles++;
			for (const auto& c : o->cells) sum.adcp_valid_cells += c.valid;
			count(o, adcp_clk);
		}
		if (use_sonar && sonar_s.due(k))
		{
			std::vector<PoleInView> in_view;
			count(sonar->sample(truth, env, in_view), sonar_clk);
			const Eigen::Matrix3d R = x.R_nb();
			const double unix_t = spec.start_unix_s + t;
			sonar_frames->line(fmt("%.3f,%.4f,%.4f,%.6f,%.6f,%zu", unix_t, x.p_n.x(), x.p_n.y(),
			                       sonar->sonarHeading(truth) / kDeg, std::atan2(R(1, 0), R(0, 0)) / kDeg,
			                       in_view.size()));
			for (const auto& p : in_view)
				sonar_truth->line(
				    fmt("%.3f,%s,%.6f,%.4f", unix_t, p.id.c_str(), p.bearing_rad / kDeg, p.range_m));
			sum.sonar_frames++;
			sum.sonar_poles_in_view += in_view.size();
		}
		if (pres_s.due(k)) count(pressure.sample(truth, env, frame), pres_clk);
		if (gps && gps_s.due(k))
			if (const auto o = gps->sample(truth, frame)) count(o, gps_clk);
		if (mag && mag_s.due(k)) count(mag->sample(truth), mag_clk);
		if (compass && compass_s.due(k)) count(compass->sample(truth), compass_clk);
		// Logged on arrival, after the latency: the pending queue keeps file order.
		if (usbl && usbl_s.due(k))
			if (const auto o = usbl->sample(truth, frame)) count(o, usbl_clk);

		if (truth_s.due(k))
		{
			const Eigen::Matrix3d R = x.R_nb();
			const Eigen::Vector3d v_n = R * x.nu_b.head<3>();
			const earth::Geodetic g = frame.toGeodetic(x.p_n);
			const double roll = std::atan2(R(2, 1), R(2, 2));
			const double pitch = -std::asin(std::clamp(R(2, 0), -1.0, 1.0));
			const double yaw = std::atan2(R(1, 0), R(0, 0));
			const Eigen::Vector3d far = env.current(x.p_n.z() + (adcp ? adcp->farRange_m() : 0.0));
			const double seabed = env.seabedDepth(x.p_n.x(), x.p_n.y());
			const auto& q = x.q_nb;
			const double unix_t = spec.start_unix_s + t;
			tum.line(fmt("%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f", unix_t, x.p_n.x(), x.p_n.y(), x.p_n.z(),
			             q.x(), q.y(), q.z(), q.w()));
			const Eigen::Vector3d bg = imu.gyroBias(), ba = imu.accelBias();
			const Eigen::Vector2d bc = adcp ? adcp->bias() : Eigen::Vector2d::Zero();
			csv.line(
			    fmt("%.3f,%.6f,%.6f,%.6f,%.6f,%.10f,%.10f,%.9f,%.9f,%.9f,%.9f,%.5f,%.5f,%.5f,"
			        "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.7f,%.7f,%.7f,%.6f,%.6f,%.6f,%.6f,"
			        "%.4e,%.4e,%.4e,%.4e,%.4e,%.4e,%.6f,%.6f,%.4f,%.4f,%.4f,%d",
			        t, unix_t, x.p_n.x(), x.p_n.y(), x.p_n.z(), g.lat_rad / kDeg, g.lon_rad / kDeg, q.w(),
			        q.x(), q.y(), q.z(), roll / kDeg, pitch / kDeg, yaw / kDeg, v_n.x(), v_n.y(), v_n.z(),
			        x.nu_b[0], x.nu_b[1], x.nu_b[2], x.nu_b[3], x.nu_b[4], x.nu_b[5], current_n.x(),
			        current_n.y(), far.x(), far.y(), bg.x(), bg.y(), bg.z(), ba.x(), ba.y(), ba.z(), bc.x(),
			        bc.y(), seabed, seabed - x.p_n.z(), sum.distance_m, x.p_n.z() > 0.5 ? 1 : 0));
		}

		const Eigen::Vector3d p_before = x.p_n;
		vehicle.step(x, cmd, current_n, dt);
		const double moved = (x.p_n - p_before).head<2>().norm();
		sum.distance_m += moved;
		if (x.p_n.z() > 0.5) sum.submerged_distance_m += moved;
		sum.max_depth_m = std::max(sum.max_depth_m, x.p_n.z());
		sum.duration_s = t;
		if (!x.p_n.allFinite() || !x.nu_b.allFinite())
			throw std::runtime_error("vehicle state diverged at t = " + std::to_string(t) + " s");
	}
	flushBefore(std::numeric_limits<mrpt::Clock::rep>::max());
	sum.gps_outliers = gps ? gps->outliers() : 0;
	for (const LoggerClock* c : {&imu_clk, &dvl_clk, &adcp_clk, &pres_clk, &gps_clk, &thr_clk, &sonar_clk,
	                             &mag_clk, &compass_clk, &usbl_clk})
	{
		sum.stamp_duplicates += c->duplicates();
		sum.stamp_out_of_order += c->outOfOrder();
	}
	return sum;
}

}  // namespace auvnav::sim
