// Bad input never crashes the navigator and never reaches the state: NaN/Inf
// samples, duplicate and backward timestamps, gaps, observations older than
// the filter, unknown sensors, denial windows.
#include <auvnav/config.h>
#include <auvnav/navigator.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/gnss_messages_ascii_nmea.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>

using namespace auvnav;

namespace
{
const std::string kConfig = std::string(AUVNAV_SOURCE_DIR) + "/config/flatfish.yaml";
constexpr double kT0 = 1492693200.0;

mrpt::obs::CObservationIMU::Ptr imuAt(double t, double fx = 0.0)
{
	using namespace mrpt::obs;
	auto o = CObservationIMU::Create();
	o->sensorLabel = "IMU";
	o->timestamp = mrpt::Clock::fromDouble(t);
	o->set(IMU_WX, 7.1e-5);
	o->set(IMU_WY, 0.0);
	o->set(IMU_WZ, 1.6e-5);
	o->set(IMU_X_ACC, fx);
	o->set(IMU_Y_ACC, 0.0);
	o->set(IMU_Z_ACC, -9.782);
	return o;
}

auvnav::obs::CObservationPressure::Ptr pressureAt(double t, double pa)
{
	auto o = auvnav::obs::CObservationPressure::Create();
	o->sensorLabel = "PRESSURE";
	o->timestamp = mrpt::Clock::fromDouble(t);
	o->pressure_pa = pa;
	o->temperature_c = 20;
	return o;
}

const SensorStats& statsOf(const std::vector<SensorStats>& all, const std::string& label,
                           const std::string& plugin)
{
	for (const auto& s : all)
		if (s.label == label && s.plugin == plugin) return s;
	throw std::runtime_error("no stats for " + label);
}

/** A navigator started at rest with position from the config (no GPS). */
struct Fixture
{
	config::Node cfg = config::Node::load(kConfig);
	PluginHost host;
	std::unique_ptr<Navigator> nav;
	double t = kT0;
	Fixture()
	{
		cfg.set("filter.initial.position", "config");
		nav = std::make_unique<Navigator>(cfg, host);
		for (int k = 0; k < 150; ++k) step();
	}
	void step()
	{
		t += 0.01;
		nav->process(*imuAt(t));
	}
};
}  // namespace

TEST(NavigatorInput, InitialisesFromLevellingAndStaysFinite)
{
	Fixture f;
	ASSERT_TRUE(f.nav->initialized());
	EXPECT_TRUE(f.nav->filter().state().allFinite());
	EXPECT_GT(f.nav->predictions(), 40u);
}

TEST(NavigatorInput, NonFiniteImuSamplesAreCountedAndDropped)
{
	Fixture f;
	const NavState before = f.nav->filter().state();
	const std::size_t preds = f.nav->predictions();
	auto bad = imuAt(f.t + 0.01);
	bad->set(mrpt::obs::IMU_WX, std::numeric_limits<double>::quiet_NaN());
	f.nav->process(*bad);
	auto inf = imuAt(f.t + 0.01);
	inf->set(mrpt::obs::IMU_Z_ACC, std::numeric_limits<double>::infinity());
	f.nav->process(*inf);
	EXPECT_EQ(f.nav->imuStats().invalid, 2u);
	EXPECT_EQ(f.nav->predictions(), preds);
	EXPECT_TRUE(f.nav->filter().state().p_n == before.p_n);
	f.step();  // a good sample afterwards works
	EXPECT_EQ(f.nav->predictions(), preds + 1);
	EXPECT_TRUE(f.nav->filter().state().allFinite());
}

TEST(NavigatorInput, DuplicateAndBackwardImuTimestampsAreRejected)
{
	Fixture f;
	const std::size_t preds = f.nav->predictions();
	f.nav->process(*imuAt(f.t));        // duplicate
	f.nav->process(*imuAt(f.t - 0.5));  // backwards
	EXPECT_EQ(f.nav->imuStats().invalid, 2u);
	EXPECT_EQ(f.nav->predictions(), preds);
	EXPECT_NE(f.nav->imuStats().last_problem.find("backwards"), std::string::npos);
}

TEST(NavigatorInput, ImuGapIsBridgedAndCounted)
{
	Fixture f;
	f.t += 2.0;  // 2 s without IMU
	f.nav->process(*imuAt(f.t));
	EXPECT_EQ(f.nav->imuGaps(), 1u);
	EXPECT_TRUE(f.nav->filter().state().allFinite());
	EXPECT_NEAR(f.nav->time(), f.t, 1e-6);
}

TEST(NavigatorInput, NanPressureIsInvalidAndNeverReachesTheState)
{
	Fixture f;
	const NavState before = f.nav->filter().state();
	const Covariance P = f.nav->filter().covariance();
	f.nav->process(*pressureAt(f.t, std::numeric_limits<double>::quiet_NaN()));
	f.nav->process(*pressureAt(f.t, std::numeric_limits<double>::infinity()));
	const auto& s = statsOf(f.nav->stats(), "PRESSURE", "pressure");
	EXPECT_EQ(s.invalid, 2u);
	EXPECT_EQ(s.accepted, 0u);
	EXPECT_TRUE(f.nav->filter().state().p_n == before.p_n);
	EXPECT_TRUE(f.nav->filter().covariance() == P);
	// A good one is accepted and moves depth toward 10 m.
	f.nav->process(*pressureAt(f.t, 101325 + 1025 * 9.782 * (10.0 + 0.3)));
	EXPECT_EQ(statsOf(f.nav->stats(), "PRESSURE", "pressure").accepted, 1u);
	EXPECT_GT(f.nav->filter().state().p_n.z(), before.p_n.z() + 1.0);
}

TEST(NavigatorInput, LateObservationsAndDeniedSensorsAreCountedNotApplied)
{
	Fixture f;
	const NavState before = f.nav->filter().state();
	f.nav->process(*pressureAt(f.t - 5.0, 200000));  // 5 s older than the filter
	EXPECT_EQ(statsOf(f.nav->stats(), "PRESSURE", "pressure").late, 1u);
	f.nav->addDenial({{"PRESSURE"}, 0.0, 1e9});
	f.nav->process(*pressureAt(f.t, 200000));
	EXPECT_EQ(statsOf(f.nav->stats(), "PRESSURE", "pressure").denied, 1u);
	EXPECT_TRUE(f.nav->filter().state().p_n == before.p_n);
}

TEST(NavigatorInput, UnknownSensorsAndWrongClassesAreHarmless)
{
	Fixture f;
	auto other = pressureAt(f.t, 150000);
	other->sensorLabel = "NOT_CONFIGURED";
	f.nav->process(*other);
	// A DVL observation arriving under the pressure label: the plugin refuses the class.
	auto dvl = auvnav::obs::CObservationDVL::Create();
	dvl->sensorLabel = "PRESSURE";
	dvl->timestamp = mrpt::Clock::fromDouble(f.t);
	f.nav->process(*dvl);
	EXPECT_EQ(statsOf(f.nav->stats(), "PRESSURE", "pressure").invalid, 1u);
	EXPECT_TRUE(f.nav->filter().state().allFinite());
}

TEST(NavigatorInput, FirstFixComesFromTheFixSensorsPluginAtItsAntenna)
{
	// position: gps starts from the GPS plugin's initialFix: the antenna's
	// point, moved to the body origin with the initial attitude, once
	// fix_consensus.min_fixes (5) fixes agree; a wild first one is outvoted.
	config::Node cfg = config::Node::load(kConfig);
	cfg.set("filter.initial.heading_deg", "90");
	cfg.set("sensors.GPS.config.position_m.0", "-0.3");
	cfg.set("sensors.GPS.config.position_m.1", "0.1");
	PluginHost host;
	Navigator nav(cfg, host);
	double t = kT0;
	for (int k = 0; k < 150; ++k) nav.process(*imuAt(t += 0.01));  // past the levelling
	EXPECT_FALSE(nav.initialized());
	EXPECT_NE(nav.waitingFor().find("GPS fix"), std::string::npos) << nav.waitingFor();
	auto gpsAt = [&](const Eigen::Vector3d& p_n)
	{
		auto gps = mrpt::obs::CObservationGPS::Create();
		gps->sensorLabel = "GPS";
		gps->timestamp = mrpt::Clock::fromDouble(t + 0.005);
		mrpt::obs::gnss::Message_NMEA_GGA gga;
		const earth::Geodetic geo = nav.frame().toGeodetic(p_n);
		gga.fields.latitude_degrees = geo.lat_rad * 180 / M_PI;
		gga.fields.longitude_degrees = geo.lon_rad * 180 / M_PI;
		gga.fields.fix_quality = 1;
		gps->setMsg(gga);
		nav.process(*gps);
		for (int k = 0; k < 100; ++k) nav.process(*imuAt(t += 0.01));
	};
	gpsAt(Eigen::Vector3d(1050, -20, 0));  // wild: 1 km north
	for (int i = 0; i < 4; ++i)
	{
		gpsAt(Eigen::Vector3d(50, -20, 0));
		EXPECT_FALSE(nav.initialized()) << "after " << i + 2 << " fixes, " << i + 1 << " agreeing";
	}
	EXPECT_NE(nav.waitingFor().find("4 of 5 agree;"), std::string::npos) << nav.waitingFor();
	gpsAt(Eigen::Vector3d(50.5, -20, 0));
	ASSERT_TRUE(nav.initialized());
	// Heading 90°: body x points east, y south. The antenna at (−0.3, 0.1) in
	// the body is 0.3 m west and 0.1 m south of the origin, so the origin is
	// 0.3 m east and 0.1 m north of the fix (the newest agreeing one).
	const Eigen::Vector3d p = nav.bodyPosition_n();
	EXPECT_NEAR(p.x(), 50.5 + 0.1, 0.02);
	EXPECT_NEAR(p.y(), -20 + 0.3, 0.02);
}

TEST(NavigatorInput, WithoutAFixConsensusSectionTheDefaultsStartFromFiveFixes)
{
	// Profiles that predate filter.initial.fix_consensus (compass_hello.yaml)
	// keep working with position: gps and get the defaults.
	std::ifstream file(kConfig);
	std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
	const auto from = text.find("    fix_consensus:"), to = text.find("    north_m:");
	ASSERT_NE(from, std::string::npos);
	ASSERT_LT(from, to);
	text.erase(from, to - from);
	const config::Node cfg = config::Node::fromText(text, kConfig);
	ASSERT_FALSE(cfg.child("filter").child("initial").has("fix_consensus"));
	PluginHost host;
	Navigator nav(cfg, host);
	double t = kT0;
	for (int k = 0; k < 150; ++k) nav.process(*imuAt(t += 0.01));  // past the levelling
	EXPECT_NE(nav.waitingFor().find("5 agreeing GPS fixes"), std::string::npos) << nav.waitingFor();
}

TEST(NavigatorInput, FixLabelNamingNoSensorIsAConfigError)
{
	config::Node cfg = config::Node::load(kConfig);
	cfg.set("filter.initial.gps_label", "GNSS");
	PluginHost host;
	try
	{
		Navigator nav(cfg, host);
		FAIL() << "accepted a gps_label that names no sensor";
	}
	catch (const config::ConfigError& e)
	{
		EXPECT_NE(std::string(e.what()).find("filter.initial.gps_label"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("'GNSS'"), std::string::npos) << e.what();
	}
}

TEST(NavigatorInput, ForwardClockJumpStopsWithAClearErrorByDefault)
{
	for (double jump : {3600.0, 1e9})
	{
		Fixture f;
		const std::size_t preds = f.nav->predictions();
		try
		{
			f.nav->process(*imuAt(f.t + jump));
			ADD_FAILURE() << "a " << jump << " s jump was predicted through";
		}
		catch (const std::runtime_error& e)
		{
			EXPECT_NE(std::string(e.what()).find("clock jumped by +"), std::string::npos) << e.what();
			EXPECT_NE(std::string(e.what()).find("clock.on_jump"), std::string::npos) << e.what();
		}
		EXPECT_EQ(f.nav->predictions(), preds);  // not one blind step
		EXPECT_TRUE(f.nav->filter().state().allFinite());
	}
}

TEST(NavigatorInput, ClockJumpsReinitialiseWhenConfiguredAndNothingAfterThemIsLost)
{
	for (double jump : {3600.0, -3600.0, 1e9})
	{
		config::Node cfg = config::Node::load(kConfig);
		cfg.set("filter.initial.position", "config");
		cfg.set("clock.on_jump", "reinitialize");
		PluginHost host;
		Navigator nav(cfg, host);
		double t = kT0;
		for (int k = 0; k < 150; ++k) nav.process(*imuAt(t += 0.01));
		ASSERT_TRUE(nav.initialized());
		const std::size_t preds = nav.predictions();
		t += jump;
		nav.process(*imuAt(t));
		EXPECT_EQ(nav.clockJumps(), 1u) << jump;
		EXPECT_FALSE(nav.initialized()) << jump;  // levelling again
		EXPECT_NE(nav.imuStats().last_problem.find("re-initialised"), std::string::npos)
		    << nav.imuStats().last_problem;
		for (int k = 0; k < 150; ++k) nav.process(*imuAt(t += 0.01));
		// Initialised again after the levelling second, predicting from the new clock on.
		EXPECT_TRUE(nav.initialized()) << jump;
		EXPECT_GT(nav.predictions(), preds + 40) << jump;
		EXPECT_NEAR(nav.time(), t, 1e-6) << jump;
		EXPECT_TRUE(nav.filter().state().allFinite());
		EXPECT_LT(nav.filter().state().p_n.head<2>().norm(), 1.0) << jump;  // no hour of blind drift
		// Readings on the new clock are used.
		nav.process(*pressureAt(t, 101325 + 1025 * 9.782 * (2.0 + 0.3)));
		EXPECT_EQ(statsOf(nav.stats(), "PRESSURE", "pressure").accepted, 1u) << jump;
	}
}

TEST(NavigatorInput, ASmallBackwardStepDropsTheSampleAndAReadingFromTheFutureIsRefused)
{
	Fixture f;
	const std::size_t preds = f.nav->predictions();
	f.nav->process(*imuAt(f.t - 0.5));  // within clock.max_backward_jump_s: dropped
	EXPECT_EQ(f.nav->predictions(), preds);
	EXPECT_EQ(f.nav->imuStats().invalid, 1u);
	const NavState before = f.nav->filter().state();
	f.nav->process(*pressureAt(f.t + 3600, 101325 + 1025 * 9.782 * (20.0 + 0.3)));
	const auto& s = statsOf(f.nav->stats(), "PRESSURE", "pressure");
	EXPECT_EQ(s.invalid, 1u);
	EXPECT_NE(s.last_problem.find("ahead of the IMU"), std::string::npos) << s.last_problem;
	EXPECT_TRUE(f.nav->filter().state().p_n == before.p_n);
}

TEST(NavigatorInput, BadClockConfigIsRefusedWithTheKey)
{
	PluginHost host;
	for (const auto& [key, value] :
	     std::vector<std::pair<std::string, std::string>>{{"clock.on_jump", "ignore"},
	                                                      {"clock.max_forward_jump_s", "0"},
	                                                      {"clock.max_forward_jump_s", "0.2"}})
	{
		config::Node cfg = config::Node::load(kConfig);
		cfg.set(key, value);
		try
		{
			Navigator nav(cfg, host);
			ADD_FAILURE() << key << "=" << value << " accepted";
		}
		catch (const config::ConfigError& e)
		{
			// 0.2 s is shorter than imu.max_gap_s (0.5 s): named there.
			const std::string name = value == "0.2" ? "max_gap_s" : key.substr(key.rfind('.') + 1);
			EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
		}
	}
}
