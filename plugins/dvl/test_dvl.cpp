// The "dvl" plugin: bottom-track velocity with lever arm and mounting rotation.
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>

#include "dvl.h"
#include "plugin_test_support.h"

using namespace auvnav;
using auvnav::obs::CObservationDVL;
using auvnav::plugins::DvlModel;
namespace at = auvnav::testing;
namespace pt = auvnav::plugins::test;

namespace
{
constexpr double kDeg = M_PI / 180;
const Eigen::Vector3d kImuPos(0.29424, 0, -0.02863);   // flatfish_sensors.yaml imu.position_m
const Eigen::Vector3d kDvlPos(0.659, -0.141, 0.206);	 // dvl.position_m

/** Covariance of a 4-beam Janus DVL (30°, 0.01 m/s per beam), as the simulator computes it. */
Eigen::Matrix3d janusCovariance(double beam_sigma = 0.01, double incl = 30 * kDeg)
{
	Eigen::Matrix<double, 4, 3> A;
	for (int i = 0; i < 4; ++i)
	{
		const double az = (45.0 + 90.0 * i) * kDeg;
		A.row(i) << std::sin(incl) * std::cos(az), std::sin(incl) * std::sin(az), std::cos(incl);
	}
	return beam_sigma * beam_sigma * (A.transpose() * A).inverse();
}

CObservationDVL::Ptr dvlObs(const Eigen::Vector3d& v_s, const Eigen::Matrix3d& cov = janusCovariance(),
							bool lock = true)
{
	auto o = CObservationDVL::Create();
	o->sensorLabel = "DVL";
	o->bottom_lock = lock;
	o->altitude_m = 10;
	o->beam_inclination_rad = 30 * kDeg;
	o->beams.assign(4, auvnav::obs::DvlBeam{11.5, lock});
	for (int i = 0; i < 3; ++i) o->velocity_s_mps[i] = v_s[i];
	for (int r = 0; r < 3; ++r)
		for (int c = 0; c < 3; ++c) o->velocity_cov[3 * r + c] = cov(r, c);
	// The nominal mounting, as the simulator writes it.
	o->sensorPose = mrpt::poses::CPose3D(kDvlPos.x(), kDvlPos.y(), kDvlPos.z(), -22.5 * kDeg, 0, 0);
	return o;
}

/** The simulator's DVL, inverted independently: the sensor point's velocity
 *  over ground from the body rate relative to the Earth, in sensor axes. */
Eigen::Vector3d trueSensorVelocity(const NavState& x, const FilterContext& ctx, const Eigen::Matrix3d& R_bs,
								   const Eigen::Vector3d& r_s)
{
	const Eigen::Vector3d w_eb_b = ctx.omega_ib_b - x.b_w - x.R_nb.transpose() * ctx.omega_ie_n;
	const Eigen::Vector3d v_s_n = x.v_n + x.R_nb * w_eb_b.cross(r_s - ctx.imu_position_b);
	return (x.R_nb * R_bs).transpose() * v_s_n;
}

Eigen::Matrix3d nominalRbs() { return at::rotationYpr(-22.5 * kDeg, 0, 0); }

Measurement prepareOne(DvlModel& model, const mrpt::obs::CObservation& o, const FilterContext& ctx)
{
	std::vector<Measurement> out;
	std::string why;
	EXPECT_EQ(model.prepare(o, ctx, out, why), PrepareStatus::Ok) << why;
	return out.empty() ? Measurement{} : out[0];
}
}  // namespace

TEST(Dvl, DefaultConfigMatchesFlatfishMounting)
{
	const DvlModel m(pt::defaultConfig(), "DVL");
	EXPECT_TRUE(m.position_b().isApprox(kDvlPos, 1e-15));
	EXPECT_TRUE(m.R_bs().isApprox(nominalRbs(), 1e-15));
	EXPECT_EQ(m.uses(), uint32_t(kAttitude | kGyroBias | kVelocity));
	EXPECT_DOUBLE_EQ(m.gateProbability(), 0.999);
	const DvlModel e(pt::configText("{}"), "DVL");
	EXPECT_TRUE(e.R_bs().isApprox(m.R_bs(), 1e-15));
	EXPECT_TRUE(e.position_b() == m.position_b());
}

TEST(Dvl, RejectsBadConfigNamingTheKey)
{
	EXPECT_THROW(DvlModel(pt::configText("position_m: [1, 2]"), "DVL"), config::ConfigError);
	EXPECT_THROW(DvlModel(pt::configText("orientation_ypr_deg: [a, 0, 0]"), "DVL"), config::ConfigError);
	EXPECT_THROW(DvlModel(pt::configText("sigma_mps: 0"), "DVL"), config::ConfigError);
	EXPECT_THROW(DvlModel(pt::configText("extra_sigma_mps: -0.1"), "DVL"), config::ConfigError);
	EXPECT_THROW(DvlModel(pt::configText("use_observation_pose: perhaps"), "DVL"), config::ConfigError);
	EXPECT_THROW(DvlModel(pt::configText("gate_probability: -1"), "DVL"), config::ConfigError);
	EXPECT_TRUE(pt::ModuleRefuses("sigma_mps: -1", "sigma_mps"));
}

TEST(Dvl, ModuleExportsEntryAndCreatesFromDefaultConfig)
{
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("dvl", pt::readFile(AUVNAV_PLUGIN_DEFAULT_CONFIG),
										  kAttitude | kGyroBias | kVelocity));
}

TEST(Dvl, WellFormedOnRandomStates)
{
	at::TestContext tc;
	tc.ctx().imu_position_b = kImuPos;
	for (const char* cfg : {"{}", "use_observation_pose: true"})
	{
		DvlModel model(pt::configText(cfg), "DVL");
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			const NavState x = at::RandomNavState(seed);
			tc.ctx().omega_ib_b = Eigen::Vector3d(0.02, -0.01, 0.1 * std::sin(seed));
			const Eigen::Vector3d v_s = trueSensorVelocity(at::RandomNavState(seed + 50), tc.ctx(), nominalRbs(), kDvlPos);
			at::WellFormedOptions opt;
			opt.seed = seed;
			opt.accept_skip = false;
			EXPECT_TRUE(at::IsWellFormed(model, *dvlObs(v_s), tc.ctx(), x, opt)) << cfg << ", seed " << seed;
		}
	}
}

TEST(Dvl, ForwardMotionAtHeading90SeenThroughThe22_5DegreeMount)
{
	at::TestContext tc;
	tc.ctx().omega_ie_n.setZero();	// no rotation at all
	tc.ctx().imu_position_b = kImuPos;
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState x;
	x.R_nb = at::rotationYpr(90 * kDeg, 0, 0);	// level, facing east
	x.v_n = Eigen::Vector3d(0, 1, 0);			// 1 m/s east = straight ahead
	const Measurement m = prepareOne(model, *dvlObs(Eigen::Vector3d::Zero()), tc.ctx());
	const Eigen::VectorXd h = at::Predict(model, m, tc.ctx(), x);
	// Sensor x is yawed 22.5° to port: forward motion = (cos 22.5°, sin 22.5°, 0).
	EXPECT_NEAR(h[0], 0.9238795325, 1e-9);
	EXPECT_NEAR(h[1], 0.3826834324, 1e-9);
	EXPECT_NEAR(h[2], 0.0, 1e-12);
}

TEST(Dvl, YawRateAddsTheLeverArmVelocity)
{
	at::TestContext tc;
	tc.ctx().omega_ie_n.setZero();
	tc.ctx().imu_position_b = kImuPos;
	tc.ctx().omega_ib_b = Eigen::Vector3d(0, 0, 0.1);  // turning to starboard, 0.1 rad/s
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState x;	 // level, heading north, IMU point at rest
	const Measurement m = prepareOne(model, *dvlObs(Eigen::Vector3d::Zero()), tc.ctx());
	const Eigen::VectorXd h = at::Predict(model, m, tc.ctx(), x);
	// ω × (r_dvl − r_imu) = 0.1 e_z × (0.36476, −0.141, 0.23463) = (0.0141, 0.036476, 0) in body,
	// then into the sensor frame (rotate by +22.5° about z).
	const double c = std::cos(22.5 * kDeg), s = std::sin(22.5 * kDeg);
	EXPECT_NEAR(h[0], c * 0.0141 - s * 0.036476, 1e-12);
	EXPECT_NEAR(h[1], s * 0.0141 + c * 0.036476, 1e-12);
	EXPECT_NEAR(h[2], 0.0, 1e-12);
	EXPECT_NEAR(h[1], 0.0390953, 1e-6);
}

TEST(Dvl, EarthRateAndGyroBiasAreRemovedFromTheGyroSample)
{
	// At rest on a rotating Earth the gyro reads R_nbᵀ ω_ie + b_w: the body
	// does not turn relative to the seabed, so the DVL sees zero velocity.
	at::TestContext tc;
	tc.ctx().imu_position_b = kImuPos;
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState x;
	x.R_nb = at::rotationYpr(40 * kDeg, 5 * kDeg, -3 * kDeg);
	x.b_w = Eigen::Vector3d(0.01, -0.02, 0.03);	// exaggerated so a wrong sign would show
	tc.ctx().omega_ib_b = x.R_nb.transpose() * tc.ctx().omega_ie_n + x.b_w;
	const Measurement m = prepareOne(model, *dvlObs(Eigen::Vector3d::Zero()), tc.ctx());
	EXPECT_LT(at::Predict(model, m, tc.ctx(), x).norm(), 1e-15);
	// A gyro bias the state does not know about shows up as lever-arm velocity.
	NavState wrong = x;
	wrong.b_w.setZero();
	EXPECT_GT(at::Predict(model, m, tc.ctx(), wrong).norm(), 5e-3);
}

TEST(Dvl, ObservationPoseOnlyWhenConfigured)
{
	at::TestContext tc;
	tc.ctx().omega_ie_n.setZero();
	DvlModel cfg_pose(pt::defaultConfig(), "DVL");
	DvlModel obs_pose(pt::configText("use_observation_pose: true"), "DVL");
	auto o = dvlObs(Eigen::Vector3d::Zero());
	o->sensorPose = mrpt::poses::CPose3D(1.0, 0, 0, 90 * kDeg, 0, 0);	// sensor x = body right
	NavState x;
	x.v_n = Eigen::Vector3d(1, 0, 0);  // forward
	const Eigen::VectorXd h_cfg = at::Predict(cfg_pose, prepareOne(cfg_pose, *o, tc.ctx()), tc.ctx(), x);
	const Eigen::VectorXd h_obs = at::Predict(obs_pose, prepareOne(obs_pose, *o, tc.ctx()), tc.ctx(), x);
	EXPECT_NEAR(h_cfg[0], std::cos(22.5 * kDeg), 1e-12);  // config: the nominal 22.5° mount
	EXPECT_NEAR(h_obs[0], 0.0, 1e-12);					  // observation: yawed 90°
	EXPECT_NEAR(h_obs[1], -1.0, 1e-12);
	// With a yaw rate the lever arm of the observation pose is used.
	tc.ctx().omega_ib_b = Eigen::Vector3d(0, 0, 0.5);
	x.v_n.setZero();
	const Eigen::VectorXd h_rot = at::Predict(obs_pose, prepareOne(obs_pose, *o, tc.ctx()), tc.ctx(), x);
	EXPECT_NEAR(h_rot[0], 0.5, 1e-12);	// ω × (1, 0, 0) = (0, 0.5, 0) body = sensor x
}

TEST(Dvl, NoiseFromObservationCovariancePlusExtra)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	const double extra2 = 0.005 * 0.005;
	const Eigen::Matrix3d C = janusCovariance();
	Measurement m = prepareOne(model, *dvlObs(Eigen::Vector3d(1, 0, 0), C), tc.ctx());
	EXPECT_TRUE(m.R.isApprox(C + extra2 * Eigen::Matrix3d::Identity(), 1e-14));
	EXPECT_NEAR(m.R(0, 0), 0.01 * 0.01 / (4 * 0.25 * 0.5) + extra2, 1e-15);	// 2e-4 + 2.5e-5
	// Zero, NaN, asymmetric or indefinite covariance: the configured σ instead.
	Eigen::Matrix3d asym = C;
	asym(0, 1) += 1e-4;
	Eigen::Matrix3d indefinite = C;
	indefinite(2, 2) = -1e-4;
	Eigen::Matrix3d nan_cov = C;
	nan_cov(1, 1) = std::nan("");
	for (const Eigen::Matrix3d& bad : {Eigen::Matrix3d(Eigen::Matrix3d::Zero()), nan_cov, asym, indefinite})
	{
		m = prepareOne(model, *dvlObs(Eigen::Vector3d(1, 0, 0), bad), tc.ctx());
		EXPECT_TRUE(m.R.isApprox((0.02 * 0.02 + extra2) * Eigen::Matrix3d::Identity(), 1e-14)) << m.R;
	}
}

TEST(Dvl, UpdateReducesVelocityError)
{
	at::TestContext tc;
	tc.ctx().imu_position_b = kImuPos;
	tc.ctx().omega_ib_b = Eigen::Vector3d(0.01, -0.02, 0.05);
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState truth;
	truth.R_nb = at::rotationYpr(30 * kDeg, 2 * kDeg, -1 * kDeg);
	truth.v_n = Eigen::Vector3d(1.0, 0.2, 0.1);
	NavState x0 = truth;
	x0.v_n = Eigen::Vector3d(0.6, 0.6, -0.1);
	ManifoldUkf ukf(ProcessModel{}, UtParams{});
	ukf.initialize(x0, at::TypicalCovariance());
	const Eigen::Vector3d z = trueSensorVelocity(truth, tc.ctx(), nominalRbs(), kDvlPos);
	const double err_before = (x0.v_n - truth.v_n).norm();
	const auto res = at::ApplyObservation(ukf, model, *dvlObs(z), tc.ctx());
	ASSERT_EQ(res.status, PrepareStatus::Ok) << res.why;
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, UpdateStatus::Accepted) << res.updates[0].why;
	const double err_after = (ukf.state().v_n - truth.v_n).norm();
	EXPECT_LT(err_after, 0.1 * err_before) << "before " << err_before << ", after " << err_after;
	// Velocity variance collapses towards the DVL's.
	EXPECT_LT((ukf.covariance().block<3, 3>(idx::vel, idx::vel).trace()), 0.01);
}

TEST(Dvl, NoBottomLockIsSkipped)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	std::vector<Measurement> out;
	std::string why;
	EXPECT_EQ(model.prepare(*dvlObs(Eigen::Vector3d(1, 0, 0), janusCovariance(), false), tc.ctx(), out, why),
			  PrepareStatus::Skip);
	EXPECT_TRUE(out.empty());
	EXPECT_NE(why.find("bottom lock"), std::string::npos) << why;
	// Without lock even garbage velocities are a Skip, not an error.
	EXPECT_EQ(model.prepare(*dvlObs(Eigen::Vector3d(NAN, 0, 0), janusCovariance(), false), tc.ctx(), out, why),
			  PrepareStatus::Skip);
}

TEST(Dvl, InvalidInputs)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	DvlModel obs_pose(pt::configText("use_observation_pose: true"), "DVL");
	std::vector<Measurement> out;
	std::string why;
	for (int axis = 0; axis < 3; ++axis)
		for (double bad : {std::nan(""), HUGE_VAL})
		{
			Eigen::Vector3d v(1, 0, 0);
			v[axis] = bad;
			EXPECT_EQ(model.prepare(*dvlObs(v), tc.ctx(), out, why), PrepareStatus::Invalid);
			EXPECT_TRUE(out.empty());
		}
	auto o = dvlObs(Eigen::Vector3d(1, 0, 0));
	o->sensorPose = mrpt::poses::CPose3D(NAN, 0, 0, 0, 0, 0);
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Ok);  // pose not used
	EXPECT_EQ(obs_pose.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_EQ(model.prepare(*auvnav::obs::CObservationPressure::Create(), tc.ctx(), out, why),
			  PrepareStatus::Invalid);
	EXPECT_NE(why.find("CObservationDVL"), std::string::npos) << why;
}

TEST(Dvl, GrossOutlierRejectedAndNanNeverChangesTheState)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	ManifoldUkf ukf(ProcessModel{}, UtParams{});
	Covariance P0 = at::TypicalCovariance();
	P0.block<3, 3>(idx::vel, idx::vel) = 0.01 * 0.01 * Eigen::Matrix3d::Identity();
	ukf.initialize(at::RandomNavState(7), P0);
	const NavState before = ukf.state();
	const Covariance P_before = ukf.covariance();
	const Eigen::Vector3d v_true = trueSensorVelocity(before, tc.ctx(), nominalRbs(), kDvlPos);
	auto res = at::ApplyObservation(ukf, model, *dvlObs(v_true + Eigen::Vector3d(2.0, 0, 0)), tc.ctx());
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, UpdateStatus::Rejected);
	EXPECT_TRUE(at::NavStateIdentical(ukf.state(), before));
	res = at::ApplyObservation(ukf, model, *dvlObs(Eigen::Vector3d(NAN, 0, 0)), tc.ctx());
	EXPECT_EQ(res.status, PrepareStatus::Invalid);
	Measurement m = prepareOne(model, *dvlObs(v_true), tc.ctx());
	m.z[2] = std::nan("");
	EXPECT_EQ(ukf.update(model, m, tc.ctx()).status, UpdateStatus::Invalid);
	EXPECT_TRUE(at::NavStateIdentical(ukf.state(), before));
	EXPECT_TRUE(ukf.covariance() == P_before);
}
