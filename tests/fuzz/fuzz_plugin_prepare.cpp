// libFuzzer harness: every core plugin's prepare (and predict on what it
// prepares) on an observation deserialised from arbitrary bytes.
//
// Input: byte 0 picks the plugin (modulo their number), the rest is a plain
// rawlog read by RawlogReader, as the navigator reads one: objects it
// refuses never reach a plugin; every observation it returns, of any class,
// is handed to measurementTime, initialFix and prepare with a nominal filter
// context, and predict runs on every measurement prepared.
// Plugins catch their own exceptions (SafeMeasurementModel), so a finding is
// a sanitizer report, a hang or a prepared measurement whose sizes disagree.
#include <auvnav/config.h>
#include <auvnav/earth.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/measurement_model.h>
#include <auvnav/state_layout.h>
#include <mrpt/obs/CObservation.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>

#include "adcp.h"
#include "ahrs.h"
#include "dvl.h"
#include "fuzz_support.h"
#include "gps.h"
#include "inertial.h"
#include "magnetometer.h"
#include "model_aiding.h"
#include "pressure.h"
#include "sonar_heading.h"
#include "usbl.h"

using namespace auvnav;
using namespace auvnav::fuzz;

namespace
{
/** A plugin built from its default configuration (plugins/<name>/<name>.yaml). */
template <class Model>
std::unique_ptr<MeasurementModel> make(const char* name)
{
	const std::string dir = std::string(AUVNAV_SOURCE_DIR) + "/plugins/" + name;
	try
	{
		auto cfg = config::Node::load(dir + "/" + name + ".yaml");
		cfg.set("config_dir", dir);  // as the navigator does: the plugin's files are relative to it
		return std::make_unique<Model>(cfg, name);
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "fuzz_plugin_prepare: %s not fuzzed, its default config is refused: %s\n", name,
		             e.what());
		return nullptr;
	}
}

struct Plugins
{
	std::vector<std::unique_ptr<MeasurementModel>> models;
	earth::TangentFrame frame{earth::Geodetic{53.1 * M_PI / 180, 8.8 * M_PI / 180, 0.0}};
	NavState mean;
	Covariance P;
	FilterContext ctx;

	Plugins()
	{
		models.push_back(make<plugins::AdcpModel>("adcp"));
		models.push_back(make<plugins::AhrsModel>("ahrs"));
		models.push_back(make<plugins::DvlModel>("dvl"));
		models.push_back(make<plugins::GpsModel>("gps"));
		models.push_back(make<plugins::InertialModel>("inertial"));
		models.push_back(make<plugins::MagnetometerModel>("magnetometer"));
		models.push_back(make<plugins::ModelAidingModel>("model_aiding"));
		models.push_back(make<plugins::PressureModel>("pressure"));
		models.push_back(make<plugins::SonarHeadingModel>("sonar_heading"));
		models.push_back(make<plugins::UsblModel>("usbl"));
		// Plugin-owned states after the core 43, checked and bound by the navigator's own code.
		static const std::string label = "FUZZ", plugin = "fuzzed";
		std::vector<LabelledModel> labelled;
		for (auto& m : models)
			if (m) labelled.push_back({label, plugin, *m});
		ProcessModel pm;
		Covariance P0 = Covariance::Identity(idx::core_dim, idx::core_dim);
		appendPluginStates(labelled, pm, P0);
		mean.extra = ExtraVector::Zero(pm.dim() - idx::core_dim);
		mean.p_n << 10, -5, 20;
		mean.v_n << 1.2, 0.1, 0.05;
		P = Covariance::Identity(mean.dim(), mean.dim()) * 0.01;
		ctx.frame = &frame;
		ctx.omega_ie_n = frame.earthRate();
		ctx.mean = &mean;
		ctx.covariance = &P;
	}
};
}  // namespace

namespace
{
void feed(MeasurementModel& model, const Plugins& plugins, const mrpt::obs::CObservation& obs)
{
	FilterContext ctx = plugins.ctx;
	const double stamp = mrpt::Clock::toDouble(obs.timestamp);
	ctx.t_s = ctx.t_measurement_s = model.measurementTime(obs, stamp);
	InitialFix fix;
	(void)model.initialFix(obs, ctx, fix);
	std::vector<Measurement> out;
	std::string why;
	if (model.prepare(obs, ctx, out, why) != PrepareStatus::Ok) return;
	for (const auto& m : out)
	{
		if (m.skipped) continue;
		FUZZ_CHECK(m.R.rows() == m.z.size() && m.R.cols() == m.z.size(), "R is not m x m");
		Eigen::VectorXd z_pred = Eigen::VectorXd::Zero(m.z.size());
		if (!model.predict(plugins.mean, m, ctx, z_pred)) continue;
		Eigen::VectorXd r(m.z.size());
		model.residual(m.z, z_pred, r);
	}
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size)
{
	static Plugins plugins;
	if (size < 2) return 0;
	auto& model = plugins.models[data[0] % plugins.models.size()];
	if (!model) return 0;
	const MemFile file(data + 1, size - 1);
	try
	{
		auvnav::io::RawlogReader reader(file.path());
		while (auto obs = reader.next()) feed(*model, plugins, *obs);
	}
	catch (const auvnav::io::RawlogError&)
	{
		// refused by the reader: what follows never reaches a plugin
	}
	return 0;
}
