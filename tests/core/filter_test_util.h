#pragma once
/** @file filter_test_util.h
 *  Shared fixtures of the filter tests: a non-trivial state, a dense fully
 *  correlated covariance, a process model with every noise term switched on,
 *  and scale-free comparison metrics.
 */
#include <auvnav/process_model.h>
#include <auvnav/so3.h>
#include <auvnav/state.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <random>

namespace auvnav::test
{
constexpr double kDeg = M_PI / 180;

/** Roll, pitch, yaw [rad] → R_nb (ZYX). */
inline Eigen::Matrix3d rpy(double roll, double pitch, double yaw)
{
	return so3::Exp(Eigen::Vector3d(0, 0, yaw)) * so3::Exp(Eigen::Vector3d(0, pitch, 0)) *
	       so3::Exp(Eigen::Vector3d(roll, 0, 0));
}

inline NavState makeState(double yaw_rad)
{
	NavState x;
	x.R_nb = rpy(10 * kDeg, -5 * kDeg, yaw_rad);
	x.b_w << 2e-3, -1e-3, 3e-3;
	x.a_n << 0.02, -0.01, 0.005;
	x.g = 9.806;
	x.b_a << 0.03, -0.02, 0.01;
	x.v_n << 1.5, 0.3, 0.1;
	x.p_n << 120, -40, 30;
	x.current_vehicle_ne << 0.2, -0.1;
	x.current_far_ne << 0.25, -0.05;
	x.b_adcp << 0.01, -0.02;
	x.M_sub << 110, 2, 5, 1, 160, -3;
	x.Dl_sub << 20, 1, 0.5, 1.5, 40, 2;
	x.Dq_sub << 30, 2, 1, 1.5, 60, 4;
	return x;
}

/** Per-coordinate standard deviations (tangent order). */
inline TangentVector makeSigmas(const Eigen::Vector3d& att_sigma_rad)
{
	TangentVector s(idx::core_dim);
	s.segment<3>(idx::att) = att_sigma_rad;
	s.segment<3>(idx::gyro_bias).setConstant(0.01);
	s.segment<3>(idx::acc).setConstant(0.05);
	s[idx::gravity] = 0.01;
	s.segment<3>(idx::acc_bias).setConstant(0.02);
	s.segment<3>(idx::vel).setConstant(0.3);
	s.segment<3>(idx::pos).setConstant(5.0);
	s.segment<4>(idx::current_vehicle).setConstant(0.2);
	s.segment<2>(idx::adcp_bias).setConstant(0.02);
	const NavState x = makeState(0);
	const TangentVector e = x.euclidean();
	for (int i = idx::inertia; i < idx::core_dim; ++i) s[i] = 0.1 * std::abs(e[i]);
	return s;
}

/** D C D with C a dense random correlation matrix (low-rank part + diagonal:
 *  correlations up to ~±0.9), D = diag(sigma). */
inline Covariance correlatedCovariance(const TangentVector& sigma, unsigned seed)
{
	std::mt19937 rng(seed);
	std::normal_distribution<double> nd;
	Eigen::MatrixXd A(sigma.size(), 8);
	for (int i = 0; i < A.size(); ++i) A.data()[i] = nd(rng);
	Covariance C = A * A.transpose();
	C.diagonal().array() += 0.2 * C.diagonal().mean();
	const TangentVector d = C.diagonal().cwiseSqrt().cwiseInverse();
	C = d.asDiagonal() * C * d.asDiagonal();
	return sigma.asDiagonal() * C * sigma.asDiagonal();
}

/** A process model with every term on and Gauss–Markov means that are not zero. */
inline ProcessModel makeProcessModel()
{
	ProcessModel m;
	auto& n = m.noise;
	n.gyro_arw = 2e-3;
	n.gyro_bias = {1e-3, 100};
	n.accel_bias = {1e-2, 200};
	n.jerk_psd = 0.01;
	n.velocity_psd = 1e-4;
	n.gravity_psd = 1e-8;
	n.current = {0.1, 600};
	n.current_spatial_var_per_m = 1e-4;
	n.current_vertical_var_per_m = 1e-3;
	m.current_far_distance_m = 8;  // the currents follow the profile with depth
	n.adcp_bias = {0.01, 1000};
	n.parameter_tau_s = 3600;
	const NavState x = makeState(0);
	TangentVector mu = TangentVector::Zero(idx::core_dim);
	mu.segment<3>(idx::gyro_bias) << 1e-3, 0, -1e-3;
	mu.segment<3>(idx::acc_bias) << 0.01, 0.01, -0.01;
	mu.segment<4>(idx::current_vehicle) << 0.1, 0.05, 0.12, 0.0;
	mu.segment<2>(idx::adcp_bias) << 0.005, 0.0;
	mu.segment<18>(idx::inertia) = 0.9 * x.euclidean().segment<18>(idx::inertia);
	m.prior_mean = mu;
	for (int i = 0; i < 18; ++i) n.parameter_sigma[i] = 0.05 * std::max(std::abs(mu[idx::inertia + i]), 1e-3);
	return m;
}

/** Appends three plugin-owned blocks of every process kind to `m` and returns
 *  their initial means: scale (1, random constant), misalignment (3, random
 *  walk), bias (2, Gauss–Markov with a non-zero mean). */
inline TangentVector appendTestPluginStates(ProcessModel& m)
{
	StateBlockSpec scale{"scale", {""}, {0.01}, {0.02}, StateProcess::RandomConstant, 0, 0};
	StateBlockSpec mis{
	    "misalignment", {"x", "y", "z"}, {0.01, -0.02, 0.03}, {0.02}, StateProcess::RandomWalk, 1e-3, 0};
	StateBlockSpec bias{"bias", {"n", "e"}, {0.5, -0.2}, {0.3, 0.2}, StateProcess::GaussMarkov, 0.4, 50};
	for (const auto& b : {scale, mis, bias}) m.appendBlock(b);
	return m.prior_mean.tail(m.dim() - idx::core_dim);
}

/** max_i |(a ⊟ b)_i| / √P_ii: the mean difference in standard deviations. */
inline double meanDiff(const NavState& a, const NavState& b, const Covariance& P)
{
	return (a.boxminus(b).array().abs() / P.diagonal().array().sqrt()).maxCoeff();
}

/** max_ij |A_ij − B_ij| / √(B_ii B_jj): the covariance difference in correlation units. */
inline double covDiff(const Covariance& A, const Covariance& B)
{
	const TangentVector s = B.diagonal().cwiseSqrt();
	return ((A - B).array() / (s * s.transpose()).array()).abs().maxCoeff();
}

}  // namespace auvnav::test
