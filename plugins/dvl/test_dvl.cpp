// The "dvl" plugin: bottom-track velocity with lever arm and mounting rotation, in every
// output frame (instrument, vehicle, Earth NED/ENU, beams) and both signs.
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/so3.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/testing/plugin_state_bench.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>

#include "dvl.h"
#include "plugin_test_support.h"

using auvnav::obs::CObservationDVL;
using auvnav::obs::DvlFrame;
using auvnav::obs::DvlSign;
using auvnav::plugins::DvlModel;

namespace
{
const Eigen::Vector3d kDvlPos(0.659, -0.141, 0.206);  // dvl.position_m

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

Eigen::Matrix3d nominalRbs()
{
	return at::rotationYpr(-22.5 * kDeg, 0, 0);
}

constexpr DvlFrame kAllFrames[] = {DvlFrame::Instrument, DvlFrame::Vehicle, DvlFrame::EarthNed,
                                   DvlFrame::EarthEnu, DvlFrame::Beam};

/** Unit vector of a beam in the sensor frame (CObservationDVL.h). */
Eigen::Vector3d beamUnit(double incl, double az)
{
	return {std::sin(incl) * std::cos(az), std::sin(incl) * std::sin(az), std::cos(incl)};
}

/** What a DVL reporting in `frame` with `sign` sees for the true state `x`,
 *  computed independently of the plugin from the DVL point's velocity in
 *  the navigation frame: instrument R_nsᵀ v, vehicle R_nbᵀ v, earth v (NED)
 *  or [E, N, −D], beams u_iᵀ R_nsᵀ v (azimuths 45° + 90° i, the first
 *  `valid_beams` valid). */
CObservationDVL::Ptr modeObs(DvlFrame frame, const NavState& x, const FilterContext& ctx,
                             DvlSign sign = DvlSign::VehicleOverBottom, int valid_beams = 4)
{
	const Eigen::Vector3d w_eb_b = ctx.omega_ib_b - x.b_w - x.R_nb.transpose() * ctx.omega_ie_n;
	const Eigen::Vector3d v_dvl_n = x.v_n + x.R_nb * w_eb_b.cross(kDvlPos - ctx.imu_position_b);
	const Eigen::Vector3d v_b = x.R_nb.transpose() * v_dvl_n;
	const Eigen::Vector3d v_s = nominalRbs().transpose() * v_b;
	const double sgn = sign == DvlSign::BottomOverInstrument ? -1 : 1;
	Eigen::Vector3d v = v_s;
	if (frame == DvlFrame::Vehicle) v = v_b;
	if (frame == DvlFrame::EarthNed) v = v_dvl_n;
	if (frame == DvlFrame::EarthEnu) v = Eigen::Vector3d(v_dvl_n.y(), v_dvl_n.x(), -v_dvl_n.z());
	auto o = dvlObs(sgn * v);
	o->frame = frame;
	o->sign = sign;
	for (int i = 0; i < 4; ++i)
	{
		auto& b = o->beams[i];
		b.azimuth_rad = (45.0 + 90.0 * i) * kDeg;
		b.valid = i < valid_beams;
		b.velocity_mps =
		    frame == DvlFrame::Beam && b.valid ? sgn * beamUnit(30 * kDeg, b.azimuth_rad).dot(v_s) : 0;
	}
	if (frame == DvlFrame::Beam)
	{
		o->velocity_s_mps.fill(std::nan(""));  // as the simulator: no 3-D velocity
		o->velocity_cov.fill(std::nan(""));
		o->beam_velocity_sigma_mps = 0.01;
		for (auto& b : o->beams)
			if (!b.valid) b.velocity_mps = std::nan("");
	}
	return o;
}

/** All measurements' z stacked, and all h(x) stacked. */
void stackZH(const DvlModel& model, const std::vector<Measurement>& ms, const FilterContext& ctx,
             const NavState& x, Eigen::VectorXd& z, Eigen::VectorXd& h)
{
	Eigen::Index n = 0;
	for (const auto& m : ms) n += m.z.size();
	z.resize(n);
	h.resize(n);
	n = 0;
	for (const auto& m : ms)
	{
		z.segment(n, m.z.size()) = m.z;
		h.segment(n, m.z.size()) = at::Predict(model, m, ctx, x);
		n += m.z.size();
	}
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
	for (const char* yaml :
	     {"position_m: [1, 2]", "orientation_ypr_deg: [a, 0, 0]", "sigma_mps: 0", "extra_sigma_mps: -0.1",
	      "use_observation_pose: perhaps", "gate_probability: -1"})
		EXPECT_TRUE(pt::ConstructorRefuses<DvlModel>(yaml));
	EXPECT_TRUE(pt::ModuleRefuses("sigma_mps: -1", "sigma_mps"));
}

TEST(Dvl, ModuleExportsEntryAndCreatesFromDefaultConfig)
{
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("dvl", pt::defaultConfigText(), kAttitude | kGyroBias | kVelocity));
}

TEST(Dvl, WellFormedOnRandomStates)
{
	pt::FlatfishContext tc;
	for (const char* cfg : {"{}", "use_observation_pose: true"})
	{
		DvlModel model(pt::configText(cfg), "DVL");
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			tc.ctx().omega_ib_b = Eigen::Vector3d(0.02, -0.01, 0.1 * std::sin(seed));
			const Eigen::Vector3d v_s =
			    trueSensorVelocity(at::RandomNavState(seed + 50), tc.ctx(), nominalRbs(), kDvlPos);
			EXPECT_TRUE(
			    pt::IsWellFormedAndUsed(model, *dvlObs(v_s), tc.ctx(), at::RandomNavState(seed), seed))
			    << cfg << ", seed " << seed;
		}
	}
}

TEST(Dvl, ForwardMotionAtHeading90SeenThroughThe22_5DegreeMount)
{
	pt::FlatfishContext tc;
	tc.ctx().omega_ie_n.setZero();  // no rotation at all
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState x;
	x.R_nb = at::rotationYpr(90 * kDeg, 0, 0);  // level, facing east
	x.v_n = Eigen::Vector3d(0, 1, 0);           // 1 m/s east = straight ahead
	const Measurement m = pt::prepareOne(model, *dvlObs(Eigen::Vector3d::Zero()), tc.ctx());
	const Eigen::VectorXd h = at::Predict(model, m, tc.ctx(), x);
	// Sensor x is yawed 22.5° to port: forward motion = (cos 22.5°, sin 22.5°, 0).
	EXPECT_NEAR(h[0], 0.9238795325, 1e-9);
	EXPECT_NEAR(h[1], 0.3826834324, 1e-9);
	EXPECT_NEAR(h[2], 0.0, 1e-12);
}

TEST(Dvl, YawRateAddsTheLeverArmVelocity)
{
	pt::FlatfishContext tc;
	tc.ctx().omega_ie_n.setZero();
	tc.ctx().omega_ib_b = Eigen::Vector3d(0, 0, 0.1);  // turning to starboard, 0.1 rad/s
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState x;  // level, heading north, IMU point at rest
	const Measurement m = pt::prepareOne(model, *dvlObs(Eigen::Vector3d::Zero()), tc.ctx());
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
	pt::FlatfishContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState x;
	x.R_nb = at::rotationYpr(40 * kDeg, 5 * kDeg, -3 * kDeg);
	x.b_w = Eigen::Vector3d(0.01, -0.02, 0.03);  // exaggerated so a wrong sign would show
	tc.ctx().omega_ib_b = x.R_nb.transpose() * tc.ctx().omega_ie_n + x.b_w;
	const Measurement m = pt::prepareOne(model, *dvlObs(Eigen::Vector3d::Zero()), tc.ctx());
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
	o->sensorPose = mrpt::poses::CPose3D(1.0, 0, 0, 90 * kDeg, 0, 0);  // sensor x = body right
	NavState x;
	x.v_n = Eigen::Vector3d(1, 0, 0);  // forward
	const Eigen::VectorXd h_cfg = at::Predict(cfg_pose, pt::prepareOne(cfg_pose, *o, tc.ctx()), tc.ctx(), x);
	const Eigen::VectorXd h_obs = at::Predict(obs_pose, pt::prepareOne(obs_pose, *o, tc.ctx()), tc.ctx(), x);
	EXPECT_NEAR(h_cfg[0], std::cos(22.5 * kDeg), 1e-12);  // config: the nominal 22.5° mount
	EXPECT_NEAR(h_obs[0], 0.0, 1e-12);                    // observation: yawed 90°
	EXPECT_NEAR(h_obs[1], -1.0, 1e-12);
	// With a yaw rate the lever arm of the observation pose is used.
	tc.ctx().omega_ib_b = Eigen::Vector3d(0, 0, 0.5);
	x.v_n.setZero();
	const Eigen::VectorXd h_rot = at::Predict(obs_pose, pt::prepareOne(obs_pose, *o, tc.ctx()), tc.ctx(), x);
	EXPECT_NEAR(h_rot[0], 0.5, 1e-12);  // ω × (1, 0, 0) = (0, 0.5, 0) body = sensor x
}

TEST(Dvl, NoiseFromObservationCovariancePlusExtra)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	const double extra2 = 0.005 * 0.005;
	const Eigen::Matrix3d C = janusCovariance();
	Measurement m = pt::prepareOne(model, *dvlObs(Eigen::Vector3d(1, 0, 0), C), tc.ctx());
	EXPECT_TRUE(m.R.isApprox(C + extra2 * Eigen::Matrix3d::Identity(), 1e-14));
	EXPECT_NEAR(m.R(0, 0), 0.01 * 0.01 / (4 * 0.25 * 0.5) + extra2, 1e-15);  // 2e-4 + 2.5e-5
	// Zero, NaN, asymmetric or indefinite covariance: the configured σ instead.
	Eigen::Matrix3d asym = C;
	asym(0, 1) += 1e-4;
	Eigen::Matrix3d indefinite = C;
	indefinite(2, 2) = -1e-4;
	Eigen::Matrix3d nan_cov = C;
	nan_cov(1, 1) = std::nan("");
	for (const Eigen::Matrix3d& bad : {Eigen::Matrix3d(Eigen::Matrix3d::Zero()), nan_cov, asym, indefinite})
	{
		m = pt::prepareOne(model, *dvlObs(Eigen::Vector3d(1, 0, 0), bad), tc.ctx());
		EXPECT_TRUE(m.R.isApprox((0.02 * 0.02 + extra2) * Eigen::Matrix3d::Identity(), 1e-14)) << m.R;
	}
}

TEST(Dvl, UpdateReducesVelocityError)
{
	pt::FlatfishContext tc;
	tc.ctx().omega_ib_b = Eigen::Vector3d(0.01, -0.02, 0.05);
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState truth;
	truth.R_nb = at::rotationYpr(30 * kDeg, 2 * kDeg, -1 * kDeg);
	truth.v_n = Eigen::Vector3d(1.0, 0.2, 0.1);
	NavState x0 = truth;
	x0.v_n = Eigen::Vector3d(0.6, 0.6, -0.1);
	ManifoldUkf ukf = pt::filterAt(x0);
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
	EXPECT_EQ(
	    model.prepare(*dvlObs(Eigen::Vector3d(NAN, 0, 0), janusCovariance(), false), tc.ctx(), out, why),
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
	EXPECT_TRUE(pt::RefusesOtherClass<obs::CObservationPressure>(model, tc.ctx(), "CObservationDVL"));
}

TEST(Dvl, GrossOutlierRejectedAndNanNeverChangesTheState)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	Covariance P0 = at::TypicalCovariance();
	P0.block<3, 3>(idx::vel, idx::vel) = 0.01 * 0.01 * Eigen::Matrix3d::Identity();
	const NavState x0 = at::RandomNavState(7);
	ManifoldUkf ukf = pt::filterAt(x0, P0);
	const Eigen::Vector3d v_true = trueSensorVelocity(x0, tc.ctx(), nominalRbs(), kDvlPos);
	auto res = at::ApplyObservation(ukf, model, *dvlObs(v_true + Eigen::Vector3d(2.0, 0, 0)), tc.ctx());
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, UpdateStatus::Rejected);
	EXPECT_TRUE(at::NavStateIdentical(ukf.state(), x0));
	EXPECT_TRUE(ukf.covariance() == P0);
	EXPECT_TRUE(pt::PrepareRefuses(model, *dvlObs(Eigen::Vector3d(NAN, 0, 0)), tc.ctx(), x0));
	Measurement m = pt::prepareOne(model, *dvlObs(v_true), tc.ctx());
	m.z[2] = std::nan("");
	EXPECT_TRUE(pt::FilterRefuses(model, m, tc.ctx(), x0));
}

// ------------------------------------------------------------ output frames

TEST(DvlFrames, HandComputedLevelEastboundCase)
{
	// Level, facing east, 1 m/s east and 0.2 m/s down, no rotation: the DVL
	// point moves with the IMU point.
	pt::FlatfishContext tc;
	tc.ctx().omega_ie_n.setZero();
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState x;
	x.R_nb = at::rotationYpr(90 * kDeg, 0, 0);
	x.v_n = Eigen::Vector3d(0, 1, 0.2);
	const auto h = [&](DvlFrame f, DvlSign sign = DvlSign::VehicleOverBottom)
	{
		auto o = modeObs(f, x, tc.ctx(), sign);
		Eigen::VectorXd z, hx;
		stackZH(model, pt::prepareAll(model, *o, tc.ctx()), tc.ctx(), x, z, hx);
		return hx;
	};
	const double c = std::cos(22.5 * kDeg), s = std::sin(22.5 * kDeg);
	EXPECT_TRUE(h(DvlFrame::Instrument).isApprox(Eigen::Vector3d(c, s, 0.2), 1e-12))
	    << h(DvlFrame::Instrument);
	EXPECT_TRUE(h(DvlFrame::Vehicle).isApprox(Eigen::Vector3d(1, 0, 0.2), 1e-12)) << h(DvlFrame::Vehicle);
	EXPECT_TRUE(h(DvlFrame::EarthNed).isApprox(Eigen::Vector3d(0, 1, 0.2), 1e-12)) << h(DvlFrame::EarthNed);
	// ENU: east first, then north, then UP (= −down).
	EXPECT_TRUE(h(DvlFrame::EarthEnu).isApprox(Eigen::Vector3d(1, 0, -0.2), 1e-12)) << h(DvlFrame::EarthEnu);
	EXPECT_TRUE(
	    h(DvlFrame::EarthEnu, DvlSign::BottomOverInstrument).isApprox(Eigen::Vector3d(-1, 0, 0.2), 1e-12));
	// Beams at 45° + 90° i, 30° from the sensor z axis: sensor velocity (c, s, 0.2).
	const Eigen::VectorXd hb = h(DvlFrame::Beam);
	ASSERT_EQ(hb.size(), 4);
	for (int i = 0; i < 4; ++i)
	{
		const double a = (45.0 + 90.0 * i) * kDeg;
		EXPECT_NEAR(hb[i], 0.5 * std::cos(a - 22.5 * kDeg) + std::cos(30 * kDeg) * 0.2, 1e-12)
		    << "beam " << i;
	}
	EXPECT_NEAR(hb[0], 0.5 * std::cos(22.5 * kDeg) + 0.1 * std::sqrt(3.0), 1e-12);
}

TEST(DvlFrames, PredictionEqualsTheIndependentlyComputedReadingInEveryFrame)
{
	// Random states with a body rate: h(x_true) must reproduce what the DVL
	// reports, in every frame and both signs (lever arm, Earth rate, gyro bias).
	pt::FlatfishContext tc;
	for (const char* cfg : {"{}", "use_observation_pose: true"})
	{
		DvlModel model(pt::configText(cfg), "DVL");
		for (uint32_t seed = 1; seed <= 10; ++seed)
		{
			const NavState x = at::RandomNavState(seed);
			tc.ctx().omega_ib_b = Eigen::Vector3d(0.05, -0.03, 0.2 * std::cos(seed));
			for (DvlFrame f : kAllFrames)
				for (DvlSign sign : {DvlSign::VehicleOverBottom, DvlSign::BottomOverInstrument})
				{
					Eigen::VectorXd z, h;
					stackZH(model, pt::prepareAll(model, *modeObs(f, x, tc.ctx(), sign), tc.ctx()), tc.ctx(),
					        x, z, h);
					ASSERT_EQ(z.size(), f == DvlFrame::Beam ? 4 : 3);
					EXPECT_LT((z - h).cwiseAbs().maxCoeff(), 1e-12)
					    << cfg << " seed " << seed << " frame " << obs::dvlFrameName(f) << " sign "
					    << obs::dvlSignName(sign) << "\nz " << z.transpose() << "\nh " << h.transpose();
				}
		}
	}
}

TEST(DvlFrames, WellFormedInEveryFrameSignAndBeamCount)
{
	pt::FlatfishContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	for (uint32_t seed = 1; seed <= 10; ++seed)
	{
		const NavState x = at::RandomNavState(seed);
		tc.ctx().omega_ib_b = Eigen::Vector3d(0.02, -0.01, 0.1 * std::sin(seed));
		// Observations of another state, so that z ≠ h.
		const NavState other = at::RandomNavState(seed + 50);
		for (DvlFrame f : kAllFrames)
			for (DvlSign sign : {DvlSign::VehicleOverBottom, DvlSign::BottomOverInstrument})
				for (int beams : {3, 4})
				{
					if (f != DvlFrame::Beam && beams == 3) continue;
					EXPECT_TRUE(pt::IsWellFormedAndUsed(model, *modeObs(f, other, tc.ctx(), sign, beams),
					                                    tc.ctx(), x, seed))
					    << obs::dvlFrameName(f) << " " << obs::dvlSignName(sign) << " beams " << beams
					    << " seed " << seed;
				}
	}
}

TEST(DvlFrames, BottomOverInstrumentNegatesThePrediction)
{
	pt::FlatfishContext tc;
	tc.ctx().omega_ib_b = Eigen::Vector3d(0.01, 0.02, -0.15);
	DvlModel model(pt::defaultConfig(), "DVL");
	const NavState x = at::RandomNavState(3);
	for (DvlFrame f : kAllFrames)
	{
		// Same reported numbers, opposite convention: h flips, z does not.
		auto vob = modeObs(f, x, tc.ctx());
		auto pd0 = modeObs(f, x, tc.ctx());
		pd0->sign = DvlSign::BottomOverInstrument;
		Eigen::VectorXd z1, h1, z2, h2;
		stackZH(model, pt::prepareAll(model, *vob, tc.ctx()), tc.ctx(), x, z1, h1);
		stackZH(model, pt::prepareAll(model, *pd0, tc.ctx()), tc.ctx(), x, z2, h2);
		EXPECT_TRUE(z1 == z2) << obs::dvlFrameName(f);
		EXPECT_TRUE(h2 == -h1) << obs::dvlFrameName(f) << ": " << h1.transpose() << " vs " << h2.transpose();
		EXPECT_GT(h1.norm(), 0.1);
	}
	// In a filter: a PD0 reading of −v moves the state exactly as a
	// vehicle-over-bottom reading of v.
	NavState truth;
	truth.R_nb = at::rotationYpr(30 * kDeg, 2 * kDeg, -1 * kDeg);
	truth.v_n = Eigen::Vector3d(1.0, 0.2, 0.1);
	NavState x0 = truth;
	x0.v_n = Eigen::Vector3d(0.6, 0.6, -0.1);
	for (DvlFrame f : kAllFrames)
	{
		ManifoldUkf a = pt::filterAt(x0), b = pt::filterAt(x0);
		const auto ra = at::ApplyObservation(a, model, *modeObs(f, truth, tc.ctx()), tc.ctx());
		const auto rb = at::ApplyObservation(
		    b, model, *modeObs(f, truth, tc.ctx(), DvlSign::BottomOverInstrument), tc.ctx());
		ASSERT_EQ(ra.status, PrepareStatus::Ok) << ra.why;
		ASSERT_EQ(rb.status, PrepareStatus::Ok) << rb.why;
		for (const auto& u : ra.updates) EXPECT_EQ(u.status, UpdateStatus::Accepted) << obs::dvlFrameName(f);
		EXPECT_TRUE(at::NavStateNear(a.state(), b.state(), 1e-12)) << obs::dvlFrameName(f);
		EXPECT_LT((a.state().v_n - truth.v_n).norm(), 0.1 * (x0.v_n - truth.v_n).norm())
		    << obs::dvlFrameName(f);
	}
}

TEST(DvlFrames, AuxLayoutAndLabels)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	const NavState x;
	const std::pair<DvlFrame, const char*> expected[] = {{DvlFrame::Instrument, "velocity"},
	                                                     {DvlFrame::Vehicle, "velocity_vehicle"},
	                                                     {DvlFrame::EarthNed, "velocity_earth_ned"},
	                                                     {DvlFrame::EarthEnu, "velocity_earth_enu"},
	                                                     {DvlFrame::Beam, "beam"}};
	for (const auto& [f, label] : expected)
	{
		const auto ms =
		    pt::prepareAll(model, *modeObs(f, x, tc.ctx(), DvlSign::BottomOverInstrument), tc.ctx());
		ASSERT_FALSE(ms.empty());
		for (std::size_t k = 0; k < ms.size(); ++k)
		{
			const Measurement& m = ms[k];
			EXPECT_EQ(m.tag, int(f));
			EXPECT_EQ(m.label, label);
			const auto& ping = m.payload<plugins::DvlPing>();
			EXPECT_TRUE(Eigen::Vector3d(ping.r_s[0], ping.r_s[1], ping.r_s[2]) == kDvlPos);
			EXPECT_EQ(ping.sign, -1.0);
			EXPECT_EQ(ping.beam_index, f == DvlFrame::Beam ? double(k) : 0.0);
		}
		if (f == DvlFrame::Instrument)
		{
			const auto& ping = ms[0].payload<plugins::DvlPing>();
			const Eigen::Vector3d rotvec(ping.axis[0], ping.axis[1], ping.axis[2]);
			EXPECT_TRUE(so3::Exp(rotvec).isApprox(nominalRbs(), 1e-14));
		}
	}
}

TEST(DvlBeams, OneScalarPerValidBeamWithTheBeamGeometry)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	const NavState x;
	for (int valid : {3, 4})
	{
		auto o = modeObs(DvlFrame::Beam, x, tc.ctx(), DvlSign::VehicleOverBottom, 4);
		if (valid == 3) o->beams[1].valid = false;  // beam 1 lost: its NaN velocity must not matter
		if (valid == 3) o->beams[1].velocity_mps = std::nan("");
		const auto ms = pt::prepareAll(model, *o, tc.ctx());
		ASSERT_EQ(ms.size(), std::size_t(valid));
		std::vector<int> used;
		for (const auto& m : ms)
		{
			ASSERT_EQ(m.z.size(), 1);
			ASSERT_EQ(m.R.rows(), 1);
			const auto& ping = m.payload<plugins::DvlPing>();
			const int i = int(ping.beam_index);
			used.push_back(i);
			EXPECT_EQ(m.z[0], o->beams[i].velocity_mps);
			// The beam's unit vector in body axes, R_bs u_i.
			const Eigen::Vector3d u_b(ping.axis[0], ping.axis[1], ping.axis[2]);
			EXPECT_TRUE(u_b.isApprox(nominalRbs() * beamUnit(30 * kDeg, o->beams[i].azimuth_rad), 1e-14))
			    << i;
			EXPECT_NEAR(u_b.norm(), 1.0, 1e-14);
			// The observation's beam sigma plus the extra sigma.
			EXPECT_NEAR(m.R(0, 0), 0.01 * 0.01 + 0.005 * 0.005, 1e-18);
		}
		EXPECT_EQ(used, valid == 4 ? std::vector<int>({0, 1, 2, 3}) : std::vector<int>({0, 2, 3}));
	}
}

TEST(DvlBeams, ThreeValidBeamsFixTheVelocityInAFilter)
{
	// Three beams span 3-D: their three scalar updates fix the velocity as
	// one 3-D update does (UpdateReducesVelocityError).
	pt::FlatfishContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	NavState truth;
	truth.R_nb = at::rotationYpr(-60 * kDeg, 3 * kDeg, 1 * kDeg);
	truth.v_n = Eigen::Vector3d(0.3, -0.8, 0.05);
	NavState x0 = truth;
	x0.v_n = Eigen::Vector3d(0.5, -0.4, 0.0);
	ManifoldUkf ukf = pt::filterAt(x0);
	const auto three_beams = modeObs(DvlFrame::Beam, truth, tc.ctx(), DvlSign::VehicleOverBottom, 3);
	const auto res = at::ApplyObservation(ukf, model, *three_beams, tc.ctx());
	ASSERT_EQ(res.status, PrepareStatus::Ok) << res.why;
	ASSERT_EQ(res.updates.size(), 3u);
	for (const auto& u : res.updates) EXPECT_EQ(u.status, UpdateStatus::Accepted) << u.why;
	EXPECT_LT((ukf.state().v_n - truth.v_n).norm(), 0.1 * (x0.v_n - truth.v_n).norm());
}

TEST(DvlBeams, FewerThanThreeValidBeamsSkipWithAReason)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	auto o = modeObs(DvlFrame::Beam, NavState{}, tc.ctx(), DvlSign::VehicleOverBottom, 2);
	std::vector<Measurement> out;
	std::string why;
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Skip);
	EXPECT_TRUE(out.empty());
	EXPECT_NE(why.find("2 valid beam"), std::string::npos) << why;
	EXPECT_NE(why.find("at least 3"), std::string::npos) << why;
	// No bottom lock is still the first reason.
	o->bottom_lock = false;
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Skip);
	EXPECT_NE(why.find("bottom lock"), std::string::npos) << why;
}

TEST(DvlBeams, BeamSigmaFromTheObservationOrTheConfig)
{
	at::TestContext tc;
	DvlModel model(pt::configText("beam_sigma_mps: 0.03\nextra_sigma_mps: 0"), "DVL");
	auto o = modeObs(DvlFrame::Beam, NavState{}, tc.ctx());
	o->beam_velocity_sigma_mps = 0.02;
	auto ms = pt::prepareAll(model, *o, tc.ctx());
	ASSERT_EQ(ms.size(), 4u);
	EXPECT_DOUBLE_EQ(ms[0].R(0, 0), 0.02 * 0.02);
	EXPECT_EQ(ms[0].label, "beam");
	for (double unknown : {0.0, -1.0, std::nan("")})
	{
		o->beam_velocity_sigma_mps = unknown;
		ms = pt::prepareAll(model, *o, tc.ctx());
		ASSERT_EQ(ms.size(), 4u);
		EXPECT_DOUBLE_EQ(ms[0].R(0, 0), 0.03 * 0.03) << unknown;
		EXPECT_EQ(ms[0].label, "beam_default_sigma");
	}
}

TEST(DvlBeams, InvalidBeamData)
{
	at::TestContext tc;
	DvlModel model(pt::defaultConfig(), "DVL");
	std::vector<Measurement> out;
	std::string why;
	auto o = modeObs(DvlFrame::Beam, NavState{}, tc.ctx());
	o->beams[2].velocity_mps = std::nan("");  // a VALID beam without a velocity
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_TRUE(out.empty());
	EXPECT_NE(why.find("beam 2"), std::string::npos) << why;
	o = modeObs(DvlFrame::Beam, NavState{}, tc.ctx());
	o->beams[0].azimuth_rad = HUGE_VAL;
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	for (double incl : {0.0, -0.1, M_PI / 2, std::nan("")})
	{
		o = modeObs(DvlFrame::Beam, NavState{}, tc.ctx());
		o->beam_inclination_rad = incl;
		EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid) << incl;
		EXPECT_NE(why.find("inclination"), std::string::npos) << why;
	}
	// The 3-D fields are not read in beam mode (NaN there is fine), but they
	// are in every other frame.
	o = modeObs(DvlFrame::Beam, NavState{}, tc.ctx());
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Ok) << why;
	o->frame = DvlFrame::Vehicle;
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	// Corrupt enum values are refused, not guessed.
	o = modeObs(DvlFrame::Instrument, NavState{}, tc.ctx());
	o->frame = static_cast<DvlFrame>(7);
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_NE(why.find("frame"), std::string::npos) << why;
	o = modeObs(DvlFrame::Instrument, NavState{}, tc.ctx());
	o->sign = static_cast<DvlSign>(3);
	EXPECT_EQ(model.prepare(*o, tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_NE(why.find("sign"), std::string::npos) << why;
}

TEST(DvlEarth, CompassAndTiltErrorsEnterTheNoise)
{
	at::TestContext tc;
	DvlModel model(pt::configText("extra_sigma_mps: 0\nearth_heading_sigma_deg: 3\nearth_tilt_sigma_deg: 1"),
	               "DVL");
	DvlModel no_att(pt::configText("extra_sigma_mps: 0\nearth_heading_sigma_deg: 0\nearth_tilt_sigma_deg: 0"),
	                "DVL");
	const Eigen::Matrix3d C = janusCovariance();
	const double sh = 3 * kDeg, st = 1 * kDeg;
	// 2 m/s north: the heading error is cross-track (east), the tilt error vertical.
	auto ned = dvlObs(Eigen::Vector3d(2, 0, 0), C);
	ned->frame = DvlFrame::EarthNed;
	Measurement m = pt::prepareOne(model, *ned, tc.ctx());
	Eigen::Matrix3d extra = Eigen::Matrix3d::Zero();
	extra(1, 1) = 4 * sh * sh;
	extra(2, 2) = 4 * st * st;
	EXPECT_TRUE(m.R.isApprox(C + extra, 1e-12)) << m.R - C;
	EXPECT_TRUE(pt::prepareOne(no_att, *ned, tc.ctx()).R.isApprox(C, 1e-15));
	// The same motion reported as ENU [0, 2, 0]: cross-track is ENU x (east).
	auto enu = dvlObs(Eigen::Vector3d(0, 2, 0), C);
	enu->frame = DvlFrame::EarthEnu;
	m = pt::prepareOne(model, *enu, tc.ctx());
	Eigen::Matrix3d extra_enu = Eigen::Matrix3d::Zero();
	extra_enu(0, 0) = 4 * sh * sh;
	extra_enu(2, 2) = 4 * st * st;
	EXPECT_TRUE(m.R.isApprox(C + extra_enu, 1e-12)) << m.R - C;
	// Diagonal motion: the heading term is rank one across the velocity
	// (north-east 1, 1: cross-track direction (−1, 1)/√2, speed √2).
	auto diag = dvlObs(Eigen::Vector3d(1, 1, 0), C);
	diag->frame = DvlFrame::EarthNed;
	DvlModel heading_only(pt::configText("extra_sigma_mps: 0\nearth_tilt_sigma_deg: 0"),
	                      "DVL");  // default 2°
	m = pt::prepareOne(heading_only, *diag, tc.ctx());
	const Eigen::Vector3d w(-1, 1, 0);
	EXPECT_TRUE((m.R - C).isApprox(std::pow(2 * kDeg, 2) * w * w.transpose(), 1e-12)) << m.R - C;
	// Other frames get no attitude term.
	auto inst = dvlObs(Eigen::Vector3d(2, 0, 0), C);
	EXPECT_TRUE(pt::prepareOne(model, *inst, tc.ctx()).R.isApprox(C, 1e-15));
}

TEST(DvlEarth, AttitudeEntersOnlyThroughTheLeverArm)
{
	// An Earth-frame velocity is v_n plus the rotated lever-arm velocity: at
	// the same v_n a different heading changes h only by R_nb (ω × l), while
	// an instrument-frame h turns with the heading.
	pt::FlatfishContext tc;
	tc.ctx().omega_ie_n.setZero();  // keep ω itself independent of R_nb
	DvlModel model(pt::defaultConfig(), "DVL");
	const Eigen::Vector3d l = kDvlPos - kImuPos;
	for (uint32_t seed = 1; seed <= 10; ++seed)
	{
		NavState a = at::RandomNavState(seed);
		a.b_w.setZero();
		NavState b = a;
		b.R_nb = at::rotationYpr(30 * kDeg, 0, 0) * a.R_nb;  // 30° more heading, same v_n
		for (const Eigen::Vector3d& w : {Eigen::Vector3d::Zero().eval(), Eigen::Vector3d(0.05, -0.02, 0.3)})
		{
			tc.ctx().omega_ib_b = w;
			const Eigen::Vector3d lever_change = (b.R_nb - a.R_nb) * w.cross(l);
			for (DvlFrame f : {DvlFrame::EarthNed, DvlFrame::EarthEnu})
			{
				const Measurement m = pt::prepareOne(model, *modeObs(f, a, tc.ctx()), tc.ctx());
				const Eigen::VectorXd dh =
				    at::Predict(model, m, tc.ctx(), b) - at::Predict(model, m, tc.ctx(), a);
				EXPECT_NEAR(dh.norm(), lever_change.norm(), 1e-12)
				    << obs::dvlFrameName(f) << " seed " << seed;
			}
			const Measurement mi =
			    pt::prepareOne(model, *modeObs(DvlFrame::Instrument, a, tc.ctx()), tc.ctx());
			const Eigen::VectorXd dhi =
			    at::Predict(model, mi, tc.ctx(), b) - at::Predict(model, mi, tc.ctx(), a);
			// |Δh| = |Δ(R_nbᵀ v_n)| = 2 sin 15° |v_n| horizontally, give or take the lever arm.
			EXPECT_GT(dhi.norm(), 0.3 * a.v_n.head<2>().norm() - lever_change.norm()) << "seed " << seed;
		}
	}
}

TEST(DvlEarth, RejectsBadAttitudeSigmas)
{
	for (const char* yaml : {"earth_heading_sigma_deg: -1", "earth_heading_sigma_deg: 91",
	                         "earth_tilt_sigma_deg: x", "beam_sigma_mps: 0"})
		EXPECT_TRUE(pt::ConstructorRefuses<DvlModel>(yaml));
	EXPECT_TRUE(pt::ModuleRefuses("earth_heading_sigma_deg: -5", "earth_heading_sigma_deg"));
}

// ------------------------------------------------------------ plugin-owned states

TEST(DvlStates, DeclaresScaleAndMisalignmentBlocksFromTheConfig)
{
	DvlModel none(pt::defaultConfig(), "DVL");
	EXPECT_EQ(at::PluginStateBench(none).extraSize(), 0);
	EXPECT_EQ(none.uses() & kPluginStates, 0u);
	DvlModel m(pt::configText(
	               "states: {scale_factor: {sigma: 0.01}, misalignment: {sigma_deg: 2, process: random_walk, "
	               "process_sigma_deg: 0.001}}"),
	           "DVL");
	const at::PluginStateBench bench(m, 0, "DVL");
	ASSERT_EQ(bench.layout.plugin_blocks.size(), 2u);
	EXPECT_EQ(bench.layout.plugin_blocks[0].name, "scale_factor");  // in declaration order
	EXPECT_EQ(bench.layout.plugin_blocks[1].name, "misalignment");
	const StateBlockSpec& scale = bench["scale_factor"].spec();
	EXPECT_EQ(scale.dimension(), 1);
	EXPECT_DOUBLE_EQ(scale.sigma[0], 0.01);
	EXPECT_EQ(scale.process, StateProcess::RandomConstant);
	const StateBlockSpec& misalignment = bench["misalignment"].spec();
	EXPECT_EQ(misalignment.dimension(), 3);
	EXPECT_NEAR(misalignment.sigma[0], 2 * kDeg, 1e-15);
	EXPECT_EQ(misalignment.process, StateProcess::RandomWalk);
	EXPECT_NEAR(misalignment.process_sigma, 0.001 * kDeg, 1e-18);
	EXPECT_NE(m.uses() & kPluginStates, 0u);
	// Bad blocks name the key.
	EXPECT_TRUE(pt::ConstructorRefuses<DvlModel>("states: {scale_factor: {sigma: 0}}"));
	EXPECT_TRUE(pt::ConstructorRefuses<DvlModel>("states: {scale: {sigma: 0.01}}"));
	EXPECT_TRUE(
	    pt::ConstructorRefuses<DvlModel>("states: {misalignment: {sigma_deg: 1, process: gauss_markov}}"));
	EXPECT_TRUE(pt::ConstructorRefuses<DvlModel>("states: {scale_factor: {sigma: 0.01, tau_s: 5}}"));
}

TEST(DvlStates, ScaleAndMisalignmentEnterHAsTheSimulatorAppliesThem)
{
	// Instrument frame, states bound after two other coordinates: h = (1 + s) R_bsᵀ Exp(δ)ᵀ v_s_b,
	// i.e. the velocity seen through the true mounting Exp(δ) R_bs, scaled.
	pt::FlatfishContext tc;
	tc.ctx().omega_ib_b = Eigen::Vector3d(0.01, -0.02, 0.15);
	DvlModel m(pt::configText("states: {scale_factor: {sigma: 0.01}, misalignment: {sigma_deg: 2}}"), "DVL");
	const at::PluginStateBench bench(m, 2);
	NavState x = bench.randomState(7);
	const double s = 0.005;
	const Eigen::Vector3d delta = Eigen::Vector3d(0.3, -0.2, 1.0) * kDeg;
	bench["scale_factor"].value(x) = s;
	bench["misalignment"].segment(x) = delta;
	const Eigen::Matrix3d R_bs_true = so3::Exp(delta) * nominalRbs();
	const Eigen::Vector3d expected = (1 + s) * trueSensorVelocity(x, tc.ctx(), R_bs_true, kDvlPos);
	const Measurement meas = pt::prepareOne(m, *dvlObs(expected), tc.ctx());
	const Eigen::VectorXd h = at::Predict(m, meas, tc.ctx(), x);
	EXPECT_LT((h - expected).cwiseAbs().maxCoeff(), 1e-12) << h.transpose() << " vs " << expected.transpose();
	// Without the states the same reading is off by about s·|v| and δ·|v|.
	NavState zero = x;
	zero.extra.setZero();
	EXPECT_GT((at::Predict(m, meas, tc.ctx(), zero) - expected).norm(), 1e-3 * expected.norm());
	// A state without the plugin's coordinates: h cannot be evaluated (not a silent read).
	const NavState short_state = at::RandomNavState(7, 3);
	EXPECT_TRUE(at::Predict(m, meas, tc.ctx(), short_state).array().isNaN().all());
	EXPECT_TRUE(pt::IsWellFormedAndUsed(m, *dvlObs(expected), tc.ctx(), x));
}

TEST(DvlStates, TheScaleTermIsEvaluatedAtTheVelocityEstimateLagSecondsBefore)
{
	// h = R_bsᵀ (v_s_b + s r_b): r_b is the filter's mean v_s_b of the newest ping at least
	// scale_reference_lag_s old (dvl.h). Formed with the state's own velocity, (1 + s) v_s_b, the
	// scale's gain carried the prior velocity error that the innovation carries with the opposite
	// sign, and every ping pulled s low (−0.3 % on the square mission, test_plugin_states.cpp).
	pt::FlatfishContext tc;
	FilterContext& ctx = tc.ctx();
	ctx.omega_ib_b = Eigen::Vector3d(0.01, -0.02, 0.15);
	DvlModel m(pt::configText("states: {scale_factor: {sigma: 0.01}, misalignment: {sigma_deg: 2}}\n"
	                          "scale_reference_lag_s: 10"),
	           "DVL");
	const at::PluginStateBench bench(m);
	const PluginState& scale = bench["scale_factor"];
	const Eigen::Vector3d delta = Eigen::Vector3d(0.3, -0.2, 1.0) * kDeg;
	auto stateWithVelocity = [&](unsigned seed)
	{
		NavState x = bench.randomState(seed);
		x.extra.setZero();
		bench["misalignment"].segment(x) = delta;
		return x;
	};
	const NavState old_mean = stateWithVelocity(11), mid_mean = stateWithVelocity(12),
	               now_mean = stateWithVelocity(13);
	NavState x = stateWithVelocity(14);
	const double s = 0.005;
	scale.value(x) = s;
	const Eigen::Matrix3d R_bs_true = so3::Exp(delta) * nominalRbs();
	const Eigen::Vector3d v_x = trueSensorVelocity(x, ctx, R_bs_true, kDvlPos);
	auto pingAt = [&](double t, const NavState& mean)
	{
		ctx.t_s = t;
		ctx.t_measurement_s = t;
		ctx.mean = &mean;
		return pt::prepareOne(m, *dvlObs(v_x), ctx);
	};
	// No ping 10 s old yet: (1 + s) times the state's own sensor velocity.
	const Measurement first = pingAt(1000.0, old_mean);
	EXPECT_LT((at::Predict(m, first, ctx, x) - (1 + s) * v_x).norm(), 1e-12);
	const Measurement early = pingAt(1005.0, mid_mean);
	EXPECT_LT((at::Predict(m, early, ctx, x) - (1 + s) * v_x).norm(), 1e-12);
	// 10.2 s later: the scale's term is the mean of the first ping (misalignment applied), not x's.
	const Measurement later = pingAt(1010.2, now_mean);
	const Eigen::Vector3d r_old = trueSensorVelocity(old_mean, ctx, R_bs_true, kDvlPos);
	const Eigen::VectorXd h = at::Predict(m, later, ctx, x);
	EXPECT_LT((h - (v_x + s * r_old)).norm(), 1e-12)
	    << h.transpose() << " vs " << (v_x + s * r_old).transpose();
	EXPECT_GT((h - (1 + s) * v_x).norm(), 1e-4);
	// A prediction with s = 0 does not depend on the reference.
	NavState x0 = x;
	scale.value(x0) = 0;
	EXPECT_LT((at::Predict(m, later, ctx, x0) - v_x).norm(), 1e-12);
	// Re-filtering from an earlier checkpoint (a delayed measurement) undoes the pings after it:
	// 1010.4 s after 1012 s still finds the 1000 s ping as its reference.
	pingAt(1012.0, mid_mean);
	const Measurement again = pingAt(1010.4, now_mean);
	EXPECT_LT((at::Predict(m, again, ctx, x) - (v_x + s * r_old)).norm(), 1e-12);
	// After a gap in bottom lock of more than twice the lag, no reference until the history refills.
	const Measurement after_gap = pingAt(1100.0, now_mean);
	EXPECT_LT((at::Predict(m, after_gap, ctx, x) - (1 + s) * v_x).norm(), 1e-12);
	EXPECT_TRUE(pt::IsWellFormedAndUsed(m, *dvlObs(v_x), ctx, x));

	// scale_reference_lag_s 0: always (1 + s) v_s_b, as before.
	DvlModel plain(pt::configText("states: {scale_factor: {sigma: 0.01}, misalignment: {sigma_deg: 2}}\n"
	                              "scale_reference_lag_s: 0"),
	               "DVL");
	const at::PluginStateBench plain_bench(plain);
	for (double t : {1000.0, 1010.2, 1020.4})
	{
		ctx.t_s = t;
		ctx.mean = &old_mean;
		const Measurement mm = pt::prepareOne(plain, *dvlObs(v_x), ctx);
		EXPECT_LT((at::Predict(plain, mm, ctx, x) - (1 + s) * v_x).norm(), 1e-12);
	}
	EXPECT_TRUE(pt::ConstructorRefuses<DvlModel>("scale_reference_lag_s: -1"));
}

TEST(DvlStates, AFilterLearnsTheScaleFactorFromVelocityKnownOtherwise)
{
	// The velocity is known to 1 mm/s (as from a GPS track): DVL readings 0.5 % high are explained
	// by the scale factor, which the filter then knows to a fraction of its prior σ.
	pt::FlatfishContext tc;
	DvlModel m(pt::configText("states: {scale_factor: {sigma: 0.02}}"), "DVL");
	const at::PluginStateBench bench(m);
	const PluginState& scale = bench["scale_factor"];
	NavState truth = bench.randomState(3);
	scale.value(truth) = 0.005;
	truth.b_w.setZero();
	Covariance P = bench.P0;  // the scale's σ 0.02 from its spec
	P.block<3, 3>(idx::vel, idx::vel) = Eigen::Matrix3d::Identity() * 1e-6;
	NavState x0 = truth;
	scale.value(x0) = 0;
	ManifoldUkf ukf(bench.process, UtParams{});
	ukf.initialize(x0, P);
	const Eigen::Vector3d v_s = (1 + 0.005) * trueSensorVelocity(truth, tc.ctx(), nominalRbs(), kDvlPos);
	for (int i = 0; i < 20; ++i)
	{
		const auto r = at::ApplyObservation(ukf, m, *dvlObs(v_s, janusCovariance(0.002)), tc.ctx());
		ASSERT_EQ(r.status, PrepareStatus::Ok) << r.why;
	}
	const double sigma = std::sqrt(ukf.covariance()(scale.tangentIndex(), scale.tangentIndex()));
	EXPECT_NEAR(scale.value(ukf.state()), 0.005, 3 * sigma);
	EXPECT_LT(sigma, 0.2 * 0.02);
	EXPECT_GT(scale.value(ukf.state()), 0.003);
}
