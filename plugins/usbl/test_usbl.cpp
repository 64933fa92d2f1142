// The "usbl" plugin: acoustic fixes with lever arm, range-dependent noise,
// measurement time and an optional bias state.
#include <auvnav/obs/CObservationUSBL.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/testing/plugin_state_bench.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>

#include "plugin_test_support.h"
#include "usbl.h"

using auvnav::obs::CObservationUSBL;
using auvnav::obs::UsblFrame;
using auvnav::plugins::UsblModel;

namespace
{
const Eigen::Vector3d kTransponder(-0.5, 0.1, -0.3);
const char* kMounted = "position_m: [-0.5, 0.1, -0.3]";

/** A fix of the transponder at p_n, in the navigation frame or as lat/lon/depth. */
CObservationUSBL::Ptr fixAt(const earth::TangentFrame& frame, const Eigen::Vector3d& p_n,
                            UsblFrame f = UsblFrame::Geodetic)
{
	auto o = CObservationUSBL::Create();
	o->sensorLabel = "USBL";
	o->timestamp = mrpt::Clock::fromDouble(1.7e9 + 2.0);
	o->frame = f;
	if (f == UsblFrame::Geodetic)
	{
		const earth::Geodetic g = frame.toGeodetic(p_n);
		o->position = {g.lat_rad / kDeg, g.lon_rad / kDeg, frame.origin().h_m - g.h_m};
	}
	else
		o->position = {p_n.x(), p_n.y(), p_n.z()};
	o->slant_range_m = 100;
	return o;
}

Eigen::Vector3d transponderOf(const NavState& x)
{
	return pt::pointOnVehicle_n(x, kTransponder);
}
}  // namespace

TEST(Usbl, DefaultConfigAndModule)
{
	UsblModel m(pt::defaultConfig(), "USBL");
	EXPECT_TRUE(m.position_b().isZero());
	EXPECT_EQ(m.uses(), uint32_t(kAttitude | kPosition));
	EXPECT_EQ(at::PluginStateBench(m).extraSize(), 0);
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("usbl", pt::defaultConfigText(), kAttitude | kPosition));
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("usbl", "states: {bias: {sigma: 1}}",
	                                      kAttitude | kPosition | kPluginStates));
}

TEST(Usbl, RejectsBadConfigNamingTheKey)
{
	for (const char* yaml : {"sigma_m: 0", "sigma_range_fraction: 2", "position_m: [0, 0, 1e6]",
	                         "states: {bais: {sigma: 1}}", "states: {bias: {sigma: -1}}"})
		EXPECT_TRUE(pt::ConstructorRefuses<UsblModel>(yaml));
	EXPECT_TRUE(pt::ModuleRefuses("sigma_cm: 3", "sigma_m"));  // unknown key, with the suggestion
}

TEST(Usbl, WellFormedOnRandomStatesWithAndWithoutBias)
{
	pt::FlatfishContext tc;
	for (const char* cfg :
	     {kMounted, "{position_m: [0, 0, 0.4], use_depth: true}", "states: {bias: {sigma: 2}}"})
	{
		UsblModel model(pt::configText(cfg), "USBL");
		const at::PluginStateBench bench(model);
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			const auto o = fixAt(tc.frame(), transponderOf(bench.randomState(seed + 3)));
			EXPECT_TRUE(pt::IsWellFormedAndUsed(model, *o, tc.ctx(), bench.randomState(seed), seed))
			    << cfg << ", seed " << seed;
		}
	}
}

TEST(Usbl, GeodeticAndLocalFixesGiveTheSamePosition)
{
	at::TestContext tc;
	UsblModel model(pt::configText("use_depth: true"), "USBL");
	for (const Eigen::Vector3d& p :
	     {Eigen::Vector3d(0, 0, 5), Eigen::Vector3d(1234.5, -987.6, 40), Eigen::Vector3d(-15000, 20000, 250)})
	{
		const Measurement g = pt::prepareOne(model, *fixAt(tc.frame(), p), tc.ctx());
		const Measurement l = pt::prepareOne(model, *fixAt(tc.frame(), p, UsblFrame::LocalNed), tc.ctx());
		ASSERT_EQ(g.z.size(), 3);
		// North/east round-trip exactly; the depth is the geodetic one (the
		// tangent plane's down grows by the Earth's curvature: 49 m at 25 km).
		EXPECT_LT((g.z - p).head<2>().norm(), 1e-6) << g.z.transpose();
		EXPECT_NEAR(g.z[2], p.z() - p.head<2>().squaredNorm() / (2 * 6.37e6), 2.0);
		EXPECT_TRUE(l.z.isApprox(p, 1e-15));
	}
}

TEST(Usbl, NoiseFromTheFixOrGrowingWithSlantRange)
{
	at::TestContext tc;
	UsblModel model(pt::configText("{sigma_m: 0.3, sigma_range_fraction: 0.01}"), "USBL");
	auto o = fixAt(tc.frame(), Eigen::Vector3d(10, 20, 30));
	o->slant_range_m = 400;  // 1 % of 400 m = 4 m, with 0.3 m: 4.011 m
	EXPECT_NEAR(pt::prepareOne(model, *o, tc.ctx()).R(0, 0), 0.09 + 16.0, 1e-9);
	o->slant_range_m = std::nan("");  // unknown range: the constant part only
	EXPECT_NEAR(pt::prepareOne(model, *o, tc.ctx()).R(1, 1), 0.09, 1e-12);
	o->covariance_ned_m2 = {4, 1, 0, 1, 9, 0, 0, 0, 25};
	const Measurement m = pt::prepareOne(model, *o, tc.ctx());
	EXPECT_EQ(m.R(0, 0), 4);
	EXPECT_EQ(m.R(0, 1), 1);
	EXPECT_EQ(m.R(1, 1), 9);
	UsblModel own(pt::configText("{sigma_m: 0.3, use_reported_covariance: false}"), "USBL");
	EXPECT_NEAR(pt::prepareOne(own, *o, tc.ctx()).R(0, 0), 0.09, 1e-12);
}

TEST(Usbl, MeasurementTimeFromTheFixElseTheNavigatorsEstimate)
{
	UsblModel model(pt::defaultConfig(), "USBL");
	at::TestContext tc;
	auto o = fixAt(tc.frame(), Eigen::Vector3d(1, 2, 3));
	EXPECT_EQ(model.measurementTime(*o, 1.7e9 + 1.5), 1.7e9 + 1.5);
	o->measurement_time = mrpt::Clock::fromDouble(1.7e9 - 0.25);
	EXPECT_NEAR(model.measurementTime(*o, 1.7e9 + 1.5), 1.7e9 - 0.25, 1e-6);
}

TEST(Usbl, LeverArmAndBiasEnterH)
{
	pt::FlatfishContext tc;
	UsblModel model(pt::configText(std::string(kMounted) + "\nstates: {bias: {sigma: 1}}"), "USBL");
	const at::PluginStateBench bench(model, 1);
	NavState x = bench.randomState(5);
	bench["bias"](x, 0) = 0.7;
	bench["bias"](x, 1) = -1.2;
	const Measurement m = pt::prepareOne(model, *fixAt(tc.frame(), Eigen::Vector3d(0, 0, 0)), tc.ctx());
	const Eigen::VectorXd h = at::Predict(model, m, tc.ctx(), x);
	const Eigen::Vector3d t = transponderOf(x);
	EXPECT_NEAR(h[0], t.x() + 0.7, 1e-12);
	EXPECT_NEAR(h[1], t.y() - 1.2, 1e-12);
	// A state without the bias coordinates cannot be evaluated.
	EXPECT_TRUE(at::Predict(model, m, tc.ctx(), at::RandomNavState(5, 1)).array().isNaN().all());
}

TEST(Usbl, InitialFixIsTheTransponderWithItsLeverArm)
{
	at::TestContext tc;
	UsblModel model(pt::configText(kMounted), "USBL");
	InitialFix f;
	ASSERT_TRUE(model.initialFix(*fixAt(tc.frame(), Eigen::Vector3d(50, -60, 12)), tc.ctx(), f));
	EXPECT_LT((f.p_n - Eigen::Vector3d(50, -60, 12)).head<2>().norm(), 1e-6);
	EXPECT_TRUE(f.r_b == kTransponder);
	auto bad = fixAt(tc.frame(), Eigen::Vector3d(0, 0, 0));
	bad->position[0] = std::nan("");
	EXPECT_FALSE(model.initialFix(*bad, tc.ctx(), f));
}

TEST(Usbl, BadFixesAreInvalidAndNeverReachTheState)
{
	at::TestContext tc;
	UsblModel model(pt::defaultConfig(), "USBL");
	std::vector<Measurement> out;
	std::string why;
	auto o = fixAt(tc.frame(), Eigen::Vector3d(0, 0, 0));
	o->position[1] = std::numeric_limits<double>::infinity();
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_NE(why.find("non-finite"), std::string::npos) << why;
	o->position = {95, 0, 0};  // latitude beyond the pole
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_TRUE(pt::RefusesOtherClass<mrpt::obs::CObservationIMU>(model, tc.ctx(), "CObservationUSBL"));
}

TEST(Usbl, UpdateReducesErrorAndAGrossOutlierIsRejected)
{
	pt::FlatfishContext tc;
	UsblModel model(pt::configText(std::string(kMounted) + "\nsigma_m: 3\nsigma_range_fraction: 0"), "USBL");
	const NavState truth = pt::levelState(30 * kDeg, Eigen::Vector3d(10, 20, 30));
	NavState x0 = truth;
	x0.p_n = Eigen::Vector3d(15, 16, 30);
	ManifoldUkf ukf = pt::filterAt(x0);  // 5 m per axis
	const double before = (x0.p_n - truth.p_n).head<2>().norm();
	auto r = at::ApplyObservation(ukf, model, *fixAt(tc.frame(), transponderOf(truth)), tc.ctx());
	ASSERT_EQ(r.status, PrepareStatus::Ok) << r.why;
	ASSERT_EQ(r.updates.size(), 1u);
	EXPECT_EQ(r.updates[0].status, UpdateStatus::Accepted);
	// Prior 5 m, fix 3 m (geodetic round trip at 20 m: sub-mm): the error keeps 9/34 of itself.
	EXPECT_NEAR((ukf.state().p_n - truth.p_n).head<2>().norm(), before * 9.0 / 34.0, 0.05 * before);
	const NavState settled = ukf.state();
	r = at::ApplyObservation(ukf, model,
	                         *fixAt(tc.frame(), transponderOf(truth) + Eigen::Vector3d(80, 60, 0)), tc.ctx());
	ASSERT_EQ(r.updates.size(), 1u);
	EXPECT_EQ(r.updates[0].status, UpdateStatus::Rejected);
	EXPECT_TRUE(at::NavStateIdentical(ukf.state(), settled));
}

TEST(UsblObservation, RoundTripKeepsEveryFieldAndACorruptFrameIsRefused)
{
	CObservationUSBL o;
	o.sensorLabel = "USBL";
	o.timestamp = mrpt::Clock::fromDouble(1.7e9 + 2.125);
	o.measurement_time = mrpt::Clock::fromDouble(1.7e9 + 0.5);
	o.frame = UsblFrame::LocalNed;
	o.position = {1.5, -2.25, 30.125};
	o.covariance_ned_m2 = {1, 0.5, 0, 0.5, 2, 0, 0, 0, 3};
	o.slant_range_m = 123.5;
	o.transponder_id = 7;
	o.sensorPose = mrpt::poses::CPose3D(-0.5, 0.1, -0.3, 0, 0, 0);
	mrpt::io::CMemoryStream buf;
	mrpt::serialization::archiveFrom(buf) << o;
	buf.Seek(0);
	auto back =
	    std::dynamic_pointer_cast<CObservationUSBL>(mrpt::serialization::archiveFrom(buf).ReadObject());
	ASSERT_TRUE(back);
	EXPECT_EQ(back->timestamp, o.timestamp);
	EXPECT_EQ(back->measurement_time, o.measurement_time);
	EXPECT_EQ(back->frame, o.frame);
	EXPECT_EQ(back->position, o.position);
	EXPECT_EQ(back->covariance_ned_m2, o.covariance_ned_m2);
	EXPECT_EQ(back->slant_range_m, o.slant_range_m);
	EXPECT_EQ(back->transponder_id, 7);
	EXPECT_EQ(back->sensorPose.x(), -0.5);
	// The frame byte follows label, pose and measurement time; find it by value.
	const auto* p = static_cast<const uint8_t*>(buf.getRawBufferData());
	std::vector<uint8_t> bytes(p, p + buf.getTotalBytesCount());
	mrpt::io::CMemoryStream probe;
	CObservationUSBL geo = o;
	geo.frame = UsblFrame::Geodetic;
	mrpt::serialization::archiveFrom(probe) << geo;
	const auto* q = static_cast<const uint8_t*>(probe.getRawBufferData());
	std::size_t at_byte = 0;
	for (std::size_t i = 0; i < bytes.size(); ++i)
		if (bytes[i] != q[i]) at_byte = i;
	ASSERT_EQ(bytes[at_byte], 1);
	bytes[at_byte] = 7;
	mrpt::io::CMemoryStream bad;
	bad.Write(bytes.data(), bytes.size());
	bad.Seek(0);
	EXPECT_ANY_THROW(mrpt::serialization::archiveFrom(bad).ReadObject());
}
