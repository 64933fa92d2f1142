// Model-aiding plugin: the measurement function against hand-computed cases,
// restoring forces, thrust wrench, positivity of parameters, and the update.
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/so3.h>
#include <auvnav/testing/model_checks.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <cmath>

#include "model_aiding.h"
#include "plugin_test_support.h"

using namespace auvnav::plugins;

namespace
{
VehicleModel unitModel()
{
	VehicleModel vm;
	vm.M = Matrix6d::Identity();
	vm.D_l = Matrix6d::Identity();
	vm.D_q = Matrix6d::Identity();
	vm.weight_n = vm.buoyancy_n = 10.0;
	return vm;
}

NavState unitState()
{
	NavState x;
	// Estimated sub-blocks equal to the unit model (stored: ln 1 = 0 on the diagonal).
	x.M_sub = storedSub(
	    Eigen::Matrix<double, 2, 3>((Eigen::Matrix<double, 2, 3>() << 1, 0, 0, 0, 1, 0).finished()));
	x.Dl_sub = x.M_sub;
	x.Dq_sub = x.M_sub;
	return x;
}

auvnav::obs::CObservationThrusters::Ptr thrusters(const std::vector<double>& e)
{
	auto o = auvnav::obs::CObservationThrusters::Create();
	o->sensorLabel = "THRUSTERS";
	o->effort = e;
	return o;
}
}  // namespace

TEST(ModelAiding, UnitModelAtOneMetrePerSecondNeedsTwoNewtons)
{
	// Analytic oracle (rock-control/control-uwv_dynamic_model test_calc.cpp):
	// unit M, D_l, D_q at steady 1 m/s surge: thrust 1·1 + 1·1² = 2 N.
	NavState x = unitState();
	x.v_n = {1, 0, 0};
	const Vector6d w = predictedWrench(unitModel(), x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
	                                   Eigen::Vector3d::Zero());
	EXPECT_NEAR(w[0], 2.0, 1e-12);
	EXPECT_NEAR(w.tail<5>().norm(), 0.0, 1e-12);
	// Heading 90° and the water moving with the vehicle at 0.4 m/s: 0.6 m/s
	// through the water: 0.6 + 0.36.
	x.R_nb = so3::Exp(Eigen::Vector3d(0, 0, M_PI / 2));
	x.v_n = {0, 1, 0};
	x.current_vehicle_ne = {0, 0.4};
	const Vector6d w2 = predictedWrench(unitModel(), x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
	                                    Eigen::Vector3d::Zero());
	EXPECT_NEAR(w2[0], 0.96, 1e-12);
	// Accelerating at 0.5 m/s² adds M·a.
	x.a_n = {0, 0.5, 0};
	EXPECT_NEAR(predictedWrench(unitModel(), x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
	                            Eigen::Vector3d::Zero())[0],
	            1.46, 1e-12);
}

TEST(ModelAiding, AngularAccelerationAndLeverArmEnter)
{
	NavState x = unitState();
	const Eigen::Vector3d alpha(0, 0, 0.2), r_imu(0.5, 0, 0);
	const Vector6d w = predictedWrench(unitModel(), x, Eigen::Vector3d::Zero(), alpha, r_imu);
	EXPECT_NEAR(w[5], 0.2, 1e-12);  // M_ψψ α
	// a_CG = a_IMU − α × r = −(0,0,0.2)×(0.5,0,0) = (0, −0.1, 0): sway force −0.1 N.
	EXPECT_NEAR(w[1], -0.1, 1e-12);
}

TEST(ModelAiding, RestoringForcesAtRollAndPitch)
{
	VehicleModel vm = unitModel();
	vm.weight_n = 2800;
	vm.buoyancy_n = 2812;
	vm.r_b_b = {0, 0, -0.05};
	const double roll = 20 * M_PI / 180, pitch = -10 * M_PI / 180;
	const Eigen::Matrix3d R = (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
	                           Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
	                              .toRotationMatrix();
	const Vector6d g = restoringWrench(vm, R);
	// Net buoyancy 12 N up in NED, expressed in the body: −(W − B) Rᵀk = 12 Rᵀk.
	const Eigen::Vector3d k_b = R.transpose() * Eigen::Vector3d::UnitZ();
	EXPECT_TRUE(g.head<3>().isApprox(12.0 * k_b, 1e-12));
	EXPECT_NEAR(k_b.x(), -std::sin(pitch), 1e-12);
	// Moment: r_B × (−B k_b) is what buoyancy applies; g holds its negative:
	// roll moment B·0.05·sin(roll)·cos(pitch), pitch moment B·0.05·sin(pitch).
	EXPECT_NEAR(g[3], 2812 * 0.05 * std::sin(roll) * std::cos(pitch), 1e-9);
	EXPECT_NEAR(g[4], 2812 * 0.05 * std::sin(pitch), 1e-9);
	EXPECT_NEAR(g[5], 0.0, 1e-12);
}

TEST(ModelAiding, ThrustWrenchThroughTheConfigurationMatrix)
{
	const ModelAidingModel m(pt::defaultConfig(), "THRUSTERS");
	// Both surge thrusters forward 10 N: Fx 20 N, My from their 0.137 m depth,
	// Mz from their asymmetric arms (−0.438 + 0.398)·10.
	const Vector6d w = m.thrustWrench({10, 10, 0, 0, 0, 0});
	EXPECT_NEAR(w[0], 20.0, 1e-12);
	EXPECT_NEAR(w[4], 2 * 0.137 * 10, 1e-12);
	EXPECT_NEAR(w[5], (-0.438 + 0.398) * 10, 1e-12);
	// Reverse efforts use gain_reverse (0.8).
	EXPECT_NEAR(m.thrustWrench({-10, -10, 0, 0, 0, 0})[0], -16.0, 1e-12);
}

TEST(ModelAiding, ParametersStayPositiveUnderLargeUpdates)
{
	NavState x = unitState();
	x.Dl_sub(0, 0) = -50.0;  // a huge negative excursion of the stored (log) value
	x.v_n = {1, 0, 0};
	const Vector6d w = predictedWrench(unitModel(), x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
	                                   Eigen::Vector3d::Zero());
	EXPECT_GT(physicalSub(x.Dl_sub)(0, 0), 0.0);
	EXPECT_NEAR(w[0], 1.0 + std::exp(-50.0), 1e-12);  // damping ≥ the quadratic term alone
}

TEST(ModelAiding, WellFormedAndRefusesBadObservations)
{
	ModelAidingModel m(pt::defaultConfig(), "THRUSTERS");
	at::TestContext tc;
	for (unsigned seed = 1; seed <= 5; ++seed)
	{
		NavState x = at::RandomNavState(seed);
		x.M_sub = storedSub((Eigen::Matrix<double, 2, 3>() << 851, 0, 0, 0, 1043, 0).finished());
		EXPECT_TRUE(at::IsWellFormed(m, *thrusters({20, 18, -5, 4, 10, 9}), tc.ctx(), x));
	}
	std::vector<Measurement> out;
	std::string why;
	EXPECT_EQ(m.prepare(*thrusters({1, 2, 3}), tc.ctx(), out, why), PrepareStatus::Invalid);
	EXPECT_NE(why.find("3 thrusters"), std::string::npos);
	EXPECT_EQ(m.prepare(*thrusters({1, 2, 3, 4, 5, NAN}), tc.ctx(), out, why), PrepareStatus::Invalid);
}

TEST(ModelAiding, SurfaceInflatesTheNoise)
{
	ModelAidingModel m(pt::defaultConfig(), "THRUSTERS");
	at::TestContext tc;
	NavState deep, shallow;
	deep.p_n.z() = 10;
	shallow.p_n.z() = 0.3;
	FilterContext c = tc.ctx();
	std::vector<Measurement> out;
	std::string why;
	c.mean = &deep;
	ASSERT_EQ(m.prepare(*thrusters({10, 10, 0, 0, 0, 0}), c, out, why), PrepareStatus::Ok);
	const double r_deep = out[0].R(0, 0);
	c.mean = &shallow;
	ASSERT_EQ(m.prepare(*thrusters({10, 10, 0, 0, 0, 0}), c, out, why), PrepareStatus::Ok);
	EXPECT_NEAR(out[0].R(0, 0), 100.0 * r_deep, 1e-9);  // factor 10 on sigma
}

TEST(ModelAiding, UpdatePullsTheCurrentAndDampingTheRightWay)
{
	// Truth: 0.5 m/s through still water; the filter believes a 0.3 m/s current
	// along the track. The thrust for 0.5 m/s through the water must pull the
	// current estimate toward zero. (Symmetric thruster gains, so that the
	// least-squares efforts reproduce the wrench exactly; horizontal DOFs only:
	// two heave thrusters cannot set roll and pitch independently.)
	std::string text = pt::defaultConfigText();
	for (std::size_t pos; (pos = text.find("gain_reverse: 0.8")) != std::string::npos;)
		text.replace(pos, 17, "gain_reverse: 1.0");
	ASSERT_NE(text.find("\ndofs: [0, 1, 5]\n"), std::string::npos);  // the default: surge, sway, yaw
	ModelAidingModel m(pt::configText(text), "THRUSTERS");
	at::TestContext tc;
	NavState truth;
	truth.v_n = {0.5, 0, 0};
	truth.M_sub = storedSub((Eigen::Matrix<double, 2, 3>() << 851, 0, 0, 0, 1042.95, 0).finished());
	truth.Dl_sub = storedSub((Eigen::Matrix<double, 2, 3>() << 39.57, 0, 0, 0, 1.4554, 0).finished());
	truth.Dq_sub = storedSub((Eigen::Matrix<double, 2, 3>() << 8.62, 0, 0, 0, 5, 0).finished());
	truth.p_n.z() = 10;
	truth.g = 9.78;
	const Vector6d tau = predictedWrench(m.vehicle(), truth, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
	                                     tc.ctx().imu_position_b);
	// Efforts that produce exactly that surge/sway/yaw wrench (least squares).
	const auto& T = m.configurationMatrix();
	Eigen::MatrixXd T3(3, T.cols());
	T3 << T.row(0), T.row(1), T.row(5);
	const Eigen::VectorXd u =
	    T3.completeOrthogonalDecomposition().solve(Eigen::Vector3d(tau[0], tau[1], tau[5]));
	const Vector6d achieved = m.thrustWrench(std::vector<double>(u.data(), u.data() + u.size()));
	ASSERT_NEAR(achieved[0], tau[0], 1e-9);
	ASSERT_NEAR(achieved[5], tau[5], 1e-9);
	NavState start = truth;
	start.current_vehicle_ne = {0.3, 0.0};
	Covariance P = at::TypicalCovariance();
	P.block<2, 2>(idx::current_vehicle, idx::current_vehicle) = 0.04 * Eigen::Matrix2d::Identity();
	// Velocity over ground known (as with DVL lock), acceleration pinned (as by
	// the accelerometer), parameters to 5 %: the wrench can then only be
	// explained by the water moving differently.
	P.block<3, 3>(idx::vel, idx::vel) = 1e-4 * Eigen::Matrix3d::Identity();
	P.block<3, 3>(idx::acc, idx::acc) = 1e-6 * Eigen::Matrix3d::Identity();
	P.block<18, 18>(idx::inertia, idx::inertia) = 0.0025 * Eigen::Matrix<double, 18, 18>::Identity();
	ManifoldUkf ukf(ProcessModel{}, UtParams{});
	ukf.initialize(start, P);
	FilterContext c = tc.ctx();
	c.mean = &ukf.state();
	c.omega_ib_b = truth.R_nb.transpose() * c.omega_ie_n;  // at rest relative to the Earth in rotation
	const auto res =
	    at::ApplyObservation(ukf, m, *thrusters(std::vector<double>(u.data(), u.data() + u.size())), c);
	ASSERT_EQ(res.updates.size(), 1u);
	ASSERT_EQ(res.updates[0].status, UpdateStatus::Accepted);
	EXPECT_LT(std::abs(ukf.state().current_vehicle_ne.x()), 0.3 * 0.5);
}

namespace
{
/** FlatFish-like inertia (surge 851, sway 1042.95 kg), no damping or restoring. */
VehicleModel munkModel()
{
	VehicleModel vm;
	vm.M = Eigen::Matrix<double, 6, 1>(851, 1042.95, 1516.78, 12, 14, 422.367).asDiagonal();
	vm.weight_n = vm.buoyancy_n = 2800;
	return vm;
}
NavState stateWithModel(const VehicleModel& vm)
{
	NavState x;
	Eigen::Matrix<double, 2, 3> M_sub = vm.M.topLeftCorner<2, 3>();
	x.M_sub = storedSub(M_sub);
	x.Dl_sub = storedSub(
	    Eigen::Matrix<double, 2, 3>((Eigen::Matrix<double, 2, 3>() << 1, 0, 0, 0, 1, 0).finished()));
	x.Dq_sub = x.Dl_sub;
	return x;
}
}  // namespace

TEST(ModelAiding, CoriolisTermCarriesTheMunkMoment)
{
	VehicleModel vm = munkModel();
	vm.D_l.setZero();
	vm.D_q.setZero();
	NavState x = stateWithModel(vm);
	x.Dl_sub = storedSub(
	    Eigen::Matrix<double, 2, 3>((Eigen::Matrix<double, 2, 3>() << 1e-12, 0, 0, 0, 1e-12, 0).finished()));
	x.Dq_sub = x.Dl_sub;
	x.v_n = {0.4, 0.1, 0};  // surge 0.4, sway 0.1 m/s, level, heading north, still water
	const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
	// Hand computation: moment = v × (M v), z = u·M_yy·v − v·M_xx·u = (1042.95 − 851)·0.04.
	const Vector6d w = predictedWrench(vm, x, zero, zero, zero);
	EXPECT_NEAR(w[5], (1042.95 - 851) * 0.4 * 0.1, 1e-9);
	EXPECT_NEAR(w.head<5>().norm(), 0.0, 1e-9);
	vm.coriolis = false;  // the paper's form has none
	EXPECT_NEAR(predictedWrench(vm, x, zero, zero, zero).norm(), 0.0, 1e-9);
}

TEST(ModelAiding, CoriolisFormEqualsInertialAccelerationFormForIsotropicMass)
{
	// M = m·I, J = j·I: ν̇_r + C(ν_r)ν_r reduces to m·a_b (a steady turn needs
	// exactly the centripetal force), so both forms must agree.
	VehicleModel vm;
	vm.M = Eigen::Matrix<double, 6, 1>(300, 300, 300, 40, 40, 40).asDiagonal();
	vm.D_l = Eigen::Matrix<double, 6, 1>(20, 20, 20, 5, 5, 5).asDiagonal();
	vm.D_q = Eigen::Matrix<double, 6, 1>(8, 8, 8, 2, 2, 2).asDiagonal();
	vm.weight_n = vm.buoyancy_n = 2800;
	NavState x;
	x.M_sub = storedSub(vm.M.topLeftCorner<2, 3>().eval());
	x.Dl_sub = storedSub(vm.D_l.topLeftCorner<2, 3>().eval());
	x.Dq_sub = storedSub(vm.D_q.topLeftCorner<2, 3>().eval());
	x.R_nb = so3::Exp(Eigen::Vector3d(0.05, -0.03, 1.2));
	x.v_n = {0.3, -0.2, 0.05};
	x.a_n = {0.01, 0.02, -0.003};
	x.current_vehicle_ne = {0.1, -0.05};
	const Eigen::Vector3d omega(0.01, -0.02, 0.15), alpha(0.001, 0.0, -0.002), r_imu(0.3, 0.0, -0.03);
	const Vector6d with = predictedWrench(vm, x, omega, alpha, r_imu);
	vm.coriolis = false;
	const Vector6d without = predictedWrench(vm, x, omega, alpha, r_imu);
	EXPECT_LT((with - without).norm(), 1e-10) << (with - without).transpose();
	// ... and they differ once the surge and sway inertia differ.
	VehicleModel aniso = vm;
	aniso.coriolis = true;
	aniso.M(1, 1) = 400;
	x.M_sub = storedSub(aniso.M.topLeftCorner<2, 3>().eval());
	aniso.coriolis = false;
	const Vector6d a_off = predictedWrench(aniso, x, omega, alpha, r_imu);
	aniso.coriolis = true;
	EXPECT_GT((predictedWrench(aniso, x, omega, alpha, r_imu) - a_off).norm(), 1e-3);
}

TEST(ModelAiding, DiagonalWrenchEqualsTheGeneralOne)
{
	// The plugin evaluates predictedWrenchDiagonal (its configured matrices
	// are diagonal): the same wrench as the general form on random states,
	// with and without the Coriolis term.
	VehicleModel vm;
	vm.M = Eigen::Matrix<double, 6, 1>(851, 1042.95, 1200, 150, 160, 170).asDiagonal();
	vm.D_l = Eigen::Matrix<double, 6, 1>(20, 30, 40, 5, 6, 7).asDiagonal();
	vm.D_q = Eigen::Matrix<double, 6, 1>(8, 9, 10, 2, 3, 4).asDiagonal();
	vm.weight_n = 2800;
	vm.buoyancy_n = 2810;
	vm.r_g_b = {0.01, -0.02, 0.05};
	vm.r_b_b = {0.0, 0.01, -0.03};
	int compared = 0;
	for (bool coriolis : {true, false})
		for (uint32_t seed = 1; seed <= 20; ++seed)
		{
			vm.coriolis = coriolis;
			const NavState x = at::RandomNavState(seed);
			const Eigen::Vector3d omega(0.01 * seed, -0.02, 0.15), alpha(0.001, 0.002 * seed, -0.002),
			    r_imu(0.3, 0.1, -0.03);
			const Vector6d general = predictedWrench(vm, x, omega, alpha, r_imu);
			const Vector6d diagonal = predictedWrenchDiagonal(vm, x, omega, alpha, r_imu);
			ASSERT_TRUE(general.allFinite());
			EXPECT_LE((general - diagonal).cwiseAbs().maxCoeff(), 1e-12 * (1 + general.cwiseAbs().maxCoeff()))
			    << "seed " << seed << ": " << general.transpose() << " vs " << diagonal.transpose();
			// The random sub-blocks are full (every placed entry matters).
			EXPECT_NE(x.M_sub(0, 2), 0.0);
			++compared;
		}
	EXPECT_EQ(compared, 40);
}

TEST(ThrustResponse, FollowsAHeldCommandWithItsTimeConstant)
{
	ThrustResponse r({0.2, 0.0});
	r.restart(10.0, Eigen::Vector2d(0, 0));
	r.hold(10.0, Eigen::Vector2d(10, -4));
	// Lagged thruster: 10 (1 − e^{−t/τ}); the one without a lag at once.
	EXPECT_NEAR(r.forceAt(10.2)[0], 10 * (1 - std::exp(-1.0)), 1e-12);
	EXPECT_NEAR(r.forceAt(10.2)[1], -4.0, 1e-12);
	EXPECT_NEAR(r.rateAt(10.2)[0], 10 * std::exp(-1.0) / 0.2, 1e-9);
	EXPECT_EQ(r.rateAt(10.2)[1], 0.0);
	// Before the command's time the force is the one it started from.
	EXPECT_EQ(r.forceAt(9.0)[0], 0.0);
	// A new command continues from where the response is.
	r.hold(10.1, Eigen::Vector2d(0, 0));
	const double f_at_switch = 10 * (1 - std::exp(-0.5));
	EXPECT_NEAR(r.forceAt(10.3)[0], f_at_switch * std::exp(-1.0), 1e-12);
}

namespace
{
/** The plugin's default configuration with every thruster lagged by
 *  `tau_s` and time_constant_sigma_s set. */
ModelAidingModel laggedModel(double tau_s, double tau_sigma_s)
{
	std::string yaml = pt::defaultConfigText();
	const auto set = [&](const std::string& from, const std::string& to)
	{
		for (std::size_t at = yaml.find(from); at != std::string::npos; at = yaml.find(from, at + to.size()))
			yaml.replace(at, from.size(), to);
	};
	set("gain_reverse: 0.8}", "gain_reverse: 0.8, time_constant_s: " + std::to_string(tau_s) + "}");
	set("\ntime_constant_sigma_s: 0\n", "\ntime_constant_sigma_s: " + std::to_string(tau_sigma_s) + "\n");
	return ModelAidingModel(pt::configText(yaml), "THRUSTERS");
}

/** Prepares thruster efforts logged at t_s with the filter at t_s − 0.01
 *  and its angular acceleration `alpha_delay_s` late. */
PrepareStatus prepareAt(ModelAidingModel& m, const std::vector<double>& effort, double t_s,
                        std::vector<Measurement>& out, double alpha_delay_s = 0)
{
	at::TestContext tc;
	FilterContext c = tc.ctx();
	c.t_measurement_s = t_s;
	c.t_s = t_s - 0.01;
	c.alpha_delay_s = alpha_delay_s;
	std::string why;
	return m.prepare(*thrusters(effort), c, out, why);
}
}  // namespace

TEST(ModelAiding, LaggedThrustIsTheResponseToEarlierCommands)
{
	ModelAidingModel m = laggedModel(0.15, 0);
	const double alpha_delay_s = 0.05;
	std::vector<Measurement> out;
	const std::vector<double> idle(6, 0.0), surge{10, 10, 0, 0, 0, 0};
	// The first command only starts the response.
	EXPECT_EQ(prepareAt(m, idle, 100.0, out, alpha_delay_s), PrepareStatus::Skip);
	// The step logged at 100.08 has not acted yet: the wrench is still idle.
	ASSERT_EQ(prepareAt(m, surge, 100.08, out, alpha_delay_s), PrepareStatus::Ok);
	EXPECT_NEAR(out[0].z[0], 0.0, 1e-12);
	// At 100.16 the step has acted for 0.16 − 0.01 − 0.05 − 0.08 = 0.02 s.
	ASSERT_EQ(prepareAt(m, surge, 100.16, out, alpha_delay_s), PrepareStatus::Ok);
	EXPECT_NEAR(out[0].z[0], 20 * (1 - std::exp(-0.02 / 0.15)), 1e-9);
	// Commands too far apart (> 1 s) start the response over.
	EXPECT_EQ(prepareAt(m, surge, 102.0, out), PrepareStatus::Skip);
	EXPECT_EQ(prepareAt(m, surge, 101.5, out), PrepareStatus::Skip);  // time went back
}

TEST(ModelAiding, TimeConstantUncertaintyWidensTheNoiseWhileThrustChanges)
{
	ModelAidingModel sure = laggedModel(0.15, 0), unsure = laggedModel(0.15, 0.05);
	std::vector<Measurement> a, b;
	const std::vector<double> idle(6, 0.0), surge{10, 10, 0, 0, 0, 0};
	for (ModelAidingModel* m : {&sure, &unsure})
	{
		std::vector<Measurement>& out = m == &sure ? a : b;
		prepareAt(*m, idle, 100.0, out);
		prepareAt(*m, surge, 100.08, out);
		ASSERT_EQ(prepareAt(*m, surge, 100.16, out), PrepareStatus::Ok);
	}
	// At 100.15 the step of 100.08 has acted 0.07 s: surge force rate
	// 20 e^{−0.07/0.15}/0.15 N/s (dofs x, y, ψ: row 0).
	const double rate = 20 * std::exp(-0.07 / 0.15) / 0.15;
	EXPECT_NEAR(b[0].R(0, 0) - a[0].R(0, 0), std::pow(0.05 * rate, 2), 1e-9);
	// Once settled the two agree.
	for (double t = 100.24; t < 102; t += 0.08)
	{
		prepareAt(sure, surge, t, a);
		prepareAt(unsure, surge, t, b);
	}
	EXPECT_NEAR(b[0].R(0, 0), a[0].R(0, 0), 1e-9);
}
