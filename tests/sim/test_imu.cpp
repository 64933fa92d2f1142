// The simulated IMU: what a tactical IMU at rest must see (WGS-84 normal
// gravity and the Earth rate), and its noise statistics (Allan deviation).
#include <auvnav/earth.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "noise.h"
#include "sensors.h"
#include "sim_test_config.h"

using namespace auvnav;
using namespace auvnav::sim;

namespace
{
constexpr double kDeg = M_PI / 180;
const earth::Geodetic kSalvador{-12.975 * kDeg, -38.43 * kDeg, 0.0};

/** IMU config of the repo with its biases switched off (noise kept). */
config::Node imuWithoutBiases()
{
	return config::Node::fromText(
	    "rate_hz: 100\nposition_m: [0.29424, 0, -0.02863]\n"
	    "gyro: {random_walk: 0.012, bias_instability: 0, bias_correlation_time_s: 300, turn_on_bias_sigma: "
	    "0}\n"
	    "accelerometer: {random_walk: 0.12, bias_instability: 0, bias_correlation_time_s: 300, "
	    "turn_on_bias_sigma: 0}\n",
	    "<imu without biases>");
}

/** Overlapping Allan deviation of `y` (sample period dt) at cluster size m. */
double allanDeviation(const std::vector<double>& y, double dt, std::size_t m)
{
	// Integrated signal θ_k = Σ y dt; AVAR = Σ (θ_{k+2m} − 2θ_{k+m} + θ_k)² / (2 τ² (N − 2m)).
	std::vector<double> theta(y.size() + 1, 0.0);
	for (std::size_t i = 0; i < y.size(); ++i) theta[i + 1] = theta[i] + y[i] * dt;
	const double tau = m * dt;
	double sum = 0;
	const std::size_t n = theta.size() - 2 * m;
	for (std::size_t k = 0; k < n; ++k)
	{
		const double d = theta[k + 2 * m] - 2 * theta[k + m] + theta[k];
		sum += d * d;
	}
	return std::sqrt(sum / (2 * tau * tau * n));
}
}  // namespace

TEST(ImuAtRest, MeanSpecificForceIsNormalGravityAndMeanRateIsEarthRate)
{
	const earth::TangentFrame frame(kSalvador);
	ImuSim imu(imuWithoutBiases(), 7);
	VehicleState x;
	x.p_n = {0, 0, 10};  // 10 m deep, at rest
	const double heading = 37 * kDeg;
	x.q_nb = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ());
	Truth t;
	t.x = &x;             // at rest: ν = 0 and ν̇ = 0
	const int n = 60000;  // 10 min at 100 Hz
	Eigen::Vector3d f_sum = Eigen::Vector3d::Zero(), w_sum = Eigen::Vector3d::Zero();
	for (int k = 0; k < n; ++k)
	{
		t.t_s = 0.01 * k;
		const auto o = imu.sample(t, frame);
		f_sum += Eigen::Vector3d(o->get(mrpt::obs::IMU_X_ACC), o->get(mrpt::obs::IMU_Y_ACC),
		                         o->get(mrpt::obs::IMU_Z_ACC));
		w_sum +=
		    Eigen::Vector3d(o->get(mrpt::obs::IMU_WX), o->get(mrpt::obs::IMU_WY), o->get(mrpt::obs::IMU_WZ));
	}
	const Eigen::Vector3d f_mean = f_sum / n, w_mean = w_sum / n;
	// White-noise σ of the mean: density / √(n dt).
	const double sigma_f = 0.12e-3 * 9.80665 / std::sqrt(n * 0.01);
	const double sigma_w = 0.012 * kDeg / 60 / std::sqrt(n * 0.01);
	const double depth_imu = 10 - 0.02863;
	const double g = earth::normalGravity(kSalvador.lat_rad, -depth_imu);
	EXPECT_NEAR(f_mean.norm(), g, 4 * sigma_f);
	EXPECT_NEAR(f_mean.z(), -g, 4 * sigma_f);  // FRD: specific force points up
	EXPECT_NEAR(f_mean.x(), 0, 4 * sigma_f);
	EXPECT_NEAR(f_mean.y(), 0, 4 * sigma_f);
	// Expected: the Earth rate in body axes (level, heading 37°).
	const Eigen::Vector3d w_expected = x.R_nb().transpose() * earth::earthRateNed(kSalvador.lat_rad);
	for (int i = 0; i < 3; ++i) EXPECT_NEAR(w_mean[i], w_expected[i], 4 * sigma_w) << "axis " << i;
	// The test resolves the Earth rate to better than 1%.
	EXPECT_LT(4 * sigma_w, 0.01 * earth::rotationRate());
}

TEST(ImuNoise, GaussMarkovSigmaPutsTheAllanFloorAtTheBiasInstability)
{
	const double tau_c = 3000;
	// KVH-1750 figures, and a floor 10x higher with the same white noise,
	// where σ is ~100x the floor's (B²√(1.5τc)/(2N): 0.116 and 11.6 °/h).
	for (const double bi_deg_h : {0.05, 0.5})
	{
		const double arw = 0.012 * kDeg / 60, bi = bi_deg_h * kDeg / 3600;
		const double s = gaussMarkovSigmaForAllanFloor(arw, bi, tau_c);
		ASSERT_GT(s, 0);
		double floor = INFINITY;
		for (double T = 0.01; T <= tau_c; T *= 1.01)
			floor = std::min(floor, std::sqrt(arw * arw / T + gaussMarkovAllanVariance(s, tau_c, T)));
		EXPECT_NEAR(floor, bi, 0.01 * bi) << bi_deg_h;
		const double approx = bi * bi * std::sqrt(1.5 * tau_c) / (2 * arw);
		EXPECT_NEAR(s, approx, 0.1 * approx) << bi_deg_h;
	}
	// AVAR limits: rate random walk q T / 3 and white 2σ²τc/T.
	EXPECT_NEAR(gaussMarkovAllanVariance(1.0, 100, 0.1), 2.0 / 100 * 0.1 / 3, 1e-6);
	EXPECT_NEAR(gaussMarkovAllanVariance(1.0, 100, 1e6), 2.0 * 100 / 1e6, 1e-7);
}

TEST(ImuNoise, SimulatedGyroAllanDeviationMatchesArwAndBiasInstability)
{
	// Configured KVH-1750-grade figures (config/sensors/flatfish_sensors.yaml).
	InertialAxisErrorParams p;
	p.random_walk = 0.012 * kDeg / 60;        // rad/√s
	p.bias_instability = 0.05 * kDeg / 3600;  // rad/s
	p.bias_tau_s = 3000;
	p.turn_on_sigma = 0;
	const double dt = 0.01;
	const std::size_t n = 10 * 3600 * 100;  // 10 h per axis: ~30 clusters at the floor
	double adev_1s = 0, adev_min = 0;
	const int axes = 3;
	for (int axis = 0; axis < axes; ++axis)
	{
		mrpt::random::CRandomGenerator rng;
		rng.randomize(100 + axis);
		InertialAxisError e(p, rng);
		std::vector<double> y(n);
		for (auto& v : y) v = e.sample(dt, rng);
		adev_1s += allanDeviation(y, dt, 100) / axes;
		double best = INFINITY;
		// Floor: minimum over cluster times 10 s … τc (3000 s).
		for (std::size_t m = 1000; m * dt <= p.bias_tau_s; m = m * 5 / 4)
			best = std::min(best, allanDeviation(y, dt, m));
		adev_min += best / axes;
	}
	EXPECT_NEAR(adev_1s, p.random_walk, 0.2 * p.random_walk);
	EXPECT_NEAR(adev_min, p.bias_instability, 0.2 * p.bias_instability);
	RecordProperty("adev_1s_deg_per_sqrt_h", std::to_string(adev_1s / kDeg * 60));
	RecordProperty("adev_min_deg_per_h", std::to_string(adev_min / kDeg * 3600));
	std::printf(
	    "gyro Allan deviation: at 1 s %.5f deg/sqrt(h) (configured ARW 0.012), minimum %.4f deg/h "
	    "(configured bias instability 0.05)\n",
	    adev_1s / kDeg * 60, adev_min / kDeg * 3600);
}
