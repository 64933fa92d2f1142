// Unit tests of the example "compass" plugin with the auvnav plugin SDK
// (auvnav/testing/model_checks.h): the model contract on random states, the
// angle wrapping, invalid input, a filter update across ±180°, the built
// module loading through the navigator's plugin host, the plugin's own
// observation class and its own state (heading bias).
#include <auvnav/plugin_host.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/testing/plugin_state_bench.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "CObservationCompass.h"
#include "compass.h"

using compass_example::CompassModel;
namespace at = auvnav::testing;

namespace
{
constexpr double kDeg = M_PI / 180;

mrpt::obs::CObservationIMU::Ptr compassObs(double heading_rad)
{
	auto o = mrpt::obs::CObservationIMU::Create();
	o->sensorLabel = "COMPASS";
	o->set(mrpt::obs::IMU_YAW, heading_rad);
	return o;
}

auvnav::config::Node configText(const std::string& yaml)
{
	return auvnav::config::Node::fromText(yaml, "test");
}

std::string readFile(const std::string& path)
{
	std::ifstream f(path);
	std::stringstream s;
	s << f.rdbuf();
	return s.str();
}

double residual(const CompassModel& m, double z, double h)
{
	Eigen::VectorXd r(1);
	m.residual(Eigen::VectorXd::Constant(1, z), Eigen::VectorXd::Constant(1, h), r);
	return r[0];
}
}  // namespace

TEST(Compass, DefaultConfig)
{
	const CompassModel m(auvnav::config::Node::load(COMPASS_DEFAULT_CONFIG), "COMPASS");
	EXPECT_DOUBLE_EQ(m.declination_rad(), 0);
	EXPECT_DOUBLE_EQ(m.sigma_rad(), 2 * kDeg);
	EXPECT_DOUBLE_EQ(m.gateProbability(), 0.999);
	EXPECT_EQ(m.uses(), uint32_t(auvnav::kAttitude));
}

TEST(Compass, RejectsBadConfigNamingTheKey)
{
	for (const char* bad : {"sigma_deg: -1", "sigma_deg: 0", "sigma_deg: 120", "declination_deg: 400",
	                        "gate_probability: 0", "gate_probability: 2"})
	{
		try
		{
			CompassModel m(configText(bad), "COMPASS");
			ADD_FAILURE() << "accepted " << bad;
		}
		catch (const auvnav::config::ConfigError& e)
		{
			const std::string key = std::string(bad).substr(0, std::string(bad).find(':'));
			EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
		}
	}
}

TEST(Compass, WellFormedOnRandomStates)
{
	at::TestContext tc;
	CompassModel model(configText("{declination_deg: -23}"), "COMPASS");
	for (uint32_t seed = 1; seed <= 20; ++seed)
	{
		at::WellFormedOptions opt;
		opt.seed = seed;
		opt.accept_skip = false;
		const double heading = (seed * 37.0 - 180) * kDeg;
		EXPECT_TRUE(at::IsWellFormed(model, *compassObs(heading), tc.ctx(), at::RandomNavState(seed), opt))
		    << "seed " << seed;
	}
}

TEST(Compass, PredictsTheYawOfTheAttitude)
{
	at::TestContext tc;
	CompassModel model(configText("{}"), "COMPASS");
	std::vector<auvnav::Measurement> out;
	std::string why;
	ASSERT_EQ(model.prepare(*compassObs(0.1), tc.ctx(), out, why), auvnav::PrepareStatus::Ok) << why;
	for (double yaw_deg : {-179.0, -90.0, -12.5, 0.0, 45.0, 135.0, 180.0})
		for (double pitch_deg : {-40.0, 0.0, 25.0})
		{
			auvnav::NavState x;
			x.R_nb = at::rotationYpr(yaw_deg * kDeg, pitch_deg * kDeg, 17 * kDeg);
			EXPECT_NEAR(at::Predict(model, out[0], tc.ctx(), x)[0], auvnav::wrapAngle(yaw_deg * kDeg), 1e-12)
			    << yaw_deg << " " << pitch_deg;
		}
}

TEST(Compass, ResidualWrapsIntoMinusPiPi)
{
	const CompassModel m(configText("{}"), "COMPASS");
	EXPECT_NEAR(residual(m, 179 * kDeg, -179 * kDeg), -2 * kDeg, 1e-12);
	EXPECT_NEAR(residual(m, -179 * kDeg, 179 * kDeg), 2 * kDeg, 1e-12);
	EXPECT_NEAR(residual(m, 10 * kDeg, 5 * kDeg), 5 * kDeg, 1e-12);
	EXPECT_DOUBLE_EQ(residual(m, M_PI, -M_PI), 0);
	EXPECT_DOUBLE_EQ(residual(m, -M_PI, 0), M_PI);  // (−π, π]: −π maps to π
	for (double a = -20; a <= 20; a += 0.37)
	{
		const double w = residual(m, a, 0);
		EXPECT_GT(w, -M_PI);
		EXPECT_LE(w, M_PI);
		EXPECT_NEAR(std::cos(w), std::cos(a), 1e-12);
		EXPECT_NEAR(std::sin(w), std::sin(a), 1e-12);
	}
}

TEST(Compass, DeclinationIsAddedAndWrapped)
{
	at::TestContext tc;
	CompassModel model(configText("{declination_deg: 20}"), "COMPASS");
	std::vector<auvnav::Measurement> out;
	std::string why;
	ASSERT_EQ(model.prepare(*compassObs(170 * kDeg), tc.ctx(), out, why), auvnav::PrepareStatus::Ok);
	ASSERT_EQ(out.size(), 1u);
	EXPECT_NEAR(out[0].z[0], -170 * kDeg, 1e-12);
	EXPECT_NEAR(out[0].R(0, 0), std::pow(2 * kDeg, 2), 1e-15);
}

TEST(Compass, InvalidInputs)
{
	at::TestContext tc;
	CompassModel model(configText("{}"), "COMPASS");
	std::vector<auvnav::Measurement> out;
	std::string why;
	for (double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL})
	{
		why.clear();
		EXPECT_EQ(model.prepare(*compassObs(bad), tc.ctx(), out, why), auvnav::PrepareStatus::Invalid) << bad;
		EXPECT_TRUE(out.empty());
		EXPECT_NE(why.find("non-finite"), std::string::npos) << why;
	}
	auto no_yaw = mrpt::obs::CObservationIMU::Create();
	no_yaw->set(mrpt::obs::IMU_WZ, 0.01);
	EXPECT_EQ(model.prepare(*no_yaw, tc.ctx(), out, why), auvnav::PrepareStatus::Invalid);
	EXPECT_NE(why.find("IMU_YAW"), std::string::npos) << why;
	EXPECT_EQ(model.prepare(*mrpt::obs::CObservationGPS::Create(), tc.ctx(), out, why),
	          auvnav::PrepareStatus::Invalid);
	EXPECT_NE(why.find("CObservationIMU"), std::string::npos) << why;
}

TEST(Compass, UpdateCorrectsHeadingAcrossTheWrap)
{
	at::TestContext tc;
	CompassModel model(configText("{sigma_deg: 1}"), "COMPASS");
	// Truth 179°, estimate −179° (2° off across ±180°): the update must turn
	// the estimate 2° towards the truth, not 358° the other way.
	auvnav::NavState x0;
	x0.R_nb = at::rotationYpr(-179 * kDeg, 0, 0);
	auvnav::ManifoldUkf ukf(auvnav::ProcessModel{}, auvnav::UtParams{});
	ukf.initialize(x0, at::TypicalCovariance());
	const auto res = at::ApplyObservation(ukf, model, *compassObs(179 * kDeg), tc.ctx());
	ASSERT_EQ(res.status, auvnav::PrepareStatus::Ok) << res.why;
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, auvnav::UpdateStatus::Accepted) << res.updates[0].why;
	const double err_after = std::abs(auvnav::wrapAngle(CompassModel::yawOf(ukf.state().R_nb) - 179 * kDeg));
	EXPECT_LT(err_after, 1.0 * kDeg) << "heading error 2 deg -> " << err_after / kDeg << " deg";
	EXPECT_LT(ukf.covariance()(2, 2), std::pow(2 * kDeg, 2));
	// Position untouched (uncorrelated in P0).
	EXPECT_TRUE(ukf.state().p_n == x0.p_n);
}

TEST(Compass, NanHeadingNeverChangesTheState)
{
	at::TestContext tc;
	CompassModel model(configText("{}"), "COMPASS");
	auvnav::ManifoldUkf ukf(auvnav::ProcessModel{}, auvnav::UtParams{});
	ukf.initialize(at::RandomNavState(3), at::TypicalCovariance());
	const auvnav::NavState before = ukf.state();
	EXPECT_EQ(at::ApplyObservation(ukf, model, *compassObs(NAN), tc.ctx()).status,
	          auvnav::PrepareStatus::Invalid);
	EXPECT_TRUE(at::NavStateIdentical(ukf.state(), before));
}

TEST(Compass, ModuleLoadsThroughThePluginHost)
{
	auvnav::PluginHost host;
	const auvnav::PluginInfo info = host.load(COMPASS_MODULE);
	EXPECT_EQ(info.name, "compass");
	EXPECT_EQ(info.abi_version, AUVNAV_PLUGIN_ABI_VERSION);
	EXPECT_EQ(info.fingerprint, AUVNAV_BUILD_FINGERPRINT);
	auto model = host.create(COMPASS_MODULE, readFile(COMPASS_DEFAULT_CONFIG), "COMPASS");
	ASSERT_TRUE(model);
	EXPECT_EQ(model->uses(), uint32_t(auvnav::kAttitude));
	try
	{
		host.create(COMPASS_MODULE, "sigma_deg: -1", "COMPASS");
		ADD_FAILURE() << "the factory accepted sigma_deg: -1";
	}
	catch (const auvnav::PluginError& e)
	{
		EXPECT_NE(std::string(e.what()).find("sigma_deg"), std::string::npos) << e.what();
	}
}

// --- The plugin's own observation class (CObservationCompass, libcompass_obs).

TEST(Compass, OwnClassRoundTripsThroughMrptSerialization)
{
	compass_example::CObservationCompass c;
	c.sensorLabel = "COMPASS";
	c.timestamp = mrpt::Clock::fromDouble(1492693200.25);
	c.heading_rad = -2.5;
	c.sensorPose = mrpt::poses::CPose3D(0.4, 0, -0.1, 0, 0, 0);
	mrpt::io::CMemoryStream buf;
	mrpt::serialization::archiveFrom(buf).WriteObject(&c);
	buf.Seek(0);
	// Read back through MRPT's class registry, as a rawlog reader does.
	const auto obj = mrpt::serialization::archiveFrom(buf).ReadObject();
	const auto back = std::dynamic_pointer_cast<compass_example::CObservationCompass>(obj);
	ASSERT_TRUE(back) << obj->GetRuntimeClass()->className;
	EXPECT_EQ(back->sensorLabel, "COMPASS");
	EXPECT_EQ(back->timestamp, c.timestamp);
	EXPECT_DOUBLE_EQ(back->heading_rad, -2.5);
	EXPECT_DOUBLE_EQ(back->sensorPose.x(), 0.4);
}

TEST(Compass, ReadsItsOwnClassLikeTheImuYaw)
{
	at::TestContext tc;
	CompassModel model(configText("{declination_deg: 10}"), "COMPASS");
	compass_example::CObservationCompass c;
	c.heading_rad = 30 * kDeg;
	std::vector<auvnav::Measurement> own, imu;
	std::string why;
	ASSERT_EQ(model.prepare(c, tc.ctx(), own, why), auvnav::PrepareStatus::Ok) << why;
	ASSERT_EQ(model.prepare(*compassObs(30 * kDeg), tc.ctx(), imu, why), auvnav::PrepareStatus::Ok) << why;
	ASSERT_EQ(own.size(), 1u);
	EXPECT_NEAR(own[0].z[0], 40 * kDeg, 1e-12);
	EXPECT_EQ(own[0].z[0], imu[0].z[0]);
	EXPECT_TRUE(at::IsWellFormed(model, c, tc.ctx(), at::RandomNavState(4)));
}

// --- The plugin's own state (heading_bias).

TEST(Compass, HeadingBiasStateIsDeclaredAndRead)
{
	at::TestContext tc;
	CompassModel model(configText("states: {heading_bias: {sigma_deg: 3, process: constant}}"), "COMPASS");
	EXPECT_TRUE(model.uses() & auvnav::kPluginStates);
	// Bound as the navigator binds it, after 2 coordinates of another plugin.
	const at::PluginStateBench bench(model, 2, "COMPASS");
	const auvnav::PluginState& bias = bench["heading_bias"];
	EXPECT_EQ(bias.dimension(), 1);
	EXPECT_NEAR(bias.spec().sigma[0], 3 * kDeg, 1e-15);
	EXPECT_EQ(bias.spec().process, auvnav::StateProcess::RandomConstant);
	EXPECT_EQ(bench.layout.tangent_names.back(), "COMPASS.heading_bias");

	std::vector<auvnav::Measurement> out;
	std::string why;
	ASSERT_EQ(model.prepare(*compassObs(0), tc.ctx(), out, why), auvnav::PrepareStatus::Ok) << why;
	auvnav::NavState x = bench.randomState(1);
	x.R_nb = at::rotationYpr(50 * kDeg, 0, 0);
	bias.value(x) = 4 * kDeg;
	EXPECT_NEAR(at::Predict(model, out[0], tc.ctx(), x)[0], 54 * kDeg, 1e-12);
	x.extra.resize(2);  // the state the model was bound into is missing: h is refused
	Eigen::VectorXd z(1);
	EXPECT_FALSE(model.predict(x, out[0], tc.ctx(), z));
}

TEST(Compass, WithoutStatesConfigThereIsNoState)
{
	CompassModel m(configText("{}"), "COMPASS");
	EXPECT_EQ(at::PluginStateBench(m).extraSize(), 0);
	EXPECT_FALSE(m.uses() & auvnav::kPluginStates);
}

TEST(Compass, MisspelledStateKeysAreRefused)
{
	for (const char* bad : {"states: {heading_bais: {sigma_deg: 3}}", "states: {heading_bias: {sigma: 3}}",
	                        "states: {heading_bias: {sigma_deg: 3, process: walk}}"})
		EXPECT_THROW(CompassModel(configText(bad), "COMPASS"), auvnav::config::ConfigError) << bad;
}
