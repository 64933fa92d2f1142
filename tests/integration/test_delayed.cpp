// Delayed measurements (navigator.h): a measurement that arrives after later
// IMU samples is applied at its own time by re-filtering, and the result is
// the one in-order processing gives.
#include <auvnav/config.h>
#include <auvnav/navigator.h>
#include <auvnav/obs/CObservationPressure.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>

#include <cmath>
#include <map>

using namespace auvnav;

namespace
{
const std::string kConfig = std::string(AUVNAV_SOURCE_DIR) + "/config/flatfish.yaml";
constexpr double kT0 = 1492693200.0;

/** An IMU sample of a vehicle accelerating gently forward and turning. */
mrpt::obs::CObservationIMU::Ptr imuAt(double t)
{
	using namespace mrpt::obs;
	auto o = CObservationIMU::Create();
	o->sensorLabel = "IMU";
	o->timestamp = mrpt::Clock::fromDouble(t);
	const double s = t - kT0;
	o->set(IMU_WX, 7.1e-5);
	o->set(IMU_WY, 0.0);
	o->set(IMU_WZ, s > 1.5 ? 0.02 : 1.6e-5);
	o->set(IMU_X_ACC, s > 1.5 ? 0.05 : 0.0);
	o->set(IMU_Y_ACC, 0.0);
	o->set(IMU_Z_ACC, -9.782);
	return o;
}

mrpt::obs::CObservation::Ptr pressureAt(double t, double depth_m)
{
	auto o = auvnav::obs::CObservationPressure::Create();
	o->sensorLabel = "PRESSURE";
	o->timestamp = mrpt::Clock::fromDouble(t);
	o->pressure_pa = 101325 + 1025 * 9.782 * (depth_m + 0.3);
	o->temperature_c = 20;
	return o;
}

const SensorStats& statsOf(const Navigator& nav, const std::string& label, const std::string& plugin)
{
	for (const auto& s : nav.stats())
		if (s.label == label && s.plugin == plugin) return s;
	throw std::runtime_error("no stats for " + label);
}

/** The navigator of config/flatfish.yaml, position from the config; the
 *  pressure plugin without its bias floor (which reads the covariance in
 *  prepare, so a replay would keep the first pass's noise). */
std::unique_ptr<Navigator> makeNavigator(PluginHost& host,
                                         const std::map<std::string, std::string>& extra = {})
{
	config::Node cfg = config::Node::load(kConfig);
	cfg.set("filter.initial.position", "config");
	cfg.set("sensors.PRESSURE.config.bias_sigma_pa", "0");
	for (const auto& [k, v] : extra) cfg.set(k, v);
	return std::make_unique<Navigator>(cfg, host);
}

/** Feeds 8 s of IMU at 100 Hz and 7 pressure readings every 0.5 s from 2 s on
 *  (depth 1.0, 1.1, 1.2 … m), each arriving `delay_s` after it was taken. */
void feed(Navigator& nav, double delay_s, double latency_in_stamp_s = 0)
{
	std::multimap<double, mrpt::obs::CObservation::Ptr> arrivals;
	for (int k = 1; k <= 800; ++k) arrivals.emplace(kT0 + 0.01 * k, imuAt(kT0 + 0.01 * k));
	int n = 0;
	for (double t = kT0 + 2.005; t < kT0 + 5.5; t += 0.5)
	{
		// The stamp is the measurement time plus what the logger added (latency_s knows it).
		arrivals.emplace(t + delay_s + 1e-6, pressureAt(t + latency_in_stamp_s, 1.0 + 0.1 * n++));
	}
	for (const auto& [t, o] : arrivals) nav.process(*o);
}

double maxStateDifference(const Navigator& a, const Navigator& b)
{
	return a.filter().state().boxminus(b.filter().state()).cwiseAbs().maxCoeff();
}
}  // namespace

TEST(DelayedMeasurements, ReFilteringEqualsInOrderProcessing)
{
	PluginHost host;
	auto in_order = makeNavigator(host), delayed = makeNavigator(host);
	feed(*in_order, 0.0);
	feed(*delayed, 1.3);  // each reading arrives after 130 more IMU samples
	const auto& s = statsOf(*delayed, "PRESSURE", "pressure");
	EXPECT_EQ(s.delayed, 7u);
	EXPECT_EQ(s.accepted, 7u);
	EXPECT_EQ(s.late, 0u);
	EXPECT_EQ(statsOf(*in_order, "PRESSURE", "pressure").delayed, 0u);
	EXPECT_GT(delayed->replayedPredictions(), 7u * 130u);
	const double dx = maxStateDifference(*in_order, *delayed);
	std::printf("re-filtered vs in order: state %.3g, %zu re-predictions for %zu predictions\n", dx,
	            delayed->replayedPredictions(), delayed->predictions());
	EXPECT_LT(dx, 1e-9);
	const double P_scale = in_order->filter().covariance().cwiseAbs().maxCoeff();
	EXPECT_LT((in_order->filter().covariance() - delayed->filter().covariance()).cwiseAbs().maxCoeff(),
	          1e-9 * P_scale);
	// The depths reached the state: the last reading said 1.6 m.
	EXPECT_GT(delayed->filter().state().p_n.z(), 1.3);
}

TEST(DelayedMeasurements, AppliedAtArrivalTheyGiveAnotherEstimate)
{
	// The same readings stamped with their arrival time (a latency nobody
	// declared) are applied 1.3 s late: the estimate differs measurably.
	PluginHost host;
	auto in_order = makeNavigator(host), naive = makeNavigator(host);
	feed(*in_order, 0.0);
	feed(*naive, 1.3, 1.3);
	EXPECT_EQ(statsOf(*naive, "PRESSURE", "pressure").delayed, 0u);
	EXPECT_GT(maxStateDifference(*in_order, *naive), 1e-3);
}

TEST(DelayedMeasurements, ConfiguredLatencyGivesTheMeasurementTime)
{
	// Stamped on arrival, declared by the sensor entry's latency_s: as in order.
	PluginHost host;
	auto in_order = makeNavigator(host),
	     declared = makeNavigator(host, {{"sensors.PRESSURE.latency_s", "1.3"}});
	feed(*in_order, 0.0);
	feed(*declared, 1.3, 1.3);
	EXPECT_EQ(statsOf(*declared, "PRESSURE", "pressure").delayed, 7u);
	EXPECT_LT(maxStateDifference(*in_order, *declared), 1e-9);
}

TEST(DelayedMeasurements, OlderThanMaxDelayIsLateAndLeavesTheStateAlone)
{
	PluginHost host;
	auto nav = makeNavigator(host, {{"filter.delayed_measurements.max_delay_s", "1.0"}});
	auto reference = makeNavigator(host, {{"filter.delayed_measurements.max_delay_s", "1.0"}});
	feed(*nav, 1.3);
	for (int k = 1; k <= 800; ++k) reference->process(*imuAt(kT0 + 0.01 * k));
	const auto& s = statsOf(*nav, "PRESSURE", "pressure");
	EXPECT_EQ(s.late, 7u);
	EXPECT_EQ(s.delayed, 0u);
	EXPECT_NE(s.last_problem.find("max_delay_s"), std::string::npos) << s.last_problem;
	EXPECT_TRUE(nav->filter().state().p_n == reference->filter().state().p_n);
	EXPECT_TRUE(nav->filter().state().R_nb == reference->filter().state().R_nb);
	EXPECT_TRUE(nav->filter().covariance() == reference->filter().covariance());
}

TEST(DelayedMeasurements, SwitchedOffEverythingLateIsCountedLate)
{
	PluginHost host;
	auto nav = makeNavigator(host, {{"filter.delayed_measurements.max_delay_s", "0"}});
	feed(*nav, 1.3);
	EXPECT_EQ(statsOf(*nav, "PRESSURE", "pressure").late, 7u);
	EXPECT_EQ(nav->replayedPredictions(), 0u);
}

TEST(DelayedMeasurements, BadDelayConfigIsRefusedWithTheKey)
{
	PluginHost host;
	for (const auto& [key, value] :
	     std::map<std::string, std::string>{{"filter.delayed_measurements.max_delay_s", "-1"},
	                                        {"filter.delayed_measurements.checkpoint_every_s", "0"},
	                                        {"filter.delayed_measurements.max_dealy_s", "5"},
	                                        {"sensors.PRESSURE.latency_s", "-0.5"}})
	{
		try
		{
			makeNavigator(host, {{key, value}});
			ADD_FAILURE() << key << "=" << value << " accepted";
		}
		catch (const config::ConfigError& e)
		{
			const std::string last = key.substr(key.rfind('.') + 1);
			EXPECT_NE(std::string(e.what()).find(last), std::string::npos) << e.what();
		}
	}
}
