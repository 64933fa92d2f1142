// The process model against analytic motion: constant body rate, Earth rate
// only, constant acceleration, Gauss–Markov decay (mean and, through the UKF,
// variance) independent of the step size, and process noise linear in dt.
#include <auvnav/process_model.h>
#include <auvnav/so3.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>

#include "filter_test_util.h"

using namespace auvnav;
using auvnav::test::kDeg;

namespace
{
double maxAbs(const Eigen::Matrix3d& A)
{
	return A.cwiseAbs().maxCoeff();
}

/** Propagates `steps` times by T/steps with constant inputs. */
NavState propagateFor(const ProcessModel& pm, NavState x, const Eigen::Vector3d& w_ib_b,
                      const Eigen::Vector3d& w_ie_n, double T, int steps)
{
	const double dt = T / steps;
	for (int i = 0; i < steps; ++i) x = pm.propagate(x, w_ib_b, w_ie_n, dt);
	return x;
}

/** Gauss–Markov coordinates (tangent indices), their σ and τ in `pm`. */
struct GmCoord
{
	int index;
	double sigma, tau;
};
std::vector<GmCoord> gaussMarkovCoordinates(const ProcessModel& pm)
{
	std::vector<GmCoord> c;
	const auto& n = pm.noise;
	for (int i = 0; i < 3; ++i) c.push_back({idx::gyro_bias + i, n.gyro_bias.sigma, n.gyro_bias.tau_s});
	for (int i = 0; i < 3; ++i) c.push_back({idx::acc_bias + i, n.accel_bias.sigma, n.accel_bias.tau_s});
	for (int i = 0; i < 4; ++i) c.push_back({idx::current_vehicle + i, n.current.sigma, n.current.tau_s});
	for (int i = 0; i < 2; ++i) c.push_back({idx::adcp_bias + i, n.adcp_bias.sigma, n.adcp_bias.tau_s});
	for (int i = 0; i < 18; ++i) c.push_back({idx::inertia + i, n.parameter_sigma[i], n.parameter_tau_s});
	return c;
}

ProcessModel fastGaussMarkovModel()
{
	ProcessModel pm = test::makeProcessModel();
	// Short correlation times so that a 50 s run decays visibly.
	pm.noise.gyro_bias.tau_s = 30;
	pm.noise.accel_bias.tau_s = 40;
	pm.noise.current.tau_s = 60;
	pm.noise.adcp_bias.tau_s = 80;
	pm.noise.parameter_tau_s = 100;
	// No spatial current noise: it depends on the (changing) speed through the
	// water and is not part of the Gauss–Markov discretisation.
	pm.noise.current_spatial_var_per_m = 0;
	pm.noise.current_vertical_var_per_m = 0;
	pm.current_far_distance_m = 0;  // no transport along the profile either
	return pm;
}

}  // namespace

TEST(ProcessModel, ConstantBodyRateAboutATiltedAxis)
{
	ProcessModel pm = test::makeProcessModel();
	NavState x = test::makeState(35 * kDeg);
	x.b_w.setZero();
	pm.prior_mean.segment<3>(idx::gyro_bias).setZero();  // zero bias stays zero
	const Eigen::Vector3d w = 0.4 * Eigen::Vector3d(1, 2, -1.5).normalized();
	const double T = 10;  // 4 rad about the axis
	const NavState y = propagateFor(pm, x, w, Eigen::Vector3d::Zero(), T, 1000);
	const Eigen::Matrix3d expected = x.R_nb * so3::Exp(w * T);
	EXPECT_LT(maxAbs(y.R_nb - expected), 1e-9);
	std::printf("constant rate, 10 s at 100 Hz: |R - R0 Exp(wT)| = %.2e\n", maxAbs(y.R_nb - expected));

	// The same with a constant gyro bias (held by its Gauss–Markov mean): the
	// bias is subtracted from the raw rate.
	const Eigen::Vector3d b(0.01, -0.02, 0.005);
	x.b_w = b;
	pm.prior_mean.segment<3>(idx::gyro_bias) = b;
	const NavState yb = propagateFor(pm, x, w + b, Eigen::Vector3d::Zero(), T, 1000);
	EXPECT_LT(maxAbs(yb.R_nb - expected), 1e-9);
	EXPECT_LT((yb.b_w - b).norm(), 1e-15);
}

TEST(ProcessModel, VehicleFixedToTheEarthKeepsItsAttitudeForAnHour)
{
	ProcessModel pm = test::makeProcessModel();
	pm.prior_mean.segment<3>(idx::gyro_bias).setZero();
	NavState x = test::makeState(-70 * kDeg);
	x.b_w.setZero();
	const double lat = -33 * kDeg, omega = 7.292115e-5;
	const Eigen::Vector3d w_ie_n(omega * std::cos(lat), 0, -omega * std::sin(lat));
	const Eigen::Vector3d w_ib_b = x.R_nb.transpose() * w_ie_n;  // the gyro sees only the Earth turning

	// 1 h at 100 Hz, re-orthonormalised every step as the filter does with its mean.
	NavState y = x, raw = x;
	for (int i = 0; i < 360000; ++i)
	{
		y = pm.propagate(y, w_ib_b, w_ie_n, 0.01);
		y.R_nb = so3::normalized(y.R_nb);
		raw = pm.propagate(raw, w_ib_b, w_ie_n, 0.01);
	}
	std::printf(
	    "Earth rate only, 1 h at 100 Hz: |R(T) - R0| = %.2e normalised each step, %.2e raw "
	    "(%.2e after one final normalisation)\n",
	    maxAbs(y.R_nb - x.R_nb), maxAbs(raw.R_nb - x.R_nb), maxAbs(so3::normalized(raw.R_nb) - x.R_nb));
	// Rounding only: about 0.1 ulp a step, accumulated over 360 000 steps, in
	// a direction that depends on the configuration's rounding pattern
	// (Rodrigues with the library's sin and cos drifted 6e-16 here and 2.2e-11
	// at latitude −60°, yaw 95°; its series form, so3.h, 5.0e-12 here and
	// 1.3e-14 there). A modelling error (a first-order turn, a wrong sign of
	// the Earth rate) is ≥ 1e-7.
	EXPECT_LT(maxAbs(y.R_nb - x.R_nb), 5e-11);
	{
		NavState x2 = x;
		x2.R_nb = test::rpy(10 * kDeg, -5 * kDeg, 95 * kDeg);
		const double lat2 = -60 * kDeg;
		const Eigen::Vector3d w_ie_n2(omega * std::cos(lat2), 0, -omega * std::sin(lat2));
		const Eigen::Vector3d w_ib_b2 = x2.R_nb.transpose() * w_ie_n2;
		NavState y2 = x2;
		for (int i = 0; i < 360000; ++i)
		{
			y2 = pm.propagate(y2, w_ib_b2, w_ie_n2, 0.01);
			y2.R_nb = so3::normalized(y2.R_nb);
		}
		std::printf("  at latitude -60 deg, yaw 95 deg: %.2e normalised each step\n",
		            maxAbs(y2.R_nb - x2.R_nb));
		EXPECT_LT(maxAbs(y2.R_nb - x2.R_nb), 5e-11);
	}
	// Without normalisation the 360000 products accumulate rounding
	// systematically (~1e-16 per step; R stops being orthonormal, and then
	// Exp(−a)·R·Exp(Rᵀa) no longer cancels exactly): ~4e-11.
	EXPECT_LT(maxAbs(raw.R_nb - x.R_nb), 1e-10);

	// Through the filter (10 Hz to keep the test short): the mean stays put.
	// Noise-free and with a (practically) certain gyro bias: an uncertain bias
	// makes the attitude uncertain (σ_b·T) and, correlated with it, moves the
	// unscented mean by a genuine second-order amount (3e-11 for σ_b = 1e-6 rad/s).
	pm.noise.gyro_arw = 0;
	pm.noise.gyro_bias.sigma = 0;
	Covariance P0 = Covariance::Identity(idx::core_dim, idx::core_dim) * 1e-12;
	P0.block<3, 3>(idx::gyro_bias, idx::gyro_bias) *= 1e-18;
	ManifoldUkf ukf(pm, UtParams{});
	ukf.initialize(x, P0);
	for (int i = 0; i < 36000; ++i) ukf.predict(w_ib_b, w_ie_n, 0.1);
	std::printf("Earth rate only, 1 h of ManifoldUkf::predict at 10 Hz: |R(T) - R0| = %.2e\n",
	            maxAbs(ukf.state().R_nb - x.R_nb));
	EXPECT_LT(maxAbs(ukf.state().R_nb - x.R_nb), 1e-12);
}

TEST(ProcessModel, ConstantAccelerationIsIntegratedExactly)
{
	const ProcessModel pm = test::makeProcessModel();
	const NavState x = test::makeState(0.3);
	for (int steps : {1, 7, 1000})
	{
		const double T = 10;
		const NavState y = propagateFor(pm, x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T, steps);
		const Eigen::Vector3d p = x.p_n + x.v_n * T + 0.5 * x.a_n * T * T;
		const Eigen::Vector3d v = x.v_n + x.a_n * T;
		EXPECT_LT((y.p_n - p).cwiseAbs().maxCoeff(), 1e-12 * p.norm()) << steps;
		EXPECT_LT((y.v_n - v).cwiseAbs().maxCoeff(), 1e-13) << steps;
		EXPECT_EQ(y.a_n, x.a_n);
		EXPECT_EQ(y.g, x.g);
	}
}

TEST(ProcessModel, GaussMarkovMeanDecaysExactlyForAnyStep)
{
	const ProcessModel pm = fastGaussMarkovModel();
	const NavState x = test::makeState(0.3);
	const double T = 50;
	const NavState one = propagateFor(pm, x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T, 1);
	const NavState many = propagateFor(pm, x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T, 1000);
	const TangentVector e0 = x.euclidean(), e1 = one.euclidean(), eN = many.euclidean();
	for (const GmCoord& c : gaussMarkovCoordinates(pm))
	{
		const double mu = pm.prior_mean[c.index];
		const double expected = mu + (e0[c.index] - mu) * std::exp(-T / c.tau);
		const double scale = std::abs(e0[c.index]) + std::abs(mu);
		EXPECT_NEAR(e1[c.index], expected, 1e-13 * scale) << tangentNames()[c.index];
		EXPECT_NEAR(eN[c.index], expected, 1e-12 * scale) << tangentNames()[c.index];
		EXPECT_GT(std::abs(e0[c.index] - expected), 1e-3 * scale) << tangentNames()[c.index];  // it did move
	}
}

TEST(ProcessModel, GaussMarkovVarianceIsExactForAnyStepThroughTheUkf)
{
	const ProcessModel pm = fastGaussMarkovModel();
	const NavState x = test::makeState(0.3);
	const double T = 50, p0 = 1e-10;
	Covariance P0 = Covariance::Identity(idx::core_dim, idx::core_dim) * p0;
	ManifoldUkf one(pm, UtParams{}), many(pm, UtParams{});
	one.initialize(x, P0);
	many.initialize(x, P0);
	one.predict(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T);
	for (int i = 0; i < 1000; ++i) many.predict(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T / 1000);
	for (const GmCoord& c : gaussMarkovCoordinates(pm))
	{
		// The currents' tangent coordinates turn with the attitude (state.h):
		// they also collect the attitude noise (δθ × c), so they are not a pure
		// Gauss–Markov variance any more; their mean decay is checked above.
		if (c.index >= idx::current_vehicle && c.index < idx::adcp_bias) continue;
		const double phi = std::exp(-T / c.tau);
		const double expected = phi * phi * p0 + c.sigma * c.sigma * (1 - phi * phi);
		ASSERT_GT(expected, 100 * p0);
		EXPECT_NEAR(one.covariance()(c.index, c.index), expected, 1e-9 * expected) << tangentNames()[c.index];
		EXPECT_NEAR(many.covariance()(c.index, c.index), expected, 1e-9 * expected)
		    << tangentNames()[c.index];
		// And the means agree between the two step sizes.
		EXPECT_NEAR(one.state().euclidean()[c.index], many.state().euclidean()[c.index],
		            1e-12 * (std::abs(x.euclidean()[c.index]) + 1e-3));
	}
	EXPECT_EQ(one.choleskyRepairs() + many.choleskyRepairs(), 0u);
}

TEST(ProcessModel, ProcessNoiseScalesLinearlyWithDt)
{
	ProcessModel pm = test::makeProcessModel();
	const double dt = 0.01;
	const Covariance Q1 = pm.noiseCovariance(dt, 0.0), Q2 = pm.noiseCovariance(2 * dt, 0.0);
	for (int i = 0; i < 3; ++i)
	{
		EXPECT_NEAR(Q1(idx::att + i, idx::att + i), pm.noise.gyro_arw * pm.noise.gyro_arw * dt, 1e-20);
		EXPECT_NEAR(Q2(idx::att + i, idx::att + i), 2 * Q1(idx::att + i, idx::att + i), 1e-20);  // not 4×
		EXPECT_NEAR(Q1(idx::acc + i, idx::acc + i), pm.noise.jerk_psd * dt, 1e-18);
	}
	EXPECT_NEAR(Q2(idx::gravity, idx::gravity), 2 * Q1(idx::gravity, idx::gravity), 1e-24);
	// Gauss–Markov increments: σ²(1 − e^{−2dt/τ}).
	for (const GmCoord& c : gaussMarkovCoordinates(pm))
		EXPECT_NEAR(Q1(c.index, c.index), c.sigma * c.sigma * (1 - std::exp(-2 * dt / c.tau)),
		            1e-12 * c.sigma * c.sigma)
		    << tangentNames()[c.index];
	// Spatial current variance: per metre moved through the water.
	const Covariance Qs = pm.noiseCovariance(dt, 1.5);
	for (int i = 0; i < 4; ++i)
		EXPECT_NEAR(Qs(idx::current_vehicle + i, idx::current_vehicle + i) -
		                Q1(idx::current_vehicle + i, idx::current_vehicle + i),
		            pm.noise.current_spatial_var_per_m * 1.5 * dt, 1e-18);
	// Symmetric positive semi-definite.
	EXPECT_EQ(Q1, Q1.transpose());
	EXPECT_GE(Eigen::SelfAdjointEigenSolver<Covariance>(Q1).eigenvalues().minCoeff(), -1e-18);
}

TEST(ProcessModel, CurrentsFollowTheProfileWhenTheDepthChanges)
{
	ProcessModel pm = test::makeProcessModel();
	pm.noise.current.tau_s = 1e15;  // isolate the transport from the decay
	pm.current_far_distance_m = 8;
	NavState x = test::makeState(0.3);
	x.v_n = Eigen::Vector3d(0.5, -0.2, 0.2);  // diving at 0.2 m/s
	x.a_n.setZero();
	x.current_vehicle_ne = Eigen::Vector2d(0.10, 0.08);
	x.current_far_ne = Eigen::Vector2d(0.02, 0.04);
	const Eigen::Vector2d gradient_per_m = (x.current_far_ne - x.current_vehicle_ne) / 8.0;
	const double T = 10;  // 2 m deeper
	for (int steps : {1, 7, 1000})
	{
		const NavState y = propagateFor(pm, x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T, steps);
		const double dz = y.p_n.z() - x.p_n.z();
		ASSERT_NEAR(dz, 2.0, 1e-10);
		// c(2 m below the old depth) on the old profile, and the gradient kept.
		EXPECT_LT((y.current_vehicle_ne - (x.current_vehicle_ne + dz * gradient_per_m)).norm(), 1e-12)
		    << steps;
		EXPECT_LT((y.current_far_ne - (x.current_far_ne + dz * gradient_per_m)).norm(), 1e-12) << steps;
		// Climbing back restores both.
		NavState up = y;
		up.v_n.z() = -0.2;
		const NavState back =
		    propagateFor(pm, up, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T, steps);
		EXPECT_LT((back.current_vehicle_ne - x.current_vehicle_ne).norm(), 1e-12) << steps;
		EXPECT_LT((back.current_far_ne - x.current_far_ne).norm(), 1e-12) << steps;
	}
	// Level flight: no transport; and off when the distance is 0.
	NavState level = x;
	level.v_n.z() = 0;
	EXPECT_LT((pm.propagate(level, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T).current_vehicle_ne -
	           x.current_vehicle_ne)
	              .norm(),
	          1e-12);
	pm.current_far_distance_m = 0;
	EXPECT_LT((pm.propagate(x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), T).current_vehicle_ne -
	           x.current_vehicle_ne)
	              .norm(),
	          1e-12);
}

TEST(ProcessModel, CurrentNoiseGrowsWithDepthChange)
{
	const ProcessModel pm = test::makeProcessModel();
	const double dt = 0.1;
	const Covariance Q0 = pm.noiseCovariance(dt, 0.4, 0.0), Qd = pm.noiseCovariance(dt, 0.4, -0.3);
	for (int i = 0; i < 4; ++i)
		EXPECT_NEAR(Qd(idx::current_vehicle + i, idx::current_vehicle + i) -
		                Q0(idx::current_vehicle + i, idx::current_vehicle + i),
		            pm.noise.current_vertical_var_per_m * 0.3 * dt, 1e-18);
	Covariance diff = Qd - Q0;
	diff.block<4, 4>(idx::current_vehicle, idx::current_vehicle).setZero();
	EXPECT_EQ(diff.cwiseAbs().maxCoeff(), 0.0);
}

TEST(ProcessModel, DiscretisedNoiseComposesOverSubsteps)
{
	// Exact discretisation: N steps of T/N from zero covariance, P ← A P Aᵀ + Q(T/N),
	// give Q(T) for the jerk-driven (p, v, a) chain and every Gauss–Markov state.
	ProcessModel pm = fastGaussMarkovModel();
	const double T = 2.0;
	for (int N : {2, 10, 200})
	{
		Covariance P = Covariance::Zero(idx::core_dim, idx::core_dim);
		for (int i = 0; i < N; ++i)
		{
			pm.applyLinearRows(P, T / N);
			Covariance Pt = P.transpose();
			pm.applyLinearRows(Pt, T / N);
			P = Pt + pm.noiseCovariance(T / N, 0.8);
		}
		const Covariance QT = pm.noiseCovariance(T, 0.8);
		// Rows 6.. are the linear part; the attitude/bias block has its own test.
		const Eigen::MatrixXd d = (P - QT).bottomRightCorner(idx::core_dim - 6, idx::core_dim - 6);
		const Eigen::VectorXd s = QT.diagonal().tail(idx::core_dim - 6).cwiseSqrt().cwiseMax(1e-30);
		const double rel = (d.array() / (s * s.transpose()).array()).abs().maxCoeff();
		EXPECT_LT(rel, 1e-10) << N;
	}
}

TEST(ProcessModel, AttitudeRandomWalkIsIndependentOfTheStepSize)
{
	// ARW² per second, whatever the step: 1 step of 1 s = 100 steps of 10 ms.
	ProcessModel pm = test::makeProcessModel();
	pm.noise.gyro_bias.sigma = 0;  // bias noise would integrate into attitude differently per step
	const NavState x = test::makeState(0.3);
	Covariance P0 = Covariance::Identity(idx::core_dim, idx::core_dim) * 1e-8;
	P0.block<3, 3>(idx::gyro_bias, idx::gyro_bias) = Eigen::Matrix3d::Identity() * 1e-20;
	ManifoldUkf one(pm, UtParams{}), many(pm, UtParams{});
	one.initialize(x, P0);
	many.initialize(x, P0);
	one.predict(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1.0);
	for (int i = 0; i < 100; ++i) many.predict(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.01);
	const double expected = 1e-8 + pm.noise.gyro_arw * pm.noise.gyro_arw * 1.0;
	for (int i = 0; i < 3; ++i)
	{
		EXPECT_NEAR(one.covariance()(i, i), expected, 1e-6 * expected);
		EXPECT_NEAR(many.covariance()(i, i), expected, 1e-6 * expected);
	}
}

TEST(ProcessModel, TailRowsOfTheLinearMapAreTheDiagonalFactors)
{
	// The prediction forms A P Aᵀ past the inertial block as P_ij a_i a_j
	// (ukf.cpp); that is exact only if those rows of A are diagonal with the
	// factors diagonalTailFactors() gives. Checked against applyLinearRows on
	// the identity, with plugin blocks of both kinds appended.
	ProcessModel pm = fastGaussMarkovModel();
	StateBlockSpec gm;
	gm.name = "scale";
	gm.components = {"x", "y"};
	gm.sigma = {0.01};
	gm.process = StateProcess::GaussMarkov;
	gm.process_sigma = 0.01;
	gm.tau_s = 50;
	pm.appendBlock(gm);
	StateBlockSpec rw = gm;
	rw.name = "bias";
	rw.components = {""};
	rw.process = StateProcess::RandomWalk;
	pm.appendBlock(rw);
	const int n = pm.dim();
	const StepDecay step = pm.decay(0.7);
	Covariance A = Covariance::Identity(n, n);
	pm.applyLinearRows(A, step);
	const TangentVector a = pm.diagonalTailFactors(step);
	ASSERT_EQ(a.size(), n - idx::adcp_bias);
	const int tail = n - idx::adcp_bias;
	const Eigen::MatrixXd expected = a.asDiagonal();
	EXPECT_EQ(Eigen::MatrixXd(A.bottomRows(tail).leftCols(idx::adcp_bias)),
	          Eigen::MatrixXd::Zero(tail, idx::adcp_bias));
	EXPECT_EQ(Eigen::MatrixXd(A.bottomRightCorner(tail, tail)), expected);
	// The factors decay (τ finite) and the random walk keeps 1.
	EXPECT_LT(a[0], 1.0);
	EXPECT_LT(a[n - 2 - idx::adcp_bias], 1.0);
	EXPECT_EQ(a[n - 1 - idx::adcp_bias], 1.0);
}

// A process model with one plugin state "scale" that walks 0.1 per √m.
ProcessModel perMetreScaleModel()
{
	ProcessModel pm;
	StateBlockSpec b;
	b.name = "scale";
	b.components = {""};
	b.sigma = {0.01};
	b.process = StateProcess::RandomWalkPerMetre;
	b.process_sigma = 0.1;
	pm.appendBlock(b);
	return pm;
}

TEST(ProcessModel, PerMetreRandomWalkGrowsWithTheDistanceThroughTheWaterNotWithTime)
{
	// σ = 0.1 per √m: 2 m moved give 0.02 whether in 1 s or in 4 s, none
	// while hovering. A per-second walk would give 0.01 × dt (0.01 and 0.04).
	ProcessModel pm = perMetreScaleModel();
	const int i = idx::extra;
	const auto var = [&](double dt, double speed_through_water, double vertical_speed)
	{ return pm.noiseCovariance(dt, speed_through_water, vertical_speed)(i, i); };
	EXPECT_NEAR(var(1.0, 2.0, 0.0), 0.01 * 2, 1e-15);
	EXPECT_NEAR(var(4.0, 0.5, 0.0), 0.01 * 2, 1e-15);
	EXPECT_EQ(var(10.0, 0.0, 0.0), 0.0);
	// Diving counts (3-D distance through the water): 1.2 m/s across, 0.5 m/s down: 1.3 m/s.
	EXPECT_NEAR(var(2.0, 1.2, -0.5), 0.01 * 1.3 * 2, 1e-15);
	// The mean stays (a walk), and the prediction's linear map keeps it (factor 1).
	EXPECT_EQ(pm.diagonalTailFactors(pm.decay(3.0))[idx::core_dim - idx::adcp_bias], 1.0);
	NavState x;
	x.extra = ExtraVector::Constant(1, 0.02);
	EXPECT_EQ(pm.propagate(x, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 3.0).extra[0], 0.02);
}

TEST(ProcessModel, PerMetreRandomWalkThroughTheFilterUsesTheStatesSpeedThroughTheWater)
{
	// The filter's prediction adds σ² × |v_n,h − current| × dt (as for the
	// currents' spatial noise): moving at 2 m/s against no current for 5 s
	// adds σ² × 10 m, in a 0.5 m/s current along the track σ² × 7.5 m.
	for (const double current_n : {0.0, 0.5})
	{
		ProcessModel pm = perMetreScaleModel();
		pm.noise.current.tau_s = 1e15;  // a steady current
		NavState x;
		x.v_n = Eigen::Vector3d(2.0, 0, 0);
		x.current_vehicle_ne = Eigen::Vector2d(current_n, 0);
		x.extra = ExtraVector::Zero(1);
		// Attitude and velocity all but known: the mean speed stays 2 m/s.
		Covariance P = Covariance::Identity(pm.dim(), pm.dim()) * 1e-12;
		P(idx::extra, idx::extra) = 1e-4;
		ManifoldUkf ukf(pm, UtParams{});
		ukf.initialize(x, P);
		for (int k = 0; k < 50; ++k) ukf.predict(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.1);
		const double distance_m = (2.0 - current_n) * 5.0;
		EXPECT_NEAR(ukf.covariance()(idx::extra, idx::extra) - 1e-4, 0.01 * distance_m, 1e-9)
		    << "current " << current_n;
	}
}
