// The "pressure" plugin: absolute pressure to depth.
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <cmath>

#include "plugin_test_support.h"
#include "pressure.h"

using auvnav::obs::CObservationPressure;
using auvnav::plugins::PressureModel;

namespace
{
const Eigen::Vector3d kSensorPos(0, 0, 0.3);  // pressure.position_m

CObservationPressure::Ptr pressureObs(double pa)
{
	auto o = CObservationPressure::Create();
	o->sensorLabel = "PRESSURE";
	o->pressure_pa = pa;
	o->temperature_c = 12;
	o->sensorPose = mrpt::poses::CPose3D(kSensorPos.x(), kSensorPos.y(), kSensorPos.z(), 0, 0, 0);
	return o;
}

/** The simulator's pressure (no noise, no bias) for state x (FlatFish IMU lever arm). */
double truePressure(const NavState& x)
{
	return 101325 + 1025 * x.g * pt::pointOnVehicle_n(x, kSensorPos).z();
}

double predictOne(PressureModel& model, const NavState& x, const FilterContext& ctx)
{
	const std::vector<Measurement> out = pt::prepareAll(model, *pressureObs(2e5), ctx);
	return out.empty() ? NAN : at::Predict(model, out[0], ctx, x)[0];
}

/** A vehicle with its IMU at p_n [m] in water under gravity 9.81 m/s², facing
 *  `yaw` (pitch, roll in radians too). */
NavState submergedAt(const Eigen::Vector3d& p_n, double yaw = 0, double pitch = 0, double roll = 0)
{
	NavState x;
	x.g = 9.81;
	x.R_nb = at::rotationYpr(yaw, pitch, roll);
	x.p_n = p_n;
	return x;
}
}  // namespace

TEST(Pressure, DefaultConfig)
{
	const PressureModel m(pt::defaultConfig(), "PRESSURE");
	EXPECT_DOUBLE_EQ(m.density_kg_m3(), 1025);
	EXPECT_DOUBLE_EQ(m.atmospheric_pressure_pa(), 101325);
	EXPECT_TRUE(m.position_b() == kSensorPos);
	EXPECT_EQ(m.uses(), uint32_t(kAttitude | kGravity | kPosition));
	EXPECT_DOUBLE_EQ(m.gateProbability(), 0.999);
	const PressureModel e(pt::configText("{}"), "PRESSURE");
	EXPECT_DOUBLE_EQ(e.density_kg_m3(), 1025);
	EXPECT_TRUE(e.position_b() == kSensorPos);
}

TEST(Pressure, RejectsBadConfigNamingTheKey)
{
	for (const char* yaml : {"density_kg_m3: 10", "atmospheric_pressure_pa: 0", "sigma_pa: 0",
	                         "position_m: 3", "gate_probability: 2"})
		EXPECT_TRUE(pt::ConstructorRefuses<PressureModel>(yaml));
	EXPECT_TRUE(pt::ModuleRefuses("density_kg_m3: 5000", "density_kg_m3"));
}

TEST(Pressure, ModuleExportsEntryAndCreatesFromDefaultConfig)
{
	EXPECT_TRUE(
	    pt::ModuleLoadsAndCreates("pressure", pt::defaultConfigText(), kAttitude | kGravity | kPosition));
}

TEST(Pressure, WellFormedOnRandomStates)
{
	pt::FlatfishContext tc;
	PressureModel model(pt::defaultConfig(), "PRESSURE");
	for (uint32_t seed = 1; seed <= 20; ++seed)
	{
		const auto o = pressureObs(truePressure(at::RandomNavState(seed + 9)) + 30);
		EXPECT_TRUE(pt::IsWellFormedAndUsed(model, *o, tc.ctx(), at::RandomNavState(seed), seed))
		    << "seed " << seed;
	}
}

TEST(Pressure, TenMetresLevelAndPitched)
{
	pt::FlatfishContext tc;
	PressureModel model(pt::defaultConfig(), "PRESSURE");
	NavState x = submergedAt(Eigen::Vector3d(5, -3, 10));  // IMU at 10 m
	// Level: the sensor is 0.3 + 0.02863 m below the IMU.
	EXPECT_NEAR(predictOne(model, x, tc.ctx()), 101325 + 1025 * 9.81 * 10.32863, 1e-8);
	EXPECT_NEAR(predictOne(model, x, tc.ctx()), 205181.9568075, 1e-6);
	// Heading does not matter.
	x.R_nb = at::rotationYpr(123 * kDeg, 0, 0);
	EXPECT_NEAR(predictOne(model, x, tc.ctx()), 205181.9568075, 1e-6);
	// 10° nose up: the sensor, 0.294 m behind the IMU, goes 0.294·sin 10° deeper.
	x.R_nb = at::rotationYpr(0, 10 * kDeg, 0);
	EXPECT_NEAR(predictOne(model, x, tc.ctx()), 101325 + 1025 * 9.81 * (10 + 0.37473161166912), 1e-6);
	// The gravity state scales the hydrostatic part.
	x.R_nb.setIdentity();
	x.g = 9.78;
	EXPECT_NEAR(predictOne(model, x, tc.ctx()), 101325 + 1025 * 9.78 * 10.32863, 1e-8);
}

TEST(Pressure, UpdateReducesDepthError)
{
	pt::FlatfishContext tc;
	PressureModel model(pt::defaultConfig(), "PRESSURE");
	const NavState truth = submergedAt(Eigen::Vector3d(20, 30, 10), 10 * kDeg, 3 * kDeg, -2 * kDeg);
	NavState x0 = truth;
	x0.p_n.z() = 12;
	ManifoldUkf ukf = pt::filterAt(x0);
	const auto res = at::ApplyObservation(ukf, model, *pressureObs(truePressure(truth)), tc.ctx());
	ASSERT_EQ(res.status, PrepareStatus::Ok) << res.why;
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, UpdateStatus::Accepted) << res.updates[0].why;
	const double err_after = std::abs(ukf.state().p_n.z() - truth.p_n.z());
	EXPECT_LT(err_after, 0.05) << "depth error 2 m -> " << err_after << " m";
	// Horizontal position untouched (uncorrelated in P0).
	EXPECT_NEAR(ukf.state().p_n.x(), 20, 1e-9);
	EXPECT_NEAR(ukf.state().p_n.y(), 30, 1e-9);
	EXPECT_LT(ukf.covariance()(idx::pos + 2, idx::pos + 2), 0.01);
}

TEST(Pressure, InvalidInputs)
{
	at::TestContext tc;
	PressureModel model(pt::defaultConfig(), "PRESSURE");
	std::vector<Measurement> out;
	std::string why;
	for (double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL, 0.0, 4.9e4, -101325.0, 1.01e8, 1e12})
	{
		why.clear();
		EXPECT_EQ(model.prepare(*pressureObs(bad), tc.ctx(), out, why), PrepareStatus::Invalid) << bad;
		EXPECT_TRUE(out.empty());
		EXPECT_FALSE(why.empty());
	}
	// The plausible extremes pass: a reading above water, and 9000 m deep.
	EXPECT_EQ(model.prepare(*pressureObs(5.0e4), tc.ctx(), out, why), PrepareStatus::Ok);
	EXPECT_EQ(model.prepare(*pressureObs(9.3e7), tc.ctx(), out, why), PrepareStatus::Ok);
	EXPECT_TRUE(pt::RefusesOtherClass<obs::CObservationDVL>(model, tc.ctx(), "CObservationPressure"));
}

TEST(Pressure, NanMeasurementNeverChangesTheState)
{
	at::TestContext tc;
	PressureModel model(pt::defaultConfig(), "PRESSURE");
	const NavState x0 = at::RandomNavState(11);
	EXPECT_TRUE(pt::PrepareRefuses(model, *pressureObs(NAN), tc.ctx(), x0));
	// A measurement with a NaN in z or in R is refused by the filter.
	Measurement m = pt::prepareOne(model, *pressureObs(2e5), tc.ctx());
	m.z[0] = std::nan("");
	EXPECT_TRUE(pt::FilterRefuses(model, m, tc.ctx(), x0));
	m.z[0] = 2e5;
	m.R(0, 0) = std::nan("");
	EXPECT_TRUE(pt::FilterRefuses(model, m, tc.ctx(), x0));
}

TEST(Pressure, BiasFloorKeepsTheDepthSigmaAtTheBias)
{
	pt::FlatfishContext tc;
	const double pa_per_m = 1025 * PressureModel::kNominalGravity;
	const double floor_m = 60 / pa_per_m;  // ~6 mm
	auto run = [&](const char* cfg, double& sigma_d, double& first_err)
	{
		PressureModel model(pt::configText(cfg), "PRESSURE");
		const NavState truth = submergedAt(Eigen::Vector3d(20, 30, 10));
		NavState x0 = truth;
		x0.p_n.z() = 12;
		// Gravity and tilt known well: otherwise their share of the depth
		// sigma (10 m x δg/g, the lever arm) would hide the averaging.
		Covariance P0 = at::TypicalCovariance();
		P0.row(idx::gravity).setZero();
		P0.col(idx::gravity).setZero();
		P0(idx::gravity, idx::gravity) = 1e-14;
		P0.topRows<3>().setZero();
		P0.leftCols<3>().setZero();
		P0.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * 1e-8;
		ManifoldUkf ukf = pt::filterAt(x0, P0);
		tc.ctx().covariance = &ukf.covariance();
		for (int k = 0; k < 200; ++k)
		{
			const auto res = at::ApplyObservation(ukf, model, *pressureObs(truePressure(truth)), tc.ctx());
			ASSERT_EQ(res.status, PrepareStatus::Ok) << res.why;
			ASSERT_EQ(res.updates.at(0).status, UpdateStatus::Accepted) << res.updates[0].why;
			if (k == 0) first_err = std::abs(ukf.state().p_n.z() - truth.p_n.z());
		}
		sigma_d = std::sqrt(ukf.covariance()(idx::pos + 2, idx::pos + 2));
		tc.ctx().covariance = nullptr;
	};
	double with_floor = 0, without = 0, err_with = 0, err_without = 0;
	run("sigma_pa: 30\nbias_sigma_pa: 60\n", with_floor, err_with);
	run("sigma_pa: 30\n", without, err_without);
	// 200 readings average the noise down to 30/sqrt(200) Pa (0.2 mm) without
	// the floor; with it the depth sigma stays at the bias (+ the sensor
	// lever arm's share of the attitude sigma, which the floor ignores).
	EXPECT_LT(without, 0.25 * floor_m);
	EXPECT_GE(with_floor, floor_m * (1 - 1e-3)) << with_floor << " m";
	EXPECT_LT(with_floor, floor_m * 1.05) << with_floor << " m";
	// The first reading still removes the 2 m depth error.
	EXPECT_LT(err_with, 0.05);
	EXPECT_LT(err_without, 0.05);
	// Below the floor an update changes (almost) nothing; without a covariance
	// in the context the noise is sigma_pa alone.
	PressureModel model(pt::configText("sigma_pa: 30\nbias_sigma_pa: 60\n"), "PRESSURE");
	std::vector<Measurement> out;
	std::string why;
	ASSERT_EQ(model.prepare(*pressureObs(2e5), tc.ctx(), out, why), PrepareStatus::Ok);
	EXPECT_DOUBLE_EQ(out[0].R(0, 0), 900);
	Covariance P = at::TypicalCovariance();
	P(idx::pos + 2, idx::pos + 2) = 0.5 * floor_m * floor_m;
	tc.ctx().covariance = &P;
	ASSERT_EQ(model.prepare(*pressureObs(2e5), tc.ctx(), out, why), PrepareStatus::Ok);
	EXPECT_GT(out[0].R(0, 0), 1e5 * 3600 * 0.5);
	EXPECT_TRUE(pt::ConstructorRefuses<PressureModel>("bias_sigma_pa: -1"));
}
