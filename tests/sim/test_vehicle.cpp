// The simulator's vehicle dynamics against analytic steady states.
#include <gtest/gtest.h>

#include <cmath>

#include "sim_test_config.h"
#include "vehicle.h"

using namespace auvnav::sim;

namespace
{
/** Runs `seconds` of dynamics at 100 Hz with constant commands, level, deep. */
VehicleState runConstant(const Vehicle& v, const Eigen::VectorXd& cmd, double seconds,
                         const Eigen::Vector3d& current_n = Eigen::Vector3d::Zero())
{
	VehicleState x;
	x.p_n = {0, 0, 50};  // deep: fully wetted hull
	x.thrust_n = Eigen::VectorXd::Zero(cmd.size());
	for (int k = 0; k < static_cast<int>(seconds * 100); ++k) v.step(x, cmd, current_n, 0.01);
	return x;
}

VehicleParams unitVehicle()
{
	// Analytic oracle of rock-control/control-uwv_dynamic_model test_calc.cpp:
	// unit inertia, unit linear and quadratic damping, 2 N => 1 m/s.
	VehicleParams p;
	p.M = Matrix6d::Identity();
	p.D_l = Matrix6d::Identity();
	p.D_q = Matrix6d::Identity();
	p.weight_n = p.buoyancy_n = 9.80665;
	p.mass_kg = 1.0;
	Thruster t;
	t.position_b = {0, 0, 0};
	t.direction_b = {1, 0, 0};
	t.max_force_n = 10;
	t.time_constant_s = 0.1;
	p.thrusters = {t};
	return p;
}
}  // namespace

TEST(Vehicle, UnitModelTwoNewtonsGiveOneMetrePerSecond)
{
	const Vehicle v(unitVehicle());
	const VehicleState x = runConstant(v, Eigen::VectorXd::Constant(1, 2.0), 60);
	EXPECT_NEAR(x.nu_b[0], 1.0, 1e-6);
	EXPECT_NEAR(x.nu_b[1], 0.0, 1e-9);
	EXPECT_NEAR(x.nu_b[2], 0.0, 1e-9);
	EXPECT_NEAR(x.p_n.z(), 50.0, 1e-9);  // neutral: no sinking
}

TEST(Vehicle, FlatFishSteadySurgeMatchesDampingBalance)
{
	VehicleParams p = VehicleParams::fromConfig(test::repoVehicle());
	p.tether_enabled = false;
	p.weight_n = p.buoyancy_n;  // neutral, so no heave/pitch transients
	for (auto& t : p.thrusters) t.efficiency_forward = t.efficiency_reverse = 1.0;
	// Open loop, the FlatFish is directionally unstable (low sway damping, no
	// linear yaw damping, Munk moment): any yaw or pitch moment makes it turn.
	// Place the two surge thrusters symmetrically in the CG's horizontal plane
	// so the run stays pure surge and checks the surge balance alone.
	p.thrusters[0].position_b = {-0.9, 0.4, 0.0};
	p.thrusters[1].position_b = {-0.9, -0.4, 0.0};
	const Vehicle v(p);
	Eigen::VectorXd cmd = Eigen::VectorXd::Zero(6);
	cmd[0] = cmd[1] = 20.0;
	const VehicleState x = runConstant(v, cmd, 300);
	const double F = 40.0, dl = 39.57, dq = 8.62;
	const double u_expected = (-dl + std::sqrt(dl * dl + 4 * dq * F)) / (2 * dq);
	EXPECT_NEAR(x.nu_b[0], u_expected, 1e-4 * u_expected);
	EXPECT_NEAR(x.nu_b[1], 0.0, 1e-3);
	EXPECT_NEAR(x.nu_b[5], 0.0, 1e-4);
}

TEST(Vehicle, SteadySpeedThroughWaterIsCurrentIndependent)
{
	const Vehicle v(unitVehicle());
	const Eigen::Vector3d current(0.3, 0, 0);
	const VehicleState x = runConstant(v, Eigen::VectorXd::Constant(1, 2.0), 60, current);
	EXPECT_NEAR(x.nu_b[0] - 0.3, 1.0, 1e-5);  // over ground = through water + current
}

TEST(Vehicle, ThrusterSaturatesAndLags)
{
	VehicleParams p = unitVehicle();
	p.thrusters[0].max_force_n = 1.0;
	p.thrusters[0].time_constant_s = 0.5;
	const Vehicle v(p);
	EXPECT_DOUBLE_EQ(v.steadyThrust(Eigen::VectorXd::Constant(1, 5.0))[0], 1.0);
	VehicleState x;
	x.p_n = {0, 0, 50};
	x.thrust_n = Eigen::VectorXd::Zero(1);
	for (int k = 0; k < 50; ++k) v.step(x, Eigen::VectorXd::Constant(1, 1.0), Eigen::Vector3d::Zero(), 0.01);
	// First-order lag: 1 − e^{−t/τ} at t = τ.
	EXPECT_NEAR(x.thrust_n[0], 1 - std::exp(-1.0), 1e-6);
}

TEST(Vehicle, RestoringMomentRightsAHeeledVehicle)
{
	VehicleParams p = VehicleParams::fromConfig(test::repoVehicle());
	const Vehicle v(p);
	const double roll = 10 * M_PI / 180;
	const Eigen::Matrix3d R = Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix();
	const Vector6d g = v.restoring(R, 20.0);
	// g is subtracted in the equation: positive roll => g_roll > 0 (moment pushes back).
	const double expected = p.buoyancy_n * std::abs(p.r_b_b.z()) * std::sin(roll);
	EXPECT_NEAR(g[3], expected, 1e-9);
	// Net vertical force in body: (W − B) projected, independent of the sign convention check above.
	EXPECT_NEAR(-g.head<3>().dot(R.transpose() * Eigen::Vector3d::UnitZ()), p.weight_n - p.buoyancy_n, 1e-9);
}

TEST(Vehicle, FloatsAtTheSurfaceWithPartialBuoyancy)
{
	VehicleParams p = VehicleParams::fromConfig(test::repoVehicle());
	const Vehicle v(p);
	VehicleState x;
	x.p_n = {0, 0, 1.0};
	x.thrust_n = Eigen::VectorXd::Zero(6);
	for (int k = 0; k < 12000; ++k) v.step(x, Eigen::VectorXd::Zero(6), Eigen::Vector3d::Zero(), 0.01);
	// Equilibrium: wetted fraction W/B of the hull => CG depth = h (W/B − 1/2).
	const double expected = p.hull_height_m * (p.weight_n / p.buoyancy_n - 0.5);
	EXPECT_NEAR(x.p_n.z(), expected, 0.005);
}

TEST(Vehicle, ConfigurationMatrixColumnsAreForceAndMoment)
{
	const VehicleParams p = VehicleParams::fromConfig(test::repoVehicle());
	const auto T = p.configurationMatrix();
	ASSERT_EQ(T.cols(), 6);
	// heave_front at (0.461, 0.019, 0) pushing down (+z): moment r × F = (0.019, −0.461, 0).
	EXPECT_NEAR(T(2, 4), 1.0, 1e-12);
	EXPECT_NEAR(T(3, 4), 0.019, 1e-12);
	EXPECT_NEAR(T(4, 4), -0.461, 1e-12);
	// Rank 5: with two heave thrusters roll and pitch cannot be set
	// independently; dropping the roll row leaves a full-rank 5 x 6 matrix.
	Eigen::FullPivLU<Eigen::MatrixXd> lu(T);
	EXPECT_EQ(lu.rank(), 5);
	Eigen::MatrixXd no_roll(5, 6);
	no_roll << T.row(0), T.row(1), T.row(2), T.row(4), T.row(5);
	EXPECT_EQ(Eigen::FullPivLU<Eigen::MatrixXd>(no_roll).rank(), 5);
}
