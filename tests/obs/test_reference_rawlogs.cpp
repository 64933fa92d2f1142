// Frozen reference rawlogs: files written by earlier serialization versions must
// stay readable with exactly the values they were written with. The expected
// values are literal copies of tests/data/README.md (not shared with the
// generator, which only ever knows the current version).
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string>

using namespace auvnav::obs;

namespace
{
const std::string kObsV0 = std::string(AUVNAV_TEST_DATA_DIR) + "/obs_v0.rawlog";
const std::string kObsV1 = std::string(AUVNAV_TEST_DATA_DIR) + "/obs_v1.rawlog";

constexpr int64_t kT0Ticks = 133444736001234567;  // 2023-11-14T22:13:20.1234567Z
constexpr int64_t kQuarterSecond_100ns = 2500000;
// Poses are compared through yaw/pitch/roll recomputed from the stored
// rotation matrix, so allow for last-bit differences between libm versions.
constexpr double kAngleTol_rad = 1e-12;

int64_t ticks(const mrpt::Clock::time_point& t)
{
	return t.time_since_epoch().count();
}

void expectPose(const mrpt::poses::CPose3D& p, double x, double y, double z, double yaw, double pitch,
                double roll)
{
	EXPECT_EQ(x, p.x());
	EXPECT_EQ(y, p.y());
	EXPECT_EQ(z, p.z());
	EXPECT_NEAR(yaw, p.yaw(), kAngleTol_rad);
	EXPECT_NEAR(pitch, p.pitch(), kAngleTol_rad);
	EXPECT_NEAR(roll, p.roll(), kAngleTol_rad);
}

// Reads the next observation and checks its class; fails the test otherwise.
template <class T>
typename T::Ptr nextAs(auvnav::io::RawlogReader& reader)
{
	const auto obs = reader.next();
	EXPECT_TRUE(obs) << "file ended early";
	if (!obs) return nullptr;
	auto typed = std::dynamic_pointer_cast<T>(obs);
	EXPECT_TRUE(typed) << "unexpected class " << obs->GetRuntimeClass()->className;
	return typed;
}

void expectReferenceDvlV0(const CObservationDVL& d)
{
	EXPECT_EQ("DVL", d.sensorLabel);
	EXPECT_EQ(kT0Ticks, ticks(d.timestamp));
	expectPose(d.sensorPose, 0.75, -0.05, 0.32, 0.7853981633974483, 0.0, 0.0);
	EXPECT_EQ((std::array<double, 3>{1.25, -0.375, 0.0625}), d.velocity_s_mps);
	EXPECT_EQ((std::array<double, 9>{1e-4, 1e-5, -2e-6, 1e-5, 2e-4, 3e-6, -2e-6, 3e-6, 4e-4}),
	          d.velocity_cov);
	EXPECT_TRUE(d.bottom_lock);
	EXPECT_EQ(12.75, d.altitude_m);
	EXPECT_EQ(0.5235987755982988, d.beam_inclination_rad);
	ASSERT_EQ(4u, d.beams.size());
	const std::array<double, 4> range_m{14.5, 14.25, 15.125, 0.0};
	const std::array<bool, 4> valid{true, true, true, false};
	for (std::size_t i = 0; i < 4; ++i)
	{
		EXPECT_EQ(range_m[i], d.beams[i].range_m) << "beam " << i;
		EXPECT_EQ(valid[i], d.beams[i].valid) << "beam " << i;
	}
}

// Version 1 of the DVL: the version-0 values plus frame, sign, beam velocities
// and azimuths (tests/data/README.md, obs_v1.rawlog).
void expectReferenceDvlV1(const CObservationDVL& d)
{
	EXPECT_EQ("DVL", d.sensorLabel);
	EXPECT_EQ(kT0Ticks, ticks(d.timestamp));
	expectPose(d.sensorPose, 0.75, -0.05, 0.32, 0.7853981633974483, 0.0, 0.0);
	EXPECT_EQ((std::array<double, 3>{1.25, -0.375, 0.0625}), d.velocity_s_mps);
	EXPECT_EQ((std::array<double, 9>{1e-4, 1e-5, -2e-6, 1e-5, 2e-4, 3e-6, -2e-6, 3e-6, 4e-4}),
	          d.velocity_cov);
	EXPECT_TRUE(d.bottom_lock);
	EXPECT_EQ(12.75, d.altitude_m);
	EXPECT_EQ(0.5235987755982988, d.beam_inclination_rad);
	EXPECT_EQ(DvlFrame::EarthEnu, d.frame);
	EXPECT_EQ(DvlSign::BottomOverInstrument, d.sign);
	EXPECT_EQ(0.0075, d.beam_velocity_sigma_mps);
	ASSERT_EQ(4u, d.beams.size());
	const double range[4] = {14.5, 14.25, 15.125, 0.0};
	const bool valid[4] = {true, true, true, false};
	const double velocity[4] = {0.625, -0.5, 0.125, 0.0};
	const double azimuth[4] = {0.7853981633974483, 2.356194490192345, -2.356194490192345,
	                           -0.7853981633974483};
	for (std::size_t i = 0; i < 4; ++i)
	{
		EXPECT_EQ(range[i], d.beams[i].range_m) << i;
		EXPECT_EQ(valid[i], d.beams[i].valid) << i;
		EXPECT_EQ(velocity[i], d.beams[i].velocity_mps) << i;
		EXPECT_EQ(azimuth[i], d.beams[i].azimuth_rad) << i;
	}
}

void expectReferenceAdcpV0(const CObservationADCP& a)
{
	EXPECT_EQ("ADCP", a.sensorLabel);
	EXPECT_EQ(kT0Ticks + kQuarterSecond_100ns, ticks(a.timestamp));
	expectPose(a.sensorPose, -0.5, 0.1, -0.2, -0.1, 0.05, 3.0);
	EXPECT_EQ(0.5, a.blank_distance_m);
	EXPECT_EQ(1.25, a.cell_size_m);
	EXPECT_EQ(0.02, a.velocity_sigma_mps);
	ASSERT_EQ(4u, a.cells.size());
	const std::array<std::array<double, 3>, 4> v_mps{
	    {{0.1, -0.2, 0.05}, {0.15, -0.25, -0.01}, {-0.3, 0.4, 0.02}, {0.0, 0.0, 0.0}}};
	const std::array<double, 4> correlation{0.95, 0.8, 0.55, 0.1};
	const std::array<bool, 4> valid{true, true, true, false};
	for (std::size_t i = 0; i < 4; ++i)
	{
		EXPECT_EQ(v_mps[i], a.cells[i].velocity_s_mps) << "cell " << i;
		EXPECT_EQ(correlation[i], a.cells[i].correlation) << "cell " << i;
		EXPECT_EQ(valid[i], a.cells[i].valid) << "cell " << i;
	}
}

void expectReferencePressureV0(const CObservationPressure& p)
{
	EXPECT_EQ("DEPTH", p.sensorLabel);
	EXPECT_EQ(kT0Ticks + 2 * kQuarterSecond_100ns, ticks(p.timestamp));
	expectPose(p.sensorPose, 1.2, -0.05, 0.1, 0.0, 0.0, 0.0);
	EXPECT_EQ(151650.25, p.pressure_pa);
	EXPECT_EQ(11.5, p.temperature_c);
}

void expectReferenceThrustersV0(const CObservationThrusters& t)
{
	EXPECT_EQ("THRUSTERS", t.sensorLabel);
	EXPECT_EQ(kT0Ticks + 3 * kQuarterSecond_100ns, ticks(t.timestamp));
	EXPECT_EQ(EffortUnit::Speed_rpm, t.unit);
	EXPECT_EQ((std::vector<double>{1200.5, -1180.25, 300.0, 0.0, -45.5, 610.0}), t.effort);
}
}  // namespace

TEST(ReferenceRawlog, ObsV0HoldsTheDocumentedValues)
{
	auvnav::io::RawlogReader reader(kObsV0);

	const auto dvl = nextAs<CObservationDVL>(reader);
	ASSERT_TRUE(dvl);
	expectReferenceDvlV0(*dvl);

	const auto adcp = nextAs<CObservationADCP>(reader);
	ASSERT_TRUE(adcp);
	expectReferenceAdcpV0(*adcp);

	const auto pressure = nextAs<CObservationPressure>(reader);
	ASSERT_TRUE(pressure);
	expectReferencePressureV0(*pressure);

	const auto thrusters = nextAs<CObservationThrusters>(reader);
	ASSERT_TRUE(thrusters);
	expectReferenceThrustersV0(*thrusters);

	EXPECT_FALSE(reader.next()) << "obs_v0.rawlog holds exactly four objects";
	EXPECT_EQ(4u, reader.objectsRead());
	EXPECT_EQ(0u, reader.actionsSkipped());
}

TEST(ReferenceRawlog, ObsV1HoldsTheDocumentedValues)
{
	auvnav::io::RawlogReader reader(kObsV1);
	const auto dvl = nextAs<CObservationDVL>(reader);
	ASSERT_TRUE(dvl);
	expectReferenceDvlV1(*dvl);
	// The other classes are still at version 0 in this file.
	const auto adcp = nextAs<CObservationADCP>(reader);
	ASSERT_TRUE(adcp);
	expectReferenceAdcpV0(*adcp);
	const auto pressure = nextAs<CObservationPressure>(reader);
	ASSERT_TRUE(pressure);
	expectReferencePressureV0(*pressure);
	const auto thrusters = nextAs<CObservationThrusters>(reader);
	ASSERT_TRUE(thrusters);
	expectReferenceThrustersV0(*thrusters);
	EXPECT_FALSE(reader.next()) << "obs_v1.rawlog holds exactly four objects";
}
