#include <auvnav/navigator_config.h>
#include <auvnav/process_model_config.h>
#include <auvnav/state.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace fs = std::filesystem;

namespace auvnav
{
namespace
{
constexpr double kDeg = M_PI / 180;

/** Rows x, y; columns x, y, ψ of the 6x6 diagonal matrix given by its
 *  diagonal, in the state's stored form (logarithms on the diagonal). */
Eigen::Matrix<double, 2, 3> subMatrix(const config::Node& n, const std::string& key)
{
	const auto d = n.numbers(key);
	if (d.size() != 6) n.fail(key, "expected 6 diagonal values");
	if (!(d[0] > 0) || !(d[1] > 0)) n.fail(key, "surge and sway entries must be positive");
	Eigen::Matrix<double, 2, 3> m = Eigen::Matrix<double, 2, 3>::Zero();
	m(0, 0) = d[0];
	m(1, 1) = d[1];
	return storedSub(m);
}

void put23(TangentVector& t, int at, const Eigen::Matrix<double, 2, 3>& m)
{
	for (int r = 0; r < 2; ++r)
		for (int c = 0; c < 3; ++c) t[at + 3 * r + c] = m(r, c);
}

ImuConfig readImu(const config::Node& imu)
{
	ImuConfig c;
	c.label = imu.string("label");
	c.position_b = imu.vector3("position_m");
	c.leveling_s = imu.inRange("leveling_s", 0.01, 600, c.leveling_s);
	c.max_gap_s = imu.inRange("max_gap_s", 0.01, 10, c.max_gap_s);
	c.angular_acceleration_tau_s =
	    imu.inRange("angular_acceleration_tau_s", 0.01, 10, c.angular_acceleration_tau_s);
	return c;
}

UtParams readUnscented(const config::Node& u)
{
	UtParams ut;
	ut.alpha = u.inRange("alpha", 1e-4, 1.0, ut.alpha);
	ut.beta = u.nonNegative("beta", ut.beta);
	ut.kappa = u.number("kappa", ut.kappa);
	ut.max_attitude_spread_rad = u.inRange("max_attitude_spread_deg", 1, 170, 30) * kDeg;
	return ut;
}

DelayedFusionParams readDelayed(const config::Node& d)
{
	DelayedFusionParams p;
	p.max_delay_s = d.inRange("max_delay_s", 0, 600, p.max_delay_s);
	p.apply_now_within_s = d.inRange("apply_now_within_s", 0, 1, p.apply_now_within_s);
	p.checkpoint_every_s = d.inRange("checkpoint_every_s", 0.001, 10, p.checkpoint_every_s);
	return p;
}

/** The initial covariance of the 43 states from filter.initial; the model
 *  parameters' σ are their process's steady-state σ. */
Covariance readInitialCovariance(const config::Node& in, const ProcessModel& pm)
{
	Covariance P0 = Covariance::Zero(idx::core_dim, idx::core_dim);
	auto set3 = [&](int at, double sigma) { P0.block<3, 3>(at, at).diagonal().setConstant(sigma * sigma); };
	const double rp = in.positive("roll_pitch_sigma_deg") * kDeg;
	P0(0, 0) = P0(1, 1) = rp * rp;
	P0(2, 2) = std::pow(in.positive("heading_sigma_deg") * kDeg, 2);
	set3(idx::gyro_bias, in.positive("gyro_bias_sigma_deg_per_h") * kDeg / 3600);
	set3(idx::acc, in.positive("acceleration_sigma_mps2"));
	P0(idx::gravity, idx::gravity) = std::pow(in.positive("gravity_sigma_mps2"), 2);
	set3(idx::acc_bias, in.positive("accel_bias_sigma_mg") * 1e-3 * 9.80665);
	set3(idx::vel, in.positive("velocity_sigma_mps"));
	set3(idx::pos, in.positive("position_sigma_m"));
	const double sc = in.positive("current_sigma_mps");
	P0.block<4, 4>(idx::current_vehicle, idx::current_vehicle).diagonal().setConstant(sc * sc);
	const double sb = in.positive("adcp_bias_sigma_mps");
	P0.block<2, 2>(idx::adcp_bias, idx::adcp_bias).diagonal().setConstant(sb * sb);
	for (int i = 0; i < 18; ++i)
		P0(idx::inertia + i, idx::inertia + i) = std::pow(std::max(pm.noise.parameter_sigma[i], 1e-6), 2);
	return P0;
}

InitialStateConfig readInitialState(const config::Node& in)
{
	InitialStateConfig c;
	const std::string position_source = in.string("position", "config");
	if (position_source != "gps" && position_source != "config")
		in.fail("position", "expected 'gps' or 'config', got '" + position_source + "'");
	c.position_from_fix = position_source == "gps";
	if (in.has("fix_consensus"))
	{
		const auto f = in.child("fix_consensus");
		FixConsensusParams& p = c.fix_consensus;
		p.min_fixes = static_cast<int>(f.inRange("min_fixes", 1, 100, p.min_fixes));
		p.max_spread_m = f.positive("max_spread_m", p.max_spread_m);
		p.window_s = f.positive("window_s", p.window_s);
	}
	c.fix_label = in.string("gps_label", "GPS");
	c.heading_rad = in.inRange("heading_deg", -360, 360) * kDeg;
	c.north_m = in.number("north_m", 0.0);
	c.east_m = in.number("east_m", 0.0);
	c.depth_m = in.number("depth_m", 0.0);
	return c;
}

ClockParams readClock(const config::Node& c)
{
	ClockParams p;
	p.max_forward_jump_s = c.inRange("max_forward_jump_s", 0.02, 3600, p.max_forward_jump_s);
	p.max_backward_jump_s = c.inRange("max_backward_jump_s", 0.0, 3600, p.max_backward_jump_s);
	const std::string action = c.string("on_jump", "stop");
	if (action != "stop" && action != "reinitialize")
		c.fail("on_jump", "expected stop or reinitialize, got '" + action + "'");
	p.stop_on_jump = action == "stop";
	return p;
}

SmootherParams readSmoother(const config::Node& sm)
{
	SmootherParams p;
	sm.allowOnly({"keep_every_s", "across_recoveries"});
	p.keep_every_s = sm.inRange("keep_every_s", 0.005, 3600, p.keep_every_s);
	p.across_recoveries = sm.boolean("across_recoveries", p.across_recoveries);
	return p;
}

AidingParams readGates(const config::Node& g)
{
	AidingParams p;
	g.allowOnly({"recovery_after_s", "consistent_rejections", "consistency_probability", "position_reinit"});
	p.recovery_after_s = g.positive("recovery_after_s", p.recovery_after_s);
	p.consistent_rejections =
	    static_cast<int>(g.inRange("consistent_rejections", 0, 8, p.consistent_rejections));
	if (p.consistent_rejections > 0 && p.consistent_rejections < 3)
		g.fail("consistent_rejections", "needs at least 3 rejections to fit a drift (0 switches it off)");
	p.consistency_probability =
	    g.inRange("consistency_probability", 0.5, 1.0 - 1e-9, p.consistency_probability);
	if (g.has("position_reinit"))
	{
		const auto r = g.child("position_reinit");
		p.reinit_fixes = static_cast<int>(r.inRange("rejected_fixes", 0, 16, p.reinit_fixes));
		if (p.reinit_fixes == 1)
			r.fail("rejected_fixes", "needs at least 2 fixes to agree (0 switches it off)");
		p.reinit_probability = r.inRange("probability", 0.5, 1.0 - 1e-9, p.reinit_probability);
		p.reinit_spread_m = r.positive("max_spread_m", p.reinit_spread_m);
	}
	return p;
}

DenialWindow readDenial(const config::Node& d)
{
	DenialWindow w;
	w.from_s = d.nonNegative("from_s");
	w.to_s = d.positive("to_s");
	if (w.to_s <= w.from_s) d.fail("to_s", "must be after from_s");
	for (const auto& l : d.strings("labels")) w.labels.push_back(l);
	return w;
}

/** `text` as a finite number of seconds, the whole of it. */
bool parseSeconds(const std::string& text, double& out)
{
	if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
	char* end = nullptr;
	out = std::strtod(text.c_str(), &end);
	return end == text.c_str() + text.size() && std::isfinite(out);
}
SensorEntry readSensor(const config::Node& s)
{
	SensorEntry e;
	e.label = s.string("label");
	e.plugin = s.string("plugin");
	e.latency_s = s.inRange("latency_s", 0, 600, 0.0);
	s.markFreeForm("config");  // the plugin checks its own keys
	// Observation libraries the entry declares are the program's to load
	// before the rawlog is opened (obs_libraries.h); accepted here.
	if (s.has("obs_libs"))
		(void)(s.isSequence("obs_libs") ? s.strings("obs_libs").size() : s.string("obs_libs").size());
	e.config_yaml = pluginConfigText(s);
	e.config_origin = s.has("config_file") ? s.filePath("config_file") : s.where("config");
	return e;
}
}  // namespace

std::string pluginConfigText(const config::Node& s)
{
	// Inline `config`, or `config_file` relative to the navigator's file.
	if (s.has("config") && s.has("config_file")) s.fail("config_file", "give either config or config_file");
	config::Node plugin_cfg = s.has("config")        ? s.child("config")
	                          : s.has("config_file") ? s.loadFile("config_file")
	                                                 : config::Node::fromText("{}", s.file());
	// Plugins receive YAML text: tell them where relative paths in it start.
	const std::string origin = s.has("config_file") ? s.filePath("config_file") : s.file();
	if (!plugin_cfg.has("config_dir"))
		plugin_cfg.set("config_dir", fs::absolute(fs::path(origin)).parent_path().string());
	return plugin_cfg.toYaml();
}

DenialWindow parseDenial(const std::string& text)
{
	const auto fail = [&](const std::string& why)
	{ throw config::ConfigError(why + " (expected LABEL:FROM:TO, seconds)"); };
	const auto a = text.find(':');
	const auto b = a == std::string::npos ? a : text.find(':', a + 1);
	if (b == std::string::npos || text.find(':', b + 1) != std::string::npos) fail("not three fields");
	DenialWindow w;
	w.labels = {text.substr(0, a)};
	if (w.labels[0].empty()) fail("no sensor label");
	const std::string from = text.substr(a + 1, b - a - 1), to = text.substr(b + 1);
	if (!parseSeconds(from, w.from_s)) fail("FROM '" + from + "' is not a number");
	if (!parseSeconds(to, w.to_s)) fail("TO '" + to + "' is not a number");
	if (!(w.from_s >= 0 && w.to_s > w.from_s)) fail("need 0 <= FROM < TO");
	return w;
}

NavigatorConfig NavigatorConfig::fromNode(const config::Node& cfg)
{
	NavigatorConfig c;
	const auto nf = cfg.child("navigation_frame").child("origin");
	c.origin = {nf.inRange("latitude_deg", -85, 85) * kDeg, nf.inRange("longitude_deg", -180, 180) * kDeg,
	            nf.number("height_m", 0.0)};
	const auto imu = cfg.child("imu");
	c.imu = readImu(imu);

	const auto f = cfg.child("filter");
	// The parameter prior: inline `vehicle_model`, or `vehicle_model_file`
	// (relative to this config file) shared with the model-aiding plugin.
	const auto vm = f.has("vehicle_model_file") ? f.loadFile("vehicle_model_file") : f.child("vehicle_model");
	put23(c.prior_mean, idx::inertia, subMatrix(vm, "inertia_diag"));
	put23(c.prior_mean, idx::damping_lin, subMatrix(vm, "linear_damping_diag"));
	put23(c.prior_mean, idx::damping_quad, subMatrix(vm, "quadratic_damping_diag"));
	c.process = processModelFromConfig(f.child("process_noise"), c.prior_mean);
	if (f.has("unscented")) c.unscented = readUnscented(f.child("unscented"));
	c.earth_rate = f.boolean("earth_rate", true);
	if (f.has("delayed_measurements")) c.delayed = readDelayed(f.child("delayed_measurements"));
	const auto in = f.child("initial");
	c.P0 = readInitialCovariance(in, c.process);
	c.initial = readInitialState(in);

	if (cfg.has("clock")) c.clock = readClock(cfg.child("clock"));
	if (c.imu.max_gap_s > c.clock.max_forward_jump_s)
		imu.fail("max_gap_s", "must not exceed clock.max_forward_jump_s (" +
		                          std::to_string(c.clock.max_forward_jump_s) +
		                          " s): longer steps are clock jumps, not gaps");
	if (cfg.has("health")) c.health = HealthLimits::fromConfig(cfg.child("health"));
	if (cfg.has("smoother")) c.smoother = readSmoother(cfg.child("smoother"));
	if (cfg.has("gates")) c.gates = readGates(cfg.child("gates"));
	if (cfg.has("denial"))
		for (const auto& d : cfg.sequence("denial")) c.denial.push_back(readDenial(d));
	for (const auto& s : cfg.sequence("sensors")) c.sensors.push_back(readSensor(s));

	if (c.initial.position_from_fix)
	{
		bool found = false;
		for (const auto& s : c.sensors) found = found || s.label == c.initial.fix_label;
		if (!found)
			in.fail("gps_label", "'" + c.initial.fix_label +
			                         "' is not the label of any entry in sensors: (the first fix comes "
			                         "from that sensor's plugin)");
	}
	// Its keys name plugin states too: checked once the plugins are loaded.
	if (f.has("sigma_limits"))
	{
		c.sigma_limits = f.child("sigma_limits");
		f.markFreeForm("sigma_limits");
	}
	// Every key must have been read: a misspelled one is an error, not a default.
	// plugin_paths and outputs belong to the program (auvnav-run checks them).
	cfg.checkAllKeysUsed({"plugin_paths", "outputs"});
	return c;
}

}  // namespace auvnav
