// The fast ManifoldUkf against the plain dense reference UKF (auvnav::core_testing)
// on a real stretch of the sample mission, with the real sensor plugins:
// IMU prediction + accelerometer, DVL, pressure, ADCP cells and model aiding.
#include <auvnav/config.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/navigator.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>

#include <cmath>
#include <map>

#include <auvnav/testing/reference_ukf.h>

using namespace auvnav;

TEST(ReferenceMission, FastFilterMatchesTheDenseReferenceOnTheSampleMission)
{
	const std::string repo = AUVNAV_SOURCE_DIR;
	auto cfg = config::Node::load(repo + "/config/flatfish.yaml");
	PluginHost host;           // declared first: outlives the navigator and the models
	Navigator nav(cfg, host);  // used for start-up (levelling, GPS start) only
	// Models to drive both filters by hand, from the same configuration.
	std::map<std::string, ModelPtr> models;
	for (const auto& s : cfg.sequence("sensors"))
	{
		if (s.string("label") != "GPS")
			models.emplace(s.string("label"),
			               host.create(s.string("plugin"), pluginConfigText(s), s.string("label")));
	}
	io::RawlogReader reader(repo + "/share/sample/sample.rawlog");
	mrpt::obs::CObservation::Ptr o;
	while ((o = reader.next()) && !nav.initialized()) nav.process(*o);
	// Skip ahead to the submerged square, where every sensor is active.
	while ((o = reader.next()) && nav.time() - nav.startTime() < 420) nav.process(*o);
	ASSERT_TRUE(o);

	ManifoldUkf fast(nav.filter().processModel(), nav.filter().utParams());
	reference::ReferenceUkf dense(nav.filter().processModel(), nav.filter().utParams());
	fast.initialize(nav.filter().state(), nav.filter().covariance());
	dense.initialize(nav.filter().state(), nav.filter().covariance());
	FilterContext ctx;
	ctx.omega_ie_n = nav.frame().earthRate();
	ctx.imu_position_b = nav.imuPosition_b();
	ctx.frame = &nav.frame();
	double t = nav.time();
	std::map<std::string, int> applied;
	double worst_mean = 0, worst_cov = 0;
	const double t_end =
	    t + 20.0;  // 20 s: 2000 predictions, ~2000 accelerometer, ~100 DVL, ~1000 ADCP-cell updates
	for (; o && t < t_end; o = reader.next())
	{
		const double t_obs = mrpt::Clock::toDouble(o->timestamp);
		if (o->sensorLabel == "IMU")
		{
			const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(o.get());
			const Eigen::Vector3d w(imu->get(mrpt::obs::IMU_WX), imu->get(mrpt::obs::IMU_WY),
			                        imu->get(mrpt::obs::IMU_WZ));
			const double dt = t_obs - t;
			if (dt <= 0) continue;
			fast.predict(w, ctx.omega_ie_n, dt);
			dense.predict(w, ctx.omega_ie_n, dt);
			ctx.omega_ib_b = w;
			t = t_obs;
		}
		const auto it = models.find(o->sensorLabel);
		if (it == models.end()) continue;
		ctx.t_s = t;
		ctx.mean = &fast.state();
		std::vector<Measurement> ms;
		std::string why;
		if (it->second->prepare(*o, ctx, ms, why) != PrepareStatus::Ok) continue;
		for (const auto& m : ms)
		{
			if (m.skipped) continue;
			const UpdateResult r = fast.update(*it->second, m, ctx);
			if (r.status != UpdateStatus::Accepted) continue;  // the reference is ungated: apply the same set
			ASSERT_TRUE(dense.update(*it->second, m, ctx));
			++applied[o->sensorLabel];
		}
		// Differences in units of the standard deviations (means) and correlation units (covariances).
		const TangentVector sd = dense.covariance().diagonal().cwiseSqrt();
		worst_mean = std::max(worst_mean,
		                      (fast.state().boxminus(dense.state()).array().abs() / sd.array()).maxCoeff());
		worst_cov = std::max(
		    worst_cov, ((fast.covariance() - dense.covariance()).array() / (sd * sd.transpose()).array())
		                   .abs()
		                   .maxCoeff());
	}
	std::printf(
	    "fast vs dense on 20 s of the sample: worst mean difference %.2e sd, covariance %.2e; updates:",
	    worst_mean, worst_cov);
	for (const auto& [label, n] : applied) std::printf(" %s %d", label.c_str(), n);
	std::printf("\n");
	for (const char* label : {"IMU", "DVL", "PRESSURE", "ADCP", "THRUSTERS"})
		EXPECT_GT(applied[label], 0) << label;
	EXPECT_LT(worst_mean, 1e-6);
	EXPECT_LT(worst_cov, 1e-6);
}
