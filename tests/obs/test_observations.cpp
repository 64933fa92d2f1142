// Serialization round trips of auvnav's observation classes, their presence in
// MRPT's class registry, and refusal of corrupt input.
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/obs/CObservationUSBL.h>
#include <gtest/gtest.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/rtti/CObject.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <sstream>
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

// A version-1 DVL in the least default configuration: every new field set.
CObservationDVL makeDvlV1()
{
	CObservationDVL d = makeDvl();
	d.frame = DvlFrame::EarthEnu;
	d.sign = DvlSign::BottomOverInstrument;
	d.beam_velocity_sigma_mps = 0.0125;
	d.beams = {{14.5, true, -0.625, 0.7853981633974483},
	           {14.25, true, 0.5, 2.356194490192345},
	           {15.125, true, 0.25, -2.356194490192345},
	           {0.0, false, std::numeric_limits<double>::quiet_NaN(), -0.7853981633974483}};
	return d;
}

// Bytes of a DVL at serialization version 0 exactly as version 0 wrote them
// (header, fields, end flag; bools as one byte each), independent of the
// current writer.
Bytes dvlVersion0Bytes(const CObservationDVL& d, uint8_t bottom_lock_byte = 1)
{
	mrpt::io::CMemoryStream buf;
	auto out = mrpt::serialization::archiveFrom(buf);
	const std::string name = "auvnav::obs::CObservationDVL";
	out << static_cast<uint8_t>(0x80 | name.size());
	out.WriteBuffer(name.data(), name.size());
	out << static_cast<uint8_t>(0);  // version
	out << d.timestamp << d.sensorLabel << d.sensorPose;
	for (double v : d.velocity_s_mps) out << v;
	for (double c : d.velocity_cov) out << c;
	out << bottom_lock_byte << d.altitude_m << d.beam_inclination_rad;
	out << static_cast<uint32_t>(d.beams.size());
	for (const auto& b : d.beams) out << b.range_m << static_cast<uint8_t>(b.valid ? 1 : 0);
	out << static_cast<uint8_t>(0x88);
	const auto* p = static_cast<const uint8_t*>(buf.getRawBufferData());
	return Bytes(p, p + buf.getTotalBytesCount());
}

// Byte offsets of the version-1 DVL fields, counted from the end of the
// object (the beams come last, then MRPT's end flag).
struct DvlV1Layout
{
	static constexpr std::size_t kBeamBytes = 3 * sizeof(double) + 1;  // range, valid, velocity, azimuth
	std::size_t beams_at, count_at, sigma_at, sign_at, frame_at, inclination_at, altitude_at, lock_at;
	DvlV1Layout(const Bytes& bytes, std::size_t beam_count)
	{
		beams_at = bytes.size() - 1 - beam_count * kBeamBytes;
		count_at = beams_at - 4;
		sigma_at = count_at - 8;
		sign_at = sigma_at - 1;
		frame_at = sign_at - 1;
		inclination_at = frame_at - 8;
		altitude_at = inclination_at - 8;
		lock_at = altitude_at - 1;
	}
	std::size_t validAt(std::size_t beam) const { return beams_at + beam * kBeamBytes + 8; }
};

// Overwrites one byte after checking it holds `expected` (see patchU32).
void patchU8(Bytes& bytes, std::size_t offset, uint8_t expected, uint8_t value)
{
	ASSERT_LT(offset, bytes.size());
	ASSERT_EQ(unsigned(expected), unsigned(bytes[offset]))
	    << "unexpected serialized layout at byte " << offset;
	bytes[offset] = value;
}

// The exception message of deserializing `bytes`, or "" if it did not throw.
std::string deserializeError(const Bytes& bytes)
{
	try
	{
		deserialize(bytes);
	}
	catch (const std::exception& e)
	{
		return e.what();
	}
	return "";
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

TEST(ObservationSerialization, DvlVersion1RoundTripKeepsTheNewFields)
{
	const auto d = makeDvlV1();
	const Bytes bytes = serialize(d);
	ASSERT_EQ(1, bytes[versionByteOffset(d)]) << "the writer must write version 1";
	const auto back = roundTrip(d);
	ASSERT_TRUE(back);
	expectSameBase(d, *back);
	expectSamePose(d.sensorPose, back->sensorPose);
	EXPECT_EQ(d.velocity_s_mps, back->velocity_s_mps);
	EXPECT_EQ(d.velocity_cov, back->velocity_cov);
	EXPECT_TRUE(back->bottom_lock);
	EXPECT_EQ(12.75, back->altitude_m);
	EXPECT_EQ(d.beam_inclination_rad, back->beam_inclination_rad);
	EXPECT_EQ(DvlFrame::EarthEnu, back->frame);
	EXPECT_EQ(DvlSign::BottomOverInstrument, back->sign);
	EXPECT_EQ(0.0125, back->beam_velocity_sigma_mps);
	ASSERT_EQ(4u, back->beams.size());
	for (std::size_t i = 0; i < d.beams.size(); ++i)
	{
		EXPECT_EQ(d.beams[i].range_m, back->beams[i].range_m) << "beam " << i;
		EXPECT_EQ(d.beams[i].valid, back->beams[i].valid) << "beam " << i;
		EXPECT_EQ(d.beams[i].azimuth_rad, back->beams[i].azimuth_rad) << "beam " << i;
		if (d.beams[i].valid)
		{
			EXPECT_EQ(d.beams[i].velocity_mps, back->beams[i].velocity_mps) << "beam " << i;
		}
	}
	EXPECT_TRUE(std::isnan(back->beams[3].velocity_mps));  // an invalid beam's NaN survives
}

TEST(ObservationSerialization, DvlEveryFrameAndSignRoundTrips)
{
	for (uint8_t f = 0; f <= uint8_t(DvlFrame::Beam); ++f)
		for (uint8_t g = 0; g <= uint8_t(DvlSign::BottomOverInstrument); ++g)
		{
			auto d = makeDvlV1();
			d.frame = DvlFrame(f);
			d.sign = DvlSign(g);
			const auto back = roundTrip(d);
			ASSERT_TRUE(back);
			EXPECT_EQ(d.frame, back->frame) << dvlFrameName(d.frame);
			EXPECT_EQ(d.sign, back->sign) << dvlSignName(d.sign);
		}
}

TEST(ObservationSerialization, DvlVersion0ReadsAsInstrumentFrameVehicleOverBottom)
{
	const auto d = makeDvl();
	const Bytes v0 = dvlVersion0Bytes(d);
	ASSERT_EQ(0, v0[versionByteOffset(d)]);
	const auto back = std::dynamic_pointer_cast<CObservationDVL>(deserialize(v0));
	ASSERT_TRUE(back);
	expectSameBase(d, *back);
	expectSamePose(d.sensorPose, back->sensorPose);
	EXPECT_EQ(d.velocity_s_mps, back->velocity_s_mps);
	EXPECT_EQ(d.velocity_cov, back->velocity_cov);
	EXPECT_TRUE(back->bottom_lock);
	EXPECT_EQ(DvlFrame::Instrument, back->frame);
	EXPECT_EQ(DvlSign::VehicleOverBottom, back->sign);
	EXPECT_EQ(0.0, back->beam_velocity_sigma_mps);
	ASSERT_EQ(4u, back->beams.size());
	EXPECT_FALSE(back->beams[3].valid);
	for (const auto& b : back->beams)
	{
		EXPECT_EQ(0.0, b.velocity_mps);
		EXPECT_EQ(0.0, b.azimuth_rad);
	}
	// Read into an existing object: the version-1 fields are reset, not kept.
	CObservationDVL existing = makeDvlV1();
	mrpt::io::CMemoryStream buf;
	buf.Write(v0.data(), v0.size());
	buf.Seek(0);
	mrpt::serialization::archiveFrom(buf).ReadObject(&existing);
	EXPECT_EQ(DvlFrame::Instrument, existing.frame);
	EXPECT_EQ(DvlSign::VehicleOverBottom, existing.sign);
	EXPECT_EQ(0.0, existing.beam_velocity_sigma_mps);
	EXPECT_EQ(0.0, existing.beams[0].azimuth_rad);
	EXPECT_EQ(0.0, existing.beams[0].velocity_mps);
}

TEST(ObservationSerialization, DvlFrameAndSignNamesParseBack)
{
	for (uint8_t f = 0; f <= uint8_t(DvlFrame::Beam); ++f)
	{
		DvlFrame parsed = DvlFrame::Instrument;
		EXPECT_TRUE(parseDvlFrame(dvlFrameName(DvlFrame(f)), parsed)) << unsigned(f);
		EXPECT_EQ(DvlFrame(f), parsed);
	}
	for (uint8_t g = 0; g <= uint8_t(DvlSign::BottomOverInstrument); ++g)
	{
		DvlSign parsed = DvlSign::VehicleOverBottom;
		EXPECT_TRUE(parseDvlSign(dvlSignName(DvlSign(g)), parsed)) << unsigned(g);
		EXPECT_EQ(DvlSign(g), parsed);
	}
	EXPECT_STREQ("earth_enu", dvlFrameName(DvlFrame::EarthEnu));
	EXPECT_STREQ("bottom_over_instrument", dvlSignName(DvlSign::BottomOverInstrument));
	DvlFrame f = DvlFrame::Vehicle;
	EXPECT_FALSE(parseDvlFrame("Earth_ENU", f));
	EXPECT_FALSE(parseDvlFrame("", f));
	EXPECT_EQ(DvlFrame::Vehicle, f) << "left untouched when unknown";
	DvlSign g = DvlSign::BottomOverInstrument;
	EXPECT_FALSE(parseDvlSign("pd0", g));
	EXPECT_EQ(DvlSign::BottomOverInstrument, g);
}

TEST(ObservationText, DvlDescriptionAndExportNameFrameAndSign)
{
	const auto d = makeDvlV1();
	std::ostringstream o;
	d.getDescriptionAsText(o);
	const std::string text = o.str();
	EXPECT_NE(std::string::npos, text.find("Frame: earth_enu")) << text;
	EXPECT_NE(std::string::npos, text.find("sign: bottom_over_instrument")) << text;
	EXPECT_NE(std::string::npos, text.find("RDI PD0")) << text;
	EXPECT_NE(std::string::npos, d.exportTxtHeader().find("[FRAME")) << d.exportTxtHeader();
	EXPECT_NE(std::string::npos, d.exportTxtHeader().find("[SIGN")) << d.exportTxtHeader();
	// 3 velocity + lock + altitude + frame + sign + beam count + 2 per beam.
	std::istringstream row(d.exportTxtDataRow());
	std::vector<std::string> cols;
	for (std::string c; row >> c;) cols.push_back(c);
	ASSERT_EQ(8u + 2 * d.beams.size(), cols.size()) << d.exportTxtDataRow();
	EXPECT_EQ("3", cols[5]);  // earth_enu
	EXPECT_EQ("1", cols[6]);  // bottom_over_instrument
	EXPECT_EQ("4", cols[7]);
	// Beam mode shows the beam velocities in the description.
	auto b = d;
	b.frame = DvlFrame::Beam;
	std::ostringstream ob;
	b.getDescriptionAsText(ob);
	EXPECT_NE(std::string::npos, ob.str().find("velocity [m/s]")) << ob.str();
	EXPECT_NE(std::string::npos, ob.str().find("-0.625")) << ob.str();
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
	patchU32(bytes, DvlV1Layout(bytes, d.beams.size()).count_at, 4, 0xFFFFFFFFu);
	EXPECT_THROW(deserialize(bytes), std::exception);
	// The same in a version-0 record.
	Bytes v0 = dvlVersion0Bytes(d);
	constexpr std::size_t kV0BeamBytes = sizeof(double) + 1;  // range + valid
	patchU32(v0, v0.size() - kEndFlagSize - d.beams.size() * kV0BeamBytes - 4, 4, 0xFFFFFFFFu);
	EXPECT_THROW(deserialize(v0), std::exception);
}

TEST(ObservationCorruption, DvlFrameOrSignCodeOutOfRangeIsCorruptData)
{
	const auto d = makeDvlV1();
	const Bytes good = serialize(d);
	const DvlV1Layout at(good, d.beams.size());
	Bytes bad_frame = good;
	patchU8(bad_frame, at.frame_at, uint8_t(DvlFrame::EarthEnu), 5);
	std::string msg = deserializeError(bad_frame);
	EXPECT_NE(std::string::npos, msg.find("corrupt data")) << msg;
	EXPECT_NE(std::string::npos, msg.find("frame")) << msg;
	Bytes bad_sign = good;
	patchU8(bad_sign, at.sign_at, uint8_t(DvlSign::BottomOverInstrument), 2);
	msg = deserializeError(bad_sign);
	EXPECT_NE(std::string::npos, msg.find("corrupt data")) << msg;
	EXPECT_NE(std::string::npos, msg.find("sign")) << msg;
	Bytes huge = good;
	patchU8(huge, at.frame_at, uint8_t(DvlFrame::EarthEnu), 0xFF);
	EXPECT_NE(std::string::npos, deserializeError(huge).find("corrupt data"));
	EXPECT_EQ("", deserializeError(good));  // the offsets above are the right ones
}

TEST(ObservationCorruption, DvlFlagsOtherThanZeroOrOneAreCorruptData)
{
	// MRPT would copy any byte into a bool; we refuse all but 0 and 1.
	const auto d = makeDvlV1();
	const Bytes good = serialize(d);
	const DvlV1Layout at(good, d.beams.size());
	Bytes bad_lock = good;
	patchU8(bad_lock, at.lock_at, 1, 2);
	std::string msg = deserializeError(bad_lock);
	EXPECT_NE(std::string::npos, msg.find("corrupt data")) << msg;
	EXPECT_NE(std::string::npos, msg.find("bottom_lock")) << msg;
	Bytes bad_valid = good;
	patchU8(bad_valid, at.validAt(3), 0, 0x7F);
	msg = deserializeError(bad_valid);
	EXPECT_NE(std::string::npos, msg.find("corrupt data")) << msg;
	EXPECT_NE(std::string::npos, msg.find("beam valid")) << msg;
	// Version 0 records get the same check.
	msg = deserializeError(dvlVersion0Bytes(makeDvl(), 3));
	EXPECT_NE(std::string::npos, msg.find("corrupt data")) << msg;
	EXPECT_NE(std::string::npos, msg.find("bottom_lock")) << msg;
}

TEST(ObservationCorruption, DvlWithAnInvalidEnumIsNotWritten)
{
	auto d = makeDvlV1();
	d.frame = static_cast<DvlFrame>(9);
	EXPECT_THROW(serialize(d), std::exception);
	d = makeDvlV1();
	d.sign = static_cast<DvlSign>(2);
	EXPECT_THROW(serialize(d), std::exception);
}

TEST(ObservationCorruption, FutureDvlVersionThrows)
{
	const auto d = makeDvl();
	Bytes bytes = serialize(d);
	const std::size_t at = versionByteOffset(d);
	ASSERT_EQ(1, bytes[at]);
	bytes[at] = 2;
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

// ------------------------------------------------- byte-edited records (issue 15)
// Every class refuses a damaged label length, a damaged mounting pose and a
// flag or enum byte no writer produces, naming the class and the field, and a
// refused record leaves the object it was read into untouched.

namespace
{
CObservationUSBL makeUsbl()
{
	CObservationUSBL u;
	u.sensorLabel = "USBL";
	u.timestamp = fixedTime(4);
	u.measurement_time = fixedTime(-5);
	u.sensorPose = mrpt::poses::CPose3D(0.4, 0.0, -0.3, 0.0, 0.0, 0.0);
	u.frame = UsblFrame::LocalNed;
	u.position = {120.5, -33.25, 41.0};
	u.covariance_ned_m2 = {4, 0, 0, 0, 4, 0, 0, 0, 9};
	u.slant_range_m = 130.0;
	u.transponder_id = 7;
	return u;
}

// The label's uint32 length follows the object header and the 8-byte timestamp.
std::size_t labelLengthOffset(const mrpt::serialization::CSerializable& obj)
{
	return versionByteOffset(obj) + 1 + sizeof(int64_t);
}

// The offset of the only occurrence of the double `v` in `bytes` (npos if
// absent or not unique): a field found by value, independent of the layout.
std::size_t uniqueDoubleOffset(const Bytes& bytes, double v)
{
	uint8_t pattern[sizeof(double)];
	std::memcpy(pattern, &v, sizeof(double));
	std::size_t found = std::string::npos;
	for (std::size_t i = 0; i + sizeof(double) <= bytes.size(); ++i)
		if (std::memcmp(&bytes[i], pattern, sizeof(double)) == 0)
		{
			if (found != std::string::npos) return std::string::npos;
			found = i;
		}
	return found;
}

void patchDouble(Bytes& bytes, double expected, double value)
{
	const std::size_t at = uniqueDoubleOffset(bytes, expected);
	ASSERT_NE(std::string::npos, at) << expected << " is not found once in the record";
	std::memcpy(&bytes[at], &value, sizeof(double));
}

void expectRefusal(const Bytes& bytes, const std::string& cls, const std::string& field)
{
	const std::string msg = deserializeError(bytes);
	EXPECT_NE(std::string::npos, msg.find("corrupt data")) << msg;
	EXPECT_NE(std::string::npos, msg.find(cls)) << msg;
	EXPECT_NE(std::string::npos, msg.find(field)) << msg;
}

struct NamedRecord
{
	std::string cls;
	std::function<Bytes()> bytes;
	std::size_t label_at;
};

std::vector<NamedRecord> everyClass()
{
	return {
	    {"CObservationDVL", [] { return serialize(makeDvlV1()); }, labelLengthOffset(makeDvl())},
	    {"CObservationADCP", [] { return serialize(makeAdcp()); }, labelLengthOffset(makeAdcp())},
	    {"CObservationPressure", [] { return serialize(makePressure()); }, labelLengthOffset(makePressure())},
	    {"CObservationThrusters", [] { return serialize(makeThrusters()); },
	     labelLengthOffset(makeThrusters())},
	    {"CObservationUSBL", [] { return serialize(makeUsbl()); }, labelLengthOffset(makeUsbl())}};
}
}  // namespace

TEST(ObservationCorruption, HugeLabelLengthIsRefusedBeforeAllocatingInEveryClass)
{
	for (const auto& rec : everyClass())
	{
		SCOPED_TRACE(rec.cls);
		Bytes bytes = rec.bytes();
		ASSERT_EQ("", deserializeError(bytes));
		uint32_t len = 0;
		std::memcpy(&len, &bytes[rec.label_at], 4);
		ASSERT_GT(len, 0u);
		ASSERT_LT(len, 20u) << "the offset does not point at the label length";
		// 4 GiB would be one allocation (and 4 GiB of RSS) with MRPT's reader.
		patchU32(bytes, rec.label_at, len, 0xFFFFFFF0u);
		expectRefusal(bytes, rec.cls, "sensorLabel length");
	}
}

TEST(ObservationCorruption, DamagedSensorPoseIsRefusedInEveryClassThatHasOne)
{
	struct Case
	{
		std::string cls;
		Bytes bytes;
		double x;
	};
	const std::vector<Case> cases = {{"CObservationDVL", serialize(makeDvlV1()), 0.75},
	                                 {"CObservationADCP", serialize(makeAdcp()), -0.5},
	                                 {"CObservationPressure", serialize(makePressure()), 1.2},
	                                 {"CObservationUSBL", serialize(makeUsbl()), 0.4}};
	for (const auto& c : cases)
	{
		SCOPED_TRACE(c.cls);
		Bytes nan_x = c.bytes;
		patchDouble(nan_x, c.x, std::numeric_limits<double>::quiet_NaN());
		expectRefusal(nan_x, c.cls, "sensorPose");
		// The rotation matrix follows x, y, z: its first element scaled by 3
		// is no rotation any more.
		Bytes skewed = c.bytes;
		const std::size_t r00 = uniqueDoubleOffset(c.bytes, c.x) + 3 * sizeof(double);
		double v = 0;
		std::memcpy(&v, &skewed[r00], sizeof v);
		ASSERT_TRUE(std::abs(v) <= 1.0) << "not a rotation element at byte " << r00;
		v = 3 * v + 0.5;
		std::memcpy(&skewed[r00], &v, sizeof v);
		expectRefusal(skewed, c.cls, "sensorPose");
	}
}

TEST(ObservationCorruption, AdcpValidFlagOtherThanZeroOrOneIsCorruptData)
{
	const auto a = makeAdcp();
	Bytes bytes = serialize(a);
	// The last cell's valid byte is the last byte before the end flag.
	patchU8(bytes, bytes.size() - kEndFlagSize - 1, 0, 2);
	expectRefusal(bytes, "CObservationADCP", "cell valid");
	patchU8(bytes, bytes.size() - kEndFlagSize - 1, 2, 0xFF);
	expectRefusal(bytes, "CObservationADCP", "cell valid");
}

TEST(ObservationCorruption, ThrusterUnitAndUsblFrameCodesNameClassAndField)
{
	const auto t = makeThrusters();
	Bytes thr = serialize(t);
	patchU8(thr, thr.size() - kEndFlagSize - t.effort.size() * sizeof(double) - 4 - 1,
	        uint8_t(EffortUnit::Speed_rpm), 2);
	expectRefusal(thr, "CObservationThrusters", "unit");

	const auto u = makeUsbl();
	Bytes usbl = serialize(u);
	// frame byte: just before the first position value.
	const std::size_t frame_at = uniqueDoubleOffset(usbl, 120.5) - 1;
	patchU8(usbl, frame_at, uint8_t(UsblFrame::LocalNed), 2);
	expectRefusal(usbl, "CObservationUSBL", "frame");
}

TEST(ObservationCorruption, RefusedRecordLeavesTheObjectItIsReadIntoUntouched)
{
	// A damaged beam flag comes after every head field: reading it into an
	// existing object must not leave that object half overwritten.
	const CObservationDVL other = makeDvl();
	CObservationDVL target = makeDvlV1();
	target.sensorLabel = "KEEP";
	Bytes bytes = serialize(other);
	const DvlV1Layout at(bytes, other.beams.size());
	patchU8(bytes, at.validAt(3), 0, 9);
	mrpt::io::CMemoryStream buf;
	buf.Write(bytes.data(), bytes.size());
	buf.Seek(0);
	EXPECT_THROW(mrpt::serialization::archiveFrom(buf).ReadObject(&target), std::exception);
	EXPECT_EQ("KEEP", target.sensorLabel);
	EXPECT_EQ(DvlFrame::EarthEnu, target.frame);
	EXPECT_EQ(0.0125, target.beam_velocity_sigma_mps);
	EXPECT_EQ(-0.625, target.beams[0].velocity_mps);
}

TEST(ObservationSerialization, UsblRoundTripKeepsEveryField)
{
	const auto u = makeUsbl();
	const auto back = roundTrip(u);
	ASSERT_TRUE(back);
	expectSameBase(u, *back);
	EXPECT_EQ(u.measurement_time, back->measurement_time);
	EXPECT_EQ(u.frame, back->frame);
	EXPECT_EQ(u.position, back->position);
	EXPECT_EQ(u.covariance_ned_m2, back->covariance_ned_m2);
	EXPECT_EQ(u.slant_range_m, back->slant_range_m);
	EXPECT_EQ(u.transponder_id, back->transponder_id);
	expectSamePose(u.sensorPose, back->sensorPose);
}
