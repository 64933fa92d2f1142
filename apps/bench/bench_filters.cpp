// auvnav-bench, BM_FastVsDenseFilter: the fast ManifoldUkf against the plain
// dense reference UKF (auvnav/testing/reference_ukf.h, 87 sigma points, full
// propagation and h on every point) on the same recorded filter steps, timed
// in one run so that their ratio does not depend on the machine.
//
// The steps come from bench/cut_120s.rawlog (the committed first 120 s of
// the sample, every sensor): the navigator starts on it as auvnav-run does,
// then the next AUVNAV_BENCH_FILTER_SECONDS (default 20) s of IMU
// predictions and sensor measurements are recorded with the real plugins.
// Each iteration replays them through both filters; the dense one applies
// the updates the fast one accepted (it has no gate), as in the reference
// tests. Counters: µs per IMU tick of each, their ratio, and the largest
// difference of the final means in σ units (a check that both did the same).
#include <auvnav/config.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/navigator.h>
#include <auvnav/plugin_host.h>
#include <auvnav/ukf.h>
#include <benchmark/benchmark.h>
#include <mrpt/obs/CObservationIMU.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <auvnav/testing/reference_ukf.h>

namespace
{
using namespace auvnav;

std::string sourceDir()
{
	const char* s = std::getenv("AUVNAV_SOURCE_DIR");
	return s ? s : AUVNAV_SOURCE_DIR_DEFAULT;
}

/** One recorded filter step: a prediction, or an update by `model`. */
struct Step
{
	bool is_prediction = false;
	Eigen::Vector3d omega_ib_b = Eigen::Vector3d::Zero();
	double dt_s = 0;
	const MeasurementModel* model = nullptr;
	Measurement measurement;
	FilterContext ctx;
};

struct FilterTrace
{
	PluginHost host;  // declared first: outlives the models
	std::map<std::string, ModelPtr> models;
	std::unique_ptr<Navigator> nav;  // holds the start state, the process model and the frame
	NavState x0;
	Covariance P0;
	std::vector<Step> steps;
	int ticks = 0;

	FilterTrace()
	{
		const auto cfg = config::Node::load(sourceDir() + "/config/flatfish.yaml");
		nav = std::make_unique<Navigator>(cfg, host);
		for (const auto& s : cfg.sequence("sensors"))
			if (s.string("label") != "GPS")
				models.emplace(s.string("label"),
				               host.create(s.string("plugin"), pluginConfigText(s), s.string("label")));
		io::RawlogReader reader(sourceDir() + "/bench/cut_120s.rawlog");
		mrpt::obs::CObservation::Ptr o;
		while (!nav->initialized() && (o = reader.next())) nav->process(*o);
		if (!nav->initialized())
			throw std::runtime_error("bench/cut_120s.rawlog: the navigator never initialised");
		x0 = nav->filter().state();
		P0 = nav->filter().covariance();
		const char* sec = std::getenv("AUVNAV_BENCH_FILTER_SECONDS");
		const double t_end = nav->time() + (sec ? std::atof(sec) : 20.0);
		// A fast filter follows the recording, so that each measurement is
		// prepared at the state it will meet (ctx.mean).
		ManifoldUkf fast(nav->filter().processModel(), nav->filter().utParams());
		fast.initialize(x0, P0);
		FilterContext ctx;
		ctx.omega_ie_n = nav->frame().earthRate();
		ctx.imu_position_b = nav->imuPosition_b();
		ctx.frame = &nav->frame();
		ctx.current_far_distance_m = nav->filter().processModel().current_far_distance_m;
		double t = nav->time();
		while ((o = reader.next()) && t < t_end)
		{
			const double t_obs = mrpt::Clock::toDouble(o->timestamp);
			if (o->sensorLabel == "IMU")
			{
				const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(o.get());
				Step p;
				p.is_prediction = true;
				p.omega_ib_b = {imu->get(mrpt::obs::IMU_WX), imu->get(mrpt::obs::IMU_WY),
				                imu->get(mrpt::obs::IMU_WZ)};
				p.dt_s = t_obs - t;
				if (p.dt_s <= 0) continue;
				fast.predict(p.omega_ib_b, ctx.omega_ie_n, p.dt_s);
				steps.push_back(p);
				++ticks;
				ctx.omega_ib_b = p.omega_ib_b;
				t = t_obs;
			}
			const auto it = models.find(o->sensorLabel);
			if (it == models.end()) continue;
			ctx.t_s = t;
			ctx.t_measurement_s = t;
			ctx.mean = &fast.state();
			ctx.covariance = &fast.covariance();
			std::vector<Measurement> ms;
			std::string why;
			if (it->second->prepare(*o, ctx, ms, why) != PrepareStatus::Ok) continue;
			for (const auto& m : ms)
			{
				if (m.skipped) continue;
				Step u;
				u.model = it->second.get();
				u.measurement = m;
				u.ctx = ctx;
				u.ctx.mean = nullptr;  // set to the replaying filter's state
				u.ctx.covariance = nullptr;
				steps.push_back(u);
				fast.update(*it->second, m, ctx);
			}
		}
	}
};

FilterTrace& trace()
{
	static FilterTrace t;
	return t;
}

void BM_FastVsDenseFilter(benchmark::State& state)
{
	auto& tr = trace();
	using Clock = std::chrono::steady_clock;
	double fast_s = 0, dense_s = 0, worst_sd = 0;
	for (auto _ : state)
	{
		const NavState& x0 = tr.x0;
		ManifoldUkf fast(tr.nav->filter().processModel(), tr.nav->filter().utParams());
		fast.initialize(x0, tr.P0);
		std::vector<char> accepted(tr.steps.size(), 0);
		auto t0 = Clock::now();
		for (std::size_t i = 0; i < tr.steps.size(); ++i)
		{
			const Step& s = tr.steps[i];
			if (s.is_prediction)
				fast.predict(s.omega_ib_b, tr.nav->frame().earthRate(), s.dt_s);
			else
			{
				FilterContext ctx = s.ctx;
				ctx.mean = &fast.state();
				accepted[i] = fast.update(*s.model, s.measurement, ctx).status == UpdateStatus::Accepted;
			}
		}
		fast_s += std::chrono::duration<double>(Clock::now() - t0).count();

		reference::ReferenceUkf dense(tr.nav->filter().processModel(), tr.nav->filter().utParams());
		dense.initialize(x0, tr.P0);
		t0 = Clock::now();
		for (std::size_t i = 0; i < tr.steps.size(); ++i)
		{
			const Step& s = tr.steps[i];
			if (s.is_prediction)
				dense.predict(s.omega_ib_b, tr.nav->frame().earthRate(), s.dt_s);
			else if (accepted[i])
			{
				FilterContext ctx = s.ctx;
				ctx.mean = &dense.state();
				dense.update(*s.model, s.measurement, ctx);
			}
		}
		dense_s += std::chrono::duration<double>(Clock::now() - t0).count();
		const TangentVector sd = dense.covariance().diagonal().cwiseSqrt();
		worst_sd =
		    std::max(worst_sd, (fast.state().boxminus(dense.state()).array().abs() / sd.array()).maxCoeff());
	}
	const double ticks = double(tr.ticks) * double(state.iterations());
	state.counters["imu_ticks"] = tr.ticks;
	state.counters["fast_us_per_tick"] = 1e6 * fast_s / ticks;
	state.counters["dense_us_per_tick"] = 1e6 * dense_s / ticks;
	state.counters["dense_over_fast"] = dense_s / fast_s;
	state.counters["worst_mean_diff_sd"] = worst_sd;
	// Both filters did the same only if their means agree (the reference
	// tests' bound): a ratio of two different computations means nothing.
	if (!(worst_sd < 1e-6))
	{
		std::fprintf(stderr, "auvnav-bench: fast and dense filters disagree by %.3g sd\n", worst_sd);
		std::exit(3);
	}
}
}  // namespace

BENCHMARK(BM_FastVsDenseFilter)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
