// DVL, ADCP and GPS availability: bottom lock only inside the altitude window,
// ADCP cells beyond the seabed invalid, GPS only with the antenna above water.
#include <gtest/gtest.h>

#include <cmath>

#include "environment.h"
#include "sensors.h"
#include "sim_test_config.h"

using namespace auvnav;
using namespace auvnav::sim;

namespace
{
constexpr double kDeg = M_PI / 180;

struct Scene
{
	VehicleState x;
	Truth t;
	explicit Scene(double depth_m, const Eigen::Vector3d& v_b = {0.5, 0, 0})
	{
		x.p_n = {0, 0, depth_m};
		x.nu_b.head<3>() = v_b;
		t.x = &x;
	}
};
}  // namespace

TEST(DvlSim, BottomLockOnlyInsideTheAltitudeWindow)
{
	const auto sensors = test::repoSensors();
	const auto dvl_cfg = sensors.child("dvl");
	const double min_alt = dvl_cfg.number("min_altitude_m"), max_alt = dvl_cfg.number("max_altitude_m");
	const double seabed = 40;
	const Environment env = Environment::fromConfig(test::flatEnvironment(seabed), 1);
	const double sensor_below_cg = dvl_cfg.vector3("position_m").z();
	auto lockedFraction = [&](double altitude)
	{
		DvlSim dvl(dvl_cfg, 3);
		Scene s(seabed - altitude - sensor_below_cg);
		int locked = 0;
		for (int k = 0; k < 200; ++k) locked += dvl.sample(s.t, env)->bottom_lock;
		return locked / 200.0;
	};
	EXPECT_EQ(lockedFraction(0.5 * min_alt), 0.0);
	EXPECT_EQ(lockedFraction(max_alt + 2.0), 0.0);
	EXPECT_GT(lockedFraction(10.0), 0.99);  // a 1 % beam dropout may cost a ping now and then
	EXPECT_GT(lockedFraction(min_alt + 0.2), 0.99);
}

TEST(DvlSim, VelocityAndAltitudeMatchTheTruthInTheSensorFrame)
{
	const auto dvl_cfg = test::repoSensors().child("dvl");
	const Environment env = Environment::fromConfig(test::flatEnvironment(30), 1);
	DvlSim dvl(dvl_cfg, 5);
	Scene s(10.0, {0.6, -0.1, 0.02});
	const double yaw_mount = -22.5 * kDeg;  // nominal; the true one adds 0.15°
	Eigen::Vector3d mean = Eigen::Vector3d::Zero();
	double alt = 0;
	int n = 0;
	for (int k = 0; k < 500; ++k)
	{
		const auto o = dvl.sample(s.t, env);
		if (!o->bottom_lock) continue;  // two of four beams dropped (rare)
		mean += Eigen::Vector3d(o->velocity_s_mps[0], o->velocity_s_mps[1], o->velocity_s_mps[2]);
		alt += o->altitude_m;
		++n;
		EXPECT_GT(o->velocity_cov[0], 0);
	}
	ASSERT_GT(n, 490);
	mean /= n;
	alt /= n;
	const Eigen::Vector3d v_s_nominal =
	    Eigen::AngleAxisd(yaw_mount, Eigen::Vector3d::UnitZ()).toRotationMatrix().transpose() *
	    Eigen::Vector3d(0.6, -0.1, 0.02);
	// Scale factor 0.2 % and 0.15° misalignment: a few mm/s at most.
	EXPECT_LT((mean - v_s_nominal).norm(), 0.005);
	EXPECT_NEAR(alt, 30 - 10 - dvl_cfg.vector3("position_m").z(), 0.01);
}

TEST(AdcpSim, CellsBeyondTheSeabedAreInvalid)
{
	const auto adcp_cfg = test::repoSensors().child("adcp");
	const double seabed = 10.0;
	const Environment env = Environment::fromConfig(test::flatEnvironment(seabed, 0.2, -0.1), 1);
	AdcpSim adcp(adcp_cfg, 2);
	Scene s(4.0, {0, 0, 0});  // at rest: cells see the current (plus bias, noise)
	const double sensor_depth = 4.0 + adcp_cfg.vector3("position_m").z();
	const double clean = (seabed - sensor_depth) * std::cos(30 * kDeg);
	const auto o = adcp.sample(s.t, env);
	ASSERT_EQ(o->cells.size(), 20u);
	int valid_inside = 0, inside = 0;
	for (std::size_t i = 0; i < o->cells.size(); ++i)
	{
		const bool beyond = o->cellDistance(i) + 0.5 * o->cell_size_m > clean;
		if (beyond)
			EXPECT_FALSE(o->cells[i].valid) << "cell " << i << " at " << o->cellDistance(i) << " m";
		else
		{
			++inside;
			valid_inside += o->cells[i].valid;
		}
	}
	EXPECT_EQ(inside, 9);        // (10 − 4.206) cos 30° = 5.02 m: cells ending at 1.0 … 5.0 m
	EXPECT_GE(valid_inside, 8);  // correlation falls with range; near cells pass
}

TEST(AdcpSim, ValidCellsMeasureCurrentRelativeToTheSensor)
{
	const auto adcp_cfg = test::repoSensors().child("adcp");
	const Environment env = Environment::fromConfig(test::flatEnvironment(100, 0.2, -0.1), 1);
	AdcpSim adcp(adcp_cfg, 2);
	Scene s(20.0, {0.5, 0, 0});
	Eigen::Vector3d mean = Eigen::Vector3d::Zero();
	int n = 0;
	for (int k = 0; k < 100; ++k)
	{
		// Held: a range-for over a temporary's member would read freed memory
		// (the temporary dies before the loop body; found by ASan).
		const auto profile = adcp.sample(s.t, env);
		for (const auto& c : profile->cells)
			if (c.valid)
			{
				mean += Eigen::Vector3d(c.velocity_s_mps[0], c.velocity_s_mps[1], c.velocity_s_mps[2]);
				++n;
			}
	}
	ASSERT_GT(n, 1000);
	mean /= n;
	const Eigen::Matrix3d R_sn =
	    Eigen::AngleAxisd(-22.5 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix().transpose();
	const Eigen::Vector3d expected = R_sn * Eigen::Vector3d(0.2 - 0.5, -0.1, 0);
	// Within the configured bias (σ 1 cm/s per axis) plus misalignment.
	EXPECT_LT((mean - expected).head<2>().norm(), 0.04);
	EXPECT_NEAR(mean.z(), 0.0, 0.01);
}

TEST(GpsSim, FixesOnlyWithTheAntennaAboveWaterAfterReacquisition)
{
	const auto gps_cfg = test::repoSensors().child("gps");
	const earth::TangentFrame frame({-12.975 * kDeg, -38.43 * kDeg, 0});
	GpsSim gps(gps_cfg, 4);
	VehicleState x;
	Truth t;
	t.x = &x;
	x.p_n = {0, 0, 5.0};  // submerged
	int fixes = 0;
	for (int k = 0; k < 30; ++k)
	{
		t.t_s = k;
		fixes += gps.sample(t, frame) != nullptr;
	}
	EXPECT_EQ(fixes, 0);
	x.p_n.z() = 0.25;  // floating: antenna 0.35 m above the water
	const double reacq = gps_cfg.number("reacquisition_s");
	int early = 0, later = 0;
	for (int k = 30; k < 130; ++k)
	{
		t.t_s = k;
		const bool fix = gps.sample(t, frame) != nullptr;
		(k - 30 < reacq ? early : later) += fix;
	}
	EXPECT_EQ(early, 0);
	EXPECT_EQ(later, 100 - static_cast<int>(reacq));
	// The fix is where the antenna is (within noise + rare outliers).
	t.t_s = 200;
	const auto o = gps.sample(t, frame);
	ASSERT_TRUE(o);
	const auto& gga = o->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>();
	const Eigen::Vector3d p =
	    frame.toNed({gga.fields.latitude_degrees * kDeg, gga.fields.longitude_degrees * kDeg, 0});
	EXPECT_LT(p.head<2>().norm(), 70.0);
}

TEST(PressureSim, PressureIsHydrostaticAtTheSensorDepth)
{
	const auto cfg = test::repoSensors().child("pressure");
	const Environment env = Environment::fromConfig(test::flatEnvironment(100), 1);
	const earth::TangentFrame frame({-12.975 * kDeg, -38.43 * kDeg, 0});
	PressureSim ps(cfg, 9);
	Scene s(20.0);
	double mean = 0;
	for (int k = 0; k < 400; ++k) mean += ps.sample(s.t, env, frame)->pressure_pa / 400;
	const double depth = 20.0 + cfg.vector3("position_m").z();
	const double expected = 101325 + 1025 * frame.gravityNed({0, 0, depth}).z() * depth;
	EXPECT_NEAR(mean, expected, 4 * 50 + 10);  // bias σ 50 Pa, noise averaged out
}
