// Serialization round trips of auvnav's observation classes, their presence in
// MRPT's class registry, and refusal of corrupt input.
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <gtest/gtest.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

using namespace auvnav::obs;
using Bytes = std::vector<uint8_t>;

namespace
{
// A fixed instant (2023-11-14T22:13:20.1234567Z) with sub-microsecond ticks so
// that any rounding through double would show.
mrpt::Clock::time_point fixedTime(int64_t extra_ticks_100ns = 0)
{
	constexpr int64_t kUnixEpochIn100ns = 116444736000000000;  // MRPT counts from 1601
	constexpr int64_t kTicks = kUnixEpochIn100ns + 1700000000LL * 10000000LL + 1234567;
	return mrpt::Clock::time_point(mrpt::Clock::duration(kTicks + extra_ticks_100ns));
}

// The serialized pose is the translation plus the rotation matrix, so compare
// those (yaw/pitch/roll are recomputed on read and may differ in the last ulp).
void expectSamePose(const mrpt::poses::CPose3D& expected, const mrpt::poses::CPose3D& actual)
{
	EXPECT_EQ(expected.x(), actual.x());
	EXPECT_EQ(expected.y(), actual.y());
	EXPECT_EQ(expected.z(), actual.z());
	for (int r = 0; r < 3; ++r)
		for (int c = 0; c < 3; ++c)
			EXPECT_EQ(expected.getRotationMatrix()(r, c), actual.getRotationMatrix()(r, c))
			    << "rotation(" << r << "," << c << ")";
}

void expectSameBase(const mrpt::obs::CObservation& expected, const mrpt::obs::CObservation& actual)
{
	EXPECT_EQ(expected.sensorLabel, actual.sensorLabel);
	EXPECT_EQ(expected.timestamp, actual.timestamp);
}

Bytes serialize(const mrpt::serialization::CSerializable& obj)
{
	mrpt::io::CMemoryStream buf;
	mrpt::serialization::archiveFrom(buf) << obj;
	const auto* p = static_cast<const uint8_t*>(buf.getRawBufferData());
	return Bytes(p, p + buf.getTotalBytesCount());
}

mrpt::serialization::CSerializable::Ptr deserialize(const Bytes& bytes)
{
	mrpt::io::CMemoryStream buf;
	buf.Write(bytes.data(), bytes.size());
	buf.Seek(0);
	return mrpt::serialization::archiveFrom(buf).ReadObject();
}

template <class T>
typename T::Ptr roundTrip(const T& obj)
{
	auto back = std::dynamic_pointer_cast<T>(deserialize(serialize(obj)));
	EXPECT_TRUE(back) << "read back an object of another class";
	return back;
}

// MRPT's object framing: [0x80|name length][class name][version byte] data [0x88].
constexpr std::size_t kEndFlagSize = 1;
std::size_t versionByteOffset(const mrpt::serialization::CSerializable& obj)
{
	return 1 + std::strlen(obj.GetRuntimeClass()->className);
}

// Overwrites the uint32 (little endian) at `offset` after checking that the
// bytes there really hold `expected`, so a layout change fails loudly instead
// of silently corrupting some other field.
void patchU32(Bytes& bytes, std::size_t offset, uint32_t expected, uint32_t value)
{
	ASSERT_LE(offset + 4, bytes.size());
	uint32_t found = 0;
	std::memcpy(&found, &bytes[offset], 4);
	ASSERT_EQ(expected, found) << "unexpected serialized layout at byte " << offset;
	std::memcpy(&bytes[offset], &value, 4);
}

CObservationDVL makeDvl()
{
	CObservationDVL d;
	d.sensorLabel = "DVL_BOTTOM";
	d.timestamp = fixedTime();
	d.sensorPose = mrpt::poses::CPose3D(0.75, -0.05, 0.32, 0.7853981633974483, 0.01, -0.02);
	d.velocity_s_mps = {1.25, -0.375, 0.0625};
	d.velocity_cov = {1e-4, 1e-5, -2e-6, 1e-5, 2e-4, 3e-6, -2e-6, 3e-6, 4e-4};
	d.bottom_lock = true;
	d.altitude_m = 12.75;
	d.beam_inclination_rad = 0.5235987755982988;
	d.beams = {{14.5, true}, {14.25, true}, {15.125, true}, {0.0, false}};
	return d;
}

CObservationADCP makeAdcp()
{
	CObservationADCP a;
	a.sensorLabel = "ADCP_UP";
	a.timestamp = fixedTime(1);
	a.sensorPose = mrpt::poses::CPose3D(-0.5, 0.1, -0.2, -0.1, 0.05, 3.0);
	a.blank_distance_m = 0.5;
	a.cell_size_m = 1.25;
	a.velocity_sigma_mps = 0.02;
	a.cells = {{{0.1, -0.2, 0.05}, 0.95, true},
	           {{0.15, -0.25, -0.01}, 0.8, true},
	           {{-0.3, 0.4, 0.02}, 0.55, true},
	           {{9.0, 9.0, 9.0}, 0.1, false}};
	return a;
}

CObservationPressure makePressure()
{
	CObservationPressure p;
	p.sensorLabel = "DEPTH";
	p.timestamp = fixedTime(2);
	p.sensorPose = mrpt::poses::CPose3D(1.2, -0.05, 0.1, 0.0, 0.0, 0.0);
	p.pressure_pa = 151650.25;
	p.temperature_c = 11.5;
	return p;
}

CObservationThrusters makeThrusters()
{
	CObservationThrusters t;
	t.sensorLabel = "THRUSTERS";
	t.timestamp = fixedTime(3);
	t.unit = EffortUnit::Speed_rpm;
	t.effort = {1200.5, -1180.25, 300.0, 0.0, -45.5, 610.0};
	return t;
}
}  // namespace

// ---------------------------------------------------------------- round trips

TEST(ObservationSerialization, DvlRoundTripKeepsEveryField)
{
	const auto d = makeDvl();
	const auto back = roundTrip(d);
	ASSERT_TRUE(back);
	expectSameBase(d, *back);
	expectSamePose(d.sensorPose, back->sensorPose);
	EXPECT_EQ(d.velocity_s_mps, back->velocity_s_mps);
	EXPECT_EQ(d.velocity_cov, back->velocity_cov);
	EXPECT_TRUE(back->bottom_lock);
	EXPECT_EQ(12.75, back->altitude_m);
	EXPECT_EQ(d.beam_inclination_rad, back->beam_inclination_rad);
	ASSERT_EQ(4u, back->beams.size());
	for (std::size_t i = 0; i < d.beams.size(); ++i)
	{
		EXPECT_EQ(d.beams[i].range_m, back->beams[i].range_m) << "beam " << i;
		EXPECT_EQ(d.beams[i].valid, back->beams[i].valid) << "beam " << i;
	}
}

TEST(ObservationSerialization, DvlWithoutLockKeepsNanAltitudeAndNoBeams)
{
	auto d = makeDvl();
	d.bottom_lock = false;
	d.altitude_m = std::numeric_limits<double>::quiet_NaN();
	d.beams.clear();
	const auto back = roundTrip(d);
	ASSERT_TRUE(back);
	EXPECT_FALSE(back->bottom_lock);
	EXPECT_TRUE(std::isnan(back->altitude_m));
	EXPECT_TRUE(back->beams.empty());
}

TEST(ObservationSerialization, AdcpRoundTripKeepsEveryField)
{
	const auto a = makeAdcp();
	const auto back = roundTrip(a);
	ASSERT_TRUE(back);
	expectSameBase(a, *back);
	expectSamePose(a.sensorPose, back->sensorPose);
	EXPECT_EQ(0.5, back->blank_distance_m);
	EXPECT_EQ(1.25, back->cell_size_m);
	EXPECT_EQ(0.02, back->velocity_sigma_mps);
	ASSERT_EQ(4u, back->cells.size());
	for (std::size_t i = 0; i < a.cells.size(); ++i)
	{
		EXPECT_EQ(a.cells[i].velocity_s_mps, back->cells[i].velocity_s_mps) << "cell " << i;
		EXPECT_EQ(a.cells[i].correlation, back->cells[i].correlation) << "cell " << i;
		EXPECT_EQ(a.cells[i].valid, back->cells[i].valid) << "cell " << i;
	}
	// Derived geometry follows the restored fields: 0.5 + 2.5 * 1.25.
	EXPECT_DOUBLE_EQ(3.625, back->cellDistance(2));
}

TEST(ObservationSerialization, PressureRoundTripKeepsEveryField)
{
	const auto p = makePressure();
	const auto back = roundTrip(p);
	ASSERT_TRUE(back);
	expectSameBase(p, *back);
	expectSamePose(p.sensorPose, back->sensorPose);
	EXPECT_EQ(151650.25, back->pressure_pa);
	EXPECT_EQ(11.5, back->temperature_c);
}

TEST(ObservationSerialization, ThrustersRoundTripKeepsEveryField)
{
	const auto t = makeThrusters();
	const auto back = roundTrip(t);
	ASSERT_TRUE(back);
	expectSameBase(t, *back);
	EXPECT_EQ(EffortUnit::Speed_rpm, back->unit);
	EXPECT_EQ(t.effort, back->effort);
	EXPECT_EQ(6u, back->thrusterCount());
}

TEST(ObservationSerialization, TimestampKeepsSubMicrosecondTicks)
{
	const auto back = roundTrip(makePressure());
	ASSERT_TRUE(back);
	EXPECT_EQ(fixedTime(2).time_since_epoch().count(), back->timestamp.time_since_epoch().count());
}

TEST(ObservationSerialization, SeveralObjectsInOneStreamComeBackInOrder)
{
	mrpt::io::CMemoryStream buf;
	auto out = mrpt::serialization::archiveFrom(buf);
	out << makeDvl() << makeAdcp() << makePressure() << makeThrusters();
	buf.Seek(0);
	auto in = mrpt::serialization::archiveFrom(buf);
	EXPECT_EQ("DVL_BOTTOM", in.ReadObject<CObservationDVL>()->sensorLabel);
	EXPECT_EQ("ADCP_UP", in.ReadObject<CObservationADCP>()->sensorLabel);
	EXPECT_EQ("DEPTH", in.ReadObject<CObservationPressure>()->sensorLabel);
	EXPECT_EQ("THRUSTERS", in.ReadObject<CObservationThrusters>()->sensorLabel);
}

// ------------------------------------------------------------------- registry

class ObservationRegistry : public ::testing::TestWithParam<std::string>
{
};

TEST_P(ObservationRegistry, ClassIsFoundByQualifiedNameAndCreatesItsType)
{
	const std::string name = GetParam();
	const mrpt::rtti::TRuntimeClassId* cls = mrpt::rtti::findRegisteredClass(name);
	ASSERT_NE(nullptr, cls) << name << " is not in MRPT's class registry";
	EXPECT_EQ(name, cls->className);
	EXPECT_TRUE(cls->derivedFrom(CLASS_ID(mrpt::obs::CObservation))) << name;
	const auto obj = cls->createObject();
	ASSERT_TRUE(obj);
	EXPECT_EQ(name, obj->GetRuntimeClass()->className);
}

INSTANTIATE_TEST_SUITE_P(AllClasses, ObservationRegistry,
                         ::testing::Values("auvnav::obs::CObservationDVL", "auvnav::obs::CObservationADCP",
                                           "auvnav::obs::CObservationPressure",
                                           "auvnav::obs::CObservationThrusters"));

// ------------------------------------------------------------- corrupt input
// Offsets are computed from the end of the object: the element array comes
// last, followed by MRPT's one-byte end flag.

TEST(ObservationCorruption, AbsurdDvlBeamCountThrowsInsteadOfAllocating)
{
	const auto d = makeDvl();
	Bytes bytes = serialize(d);
	constexpr std::size_t kBeamBytes = sizeof(double) + 1;  // range + bool
	const std::size_t count_at = bytes.size() - kEndFlagSize - d.beams.size() * kBeamBytes - 4;
	patchU32(bytes, count_at, 4, 0xFFFFFFFFu);
	EXPECT_THROW(deserialize(bytes), std::exception);
}

TEST(ObservationCorruption, AbsurdAdcpCellCountThrows)
{
	const auto a = makeAdcp();
	Bytes bytes = serialize(a);
	constexpr std::size_t kCellBytes = 4 * sizeof(double) + 1;  // velocity, correlation, valid
	const std::size_t count_at = bytes.size() - kEndFlagSize - a.cells.size() * kCellBytes - 4;
	patchU32(bytes, count_at, 4, 50'000'000u);
	try
	{
		deserialize(bytes);
		FAIL() << "an ADCP profile claiming 50 million cells was accepted";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string::npos, std::string(e.what()).find("ADCP cell count"))
		    << "message was: " << e.what();
	}
}

TEST(ObservationCorruption, ThrusterCountJustAboveLimitThrows)
{
	const auto t = makeThrusters();
	Bytes bytes = serialize(t);
	const std::size_t count_at = bytes.size() - kEndFlagSize - t.effort.size() * sizeof(double) - 4;
	patchU32(bytes, count_at, 6, 65);
	EXPECT_THROW(deserialize(bytes), std::exception);
}

TEST(ObservationCorruption, UnknownThrusterUnitThrows)
{
	const auto t = makeThrusters();
	Bytes bytes = serialize(t);
	const std::size_t unit_at = bytes.size() - kEndFlagSize - t.effort.size() * sizeof(double) - 4 - 1;
	ASSERT_EQ(uint8_t(EffortUnit::Speed_rpm), bytes[unit_at]);
	bytes[unit_at] = 7;
	EXPECT_THROW(deserialize(bytes), std::exception);
}

TEST(ObservationCorruption, FutureSerializationVersionThrows)
{
	const auto p = makePressure();
	Bytes bytes = serialize(p);
	const std::size_t at = versionByteOffset(p);
	ASSERT_EQ(0, bytes[at]) << "version-0 object expected";
	bytes[at] = 1;
	EXPECT_THROW(deserialize(bytes), std::exception);
}

TEST(ObservationCorruption, TruncatedObjectThrowsAtEveryCut)
{
	const Bytes full = serialize(makeAdcp());
	for (std::size_t cut : {std::size_t(1), std::size_t(10), versionByteOffset(makeAdcp()) + 1,
	                        full.size() / 2, full.size() - 1})
	{
		const Bytes cut_bytes(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(cut));
		EXPECT_THROW(deserialize(cut_bytes), std::exception) << "cut at byte " << cut;
	}
}
