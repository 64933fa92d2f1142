// The "gps" plugin: NMEA GGA horizontal position with lever arm and outlier gate.
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/testing/plugin_state_bench.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/gnss_messages_ascii_nmea.h>

#include <cmath>

#include "gps.h"
#include "plugin_test_support.h"

using auvnav::plugins::GpsModel;
using mrpt::obs::CObservationGPS;

namespace
{
const Eigen::Vector3d kAntennaPos(-0.3, 0, -0.6);  // gps.position_m

/** A GGA fix at navigation-frame position `p_n`, as the simulator writes it. */
CObservationGPS::Ptr ggaObs(const earth::TangentFrame& frame, const Eigen::Vector3d& p_n, int fix_quality = 1,
                            float hdop = 1.0f)
{
	const earth::Geodetic g = frame.toGeodetic(p_n);
	mrpt::obs::gnss::Message_NMEA_GGA gga;
	gga.fields.latitude_degrees = g.lat_rad / kDeg;
	gga.fields.longitude_degrees = g.lon_rad / kDeg;
	gga.fields.altitude_meters = g.h_m;
	gga.fields.fix_quality = static_cast<uint8_t>(fix_quality);
	gga.fields.satellitesUsed = 8;
	gga.fields.HDOP = hdop;
	auto o = CObservationGPS::Create();
	o->sensorLabel = "GPS";
	o->sensorPose = mrpt::poses::CPose3D(kAntennaPos.x(), kAntennaPos.y(), kAntennaPos.z(), 0, 0, 0);
	o->setMsg(gga);
	return o;
}

Eigen::Vector3d antennaPosition(const NavState& x)
{
	return pt::pointOnVehicle_n(x, kAntennaPos);
}

/** A GGA fix of the antenna at `p_n` stamped `t_s` [s]. */
CObservationGPS::Ptr ggaObsAt(double t_s, const earth::TangentFrame& frame, const Eigen::Vector3d& p_n)
{
	auto o = ggaObs(frame, p_n);
	o->timestamp = mrpt::Clock::fromDouble(t_s);
	return o;
}
}  // namespace

TEST(Gps, DefaultConfig)
{
	const GpsModel m(pt::defaultConfig(), "GPS");
	EXPECT_TRUE(m.position_b() == kAntennaPos);
	EXPECT_EQ(m.uses(), uint32_t(kAttitude | kPosition));
	EXPECT_DOUBLE_EQ(m.gateProbability(), 0.999);
	EXPECT_TRUE(GpsModel(pt::configText("{}"), "GPS").position_b() == kAntennaPos);
}

TEST(Gps, RejectsBadConfigNamingTheKey)
{
	for (const char* yaml :
	     {"sigma_m: 0", "scale_by_hdop: 2", "position_m: [0, 0, 1e6]", "gate_probability: 0"})
		EXPECT_TRUE(pt::ConstructorRefuses<GpsModel>(yaml));
	EXPECT_TRUE(pt::ModuleRefuses("sigma_m: -3", "sigma_m"));
	EXPECT_TRUE(pt::ModuleRefuses("sigma_m: [1", "malformed"));
}

TEST(Gps, ModuleExportsEntryAndCreatesFromDefaultConfig)
{
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("gps", pt::defaultConfigText(), kAttitude | kPosition));
	EXPECT_TRUE(pt::ModuleLoadsAndCreates(
	    "gps", "states: {bias: {sigma: 1.5, process: gauss_markov, process_sigma: 1.5, tau_s: 60}}",
	    kAttitude | kPosition | kPluginStates));
}

TEST(Gps, WellFormedOnRandomStates)
{
	pt::FlatfishContext tc;
	for (const char* cfg : {"{}", "scale_by_hdop: true", "states: {bias: {sigma: 2}}"})
	{
		GpsModel model(pt::configText(cfg), "GPS");
		// After another plugin's one state (the bias, if any, is bound at 1).
		const at::PluginStateBench bench(model, 1);
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			const NavState x = bench.randomState(seed);
			const Eigen::Vector3d p = antennaPosition(at::RandomNavState(seed + 3));
			EXPECT_TRUE(pt::IsWellFormedAndUsed(model, *ggaObs(tc.frame(), p, 1, 1.4f), tc.ctx(), x, seed))
			    << cfg << ", seed " << seed;
		}
	}
}

TEST(Gps, FixConvertsBackToTheNavigationFrame)
{
	at::TestContext tc;
	GpsModel model(pt::defaultConfig(), "GPS");
	for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1234.5, -987.6, -1.0),
	                                 Eigen::Vector3d(-20000, 15000, -0.5)})
	{
		const Measurement m = pt::prepareOne(model, *ggaObs(tc.frame(), p), tc.ctx());
		ASSERT_EQ(m.z.size(), 2);
		EXPECT_NEAR(m.z[0], p.x(), 1e-6);
		EXPECT_NEAR(m.z[1], p.y(), 1e-6);
		EXPECT_TRUE(m.R.isApprox(9.0 * Eigen::Matrix2d::Identity(), 1e-15));
	}
}

TEST(Gps, LeverArmAtHeading180)
{
	pt::FlatfishContext tc;
	GpsModel model(pt::defaultConfig(), "GPS");
	NavState x;
	x.R_nb = at::rotationYpr(180 * kDeg, 0, 0);  // facing south
	x.p_n = Eigen::Vector3d(10, 20, 0);
	const Measurement m = pt::prepareOne(model, *ggaObs(tc.frame(), Eigen::Vector3d(10, 20, -0.6)), tc.ctx());
	const Eigen::VectorXd h = at::Predict(model, m, tc.ctx(), x);
	// Antenna 0.59424 m behind the IMU; facing south, behind is north.
	EXPECT_NEAR(h[0], 10.59424, 1e-12);
	EXPECT_NEAR(h[1], 20.0, 1e-12);
	// Heading 90 (east): behind is west.
	x.R_nb = at::rotationYpr(90 * kDeg, 0, 0);
	const Eigen::VectorXd h90 = at::Predict(model, m, tc.ctx(), x);
	EXPECT_NEAR(h90[0], 10.0, 1e-12);
	EXPECT_NEAR(h90[1], 20 - 0.59424, 1e-12);
	// 10° roll to starboard: the mast (0.57 m above the IMU) leans to starboard = west when facing south.
	x.R_nb = at::rotationYpr(180 * kDeg, 0, 10 * kDeg);
	const Eigen::VectorXd hr = at::Predict(model, m, tc.ctx(), x);
	EXPECT_NEAR(hr[0], 10.59424, 1e-12);
	EXPECT_NEAR(hr[1], 20 - 0.57137 * std::sin(10 * kDeg), 1e-12);
}

TEST(Gps, HdopScalingOnlyWhenConfiguredAndReported)
{
	at::TestContext tc;
	GpsModel plain(pt::defaultConfig(), "GPS");
	GpsModel scaled(pt::configText("scale_by_hdop: true\nsigma_m: 2.0"), "GPS");
	const Eigen::Vector3d p(5, 5, -1);
	EXPECT_NEAR(pt::prepareOne(plain, *ggaObs(tc.frame(), p, 1, 2.5f), tc.ctx()).R(0, 0), 9.0, 1e-12);
	EXPECT_NEAR(pt::prepareOne(scaled, *ggaObs(tc.frame(), p, 1, 2.5f), tc.ctx()).R(1, 1), 25.0, 1e-12);
	EXPECT_NEAR(pt::prepareOne(scaled, *ggaObs(tc.frame(), p, 1, 0.0f), tc.ctx()).R(0, 0), 4.0,
	            1e-12);  // not reported
	EXPECT_NEAR(pt::prepareOne(scaled, *ggaObs(tc.frame(), p, 1, NAN), tc.ctx()).R(0, 0), 4.0, 1e-12);
	EXPECT_EQ(pt::prepareOne(scaled, *ggaObs(tc.frame(), p, 1, 2.5f), tc.ctx()).R(0, 1), 0.0);
}

TEST(Gps, UpdateReducesPositionError)
{
	pt::FlatfishContext tc;
	GpsModel model(pt::defaultConfig(), "GPS");
	const NavState truth = pt::levelState(180 * kDeg, Eigen::Vector3d(10, 20, 0));
	NavState x0 = truth;
	x0.p_n = Eigen::Vector3d(15, 16, 0);
	ManifoldUkf ukf = pt::filterAt(x0);  // 5 m per axis
	const double err_before = (x0.p_n - truth.p_n).head<2>().norm();
	const auto res = at::ApplyObservation(ukf, model, *ggaObs(tc.frame(), antennaPosition(truth)), tc.ctx());
	ASSERT_EQ(res.status, PrepareStatus::Ok) << res.why;
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, UpdateStatus::Accepted) << res.updates[0].why;
	const double err_after = (ukf.state().p_n - truth.p_n).head<2>().norm();
	// Prior 5 m, fix 3 m: the error keeps 9/34 of itself (Kalman gain 25/34).
	EXPECT_NEAR(err_after, err_before * 9.0 / 34.0, 0.05 * err_before) << "before " << err_before;
	EXPECT_NEAR(ukf.state().p_n.z(), 0.0, 1e-9);  // depth is not observed
}

TEST(Gps, GrossOutlierIsRejectedAndLeavesTheStateUnchanged)
{
	pt::FlatfishContext tc;
	GpsModel model(pt::defaultConfig(), "GPS");
	const NavState truth = pt::levelState(45 * kDeg, Eigen::Vector3d(-40, 70, 0));
	ManifoldUkf ukf = pt::filterAt(truth);
	const NavState before = ukf.state();
	const Covariance P_before = ukf.covariance();
	const Eigen::Vector3d outlier = antennaPosition(truth) + Eigen::Vector3d(60, -80, 0);  // 100 m off
	const auto res = at::ApplyObservation(ukf, model, *ggaObs(tc.frame(), outlier), tc.ctx());
	ASSERT_EQ(res.status, PrepareStatus::Ok) << res.why;
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, UpdateStatus::Rejected);
	EXPECT_GT(res.updates[0].nis, ManifoldUkf::chiSquareQuantile(2, 0.999));
	EXPECT_TRUE(at::NavStateIdentical(ukf.state(), before));
	EXPECT_TRUE(ukf.covariance() == P_before);
	// A 3 m error is accepted.
	const auto ok = at::ApplyObservation(
	    ukf, model, *ggaObs(tc.frame(), antennaPosition(truth) + Eigen::Vector3d(3, 0, 0)), tc.ctx());
	ASSERT_EQ(ok.updates.size(), 1u);
	EXPECT_EQ(ok.updates[0].status, UpdateStatus::Accepted);
}

TEST(Gps, NoFixOrNoGgaIsSkipped)
{
	at::TestContext tc;
	GpsModel model(pt::defaultConfig(), "GPS");
	std::vector<Measurement> out;
	std::string why;
	EXPECT_EQ(model.prepare(*ggaObs(tc.frame(), Eigen::Vector3d(1, 2, 0), 0), tc.ctx(), out, why),
	          PrepareStatus::Skip);
	EXPECT_TRUE(out.empty());
	EXPECT_NE(why.find("fix"), std::string::npos) << why;
	auto rmc_only = CObservationGPS::Create();
	rmc_only->setMsg(mrpt::obs::gnss::Message_NMEA_RMC());
	EXPECT_EQ(model.prepare(*rmc_only, tc.ctx(), out, why), PrepareStatus::Skip);
	EXPECT_EQ(model.prepare(*CObservationGPS::Create(), tc.ctx(), out, why), PrepareStatus::Skip);
}

TEST(Gps, InvalidInputs)
{
	at::TestContext tc;
	GpsModel model(pt::defaultConfig(), "GPS");
	std::vector<Measurement> out;
	std::string why;
	auto withLatLon = [&](double lat, double lon)
	{
		auto o = ggaObs(tc.frame(), Eigen::Vector3d::Zero());
		auto& f = o->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>().fields;
		f.latitude_degrees = lat;
		f.longitude_degrees = lon;
		return o;
	};
	for (const auto& [lat, lon] : std::vector<std::pair<double, double>>{
	         {NAN, 8.8}, {53.1, NAN}, {HUGE_VAL, 8.8}, {95.0, 8.8}, {53.1, -190.0}})
	{
		EXPECT_EQ(model.prepare(*withLatLon(lat, lon), tc.ctx(), out, why), PrepareStatus::Invalid)
		    << lat << " " << lon;
		EXPECT_TRUE(out.empty());
	}
	// No navigation frame in the context.
	FilterContext no_frame;
	EXPECT_EQ(model.prepare(*ggaObs(tc.frame(), Eigen::Vector3d::Zero()), no_frame, out, why),
	          PrepareStatus::Invalid);
	// A missing altitude still gives the horizontal position.
	auto no_alt = ggaObs(tc.frame(), Eigen::Vector3d(100, 50, 0));
	no_alt->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>().fields.altitude_meters = NAN;
	const Measurement m = pt::prepareOne(model, *no_alt, tc.ctx());
	EXPECT_NEAR(m.z[0], 100, 1e-3);
	EXPECT_NEAR(m.z[1], 50, 1e-3);
	EXPECT_TRUE(pt::RefusesOtherClass<obs::CObservationPressure>(model, tc.ctx(), "CObservationGPS"));
}

TEST(Gps, NanMeasurementNeverChangesTheState)
{
	at::TestContext tc;
	GpsModel model(pt::defaultConfig(), "GPS");
	const NavState x0 = at::RandomNavState(5);
	Measurement m = pt::prepareOne(model, *ggaObs(tc.frame(), x0.p_n), tc.ctx());
	m.z[0] = std::nan("");
	EXPECT_TRUE(pt::FilterRefuses(model, m, tc.ctx(), x0));
}

TEST(Gps, MinIntervalUsesOneFixPerCorrelationTime)
{
	at::TestContext tc;
	GpsModel model(pt::configText("min_interval_s: 30\n"), "GPS");
	// 100 s of 1 Hz fixes: used at t = 0, 30, 60, 90 s.
	const auto fix = ggaObs(tc.frame(), Eigen::Vector3d(10, 20, 0));
	const pt::Offered n = pt::offerInTurn(model, tc.ctx(), *fix, 100, 1492693200.0, 1.0);
	EXPECT_EQ(n.used, 4);
	EXPECT_EQ(n.skipped, 96);
	EXPECT_TRUE(pt::ConstructorRefuses<GpsModel>("min_interval_s: -1\n"));
}

TEST(Gps, CorrelatedErrorIsInflatedByItsEffectiveSampleSize)
{
	at::TestContext tc;
	GpsModel model(pt::configText("sigma_m: 1.0\ncorrelated_sigma_m: 1.5\ncorrelation_time_s: 60\n"), "GPS");
	auto fixAt = [&](double t)
	{
		return pt::prepareOne(model, *ggaObsAt(1492693200.0 + t, tc.frame(), Eigen::Vector3d(10, 20, 0)),
		                      tc.ctx())
		    .R;
	};
	// First fix: nothing to share an error with: 1 + 1.5².
	EXPECT_NEAR(fixAt(0)(0, 0), 1 + 2.25, 1e-9);
	// 30 s later: ρ = exp(-0.5), variance 1 + 2.25 (1+ρ)/(1-ρ) = 10.18 (σ 3.19 m).
	const double rho = std::exp(-0.5);
	const Eigen::MatrixXd R30 = fixAt(30);
	EXPECT_NEAR(R30(1, 1), 1 + 2.25 * (1 + rho) / (1 - rho), 1e-9);
	EXPECT_NEAR(std::sqrt(R30(0, 0)), 3.19, 0.01);
	EXPECT_EQ(R30(0, 1), 0.0);
	// After a 20-minute dive the errors are unrelated again.
	EXPECT_NEAR(fixAt(1230)(0, 0), 1 + 2.25, 1e-6);
	// Off by default: sigma_m alone.
	GpsModel plain(pt::configText("sigma_m: 2.0\n"), "GPS");
	EXPECT_NEAR(pt::prepareOne(plain, *ggaObs(tc.frame(), Eigen::Vector3d(1, 2, 0)), tc.ctx()).R(0, 0), 4.0,
	            1e-12);
	EXPECT_TRUE(pt::ConstructorRefuses<GpsModel>("correlated_sigma_m: -1\n"));
	EXPECT_TRUE(pt::ConstructorRefuses<GpsModel>("correlation_time_s: 0\n"));
}

TEST(Gps, BiasStateEntersHAndTheOutlierTest)
{
	pt::FlatfishContext tc;
	GpsModel model(
	    pt::configText("states: {bias: {sigma: 1.5, process: gauss_markov, process_sigma: 1.5, tau_s: 60}}"),
	    "GPS");
	EXPECT_EQ(model.uses(), uint32_t(kAttitude | kPosition | kPluginStates));
	EXPECT_EQ(model.structure().affine_in, uint32_t(kPosition | kPluginStates));
	const at::PluginStateBench bench(model, 2);
	ASSERT_EQ(bench.layout.plugin_blocks.size(), 2u);  // the other plugin's, then the bias
	const PluginState& bias = bench["bias"];
	EXPECT_EQ(bias.dimension(), 2);
	EXPECT_EQ(bias.spec().process, StateProcess::GaussMarkov);
	EXPECT_DOUBLE_EQ(bias.spec().tau_s, 60);
	NavState x = bench.randomState(7);
	bias(x, 0) = 0.8;
	bias(x, 1) = -1.3;
	const Eigen::Vector3d a = antennaPosition(x);
	const Measurement m = pt::prepareOne(model, *ggaObs(tc.frame(), a), tc.ctx());
	EXPECT_NEAR(m.R(0, 0), 9.0, 1e-12);  // sigma_m alone: no inflation for the correlated part
	const Eigen::VectorXd h = at::Predict(model, m, tc.ctx(), x);
	EXPECT_NEAR(h[0], a.x() + 0.8, 1e-12);
	EXPECT_NEAR(h[1], a.y() - 1.3, 1e-12);
	// A state without the bias coordinates cannot be evaluated.
	EXPECT_TRUE(at::Predict(model, m, tc.ctx(), at::RandomNavState(7, 2)).array().isNaN().all());

	// The rate limiter's outlier test counts the bias: its mean, and its
	// covariance with the cross term at the bias's tangent index (43 + the
	// bound index, here after another plugin's one state). A fix 12 m north
	// is tried twice, 1 s apart: one used if it is inside the gate (the
	// second falls within min_interval_s), two if an outlier (the interval
	// is not spent on it).
	auto offeredWith = [&](double bias_n, double var_p, double var_b, double cov_pb)
	{
		GpsModel limited(pt::configText("{sigma_m: 1.0, min_interval_s: 30, states: {bias: {sigma: 1}}}"),
		                 "GPS");
		const at::PluginStateBench limited_bench(limited, 1);
		NavState mean = limited_bench.randomState(9);
		mean.extra << 0, bias_n, 0;
		Covariance P = Covariance::Identity(46, 46) * 1e-4;
		for (int i = 0; i < 2; ++i)
		{
			const int ip = idx::pos + i, ib = limited_bench["bias"].tangentIndex(i);
			P(ip, ip) = var_p;
			P(ib, ib) = var_b;
			P(ip, ib) = P(ib, ip) = cov_pb;
		}
		FilterContext ctx = tc.ctx();
		ctx.mean = &mean;
		ctx.covariance = &P;
		const Eigen::Vector3d fix = antennaPosition(mean) + Eigen::Vector3d(12, 0, 0);
		int used = 0;
		for (int k = 0; k < 2; ++k)
		{
			std::vector<Measurement> out;
			std::string why;
			used += limited.prepare(*ggaObsAt(1492693200.0 + k, tc.frame(), fix), ctx, out, why) ==
			        PrepareStatus::Ok;
		}
		return used;
	};
	// The bias's mean: 12 m in it, the fix agrees; without it, an outlier.
	EXPECT_EQ(offeredWith(12.0, 0.01, 1, 0), 1);
	EXPECT_EQ(offeredWith(0.0, 0.01, 1, 0), 2);
	// A bias σ of 10 m explains 12 m (NIS 144/101); σ 1 m did not (above).
	EXPECT_EQ(offeredWith(0.0, 0.01, 100, 0), 1);
	// Position and bias σ 10 m each but anti-correlated (their sum's variance
	// 0.2 m²): 12 m is an outlier (NIS 144/1.2); without the cross term
	// (S = 201 m²) it would not be.
	EXPECT_EQ(offeredWith(0.0, 100, 100, -99.9), 2);
	EXPECT_EQ(offeredWith(0.0, 100, 100, 0), 1);
}

TEST(Gps, BiasStateAndCorrelatedSigmaAreExclusive)
{
	EXPECT_TRUE(pt::ConstructorRefuses<GpsModel>("{correlated_sigma_m: 1.5, states: {bias: {sigma: 1.5}}}"));
	EXPECT_TRUE(pt::ModuleRefuses("{correlated_sigma_m: 1.5, states: {bias: {sigma: 1.5}}}", "states.bias"));
	EXPECT_TRUE(pt::ConstructorRefuses<GpsModel>("states: {bais: {sigma: 1}}"));
	EXPECT_TRUE(pt::ConstructorRefuses<GpsModel>("states: {bias: {sigma: 0}}"));
	EXPECT_NO_THROW(GpsModel(pt::configText("{correlated_sigma_m: 0, states: {bias: {sigma: 1.5}}}"), "GPS"));
}

TEST(Gps, InitialFixIsTheAntennaPositionWithItsLeverArm)
{
	// The navigator starts from this (position: gps): the antenna's point in
	// the navigation frame and where the antenna sits on the body.
	at::TestContext tc;
	GpsModel model(pt::configText("position_m: [-0.3, 0.1, -0.6]"), "GPS");
	const Eigen::Vector3d p(123.4, -56.7, 0.0);
	InitialFix fix;
	ASSERT_TRUE(model.initialFix(*ggaObs(tc.frame(), p), tc.ctx(), fix));
	EXPECT_LT((fix.p_n.head<2>() - p.head<2>()).norm(), 1e-6);
	EXPECT_TRUE(fix.r_b.isApprox(Eigen::Vector3d(-0.3, 0.1, -0.6)));
	// No fix, no frame, wrong class: nothing to start from (and no exception).
	EXPECT_FALSE(model.initialFix(*ggaObs(tc.frame(), p, 0), tc.ctx(), fix));
	FilterContext no_frame;
	EXPECT_FALSE(model.initialFix(*ggaObs(tc.frame(), p), no_frame, fix));
	EXPECT_FALSE(model.initialFix(*auvnav::obs::CObservationPressure::Create(), tc.ctx(), fix));
	// Unlike prepare, it is not rate limited: every valid fix offers a start.
	GpsModel limited(pt::configText("min_interval_s: 100"), "GPS");
	EXPECT_TRUE(limited.initialFix(*ggaObs(tc.frame(), p), tc.ctx(), fix));
	EXPECT_TRUE(limited.initialFix(*ggaObs(tc.frame(), p), tc.ctx(), fix));
}
