// The simulator's magnetic compass (apps/sim/compass.h): the heading it writes
// is the true heading minus the declination plus the deviation, wrapped, in
// a CObservationIMU with IMU_YAW only; its noise has the configured sigma;
// and the FlatFish sensors file keeps it off unless a mission enables it.
#include <auvnav/angles.h>
#include <auvnav/config.h>
#include <gtest/gtest.h>

#include <cmath>

#include "compass.h"

using namespace auvnav;
using namespace auvnav::sim;

namespace
{
constexpr double kDeg = M_PI / 180;

config::Node compassConfig(double noise_deg, double bias_deg)
{
	return config::Node::fromText(
	    "rate_hz: 10\nposition_m: [0.4, 0, -0.1]\nnoise_sigma_deg: " + std::to_string(noise_deg) +
	        "\nbias_deg: " + std::to_string(bias_deg) + "\n",
	    "<compass>");
}

struct AtYaw
{
	VehicleState x;
	Truth t;
	explicit AtYaw(double yaw_deg)
	{
		x.q_nb = Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()) *
		         Eigen::AngleAxisd(4 * kDeg, Eigen::Vector3d::UnitY());
		t.x = &x;
		t.stamp = mrpt::Clock::fromDouble(1492693200.5);
	}
};
}  // namespace

TEST(CompassSim, HeadingIsTrueMinusDeclinationPlusDeviation)
{
	CompassSim compass(compassConfig(0, 1.5), -23 * kDeg, 1);
	for (double yaw : {-170.0, -45.0, 0.0, 20.0, 165.0})
	{
		AtYaw pose(yaw);
		const auto o = compass.sample(pose.t);
		ASSERT_TRUE(o->has(mrpt::obs::IMU_YAW));
		EXPECT_FALSE(o->has(mrpt::obs::IMU_WZ));
		EXPECT_FALSE(o->has(mrpt::obs::IMU_MAG_X));
		EXPECT_EQ(o->sensorLabel, "COMPASS");
		EXPECT_EQ(o->timestamp, pose.t.stamp);
		const double psi = o->get(mrpt::obs::IMU_YAW);
		EXPECT_GT(psi, -M_PI);
		EXPECT_LE(psi, M_PI);
		EXPECT_NEAR(wrapAngle(psi - (yaw + 23 + 1.5) * kDeg), 0, 1e-12) << yaw;
	}
}

TEST(CompassSim, NoiseHasTheConfiguredSigma)
{
	CompassSim compass(compassConfig(1.0, 0), 0, 7);
	AtYaw pose(30);
	double sum = 0, sum2 = 0;
	const int n = 4000;
	for (int i = 0; i < n; ++i)
	{
		const double e = wrapAngle(compass.sample(pose.t)->get(mrpt::obs::IMU_YAW) - 30 * kDeg);
		sum += e;
		sum2 += e * e;
	}
	const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
	EXPECT_NEAR(mean, 0, 0.1 * kDeg);
	EXPECT_NEAR(sigma, 1.0 * kDeg, 0.05 * kDeg);
}

TEST(CompassSim, MisspelledKeyIsRefusedWithItsName)
{
	const auto n =
	    config::Node::fromText("rate_hz: 10\nposition_m: [0, 0, 0]\nnoise_sigma_deg: 1\nbias_dg: 2\n", "<c>");
	CompassSim compass(n, 0, 1);
	try
	{
		n.checkAllKeysUsed();
		FAIL() << "bias_dg accepted";
	}
	catch (const config::ConfigError& e)
	{
		EXPECT_NE(std::string(e.what()).find("bias_dg"), std::string::npos) << e.what();
		EXPECT_NE(std::string(e.what()).find("bias_deg"), std::string::npos) << e.what();
	}
}
