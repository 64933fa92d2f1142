// The "inertial" plugin: accelerometer update of the acceleration state.
#include <auvnav/testing/model_checks.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>

#include <cmath>

#include "inertial.h"
#include "plugin_test_support.h"

using auvnav::plugins::InertialModel;

namespace
{
mrpt::obs::CObservationIMU::Ptr imuObs(const Eigen::Vector3d& f,
                                       const Eigen::Vector3d& w = Eigen::Vector3d::Zero())
{
	using namespace mrpt::obs;
	auto o = CObservationIMU::Create();
	o->sensorLabel = "IMU";
	o->set(IMU_X_ACC, f.x());
	o->set(IMU_Y_ACC, f.y());
	o->set(IMU_Z_ACC, f.z());
	o->set(IMU_WX, w.x());
	o->set(IMU_WY, w.y());
	o->set(IMU_WZ, w.z());
	return o;
}

/** The specific force the simulator's IMU would give for state x (no noise,
 *  no Coriolis): R_nbᵀ (a_n − g e_z) + b_a. */
Eigen::Vector3d specificForce(const NavState& x)
{
	return x.R_nb.transpose() * (x.a_n - Eigen::Vector3d(0, 0, x.g)) + x.b_a;
}

Eigen::Vector3d measure(InertialModel& model, const NavState& x, const FilterContext& ctx)
{
	return at::Predict(model, pt::prepareAll(model, *imuObs(specificForce(x)), ctx).at(0), ctx, x);
}

NavState levelAtRest()
{
	NavState x;
	x.g = 9.81;
	return x;
}
}  // namespace

TEST(Inertial, DefaultConfigLoadsAndGivesDocumentedNoise)
{
	const InertialModel m(pt::defaultConfig(), "IMU");
	// σ² = (VRW·√rate)² + extra²: 0.12 mg/√Hz at 100 Hz is 0.0117680 m/s².
	const double white = 0.12e-3 * 9.80665 * std::sqrt(100.0);
	EXPECT_NEAR(m.sigma_mps2(), std::sqrt(white * white + 0.02 * 0.02), 1e-12);
	EXPECT_NEAR(m.sigma_mps2(), 0.0232053, 1e-6);
	EXPECT_DOUBLE_EQ(m.gateProbability(), 0.999);
	EXPECT_EQ(m.uses(), uint32_t(kAttitude | kAcceleration | kGravity | kAccelBias));
	EXPECT_EQ(tangentPrefix(m.uses()), 13);
	// Empty config = the same defaults.
	EXPECT_DOUBLE_EQ(InertialModel(pt::configText("{}"), "IMU").sigma_mps2(), m.sigma_mps2());
}

TEST(Inertial, RejectsBadConfigNamingTheKey)
{
	for (const char* yaml :
	     {"rate_hz: 0", "vrw_mg_per_sqrt_hz: -1", "vrw_mg_per_sqrt_hz: 0\nextra_sigma_mps2: 0",
	      "gate_probability: 0", "gate_probability: 1.5", "coriolis: maybe"})
		EXPECT_TRUE(pt::ConstructorRefuses<InertialModel>(yaml));
	EXPECT_TRUE(pt::ModuleRefuses("rate_hz: -5", "rate_hz"));
}

TEST(Inertial, ModuleExportsEntryAndCreatesFromDefaultConfig)
{
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("inertial", pt::defaultConfigText(),
	                                      kAttitude | kAcceleration | kGravity | kAccelBias));
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("inertial", "coriolis: true",
	                                      kAttitude | kAcceleration | kGravity | kAccelBias | kVelocity));
}

TEST(Inertial, WellFormedOnRandomStates)
{
	pt::FlatfishContext tc;
	tc.ctx().omega_ib_b = Eigen::Vector3d(0.01, -0.02, 0.1);
	for (const char* cfg : {"{}", "coriolis: true"})
	{
		InertialModel model(pt::configText(cfg), "IMU");
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			const NavState x = at::RandomNavState(seed);
			const Eigen::Vector3d f =
			    specificForce(at::RandomNavState(seed + 100)) + Eigen::Vector3d(0.01, -0.02, 0.03);
			EXPECT_TRUE(pt::IsWellFormedAndUsed(model, *imuObs(f), tc.ctx(), x, seed))
			    << cfg << ", seed " << seed;
		}
	}
}

TEST(Inertial, AtRestLevelMeasuresMinusG)
{
	at::TestContext tc;
	InertialModel model(pt::defaultConfig(), "IMU");
	const Eigen::Vector3d h = measure(model, levelAtRest(), tc.ctx());
	EXPECT_NEAR(h.x(), 0, 1e-15);
	EXPECT_NEAR(h.y(), 0, 1e-15);
	EXPECT_NEAR(h.z(), -9.81, 1e-15);
}

TEST(Inertial, TenDegreesRollTiltsGravityIntoBodyY)
{
	at::TestContext tc;
	InertialModel model(pt::defaultConfig(), "IMU");
	NavState x = levelAtRest();
	x.R_nb = at::rotationYpr(0, 0, 10 * kDeg);  // starboard down
	const Eigen::Vector3d h = measure(model, x, tc.ctx());
	// Body y (right) dips down: the upward specific force has −g sin φ on it.
	EXPECT_NEAR(h.x(), 0, 1e-12);
	EXPECT_NEAR(h.y(), -9.81 * std::sin(10 * kDeg), 1e-12);  // −1.70348
	EXPECT_NEAR(h.z(), -9.81 * std::cos(10 * kDeg), 1e-12);  // −9.66096
	EXPECT_NEAR(h.y(), -1.7034886, 1e-7);
	// And 10° nose up: body x points up, f_x = +g sin θ.
	x.R_nb = at::rotationYpr(0, 10 * kDeg, 0);
	const Eigen::Vector3d hp = measure(model, x, tc.ctx());
	EXPECT_NEAR(hp.x(), 9.81 * std::sin(10 * kDeg), 1e-12);
	EXPECT_NEAR(hp.z(), -9.81 * std::cos(10 * kDeg), 1e-12);
}

TEST(Inertial, AccelerationAndBiasAtHeading90)
{
	at::TestContext tc;
	InertialModel model(pt::defaultConfig(), "IMU");
	NavState x = levelAtRest();
	x.R_nb = at::rotationYpr(90 * kDeg, 0, 0);  // facing east
	x.a_n = Eigen::Vector3d(1.0, 0, 0);         // accelerating north = to port
	x.b_a = Eigen::Vector3d(0.01, 0.02, 0.03);
	const Eigen::Vector3d h = measure(model, x, tc.ctx());
	EXPECT_NEAR(h.x(), 0.01, 1e-12);
	EXPECT_NEAR(h.y(), -1.0 + 0.02, 1e-12);
	EXPECT_NEAR(h.z(), -9.81 + 0.03, 1e-12);
}

TEST(Inertial, OptionalCoriolisTerm)
{
	at::TestContext tc;  // 53.1° N
	InertialModel model(pt::configText("coriolis: true"), "IMU");
	NavState x = levelAtRest();
	x.v_n = Eigen::Vector3d(1.0, 0, 0);
	const Eigen::Vector3d h = measure(model, x, tc.ctx());
	// 2 ω_ie × v for v north: only east, −2 Ω sin(lat) (pushes to starboard in the north).
	const double omega = 7.292115e-5;
	EXPECT_NEAR(h.y(), -2 * omega * std::sin(53.1 * kDeg), 1e-10);
	EXPECT_NEAR(h.y(), -1.1665e-4, 1e-7);
	EXPECT_NEAR(h.x(), 0, 1e-12);
	EXPECT_NEAR(h.z(), -9.81, 1e-9);
}

TEST(Inertial, UpdateReducesTiltError)
{
	at::TestContext tc;
	InertialModel model(pt::defaultConfig(), "IMU");
	const NavState truth = levelAtRest();
	NavState x0 = truth;
	x0.R_nb = at::rotationYpr(0, -2 * kDeg, 3 * kDeg);  // 3.6° tilt error
	Covariance P0 = at::TypicalCovariance();
	P0.block<3, 3>(idx::att, idx::att) = Eigen::Matrix3d::Identity() * std::pow(5 * kDeg, 2);
	ManifoldUkf ukf = pt::filterAt(x0, P0);
	const double tilt_before = x0.boxminus(truth).segment<2>(idx::att).norm();
	ASSERT_GT(tilt_before, 3 * kDeg);

	const auto res = at::ApplyObservation(ukf, model, *imuObs(specificForce(truth)), tc.ctx());
	ASSERT_EQ(res.status, PrepareStatus::Ok) << res.why;
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, UpdateStatus::Accepted) << res.updates[0].why;
	const double tilt_after = ukf.state().boxminus(truth).segment<2>(idx::att).norm();
	EXPECT_LT(tilt_after, 0.2 * tilt_before)
	    << "before " << tilt_before / kDeg << "°, after " << tilt_after / kDeg << "°";
	// The attitude variance of the tilt axes shrank; heading is unobservable here.
	EXPECT_LT(ukf.covariance()(idx::att, idx::att), P0(idx::att, idx::att));
	EXPECT_LT(ukf.covariance()(idx::att + 1, idx::att + 1), P0(idx::att + 1, idx::att + 1));
	EXPECT_NEAR(ukf.covariance()(idx::att + 2, idx::att + 2), P0(idx::att + 2, idx::att + 2),
	            1e-6 * P0(idx::att + 2, idx::att + 2));
}

TEST(Inertial, InvalidInputs)
{
	at::TestContext tc;
	InertialModel model(pt::defaultConfig(), "IMU");
	std::vector<Measurement> out;
	std::string why;
	for (double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL})
		for (int axis = 0; axis < 3; ++axis)
		{
			Eigen::Vector3d f(0, 0, -9.81);
			f[axis] = bad;
			why.clear();
			EXPECT_EQ(model.prepare(*imuObs(f), tc.ctx(), out, why), PrepareStatus::Invalid);
			EXPECT_TRUE(out.empty());
			EXPECT_FALSE(why.empty());
		}
	// Missing accelerometer axis (gyro only).
	auto gyro_only = mrpt::obs::CObservationIMU::Create();
	gyro_only->set(mrpt::obs::IMU_WX, 0.0);
	gyro_only->set(mrpt::obs::IMU_X_ACC, 0.0);
	gyro_only->set(mrpt::obs::IMU_Y_ACC, 0.0);
	EXPECT_EQ(model.prepare(*gyro_only, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_NE(why.find("missing"), std::string::npos) << why;
	// Wrong observation class.
	EXPECT_TRUE(pt::RefusesOtherClass<mrpt::obs::CObservationGPS>(model, tc.ctx(), "CObservationIMU"));
}

TEST(Inertial, NanMeasurementNeverChangesTheState)
{
	at::TestContext tc;
	InertialModel model(pt::defaultConfig(), "IMU");
	const NavState x0 = at::RandomNavState(3);
	// Through the plugin: prepare refuses, nothing reaches the filter.
	EXPECT_TRUE(pt::PrepareRefuses(model, *imuObs(Eigen::Vector3d(0, std::nan(""), -9.8)), tc.ctx(), x0));
	// Directly: a measurement with a NaN is refused by the filter.
	Measurement m = pt::prepareOne(model, *imuObs(Eigen::Vector3d(0, 0, -9.8)), tc.ctx());
	m.z[1] = std::nan("");
	EXPECT_TRUE(pt::FilterRefuses(model, m, tc.ctx(), x0));
}
