// The "ahrs" plugin: an IMU's own attitude output (quaternion or yaw/pitch/roll) as an SO(3) or heading
// update.
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/so3.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>

#include <cmath>

#include "ahrs.h"
#include "level_heading.h"
#include "plugin_test_support.h"

using auvnav::plugins::AhrsModel;
using mrpt::obs::CObservationIMU;

namespace
{
CObservationIMU::Ptr emptyObs(double t_s = 1.7e9,
                              const Eigen::Vector3d& mount_ypr_deg = Eigen::Vector3d::Zero())
{
	auto o = CObservationIMU::Create();
	o->sensorLabel = "AHRS";
	o->timestamp = mrpt::Clock::fromDouble(t_s);
	o->sensorPose = mrpt::poses::CPose3D(0, 0, 0, mount_ypr_deg[0] * kDeg, mount_ypr_deg[1] * kDeg,
	                                     mount_ypr_deg[2] * kDeg);
	return o;
}

/** An orientation output R_rs as a quaternion. */
CObservationIMU::Ptr quatObs(const Eigen::Matrix3d& R_rs,
                             const Eigen::Vector3d& mount_ypr_deg = Eigen::Vector3d::Zero(),
                             double t_s = 1.7e9)
{
	auto o = emptyObs(t_s, mount_ypr_deg);
	const Eigen::Quaterniond q(R_rs);
	o->set(mrpt::obs::IMU_ORI_QUAT_W, q.w());
	o->set(mrpt::obs::IMU_ORI_QUAT_X, q.x());
	o->set(mrpt::obs::IMU_ORI_QUAT_Y, q.y());
	o->set(mrpt::obs::IMU_ORI_QUAT_Z, q.z());
	return o;
}

CObservationIMU::Ptr yprObs(double yaw, double pitch, double roll)
{
	auto o = emptyObs();
	o->set(mrpt::obs::IMU_YAW, yaw);
	o->set(mrpt::obs::IMU_PITCH, pitch);
	o->set(mrpt::obs::IMU_ROLL, roll);
	return o;
}

Eigen::Matrix3d measured(const AhrsModel& model, const mrpt::obs::CObservation& o)
{
	std::string why;
	const auto R = model.measuredAttitude(o, why);
	EXPECT_TRUE(R.has_value()) << why;
	return R ? *R : Eigen::Matrix3d::Constant(std::nan(""));
}

double angleBetween(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B)
{
	return so3::Log(A * B.transpose()).norm();
}

Covariance attitudeCovariance(double tilt_sigma, double heading_sigma)
{
	Covariance P = at::TypicalCovariance();
	P.block<3, 3>(idx::att, idx::att).setZero();
	P(0, 0) = P(1, 1) = tilt_sigma * tilt_sigma;
	P(2, 2) = heading_sigma * heading_sigma;
	return P;
}
}  // namespace

TEST(Ahrs, DefaultConfig)
{
	const AhrsModel m(pt::defaultConfig(), "AHRS");
	EXPECT_EQ(m.uses(), uint32_t(kAttitude));
	EXPECT_FALSE(m.headingOnly());
	EXPECT_TRUE(m.R_nr().isIdentity(1e-15));  // ned, magnetic with declination 0
	EXPECT_DOUBLE_EQ(m.gateProbability(), 0.999);
	EXPECT_TRUE(AhrsModel(pt::configText("{}"), "AHRS").R_nr().isIdentity(1e-15));
}

TEST(Ahrs, ModuleExportsEntryAndCreatesFromDefaultConfig)
{
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("ahrs", pt::defaultConfigText(), kAttitude));
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("ahrs", "heading_only: true\nreference_frame: enu", kAttitude));
}

TEST(Ahrs, RejectsBadConfigNamingTheKey)
{
	// The key each message must name is the one on the yaml's last line; the
	// last case is a misspelled key.
	for (const char* yaml :
	     {"reference_frame: nwu", "heading_reference: grid", "declination_deg: 200",
	      "heading_reference: 'true'\ndeclination_deg: 4", "orientation_ypr_deg: [0, 0]", "sigma_roll_deg: 0",
	      "sigma_pitch_deg: .nan", "sigma_heading_deg: 500", "heading_only: 3", "gate_probability: 1.5",
	      "min_interval_s: -2", "sigma_yaw_deg: 1"})
		EXPECT_TRUE(pt::RefusesNamingTheKey<AhrsModel>(yaml)) << yaml;
}

TEST(Ahrs, WellFormedOnRandomStates)
{
	at::TestContext tc;
	for (const char* cfg : {"{}", "heading_only: true", "reference_frame: enu\ndeclination_deg: -12"})
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			AhrsModel model(pt::configText(cfg), "AHRS");
			const NavState x = at::RandomNavState(seed);
			const NavState mean = at::RandomNavState(seed + 50);
			tc.ctx().mean = (seed % 2) ? &mean : nullptr;
			const auto o = (seed % 3)
			                   ? quatObs(at::RandomNavState(seed + 7).R_nb, Eigen::Vector3d(10, 180, 5))
			                   : yprObs(0.3 * seed, 0.2, -0.1);
			EXPECT_TRUE(pt::IsWellFormedAndUsed(model, *o, tc.ctx(), x, seed)) << cfg << ", seed " << seed;
		}
	tc.ctx().mean = nullptr;
}

TEST(Ahrs, KnownAttitudesInEveryConvention)
{
	const Eigen::Matrix3d R = at::rotationYpr(30 * kDeg, 10 * kDeg, -5 * kDeg);
	// NED, true heading, mounted as the body: the reported attitude itself.
	AhrsModel ned(pt::configText("heading_reference: 'true'"), "AHRS");
	EXPECT_LT(angleBetween(measured(ned, *quatObs(R)), R), 1e-12);
	// The same as yaw/pitch/roll.
	EXPECT_LT(angleBetween(measured(ned, *yprObs(30 * kDeg, 10 * kDeg, -5 * kDeg)), R), 1e-12);
	// Magnetic heading 27° with declination +3°: true heading 30°.
	AhrsModel mag(pt::configText("declination_deg: 3"), "AHRS");
	EXPECT_LT(angleBetween(measured(mag, *yprObs(27 * kDeg, 10 * kDeg, -5 * kDeg)), R), 1e-12);
	// ENU with FLU sensor axes (sensorPose roll 180°), as ROS sensor_msgs/Imu:
	// a vehicle facing north, level, reports yaw +90° (counter-clockwise from east).
	AhrsModel enu(pt::configText("reference_frame: enu\nheading_reference: 'true'"), "AHRS");
	const Eigen::Matrix3d R_enu_north =
	    Eigen::AngleAxisd(90 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
	EXPECT_LT(angleBetween(measured(enu, *quatObs(R_enu_north, Eigen::Vector3d(0, 0, 180))),
	                       Eigen::Matrix3d::Identity()),
	          1e-12);
	// Facing east, nose 10° up: ENU yaw 0, and FLU pitch is −10° (y left, nose up is negative).
	const Eigen::Matrix3d R_enu_east_up =
	    Eigen::AngleAxisd(-10 * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
	EXPECT_LT(angleBetween(measured(enu, *quatObs(R_enu_east_up, Eigen::Vector3d(0, 0, 180))),
	                       at::rotationYpr(90 * kDeg, 10 * kDeg, 0)),
	          1e-12);
	// Mounting from the config instead of the observation: sensor yawed 90°
	// in the body (sensor x = body right); the sensor facing north means the
	// body faces west.
	AhrsModel mounted(pt::configText("heading_reference: 'true'\norientation_ypr_deg: [90, 0, 0]"), "AHRS");
	EXPECT_LT(
	    angleBetween(measured(mounted, *quatObs(Eigen::Matrix3d::Identity(), Eigen::Vector3d(45, 0, 0))),
	                 at::rotationYpr(-90 * kDeg, 0, 0)),
	    1e-12);
	// The quaternion wins over angles present in the same observation.
	auto both = quatObs(R);
	both->set(mrpt::obs::IMU_YAW, 2.0);
	both->set(mrpt::obs::IMU_PITCH, 0.0);
	both->set(mrpt::obs::IMU_ROLL, 0.0);
	EXPECT_LT(angleBetween(measured(ned, *both), R), 1e-12);
}

TEST(Ahrs, ResidualIsTheSo3LogAndItsJacobianIsTheIdentity)
{
	at::TestContext tc;
	AhrsModel model(pt::configText("heading_reference: 'true'"), "AHRS");
	const Eigen::Matrix3d R_meas = at::rotationYpr(-120 * kDeg, 20 * kDeg, 15 * kDeg);
	const Measurement m = pt::prepareOne(model, *quatObs(R_meas), tc.ctx());
	ASSERT_EQ(m.z.size(), 3);
	const Eigen::Vector3d phi(0.02, -0.05, 0.3);
	NavState x;
	x.R_nb = so3::Exp(-phi) * R_meas;
	Eigen::VectorXd r(3);
	model.residual(m.z, at::Predict(model, m, tc.ctx(), x), r);
	EXPECT_LT((r - phi).norm(), 1e-12) << r.transpose();  // Log(R_meas R_predᵀ)
	// ∂h/∂δθ at the measured attitude is I (finite differences).
	x.R_nb = R_meas;
	const double eps = 1e-6;
	Eigen::Matrix3d H;
	for (int j = 0; j < 3; ++j)
	{
		TangentVector d = TangentVector::Zero(idx::core_dim);
		d[idx::att + j] = eps;
		H.col(j) =
		    (at::Predict(model, m, tc.ctx(), x.boxplus(d)) - at::Predict(model, m, tc.ctx(), x.boxplus(-d))) /
		    (2 * eps);
	}
	EXPECT_LT((H - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-8) << H;
}

TEST(Ahrs, NoiseMapsRollPitchHeadingToNedAxes)
{
	at::TestContext tc;
	AhrsModel model(pt::configText("sigma_roll_deg: 1\nsigma_pitch_deg: 2\nsigma_heading_deg: 5"), "AHRS");
	const double vr = std::pow(1 * kDeg, 2), vp = std::pow(2 * kDeg, 2), vh = std::pow(5 * kDeg, 2);
	// Level, facing north: roll about north, pitch about east.
	Measurement m = pt::prepareOne(model, *yprObs(0, 0, 0), tc.ctx());
	EXPECT_NEAR(m.R(0, 0), vr, 2e-6 * vh);
	EXPECT_NEAR(m.R(1, 1), vp, 2e-6 * vh);
	EXPECT_NEAR(m.R(2, 2), vh, 2e-6 * vh);
	EXPECT_NEAR(m.R(0, 1), 0, 1e-15);
	// Facing east: roll about east, pitch about south.
	m = pt::prepareOne(model, *yprObs(90 * kDeg, 0, 0), tc.ctx());
	EXPECT_NEAR(m.R(0, 0), vp, 2e-6 * vh);
	EXPECT_NEAR(m.R(1, 1), vr, 2e-6 * vh);
	// Nose up 30°: the roll axis tilts toward the vertical and shares heading's axis.
	m = pt::prepareOne(model, *yprObs(0, 30 * kDeg, 0), tc.ctx());
	EXPECT_NEAR(m.R(0, 0), vr * 0.75, 2e-6 * vh);
	EXPECT_NEAR(m.R(2, 2), vh + vr * 0.25, 2e-6 * vh);
	EXPECT_NEAR(m.R(0, 2), -vr * std::sqrt(0.75) * 0.5, 2e-6 * vh);
	// Pitch 90°: J loses rank, R stays positive definite.
	m = pt::prepareOne(model, *yprObs(0, 90 * kDeg, 0), tc.ctx());
	EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(m.R).eigenvalues().minCoeff(), 0.0);
}

TEST(Ahrs, FullUpdateCorrectsEveryAxisHeadingOnlyJustTheHeading)
{
	at::TestContext tc;
	const Eigen::Matrix3d R_true = at::rotationYpr(75 * kDeg, -12 * kDeg, 8 * kDeg);
	NavState prior;
	prior.R_nb = so3::Exp(Eigen::Vector3d(3, -3, 6) * kDeg) * R_true;
	for (bool heading_only : {false, true})
	{
		AhrsModel model(
		    pt::configText(
		        std::string("heading_reference: 'true'\nsigma_roll_deg: 0.5\nsigma_pitch_deg: 0.5\n"
		                    "sigma_heading_deg: 1\nheading_only: ") +
		        (heading_only ? "true" : "false")),
		    "AHRS");
		ManifoldUkf ukf = pt::filterAt(prior, attitudeCovariance(5 * kDeg, 20 * kDeg));
		tc.ctx().mean = &ukf.state();
		const auto res = at::ApplyObservation(ukf, model, *quatObs(R_true), tc.ctx());
		ASSERT_EQ(res.updates.size(), 1u) << res.why;
		EXPECT_EQ(res.updates[0].status, UpdateStatus::Accepted);
		const Eigen::Vector3d err = so3::Log(ukf.state().R_nb * R_true.transpose());
		if (!heading_only)
		{
			// Gains 25/25.25 (tilt) and 400/401 (heading) in the linear case.
			EXPECT_LT(err.head<2>().norm(), 0.1 * kDeg) << err.transpose() / kDeg;
			EXPECT_LT(std::abs(err.z()), 0.1 * kDeg) << err.transpose() / kDeg;
		}
		else
		{
			// Only turned about down (roll and pitch as before); the heading
			// (azimuth of the levelled forward axis) is corrected.
			EXPECT_NEAR(pt::rollOf(ukf.state().R_nb), pt::rollOf(prior.R_nb), 1e-9);
			EXPECT_NEAR(pt::pitchOf(ukf.state().R_nb), pt::pitchOf(prior.R_nb), 1e-9);
			const Eigen::Vector3d u_b = plugins::levelReferenceDirection_b(prior.R_nb);
			EXPECT_NEAR(
			    wrapAngle(plugins::azimuthOf(ukf.state().R_nb, u_b) - plugins::azimuthOf(R_true, u_b)), 0,
			    0.05 * kDeg);
		}
	}
	tc.ctx().mean = nullptr;
}

TEST(Ahrs, HeadingOnlyCarriesNoTiltInformationAndWraps)
{
	at::TestContext tc;
	AhrsModel model(pt::configText("heading_only: true\nheading_reference: 'true'\nsigma_heading_deg: 2"),
	                "AHRS");
	const NavState x = at::RandomNavState(3);
	tc.ctx().mean = &x;
	const Measurement m = pt::prepareOne(model, *quatObs(x.R_nb), tc.ctx());
	for (int j = 0; j < 3; ++j)
	{
		TangentVector d = TangentVector::Zero(idx::core_dim);
		d[idx::att + j] = 1e-6;
		const double dh = wrapAngle(at::Predict(model, m, tc.ctx(), x.boxplus(d))[0] -
		                            at::Predict(model, m, tc.ctx(), x.boxplus(-d))[0]) /
		                  2e-6;
		EXPECT_NEAR(dh, j == 2 ? 1.0 : 0.0, 1e-7) << j;
	}
	EXPECT_NEAR(wrapAngle(m.z[0] - pt::headingOf(x.R_nb)), 0, 1e-9);
	// Across ±180°: truth −178°, prior 179°: the update goes +3° through 180°.
	const Eigen::Matrix3d R_true = at::rotationYpr(-178 * kDeg, 5 * kDeg, 2 * kDeg);
	NavState prior;
	prior.R_nb = at::rotationYpr(179 * kDeg, 5 * kDeg, 2 * kDeg);
	ManifoldUkf ukf = pt::filterAt(prior, attitudeCovariance(2 * kDeg, 10 * kDeg));
	tc.ctx().mean = &ukf.state();
	const auto res = at::ApplyObservation(ukf, model, *quatObs(R_true), tc.ctx());
	ASSERT_EQ(res.updates.size(), 1u);
	EXPECT_EQ(res.updates[0].status, UpdateStatus::Accepted);
	// Gain 100/104: 3° · 4/104 left.
	EXPECT_NEAR(wrapAngle(pt::headingOf(ukf.state().R_nb) - pt::headingOf(R_true)), -3 * kDeg * 4 / 104,
	            0.02 * kDeg);
	Eigen::VectorXd z(1), h(1), r(1);
	z[0] = -179.5 * kDeg;
	h[0] = 179.5 * kDeg;
	model.residual(z, h, r);
	EXPECT_NEAR(r[0], kDeg, 1e-12);
	tc.ctx().mean = nullptr;
}

TEST(Ahrs, InvalidObservations)
{
	at::TestContext tc;
	for (const char* cfg : {"{}", "heading_only: true"})
	{
		AhrsModel model(pt::configText(cfg), "AHRS");
		std::vector<Measurement> out;
		std::string why;
		const auto expectInvalid = [&](const mrpt::obs::CObservation& o, const std::string& reason)
		{
			out.clear();
			EXPECT_EQ(model.prepare(o, tc.ctx(), out, why), PrepareStatus::Invalid) << reason;
			EXPECT_NE(why.find(reason), std::string::npos) << why;
			EXPECT_TRUE(out.empty());
		};
		for (int k = 0; k < 4; ++k)
		{
			auto o = quatObs(Eigen::Matrix3d::Identity());
			o->set(static_cast<mrpt::obs::TIMUDataIndex>(mrpt::obs::IMU_ORI_QUAT_X + k), std::nan(""));
			expectInvalid(*o, "non-finite quaternion");
		}
		auto incomplete = emptyObs();
		incomplete->set(mrpt::obs::IMU_ORI_QUAT_W, 1.0);
		incomplete->set(mrpt::obs::IMU_ORI_QUAT_Z, 0.0);
		expectInvalid(*incomplete, "incomplete quaternion");
		auto not_unit = quatObs(Eigen::Matrix3d::Identity());
		not_unit->set(mrpt::obs::IMU_ORI_QUAT_W, 2.0);
		expectInvalid(*not_unit, "norm");
		auto zero = quatObs(Eigen::Matrix3d::Identity());
		zero->set(mrpt::obs::IMU_ORI_QUAT_W, 0.0);
		expectInvalid(*zero, "norm");
		expectInvalid(*yprObs(std::nan(""), 0, 0), "non-finite yaw/pitch/roll");
		expectInvalid(*yprObs(0, HUGE_VAL, 0), "non-finite yaw/pitch/roll");
		auto two_angles = emptyObs();
		two_angles->set(mrpt::obs::IMU_YAW, 0.1);
		two_angles->set(mrpt::obs::IMU_PITCH, 0.1);
		expectInvalid(*two_angles, "neither");
		expectInvalid(*emptyObs(), "neither");
		expectInvalid(*obs::CObservationPressure::Create(), "CObservationIMU");
		// Slightly off unit (rounded output) is renormalised.
		auto rounded = quatObs(Eigen::Matrix3d::Identity());
		rounded->set(mrpt::obs::IMU_ORI_QUAT_W, 1.004);
		EXPECT_EQ(model.prepare(*rounded, tc.ctx(), out, why), PrepareStatus::Ok) << why;
	}
}

TEST(Ahrs, NanMeasurementNeverChangesTheState)
{
	at::TestContext tc;
	AhrsModel model(pt::defaultConfig(), "AHRS");
	const NavState x0 = at::RandomNavState(5);
	Measurement m = pt::prepareOne(model, *quatObs(x0.R_nb), tc.ctx());
	m.R(1, 1) = std::nan("");
	EXPECT_TRUE(pt::FilterRefuses(model, m, tc.ctx(), x0));
}

TEST(Ahrs, MinIntervalThinsTheOutput)
{
	at::TestContext tc;
	AhrsModel model(pt::configText("min_interval_s: 0.42"), "AHRS");
	// 2 s at 20 Hz: used at t = 0, 0.45, 0.9, 1.35, 1.8 s.
	const auto attitude = quatObs(Eigen::Matrix3d::Identity());
	const pt::Offered n = pt::offerInTurn(model, tc.ctx(), *attitude, 40, 1.7e9, 0.05);
	EXPECT_EQ(n.used, 5);
	EXPECT_EQ(model.rateLimitedCount(), 35u);
}
