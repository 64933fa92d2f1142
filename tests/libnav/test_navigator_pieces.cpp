// The navigator's pieces on their own (aiding_policy.h, filter_history.h)
// and a Navigator built in-process from a model the test owns: no plugin
// host, no shared library.
#include <auvnav/aiding_policy.h>
#include <auvnav/filter_history.h>
#include <auvnav/navigator.h>
#include <auvnav/obs/CObservationPressure.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>

#include <cmath>

namespace auvnav
{
namespace
{
Measurement fix(double sigma_m)
{
	Measurement m;
	m.z = Eigen::Vector2d::Zero();
	m.R = Eigen::Matrix2d::Identity() * sigma_m * sigma_m;
	return m;
}

UpdateResult rejected(const Eigen::Vector2d& nu)
{
	UpdateResult r;
	r.status = UpdateStatus::Rejected;
	r.innovation = nu;
	return r;
}

TEST(AidingPolicy, AgreeingRejectedFixesReinitializeThePosition)
{
	AidingParams p;
	p.reinit_fixes = 3;
	const AidingPolicy policy(p);
	SensorAiding s;
	const Measurement m = fix(2.0);
	const Eigen::Vector2d off(40, -25);  // the state is 47 m off; the fixes say the same
	EXPECT_EQ(policy.decide(s, m, rejected(off), 1.0, true, kPosition), AidingAction::Keep);
	AidingPolicy::settle(s.gate, UpdateStatus::Rejected, 1.0);
	EXPECT_EQ(policy.decide(s, m, rejected(off + Eigen::Vector2d(0.5, 0)), 2.0, true, kPosition),
	          AidingAction::Keep);
	AidingPolicy::settle(s.gate, UpdateStatus::Rejected, 2.0);
	EXPECT_EQ(policy.decide(s, m, rejected(off - Eigen::Vector2d(0, 0.5)), 3.0, true, kPosition),
	          AidingAction::ReinitializePosition);
	const auto [mean, first] = policy.reinitialized(s, 3.0);
	EXPECT_TRUE(first);
	EXPECT_NEAR(mean.x(), off.x() + 0.5 / 3, 1e-9);
	EXPECT_NEAR(mean.y(), off.y() - 0.5 / 3, 1e-9);
	EXPECT_EQ(s.gate.fix_run.size(), 0u);
	// A re-filtering pass makes the same decisions again: counted once.
	for (int i = 0; i < 3; ++i)
	{
		const Eigen::Vector2d nu = off + Eigen::Vector2d(0.1 * i, 0);
		if (policy.decide(s, m, rejected(nu), 1.0 + i, true, kPosition) == AidingAction::ReinitializePosition)
			EXPECT_FALSE(policy.reinitialized(s, 1.0 + i).second);
		else
			AidingPolicy::settle(s.gate, UpdateStatus::Rejected, 1.0 + i);
	}
	EXPECT_TRUE(policy.reinitialized(s, 4.0).second);  // a later fix counts
}

TEST(AidingPolicy, ScatteredRejectedFixesDoNotMoveThePosition)
{
	const AidingPolicy policy;
	SensorAiding s;
	const Measurement m = fix(2.0);
	const Eigen::Vector2d offs[] = {{40, 0}, {-40, 0}, {0, 40}, {0, -40}};
	for (int i = 0; i < 4; ++i)
	{
		EXPECT_NE(policy.decide(s, m, rejected(offs[i]), i, true, kPosition),
		          AidingAction::ReinitializePosition);
		AidingPolicy::settle(s.gate, UpdateStatus::Rejected, i);
	}
}

TEST(AidingPolicy, RecoveryAfterALongRunOfRejections)
{
	AidingParams p;
	p.recovery_after_s = 30;
	p.consistent_rejections = 0;
	const AidingPolicy policy(p);
	SensorAiding s;
	Measurement m;
	m.z = Eigen::Vector3d::Zero();
	m.R = Eigen::Matrix3d::Identity();
	UpdateResult r;
	r.status = UpdateStatus::Rejected;
	r.innovation = Eigen::Vector3d(5, -3, 1);
	for (double t : {0.0, 10.0, 30.0})
	{
		EXPECT_EQ(policy.decide(s, m, r, t, false, kVelocity), AidingAction::Keep) << t;
		AidingPolicy::settle(s.gate, UpdateStatus::Rejected, t);
	}
	EXPECT_DOUBLE_EQ(s.gate.rejecting_since_s, 0.0);
	EXPECT_EQ(policy.decide(s, m, r, 30.5, false, kVelocity), AidingAction::RecoverNoise);
	AidingPolicy::settle(s.gate, UpdateStatus::Recovered, 30.5);
	EXPECT_LT(s.gate.rejecting_since_s, 0);
}

TEST(AidingPolicy, ConsistentRejectionsOfAnAbsoluteAidWidenTheState)
{
	const AidingPolicy policy;  // consistent_rejections 5
	SensorAiding depth, velocity;
	Measurement m;
	m.z = Eigen::VectorXd::Zero(1);
	m.R = Eigen::MatrixXd::Identity(1, 1) * 0.01;
	UpdateResult r;
	r.status = UpdateStatus::Rejected;
	AidingAction a_depth = AidingAction::Keep, a_vel = AidingAction::Keep;
	for (int i = 0; i < 5; ++i)
	{
		r.innovation = Eigen::VectorXd::Constant(1, 1.0 + 0.01 * i);  // the same bias every time
		a_depth = policy.decide(depth, m, r, i, false, kPosition);
		a_vel = policy.decide(velocity, m, r, i, false, kVelocity | kAttitude);
		AidingPolicy::settle(depth.gate, UpdateStatus::Rejected, i);
		AidingPolicy::settle(velocity.gate, UpdateStatus::Rejected, i);
	}
	EXPECT_EQ(a_depth, AidingAction::RecoverState);
	EXPECT_EQ(a_vel, AidingAction::RecoverNoise);
}

FilterCheckpoint checkpointAt(std::size_t event, double t_s)
{
	FilterCheckpoint c;
	c.event = event;
	c.t_s = t_s;
	return c;
}

TEST(FilterHistory, RewindFindsInOrderPlaceAndDropsLaterCheckpoints)
{
	DelayedFusionParams p;
	p.max_delay_s = 1.0;
	p.checkpoint_every_s = 0.25;
	FilterHistory h(p);
	EXPECT_FALSE(h.rewindFor(0.0));  // nothing kept
	// IMU at 0.0, 0.1, …, 0.9; a measurement event after the IMU at 0.5 (t_obs 0.52).
	for (int i = 0; i < 10; ++i)
	{
		const double t = 0.1 * i;
		if (h.checkpointDue(t)) h.addCheckpoint(checkpointAt(h.end(), t));
		h.pushImu(t, Eigen::Vector3d::Zero());
		if (i == 5)
		{
			FilterEvent e;
			e.t_obs = 0.52;
			e.t = t;
			h.insert(h.end(), std::move(e));
		}
	}
	// Checkpoints before events 0 (t 0), 3 (t 0.3), 7 (t 0.6: events shift by the measurement), 10 (t 0.9).
	ASSERT_EQ(h.end(), 11u);
	const auto ins = h.rewindFor(0.55);
	ASSERT_TRUE(ins);
	EXPECT_EQ(*ins, 7u);  // after IMU 0.5 and the measurement taken at 0.52
	EXPECT_EQ(h.lastCheckpoint().event, 7u);
	const auto early = h.rewindFor(0.31);
	ASSERT_TRUE(early);
	EXPECT_EQ(*early, 4u);  // after the IMU at 0.3
	EXPECT_EQ(h.lastCheckpoint().event, 3u);
	EXPECT_FALSE(h.rewindFor(-1.0));  // older than everything kept
}

TEST(FilterHistory, TrimKeepsWhatTheLongestDelayNeeds)
{
	DelayedFusionParams p;
	p.max_delay_s = 0.5;
	p.checkpoint_every_s = 0.25;
	FilterHistory h(p);
	for (int i = 0; i <= 20; ++i)
	{
		const double t = 0.1 * i;
		if (h.checkpointDue(t)) h.addCheckpoint(checkpointAt(h.end(), t));
		h.trim(t);
		h.pushImu(t, Eigen::Vector3d::Zero());
	}
	// At t = 2.0 a measurement 0.5 s old still finds a checkpoint before it.
	const auto ins = h.rewindFor(1.5);
	ASSERT_TRUE(ins);
	EXPECT_LE(h.lastCheckpoint().t_s, 1.5);
	EXPECT_FALSE(h.rewindFor(0.5));  // long trimmed
}

/** A toy depth sensor: z = the IMU's depth [m], 1e-4 m per pascal of a
 *  pressure observation (no atmosphere, no density: a test's own model). */
class ToyDepthModel : public SafeMeasurementModel
{
 public:
	uint32_t doUses() const override { return kPosition; }

 protected:
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext&,
	                        std::vector<Measurement>& out, std::string& why) override
	{
		const auto* p = dynamic_cast<const obs::CObservationPressure*>(&obs);
		if (!p)
		{
			why = "not a pressure observation";
			return PrepareStatus::Invalid;
		}
		Measurement m;
		m.z = Eigen::VectorXd::Constant(1, p->pressure_pa * 1e-4);
		m.R = Eigen::MatrixXd::Constant(1, 1, 0.05 * 0.05);
		out.push_back(m);
		return PrepareStatus::Ok;
	}
	bool doPredict(const NavState& x, const Measurement&, const FilterContext&,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override
	{
		z_pred[0] = x.p_n.z();
		return true;
	}
};

NavigatorConfig toyConfig()
{
	auto cfg = config::Node::load(std::string(AUVNAV_SOURCE_DIR) + "/config/flatfish.yaml");
	cfg.set("filter.initial.position", "config");
	return NavigatorConfig::fromNode(cfg);
}

std::vector<SensorSource> toySensors()
{
	std::vector<SensorSource> s;
	s.push_back(
	    {"DEPTH", "in-process", ModelPtr(new ToyDepthModel, [](MeasurementModel* m) { delete m; }), 0.0});
	return s;
}

mrpt::obs::CObservationIMU::Ptr imuAt(double t_s)
{
	auto o = mrpt::obs::CObservationIMU::Create();
	o->sensorLabel = "IMU";
	o->timestamp = mrpt::Clock::fromDouble(t_s);
	o->set(mrpt::obs::IMU_WX, 0.0), o->set(mrpt::obs::IMU_WY, 0.0), o->set(mrpt::obs::IMU_WZ, 0.0);
	o->set(mrpt::obs::IMU_X_ACC, 0.0), o->set(mrpt::obs::IMU_Y_ACC, 0.0), o->set(mrpt::obs::IMU_Z_ACC, -9.81);
	return o;
}

TEST(Navigator, RunsAnInProcessModelWithoutAPluginHost)
{
	Navigator nav(toyConfig(), toySensors());
	ASSERT_EQ(nav.stats().size(), 2u);
	const double t0 = 1.7e9, depth_m = 5.0;
	for (int k = 0; k < 2000; ++k)  // 20 s at 100 Hz, a depth every 0.1 s
	{
		const double t = t0 + 0.01 * k;
		nav.process(*imuAt(t));
		if (k % 10 == 5)
		{
			auto p = obs::CObservationPressure::Create();
			p->sensorLabel = "DEPTH";
			p->timestamp = mrpt::Clock::fromDouble(t);
			p->pressure_pa = depth_m * 1e4;
			nav.process(*p);
		}
	}
	nav.finish();
	ASSERT_TRUE(nav.initialized());
	const SensorStats depth = nav.stats()[1];
	EXPECT_EQ(depth.label, "DEPTH");
	EXPECT_EQ(depth.plugin, "in-process");
	EXPECT_EQ(depth.before_init, 10u);  // levelling takes the first second
	EXPECT_GE(depth.accepted, 185u);    // every later one, bar the gate's first rejections
	EXPECT_NEAR(nav.filter().state().p_n.z(), depth_m, 0.05);
	EXPECT_LT(std::sqrt(nav.filter().covariance()(idx::pos + 2, idx::pos + 2)), 0.05);
}

/** The toy depth model, keeping the context of its last prepare. */
class ContextRecordingDepthModel final : public ToyDepthModel
{
 public:
	FilterContext last;

 protected:
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override
	{
		last = ctx;
		return ToyDepthModel::doPrepare(obs, ctx, out, why);
	}
};

TEST(Navigator, AngularAccelerationLagsByTheDelayItStates)
{
	auto* model = new ContextRecordingDepthModel;
	std::vector<SensorSource> sensors;
	sensors.push_back({"DEPTH", "in-process", ModelPtr(model, [](MeasurementModel* m) { delete m; }), 0.0});
	const NavigatorConfig cfg = toyConfig();
	Navigator nav(cfg, std::move(sensors));
	// At rest for 2 s, then a yaw rate growing as j t²/2: the angular
	// acceleration is the ramp j t, which a lag of d turns into j (t − d).
	const double t0 = 1.7e9, t_turn = t0 + 2.0, jerk = 0.05;
	for (int k = 0; k <= 500; ++k)
	{
		const double t = t0 + 0.01 * k;
		const double since_s = std::max(0.0, t - t_turn);
		auto imu = imuAt(t);
		imu->set(mrpt::obs::IMU_WZ, jerk * since_s * since_s / 2);
		nav.process(*imu);
		if (k % 10 == 5)
		{
			auto p = obs::CObservationPressure::Create();
			p->sensorLabel = "DEPTH";
			p->timestamp = mrpt::Clock::fromDouble(t);
			p->pressure_pa = 5e4;
			nav.process(*p);
		}
	}
	const FilterContext& c = model->last;
	EXPECT_NEAR(c.alpha_delay_s, cfg.imu.angular_acceleration_tau_s + 0.005, 1e-6);  // stamps: ~0.2 µs
	ASSERT_GT(c.t_s - t_turn, 2.5);  // the low-pass has settled on the ramp
	EXPECT_NEAR(c.alpha_b.z(), jerk * (c.t_s - t_turn - c.alpha_delay_s), 1e-6);
}

TEST(Navigator, RefusesAStartFixSensorItWasNotGiven)
{
	NavigatorConfig c = toyConfig();
	c.initial.position_from_fix = true;
	c.initial.fix_label = "GPS";
	EXPECT_THROW(Navigator(c, toySensors()), std::invalid_argument);
}

TEST(Navigator, DenialOfAnUnknownSensorIsRefused)
{
	Navigator nav(toyConfig(), toySensors());
	EXPECT_NO_THROW(nav.addDenial(parseDenial("DEPTH:10:20")));
	try
	{
		nav.addDenial(parseDenial("depth:10:20"));  // labels are case-sensitive
		ADD_FAILURE() << "no error";
	}
	catch (const std::invalid_argument& e)
	{
		EXPECT_STREQ(e.what(), "denial of an unknown sensor 'depth' (the sensors: DEPTH)");
	}
}

TEST(DenialWindow, ParsesLabelAndSecondsStrictly)
{
	const DenialWindow w = parseDenial("GPS:1200:1e9");
	ASSERT_EQ(w.labels.size(), 1u);
	EXPECT_EQ(w.labels[0], "GPS");
	EXPECT_EQ(w.from_s, 1200);
	EXPECT_EQ(w.to_s, 1e9);
	const std::pair<const char*, const char*> bad[] = {{"GPS:abc:100", "FROM 'abc' is not a number"},
	                                                   {"GPS::100", "FROM '' is not a number"},
	                                                   {"GPS:0:100s", "TO '100s' is not a number"},
	                                                   {"GPS:0:inf", "TO 'inf' is not a number"},
	                                                   {":0:100", "no sensor label"},
	                                                   {"GPS:100", "not three fields"},
	                                                   {"GPS:0:1:2", "not three fields"},
	                                                   {"GPS:100:50", "need 0 <= FROM < TO"},
	                                                   {"GPS:-5:50", "need 0 <= FROM < TO"}};
	for (const auto& [text, why] : bad)
	{
		try
		{
			parseDenial(text);
			ADD_FAILURE() << text << ": no error";
		}
		catch (const config::ConfigError& e)
		{
			EXPECT_EQ(std::string(e.what()), std::string(why) + " (expected LABEL:FROM:TO, seconds)") << text;
		}
	}
}

}  // namespace
}  // namespace auvnav
