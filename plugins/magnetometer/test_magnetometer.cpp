// The "magnetometer" plugin: raw 3-axis field, hard/soft iron, heading and vector modes, disturbance gate.
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/so3.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/testing/plugin_state_bench.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>

#include <cmath>

#include "level_heading.h"
#include "magnetometer.h"
#include "plugin_test_support.h"

using auvnav::plugins::MagnetometerModel;
using mrpt::obs::CObservationIMU;

namespace
{
constexpr double kF = 49.6, kD = 3.0 * kDeg, kI = 68.0 * kDeg;  // magnetometer.yaml defaults

Eigen::Vector3d fieldN()
{
	return plugins::earthField_n(kF, kD, kI);
}

/** A magnetometer observation with the raw reading `raw_ut` [µT] (stored in gauss). */
CObservationIMU::Ptr magObs(const Eigen::Vector3d& raw_ut,
                            const Eigen::Vector3d& mount_ypr_deg = Eigen::Vector3d::Zero(),
                            double t_s = 1.7e9)
{
	auto o = CObservationIMU::Create();
	o->sensorLabel = "MAG";
	o->timestamp = mrpt::Clock::fromDouble(t_s);
	o->sensorPose = mrpt::poses::CPose3D(0.1, 0.0, -0.2, mount_ypr_deg[0] * kDeg, mount_ypr_deg[1] * kDeg,
	                                     mount_ypr_deg[2] * kDeg);
	o->set(mrpt::obs::IMU_MAG_X, raw_ut.x() / 100);
	o->set(mrpt::obs::IMU_MAG_Y, raw_ut.y() / 100);
	o->set(mrpt::obs::IMU_MAG_Z, raw_ut.z() / 100);
	return o;
}

/** The noise-free reading of a sensor mounted `mount_ypr_deg` at attitude R_nb. */
Eigen::Vector3d reading(const Eigen::Matrix3d& R_nb,
                        const Eigen::Vector3d& mount_ypr_deg = Eigen::Vector3d::Zero(),
                        const Eigen::Vector3d& b = Eigen::Vector3d::Zero(),
                        const Eigen::Matrix3d& S = Eigen::Matrix3d::Identity())
{
	const Eigen::Matrix3d R_bs =
	    at::rotationYpr(mount_ypr_deg[0] * kDeg, mount_ypr_deg[1] * kDeg, mount_ypr_deg[2] * kDeg);
	return plugins::predictedReading_s(R_nb, R_bs, fieldN(), b, S);
}

PrepareStatus prepare(MagnetometerModel& model, const mrpt::obs::CObservation& o, const FilterContext& ctx,
                      std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	why.clear();
	return model.prepare(o, ctx, out, why);
}

const char* kVector = "mode: vector\n";
}  // namespace

TEST(Magnetometer, DefaultConfig)
{
	const MagnetometerModel m(pt::defaultConfig(), "MAG");
	EXPECT_EQ(m.mode(), MagnetometerModel::Mode::Heading);
	EXPECT_EQ(m.uses(), uint32_t(kAttitude));
	EXPECT_DOUBLE_EQ(m.gateProbability(), 0.999);
	// F [cos I cos D, cos I sin D, sin I] for 49.6 µT, D 3°, I 68°.
	EXPECT_NEAR(m.field_n_ut().x(), 49.6 * 0.374606593 * 0.998629535, 1e-6);
	EXPECT_NEAR(m.field_n_ut().y(), 49.6 * 0.374606593 * 0.052335956, 1e-6);
	EXPECT_NEAR(m.field_n_ut().z(), 49.6 * 0.927183855, 1e-6);
	EXPECT_NEAR(m.field_n_ut().norm(), 49.6, 1e-12);
	EXPECT_TRUE(m.hardIron_ut().isZero());
	EXPECT_TRUE(m.softIron().isIdentity());
	EXPECT_NEAR(m.headingSigma_rad(), 3 * kDeg, 1e-15);
	// The file and the built-in defaults agree.
	const MagnetometerModel d(pt::configText("{}"), "MAG");
	EXPECT_TRUE(d.field_n_ut() == m.field_n_ut());
	EXPECT_EQ(d.noise_ut(), m.noise_ut());
}

TEST(Magnetometer, ModuleExportsEntryAndCreatesFromDefaultConfig)
{
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("magnetometer", pt::defaultConfigText(), kAttitude));
	EXPECT_TRUE(pt::ModuleLoadsAndCreates("magnetometer", "mode: vector", kAttitude));
}

TEST(Magnetometer, RejectsBadConfigNamingTheKey)
{
	// The key each message must name is the one on the yaml's last line. Among
	// them: a field in nT or gauss (500), heading mode near the magnetic pole
	// (inclination 88°), a singular and a reflecting soft-iron matrix, and a
	// misspelled key (the last).
	for (const char* yaml :
	     {"mode: sideways", "field_ut: -5", "field_ut: 500", "declination_deg: 200", "inclination_deg: 95",
	      "inclination_deg: 88", "hard_iron_ut: [1, 2]", "hard_iron_ut: [1e5, 0, 0]",
	      "soft_iron: [1, 0, 0, 0, 1, 0, 0, 0]", "soft_iron: [1, 0, 0, 0, 1, 0, 0, 0, 0]",
	      "soft_iron: [1, 0, 0, 0, -1, 0, 0, 0, 1]", "soft_iron: [20, 0, 0, 0, 20, 0, 0, 0, 20]",
	      "noise_ut: 0", "heading_sigma_deg: -1", "norm_tolerance: 0", "dip_tolerance_deg: 0",
	      "gate_probability: 0", "min_interval_s: -1", "heading_sigma: 2"})
		EXPECT_TRUE(pt::RefusesNamingTheKey<MagnetometerModel>(yaml)) << yaml;
	// Near the pole the vector mode is still fine.
	EXPECT_NO_THROW(MagnetometerModel(pt::configText("mode: vector\ninclination_deg: 88"), "MAG"));
}

TEST(Magnetometer, WellFormedOnRandomStatesInBothModes)
{
	at::TestContext tc;
	for (const char* cfg :
	     {"", kVector,
	      "hard_iron_ut: [12, -30, 5]\nsoft_iron: [1.1, 0.05, 0, 0.05, 0.9, 0.02, 0, 0.02, 1.0]"})
	{
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			MagnetometerModel model(
			    pt::configText(std::string(cfg) + "\ndip_tolerance_deg: 180\nnorm_tolerance: 10"), "MAG");
			const NavState x = at::RandomNavState(seed);
			const NavState mean = at::RandomNavState(seed + 100);
			tc.ctx().mean = &mean;
			const Eigen::Vector3d mount(90, 0, 180);
			const auto o = magObs(reading(mean.R_nb, mount, model.hardIron_ut(), model.softIron()), mount);
			EXPECT_TRUE(pt::IsWellFormedAndUsed(model, *o, tc.ctx(), x, seed)) << cfg << ", seed " << seed;
		}
	}
	tc.ctx().mean = nullptr;
}

TEST(Magnetometer, PredictedFieldForKnownAttitudes)
{
	at::TestContext tc;
	MagnetometerModel model(pt::configText(kVector), "MAG");
	const Eigen::Vector3d mn = fieldN();
	NavState x;
	const Measurement m = pt::prepareOne(model, *magObs(mn), tc.ctx());
	// Level, facing north: the NED field itself.
	EXPECT_TRUE(at::Predict(model, m, tc.ctx(), x).isApprox(mn, 1e-12));
	// Facing east: forward = east, right = south.
	x.R_nb = at::rotationYpr(90 * kDeg, 0, 0);
	EXPECT_TRUE(at::Predict(model, m, tc.ctx(), x).isApprox(Eigen::Vector3d(mn.y(), -mn.x(), mn.z()), 1e-12));
	// Upside down (roll 180°): right = west, down = up.
	x.R_nb = at::rotationYpr(0, 0, 180 * kDeg);
	EXPECT_TRUE(
	    at::Predict(model, m, tc.ctx(), x).isApprox(Eigen::Vector3d(mn.x(), -mn.y(), -mn.z()), 1e-12));
	// Nose up 90°: forward = up, down = north.
	x.R_nb = at::rotationYpr(0, 90 * kDeg, 0);
	EXPECT_NEAR((at::Predict(model, m, tc.ctx(), x) - Eigen::Vector3d(-mn.z(), mn.y(), mn.x())).norm(), 0,
	            1e-12);

	// Sensor yawed 90° in the body (its x = body right) with hard and soft
	// iron: raw = b + S [R_bsᵀ m_b]; facing north level, m_b = m_n and the
	// sensor sees (m_E, −m_N, m_D).
	MagnetometerModel cal(pt::configText("mode: vector\nhard_iron_ut: [10, -20, 30]\n"
	                                     "soft_iron: [1.2, 0, 0, 0, 0.8, 0, 0, 0, 1.0]"),
	                      "MAG");
	const Measurement mc =
	    pt::prepareOne(cal,
	                   *magObs(Eigen::Vector3d(10 + 1.2 * mn.y(), -20 - 0.8 * mn.x(), 30 + mn.z()),
	                           Eigen::Vector3d(90, 0, 0)),
	                   tc.ctx());
	x.R_nb.setIdentity();
	const Eigen::VectorXd h = at::Predict(cal, mc, tc.ctx(), x);
	EXPECT_NEAR(h[0], 10 + 1.2 * mn.y(), 1e-12);
	EXPECT_NEAR(h[1], -20 - 0.8 * mn.x(), 1e-12);
	EXPECT_NEAR(h[2], 30 + mn.z(), 1e-12);
	EXPECT_TRUE(h.isApprox(mc.z, 1e-12));  // the reading that was made for it
	// The gauss → µT conversion: 0.5 G is 50 µT.
	EXPECT_NEAR(pt::prepareOne(model, *magObs(Eigen::Vector3d(50, 0, 0)), tc.ctx()).z[0], 50.0, 1e-12);
}

TEST(Magnetometer, VectorJacobianMatchesFiniteDifferences)
{
	// Analytic: with R ← Exp(δ) R, ∂h/∂δ = S R_bsᵀ R_nbᵀ [m_n]×.
	at::TestContext tc;
	MagnetometerModel model(
	    pt::configText("mode: vector\nhard_iron_ut: [5, 6, 7]\n"
	                   "soft_iron: [1.1, 0.05, 0, 0.05, 0.9, 0.02, 0, 0.02, 1.0]\nnorm_tolerance: 10"),
	    "MAG");
	const Measurement m =
	    pt::prepareOne(model, *magObs(Eigen::Vector3d(40, 10, 20), Eigen::Vector3d(30, 10, -5)), tc.ctx());
	const Eigen::Matrix3d R_bs = at::rotationYpr(30 * kDeg, 10 * kDeg, -5 * kDeg);
	for (uint32_t seed = 1; seed <= 5; ++seed)
	{
		const NavState x = at::RandomNavState(seed);
		const Eigen::Matrix3d H =
		    model.softIron() * R_bs.transpose() * x.R_nb.transpose() * so3::skew(fieldN());
		Eigen::Matrix3d H_fd;
		const double eps = 1e-6;
		for (int j = 0; j < 3; ++j)
		{
			TangentVector d = TangentVector::Zero(idx::core_dim);
			d[idx::att + j] = eps;
			H_fd.col(j) = (at::Predict(model, m, tc.ctx(), x.boxplus(d)) -
			               at::Predict(model, m, tc.ctx(), x.boxplus(-d))) /
			              (2 * eps);
		}
		EXPECT_LT((H_fd - H).cwiseAbs().maxCoeff(), 1e-6) << "seed " << seed << "\n" << H_fd << "\nvs\n" << H;
		EXPECT_GT(H.norm(), 10.0);  // not trivially zero
	}
}

TEST(Magnetometer, HeadingCarriesNoTiltInformation)
{
	// Finite differences of the heading h at the mean: exactly (0, 0, 1), also tilted.
	at::TestContext tc;
	MagnetometerModel model(pt::defaultConfig(), "MAG");
	for (uint32_t seed = 1; seed <= 10; ++seed)
	{
		const NavState x = at::RandomNavState(seed);  // roll, pitch up to ±30°
		tc.ctx().mean = &x;
		const Measurement m = pt::prepareOne(model, *magObs(reading(x.R_nb)), tc.ctx());
		const double eps = 1e-6;
		for (int j = 0; j < 3; ++j)
		{
			TangentVector d = TangentVector::Zero(idx::core_dim);
			d[idx::att + j] = eps;
			const double dh = wrapAngle(at::Predict(model, m, tc.ctx(), x.boxplus(d))[0] -
			                            at::Predict(model, m, tc.ctx(), x.boxplus(-d))[0]) /
			                  (2 * eps);
			EXPECT_NEAR(dh, j == 2 ? 1.0 : 0.0, 1e-7) << "seed " << seed << ", axis " << j;
		}
		// At the truth, h equals z, which is the usual heading (Euler yaw) of x.
		EXPECT_NEAR(wrapAngle(m.z[0] - pt::headingOf(x.R_nb)), 0.0, 1e-9);
		EXPECT_NEAR(wrapAngle(at::Predict(model, m, tc.ctx(), x)[0] - m.z[0]), 0.0, 1e-9);
	}
	tc.ctx().mean = nullptr;
}

TEST(Magnetometer, HeadingResidualIsTheHeadingError)
{
	// Mean turned by −12° about down from the truth (tilt right): residual +12°,
	// for a tilted vehicle and a tilted sensor mount with hard/soft iron.
	at::TestContext tc;
	const char* cal =
	    "hard_iron_ut: [10, -20, 30]\nsoft_iron: [1.1, 0.05, 0, 0.05, 0.9, 0.02, 0, 0.02, 1.0]\n";
	MagnetometerModel model(pt::configText(cal), "MAG");
	MagnetometerModel uncalibrated(pt::defaultConfig(), "MAG");
	const Eigen::Vector3d mount(45, 5, 180);
	for (double yaw_deg : {0.0, 100.0, -170.0})
	{
		const Eigen::Matrix3d R_true = at::rotationYpr(yaw_deg * kDeg, -15 * kDeg, 20 * kDeg);
		NavState mean;
		mean.R_nb = so3::Exp(Eigen::Vector3d(0, 0, -12 * kDeg)) * R_true;
		tc.ctx().mean = &mean;
		const auto o = magObs(reading(R_true, mount, model.hardIron_ut(), model.softIron()), mount);
		const Measurement m = pt::prepareOne(model, *o, tc.ctx());
		Eigen::VectorXd r(1);
		model.residual(m.z, at::Predict(model, m, tc.ctx(), mean), r);
		EXPECT_NEAR(r[0], 12 * kDeg, 1e-9) << yaw_deg;
		NavState truth;
		truth.R_nb = R_true;
		model.residual(m.z, at::Predict(model, m, tc.ctx(), truth), r);
		EXPECT_NEAR(r[0], 0.0, 1e-9) << yaw_deg;
		EXPECT_NEAR(wrapAngle(m.z[0] - yaw_deg * kDeg), 0.0, 1e-9);
		// Without the calibration the same reading is off (or gated out).
		std::vector<Measurement> out;
		std::string why;
		if (prepare(uncalibrated, *o, tc.ctx(), out, why) == PrepareStatus::Ok)
		{
			EXPECT_GT(std::abs(wrapAngle(out[0].z[0] - yaw_deg * kDeg)), 2 * kDeg) << yaw_deg;
		}
	}
	tc.ctx().mean = nullptr;
}

namespace
{
struct UpdateOutcome
{
	NavState x;
	UpdateStatus status;
};

/** at::TypicalCovariance() with the heading's σ `sigma_heading` [rad] (tilt 2°). */
Covariance headingCovariance(double sigma_heading)
{
	Covariance P = at::TypicalCovariance();
	P(idx::att + 2, idx::att + 2) = sigma_heading * sigma_heading;
	return P;
}

/** One update of a filter whose mean is `prior` (attitude σ: tilt 2°, heading `sigma_heading`). */
UpdateOutcome updateOnce(MagnetometerModel& model, const NavState& prior, const Eigen::Vector3d& raw_ut,
                         double sigma_heading = 30 * kDeg)
{
	at::TestContext tc;
	ManifoldUkf ukf = pt::filterAt(prior, headingCovariance(sigma_heading));
	tc.ctx().mean = &ukf.state();
	const auto res = at::ApplyObservation(ukf, model, *magObs(raw_ut), tc.ctx());
	EXPECT_EQ(res.status, PrepareStatus::Ok) << res.why;
	EXPECT_EQ(res.updates.size(), 1u);
	return {ukf.state(), res.updates.empty() ? UpdateStatus::Invalid : res.updates[0].status};
}
}  // namespace

TEST(Magnetometer, HeadingAndVectorModesAgreeOnTheHeading)
{
	MagnetometerModel heading(pt::configText("heading_sigma_deg: 1"), "MAG");
	// Vector noise giving the same heading σ: σ_B / (F cos I) = 1°.
	MagnetometerModel vector(
	    pt::configText("mode: vector\nnoise_ut: " + std::to_string(kF * std::cos(kI) * kDeg)), "MAG");
	const Eigen::Matrix3d R_true = at::rotationYpr(40 * kDeg, 5 * kDeg, -8 * kDeg);
	// One update from a heading error with prior σ (tilt 2°, heading σ),
	// measurement σ 1° (heading) or F cos I · 1° (vector). The heading mode is
	// exactly linear in the heading: it leaves error/(1 + σ²/1°²) and never
	// touches roll/pitch. One field vector fixes only the two rotation axes
	// perpendicular to it: a rotation about the field (dip 68°, so mostly
	// about down) is unobservable, and the linear Kalman update splits the
	// heading error between heading and tilt by their prior σ. The vector
	// mode is compared with that linear update (3 × 3, computed here); the
	// UKF's sigma points at ±γσ (γ ≈ 0.3·√43 ≈ 2) add the curvature of
	// cos/sin, which matters at σ = 30°: there the UKF overshoots a 15°
	// error by 2.1° (linear: 0.4° short), a 3° error by 0.46°.
	struct Case
	{
		double error_deg, sigma_deg, tolerance_deg;
	};
	const double sigma_vec = kF * std::cos(kI) * kDeg;
	for (const Case c : {Case{15, 30, 3.0}, Case{3, 30, 0.6}, Case{3, 5, 0.05}})
	{
		NavState prior;
		prior.R_nb = so3::Exp(Eigen::Vector3d(0, 0, -c.error_deg * kDeg)) * R_true;
		const auto h = updateOnce(heading, prior, reading(R_true), c.sigma_deg * kDeg);
		const auto v = updateOnce(vector, prior, reading(R_true), c.sigma_deg * kDeg);
		ASSERT_EQ(h.status, UpdateStatus::Accepted);
		ASSERT_EQ(v.status, UpdateStatus::Accepted);
		const double err_h = wrapAngle(pt::headingOf(h.x.R_nb) - pt::headingOf(R_true));
		EXPECT_NEAR(err_h, -c.error_deg * kDeg / (1 + c.sigma_deg * c.sigma_deg), 1e-3 * kDeg)
		    << c.error_deg << "/" << c.sigma_deg << ": " << err_h / kDeg;
		EXPECT_NEAR(pt::rollOf(h.x.R_nb), pt::rollOf(prior.R_nb), 1e-9);
		EXPECT_NEAR(pt::pitchOf(h.x.R_nb), pt::pitchOf(prior.R_nb), 1e-9);
		// Linear Kalman update of the attitude error (NED axes): the reading
		// m_b = R_nbᵀ m_n changes by R_nbᵀ [m_n]× δ for R ← Exp(δ) R.
		const Eigen::Matrix3d H = R_true.transpose() * so3::skew(fieldN());
		const Eigen::Vector3d prior_sd(2 * kDeg, 2 * kDeg, c.sigma_deg * kDeg);
		const Eigen::Matrix3d P = prior_sd.cwiseAbs2().asDiagonal();
		const Eigen::Matrix3d K =
		    P * H.transpose() *
		    (H * P * H.transpose() + sigma_vec * sigma_vec * Eigen::Matrix3d::Identity()).inverse();
		const Eigen::Vector3d e_linear =
		    (Eigen::Matrix3d::Identity() - K * H) * Eigen::Vector3d(0, 0, -c.error_deg * kDeg);
		const Eigen::Vector3d e_v = so3::Log(v.x.R_nb * R_true.transpose());
		EXPECT_LT((e_v - e_linear).cwiseAbs().maxCoeff(), c.tolerance_deg * kDeg)
		    << c.error_deg << "/" << c.sigma_deg << ": UKF " << e_v.transpose() / kDeg << " deg, linear "
		    << e_linear.transpose() / kDeg << " deg";
		// Both modes correct most of the heading error when the heading is the
		// uncertain part (σ 30° ≫ tilt 2°).
		if (c.sigma_deg >= 30)
		{
			EXPECT_LT(std::abs(e_v.z()), 0.2 * c.error_deg * kDeg) << e_v.z() / kDeg;
			EXPECT_LT(std::abs(err_h), 0.01 * c.error_deg * kDeg);
		}
	}
}

TEST(Magnetometer, DisturbedDipPullsTiltOnlyInVectorMode)
{
	// A 4 µT disturbance (e.g. thruster currents) at right angles to the
	// field in its vertical plane: dip +4.6°, norm and horizontal direction
	// unchanged to first order, inside the gate. The vector mode reads it as
	// a tilt, the heading mode cannot.
	MagnetometerModel heading(pt::defaultConfig(), "MAG");
	MagnetometerModel vector(pt::configText("mode: vector\nnoise_ut: 0.5"), "MAG");
	const Eigen::Matrix3d R_true = at::rotationYpr(-60 * kDeg, 0, 0);
	NavState prior;
	prior.R_nb = R_true;
	const Eigen::Vector3d steeper_n(-std::sin(kI) * std::cos(kD), -std::sin(kI) * std::sin(kD), std::cos(kI));
	const Eigen::Vector3d raw = reading(R_true) + R_true.transpose() * (4.0 * steeper_n);
	const auto h = updateOnce(heading, prior, raw);
	const auto v = updateOnce(vector, prior, raw);
	ASSERT_EQ(h.status, UpdateStatus::Accepted);
	ASSERT_EQ(v.status, UpdateStatus::Accepted);
	const double tilt_h = (so3::Log(h.x.R_nb * R_true.transpose())).head<2>().norm();
	const double tilt_v = (so3::Log(v.x.R_nb * R_true.transpose())).head<2>().norm();
	EXPECT_LT(tilt_h, 1e-9);
	EXPECT_GT(tilt_v, 1.0 * kDeg) << tilt_v / kDeg;
	// The horizontal field keeps its direction, hence the heading mode its heading.
	EXPECT_NEAR(wrapAngle(pt::headingOf(h.x.R_nb) - pt::headingOf(R_true)), 0.0, 1e-6);
}

TEST(Magnetometer, DisturbanceGateSkipsNormAndDipChanges)
{
	at::TestContext tc;
	for (const char* cfg : {"{}", kVector})
	{
		MagnetometerModel model(pt::configText(cfg), "MAG");
		const Eigen::Matrix3d R = at::rotationYpr(30 * kDeg, 10 * kDeg, 5 * kDeg);
		NavState mean;
		mean.R_nb = R;
		tc.ctx().mean = &mean;
		std::vector<Measurement> out;
		std::string why;
		// 30 % stronger (a thruster at full power next to the sensor): skipped.
		EXPECT_EQ(prepare(model, *magObs(1.3 * reading(R)), tc.ctx(), out, why), PrepareStatus::Skip) << cfg;
		EXPECT_NE(why.find("norm"), std::string::npos) << why;
		EXPECT_TRUE(out.empty());
		EXPECT_EQ(model.disturbedCount(), 1u);
		EXPECT_EQ(prepare(model, *magObs(0.7 * reading(R)), tc.ctx(), out, why), PrepareStatus::Skip);
		EXPECT_EQ(model.disturbedCount(), 2u);
		// 8 % stronger: within the 10 % tolerance.
		EXPECT_EQ(prepare(model, *magObs(1.08 * reading(R)), tc.ctx(), out, why), PrepareStatus::Ok) << why;
		// Same norm, dip 15° off (field turned about the body's levelled right axis).
		const Eigen::Matrix3d tilt_field =
		    so3::Exp(-15 * kDeg * Eigen::Vector3d(-std::sin(kD), std::cos(kD), 0));
		const Eigen::Vector3d raw_dip = R.transpose() * tilt_field * fieldN();
		EXPECT_NEAR(raw_dip.norm(), kF, 1e-9);
		EXPECT_EQ(prepare(model, *magObs(raw_dip), tc.ctx(), out, why), PrepareStatus::Skip) << cfg;
		EXPECT_NE(why.find("dip"), std::string::npos) << why;
		EXPECT_EQ(model.disturbedCount(), 3u);
		// 5° of dip: accepted.
		const Eigen::Vector3d raw_dip5 =
		    R.transpose() * so3::Exp(-5 * kDeg * Eigen::Vector3d(-std::sin(kD), std::cos(kD), 0)) * fieldN();
		EXPECT_EQ(prepare(model, *magObs(raw_dip5), tc.ctx(), out, why), PrepareStatus::Ok) << why;
		EXPECT_EQ(model.disturbedCount(), 3u);
	}
	// Without a mean the vector mode still checks the norm; heading mode skips.
	tc.ctx().mean = nullptr;
	MagnetometerModel vector(pt::configText(kVector), "MAG");
	MagnetometerModel heading(pt::defaultConfig(), "MAG");
	std::vector<Measurement> out;
	std::string why;
	EXPECT_EQ(prepare(vector, *magObs(1.3 * fieldN()), tc.ctx(), out, why), PrepareStatus::Skip);
	EXPECT_EQ(prepare(vector, *magObs(fieldN()), tc.ctx(), out, why), PrepareStatus::Ok);
	EXPECT_EQ(prepare(heading, *magObs(fieldN()), tc.ctx(), out, why), PrepareStatus::Skip);
	EXPECT_NE(why.find("tilt"), std::string::npos) << why;
}

TEST(Magnetometer, HeadingWrapsAcross180)
{
	at::TestContext tc;
	MagnetometerModel model(pt::configText("heading_sigma_deg: 2"), "MAG");
	Eigen::VectorXd z(1), h(1), r(1);
	z[0] = 179 * kDeg;
	h[0] = -179 * kDeg;
	model.residual(z, h, r);
	EXPECT_NEAR(r[0], -2 * kDeg, 1e-12);
	model.residual(h, z, r);
	EXPECT_NEAR(r[0], 2 * kDeg, 1e-12);
	// Truth −177°, mean 178°: 5° apart across the wrap. The update turns the
	// heading by about +5° (through 180°), not by −355°.
	const Eigen::Matrix3d R_true = at::rotationYpr(-177 * kDeg, 3 * kDeg, -4 * kDeg);
	NavState prior;
	prior.R_nb = at::rotationYpr(178 * kDeg, 3 * kDeg, -4 * kDeg);
	const auto u = updateOnce(model, prior, reading(R_true), 10 * kDeg);
	ASSERT_EQ(u.status, UpdateStatus::Accepted);
	// Gain 100/104: the heading lands at 178 + 5·100/104 = 182.8 ≡ −177.2°.
	EXPECT_NEAR(wrapAngle(pt::headingOf(u.x.R_nb) - pt::headingOf(R_true)), -5 * kDeg * 4 / 104, 0.05 * kDeg);
	// The measured heading itself is wrapped into (−180°, 180°].
	NavState mean;
	mean.R_nb = R_true;
	tc.ctx().mean = &mean;
	const Measurement m = pt::prepareOne(model, *magObs(reading(R_true)), tc.ctx());
	EXPECT_NEAR(m.z[0], -177 * kDeg, 1e-9);
	tc.ctx().mean = nullptr;
}

TEST(Magnetometer, InvalidObservations)
{
	at::TestContext tc;
	NavState mean;
	tc.ctx().mean = &mean;
	for (const char* cfg : {"{}", kVector})
	{
		MagnetometerModel model(pt::configText(cfg), "MAG");
		std::vector<Measurement> out;
		std::string why;
		for (int axis = 0; axis < 3; ++axis)
			for (double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL})
			{
				auto o = magObs(fieldN());
				o->set(static_cast<mrpt::obs::TIMUDataIndex>(mrpt::obs::IMU_MAG_X + axis), bad);
				EXPECT_EQ(prepare(model, *o, tc.ctx(), out, why), PrepareStatus::Invalid) << axis;
				EXPECT_NE(why.find("non-finite IMU_MAG_"), std::string::npos) << why;
				EXPECT_TRUE(out.empty());
			}
		auto missing = CObservationIMU::Create();
		missing->set(mrpt::obs::IMU_MAG_X, 0.2);
		missing->set(mrpt::obs::IMU_MAG_Y, 0.0);
		missing->set(mrpt::obs::IMU_WZ, 0.01);  // a gyro sample is not a magnetometer reading
		EXPECT_EQ(prepare(model, *missing, tc.ctx(), out, why), PrepareStatus::Invalid);
		EXPECT_NE(why.find("missing IMU_MAG_Z"), std::string::npos) << why;
		EXPECT_EQ(prepare(model, *CObservationIMU::Create(), tc.ctx(), out, why), PrepareStatus::Invalid);
		EXPECT_NE(why.find("missing IMU_MAG_X"), std::string::npos) << why;
		EXPECT_TRUE(pt::RefusesOtherClass<obs::CObservationPressure>(model, tc.ctx(), "CObservationIMU"));
		EXPECT_EQ(model.disturbedCount(), 0u);  // invalid is not "disturbed"
	}
	tc.ctx().mean = nullptr;
}

TEST(Magnetometer, NanMeasurementNeverChangesTheState)
{
	at::TestContext tc;
	MagnetometerModel model(pt::configText(kVector), "MAG");
	const NavState x0 = at::RandomNavState(5);
	Measurement m = pt::prepareOne(model, *magObs(reading(x0.R_nb)), tc.ctx());
	m.z[1] = std::nan("");
	EXPECT_TRUE(pt::FilterRefuses(model, m, tc.ctx(), x0));
}

TEST(Magnetometer, GrossHeadingOutlierFailsTheChiSquareGate)
{
	MagnetometerModel model(pt::defaultConfig(), "MAG");
	// A reading 60° off in heading with an attitude σ of 2°: rejected.
	const Eigen::Matrix3d R = at::rotationYpr(10 * kDeg, 0, 0);
	NavState prior;
	prior.R_nb = R;
	const auto u = updateOnce(model, prior, reading(at::rotationYpr(70 * kDeg, 0, 0)), 2 * kDeg);
	EXPECT_EQ(u.status, UpdateStatus::Rejected);
	EXPECT_TRUE(at::NavStateNear(u.x, prior, 1e-12));
}

TEST(Magnetometer, MinIntervalThinsTheReadings)
{
	at::TestContext tc;
	MagnetometerModel model(pt::configText("mode: vector\nmin_interval_s: 0.95"), "MAG");
	// 5 s at 10 Hz: used at t = 0, 1, 2, 3, 4 s.
	const auto field = magObs(fieldN());
	const pt::Offered n = pt::offerInTurn(model, tc.ctx(), *field, 50, 1.7e9, 0.1);
	EXPECT_EQ(n.used, 5);
	EXPECT_EQ(model.rateLimitedCount(), 45u);
}

TEST(Magnetometer, HeadingModeFromLargeInitialErrorsNeverClaimsAFalseHeading)
{
	// A vehicle at rest, 20 heading-mode updates (noise-free readings, heading
	// σ 3°) from `error` off with heading σ `sigma`. Measured (UtParams
	// defaults, γ ≈ 2):
	//  - σ 60° or 90°: every error up to 179° converges to < 0.03°, σ = 3°/√20;
	//  - σ 30°: 30° and 90° converge (90°: to 0.045°), 135° and 179° (> 4σ)
	//    fail the χ² gate;
	//  - σ 180°: every update is rejected. The heading sigma points sit at
	//    ±γσ ≈ ±354°, which wrap to ±6°: the predicted spread is tiny and any
	//    innovation fails the gate. The heading σ stays 180° (no false
	//    collapse), but the magnetometer cannot align from it: the alignment
	//    must seed the heading (issue 13), or the UKF must not wrap its
	//    sigma points (libnav).
	// Either the filter converges to the truth, or it leaves heading and σ alone.
	MagnetometerModel model(pt::defaultConfig(), "MAG");
	const Eigen::Matrix3d R_true = at::rotationYpr(20 * kDeg, 2 * kDeg, -3 * kDeg);
	for (double sigma_deg : {30.0, 60.0, 90.0, 180.0})
		for (double error_deg : {30.0, 90.0, 135.0, 179.0})
		{
			at::TestContext tc;
			NavState prior;
			prior.R_nb = so3::Exp(Eigen::Vector3d(0, 0, -error_deg * kDeg)) * R_true;
			ManifoldUkf ukf = pt::filterAt(prior, headingCovariance(sigma_deg * kDeg));
			const NavState start = ukf.state();
			tc.ctx().mean = &ukf.state();
			int rejected = 0;
			for (int k = 0; k < 20; ++k)
			{
				const auto res = at::ApplyObservation(ukf, model, *magObs(reading(R_true)), tc.ctx());
				ASSERT_EQ(res.updates.size(), 1u) << res.why;
				if (res.updates[0].status == UpdateStatus::Rejected) ++rejected;
			}
			const double err = wrapAngle(pt::headingOf(ukf.state().R_nb) - pt::headingOf(R_true));
			const double sigma = std::sqrt(ukf.covariance()(2, 2));
			const bool converged =
			    std::abs(err) < 0.1 * kDeg && std::abs(sigma - 3 * kDeg / std::sqrt(20.0)) < 1e-3 * kDeg;
			const bool untouched =
			    rejected == 20 && at::NavStateIdentical(ukf.state(), start) && sigma == sigma_deg * kDeg;
			EXPECT_TRUE(converged || untouched)
			    << "sigma " << sigma_deg << ", error " << error_deg << ": " << err / kDeg << " deg, sigma "
			    << sigma / kDeg << " deg, rejected " << rejected;
			if (sigma_deg == 60 || sigma_deg == 90 || (error_deg <= 90 && sigma_deg == 30))
			{
				EXPECT_TRUE(converged) << sigma_deg << " " << error_deg;
			}
		}
}

TEST(Magnetometer, ForcedRecoveryAtHeadingSigma180NeverClaimsAFalseHeading)
{
	// With heading σ 180° the UKF's heading sigma points (±γσ ≈ ±354°) used to
	// wrap onto the mean, every update failed the gate, and the recovery path
	// (update(..., recovery = true)) then applied them with inflated noise:
	// from 90° off the heading mode ended 111° off with σ 7.3° after 20
	// readings. Fixed by the attitude sigma-point limit (ukf.h); kept as a
	// regression test.
	MagnetometerModel model(pt::defaultConfig(), "MAG");
	const Eigen::Matrix3d R_true = at::rotationYpr(20 * kDeg, 2 * kDeg, -3 * kDeg);
	for (double error_deg : {30.0, 90.0, 179.0})
	{
		at::TestContext tc;
		NavState prior;
		prior.R_nb = so3::Exp(Eigen::Vector3d(0, 0, -error_deg * kDeg)) * R_true;
		ManifoldUkf ukf = pt::filterAt(prior, headingCovariance(180 * kDeg));
		tc.ctx().mean = &ukf.state();
		for (int k = 0; k < 20; ++k)
		{
			std::vector<Measurement> out;
			std::string why;
			ASSERT_EQ(model.prepare(*magObs(reading(R_true)), tc.ctx(), out, why), PrepareStatus::Ok) << why;
			ukf.update(model, out[0], tc.ctx(), /*recovery=*/true);
		}
		const double err = wrapAngle(pt::headingOf(ukf.state().R_nb) - pt::headingOf(R_true));
		const double sigma = std::sqrt(ukf.covariance()(2, 2));
		EXPECT_LE(std::abs(err), 3 * sigma)
		    << error_deg << ": " << err / kDeg << " deg off with sigma " << sigma / kDeg;
	}
}

TEST(MagnetometerStates, HeadingBiasAddsToTheHeadingAndIsDeclared)
{
	at::TestContext tc;
	MagnetometerModel plain(pt::defaultConfig(), "MAG");
	EXPECT_EQ(at::PluginStateBench(plain).extraSize(), 0);
	EXPECT_EQ(plain.uses(), uint32_t(kAttitude));
	MagnetometerModel model(pt::configText("states: {heading_bias: {sigma_deg: 4, process: gauss_markov, "
	                                       "process_sigma_deg: 4, tau_s: 120}}"),
	                        "MAG");
	const at::PluginStateBench bench(model, 1, "MAG");
	const PluginState& bias = bench["heading_bias"];
	EXPECT_EQ(bench.layout.tangent_names.back(), "MAG.heading_bias");
	EXPECT_EQ(bias.spec().process, StateProcess::GaussMarkov);
	EXPECT_NEAR(bias.spec().process_sigma, 4 * kDeg, 1e-15);
	EXPECT_DOUBLE_EQ(bias.spec().tau_s, 120);
	EXPECT_EQ(model.uses(), uint32_t(kAttitude | kPluginStates));
	for (uint32_t seed = 1; seed <= 5; ++seed)
	{
		NavState x = bench.randomState(seed);
		bias.value(x) = 3 * kDeg;
		tc.ctx().mean = &x;
		const Measurement m = pt::prepareOne(model, *magObs(reading(x.R_nb)), tc.ctx());
		const Measurement mp = pt::prepareOne(plain, *magObs(reading(x.R_nb)), tc.ctx());
		EXPECT_NEAR(wrapAngle(at::Predict(model, m, tc.ctx(), x)[0] - at::Predict(plain, mp, tc.ctx(), x)[0]),
		            3 * kDeg, 1e-12);
		EXPECT_TRUE(pt::IsWellFormedAndUsed(model, *magObs(reading(x.R_nb)), tc.ctx(), x, seed)) << seed;
		// The bias block missing from the state: h refuses instead of reading past the end.
		const NavState short_state = at::RandomNavState(seed, 1);
		EXPECT_TRUE(std::isnan(at::Predict(model, m, tc.ctx(), short_state)[0]));
	}
	tc.ctx().mean = nullptr;
	EXPECT_THROW(
	    MagnetometerModel(pt::configText("mode: vector\nstates: {heading_bias: {sigma_deg: 4}}"), "MAG"),
	    config::ConfigError);
	EXPECT_THROW(MagnetometerModel(pt::configText("states: {hard_iron: {sigma: 4}}"), "MAG"),
	             config::ConfigError);
}
