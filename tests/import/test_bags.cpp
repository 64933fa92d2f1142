// Bag readers of the importer: ROS 1 bags written with rosbag_storage and the
// Debian message classes, ROS 2 bags written as SQLite + CDR here; the custom
// DVL type proves that the readers use the definitions stored in the bags.
// Also the definition parser and decoder on their own, and how missing,
// foreign, truncated and inconsistent files are reported.
#include <auvnav/import/importer.h>
#include <auvnav/import/record.h>
#include <auvnav/import/time_format.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>

#include "bag_writers.h"
#include "msg_definition.h"

#include <sqlite3.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace auvnav::import;
using namespace auvnav::import::testing;

namespace
{
// 2023-11-14T22:13:20Z plus nanoseconds that a double of UNIX seconds loses.
constexpr uint32_t kSec0 = 1700000000;
constexpr uint32_t kNsec0 = 123456789;
constexpr TimeNs kNs = 1000000000;

fs::path scratchDir()
{
	static const fs::path dir = auvnav::testing::scratchFolder("bags_test", "files");
	return dir;
}

std::string scratch(const std::string& name)
{
	return (scratchDir() / name).string();
}

std::vector<Record> readAll(RecordSource& source)
{
	std::vector<Record> records;
	Record r;
	while (source.next(r)) records.push_back(r);
	return records;
}

const Value& field(const Record& r, const std::string& name)
{
	static const Value missing;
	const int i = r.indexOf(name);
	EXPECT_GE(i, 0) << "no field " << name << " in " << r.where;
	return i >= 0 ? r.values[static_cast<std::size_t>(i)] : missing;
}

double num(const Record& r, const std::string& name)
{
	const Value& v = field(r, name);
	EXPECT_EQ(v.kind, Value::Kind::Number) << name;
	return v.number;
}

TimeNs timeOf(const Record& r, const std::string& name)
{
	const Value& v = field(r, name);
	EXPECT_EQ(v.kind, Value::Kind::Time) << name;
	return v.time_ns;
}

std::string text(const Record& r, const std::string& name)
{
	const Value& v = field(r, name);
	EXPECT_EQ(v.kind, Value::Kind::Text) << name;
	return v.text;
}

/** The ImportError message of `f`, or a test failure. */
std::string errorOf(const std::function<void()>& f)
{
	try
	{
		f();
	}
	catch (const ImportError& e)
	{
		return e.what();
	}
	catch (const std::exception& e)
	{
		ADD_FAILURE() << "not an ImportError: " << e.what();
		return e.what();
	}
	ADD_FAILURE() << "no ImportError";
	return {};
}

std::string drain(const std::string& path, const std::string& topic, bool ros2)
{
	return errorOf(
	    [&]
	    {
		    auto source = ros2 ? openRos2Bag(path, topic) : openRos1Bag(path, topic);
		    Record r;
		    while (source->next(r))
		    {
		    }
	    });
}

void truncateCopy(const std::string& from, const std::string& to, std::uintmax_t size)
{
	fs::copy_file(from, to, fs::copy_options::overwrite_existing);
	fs::resize_file(to, size);
}

std::vector<std::string> expectedArray(const std::string& name, int n)
{
	std::vector<std::string> names{name + "[]"};
	for (int i = 0; i < n; ++i) names.push_back(name + "[" + std::to_string(i) + "]");
	return names;
}

/** Field names of sensor_msgs/Imu: ROS 1 has header.seq, ROS 2 not. */
std::vector<std::string> imuNames(bool ros1)
{
	std::vector<std::string> names;
	if (ros1) names.push_back("header.seq");
	for (const char* n : {"header.stamp", "header.frame_id", "orientation.x", "orientation.y",
	                      "orientation.z", "orientation.w"})
		names.push_back(n);
	const auto append = [&](const std::vector<std::string>& more)
	{ names.insert(names.end(), more.begin(), more.end()); };
	append(expectedArray("orientation_covariance", 9));
	append({"angular_velocity.x", "angular_velocity.y", "angular_velocity.z"});
	append(expectedArray("angular_velocity_covariance", 9));
	append({"linear_acceleration.x", "linear_acceleration.y", "linear_acceleration.z"});
	append(expectedArray("linear_acceleration_covariance", 9));
	return names;
}

// ------------------------------------------------------------ test messages

std_msgs::Header header(uint32_t seq, int i, const std::string& frame)
{
	std_msgs::Header h;
	h.seq = seq;
	h.stamp.sec = kSec0 + static_cast<uint32_t>(i);
	h.stamp.nsec = kNsec0;
	h.frame_id = frame;
	return h;
}

TimeNs stampNs(int i)
{
	return static_cast<TimeNs>(kSec0 + i) * kNs + kNsec0;
}
TimeNs recordNs(int i)
{
	return static_cast<TimeNs>(kSec0 + i) * kNs + 987654321;
}

sensor_msgs::Imu makeImu(int i)
{
	sensor_msgs::Imu m;
	m.header = header(100 + static_cast<uint32_t>(i), i, "imu_link");
	m.orientation.x = 0.1 * i;
	m.orientation.y = -0.2;
	m.orientation.z = 0.3;
	m.orientation.w = 0.9;
	for (std::size_t k = 0; k < 9; ++k)
	{
		m.orientation_covariance[k] = 1.0 + static_cast<double>(k);
		m.angular_velocity_covariance[k] = 10.0 + static_cast<double>(k);
		m.linear_acceleration_covariance[k] = 100.0 + static_cast<double>(k);
	}
	m.angular_velocity.x = 0.01;
	m.angular_velocity.y = -0.02;
	m.angular_velocity.z = 0.03 * i;
	m.linear_acceleration.x = 0.5;
	m.linear_acceleration.y = -0.25;
	m.linear_acceleration.z = 9.81;
	return m;
}

sensor_msgs::MagneticField makeMag(int i)
{
	sensor_msgs::MagneticField m;
	m.header = header(5, i, "mag");
	m.magnetic_field.x = 2.1e-5;
	m.magnetic_field.y = -3.5e-6;
	m.magnetic_field.z = 4.4e-5;
	m.magnetic_field_covariance[4] = 1e-12;
	return m;
}

sensor_msgs::FluidPressure makePressure(int i)
{
	sensor_msgs::FluidPressure m;
	m.header = header(6, i, "depth");
	m.fluid_pressure = 101325.0 + 1000.0 * i;
	m.variance = 4.0;
	return m;
}

sensor_msgs::NavSatFix makeFix(int i)
{
	sensor_msgs::NavSatFix m;
	m.header = header(7, i, "gps");
	m.status.status = sensor_msgs::NavSatStatus::STATUS_NO_FIX;
	m.status.service = sensor_msgs::NavSatStatus::SERVICE_GPS | sensor_msgs::NavSatStatus::SERVICE_GALILEO;
	m.latitude = 43.123456789;
	m.longitude = -8.987654321;
	m.altitude = -12.5;
	m.position_covariance[0] = 2.25;
	m.position_covariance[8] = 9.0;
	m.position_covariance_type = sensor_msgs::NavSatFix::COVARIANCE_TYPE_DIAGONAL_KNOWN;
	return m;
}

geometry_msgs::TwistWithCovarianceStamped makeTwist(int i)
{
	geometry_msgs::TwistWithCovarianceStamped m;
	m.header = header(8, i, "dvl");
	m.twist.twist.linear.x = 1.25;
	m.twist.twist.linear.y = -0.125;
	m.twist.twist.linear.z = 0.0625;
	m.twist.twist.angular.z = -0.5;
	m.twist.covariance[0] = 0.01;
	m.twist.covariance[35] = 0.36;
	return m;
}

nav_msgs::Odometry makeOdom(int i)
{
	nav_msgs::Odometry m;
	m.header = header(9, i, "odom");
	m.child_frame_id = "base_link";
	m.pose.pose.position.x = 10.5;
	m.pose.pose.position.y = -20.25;
	m.pose.pose.position.z = -3.0;
	m.pose.pose.orientation.w = 1.0;
	m.pose.covariance[7] = 0.7;
	m.twist.twist.linear.x = 1.5;
	m.twist.twist.angular.z = 0.05;
	m.twist.covariance[35] = 3.5;
	return m;
}

auvnav_test::DvlData makeDvl(int i, std::size_t ranges)
{
	auvnav_test::DvlData m;
	m.header = header(11, i, "dvl_link");
	m.beam_velocity = {0.5, -0.25, 0.125, 1.0 + i};
	for (std::size_t k = 0; k < ranges; ++k) m.ranges.push_back(10.0f + static_cast<float>(k) * 0.5f);
	m.bottom.velocity.x = 1.5;
	m.bottom.velocity.y = -0.75;
	m.bottom.velocity.z = 0.03125;
	m.bottom.quality = -7;
	m.bottom.age = ros::Duration(-2, 500000000);  // -1.5 s
	m.valid = i % 2 == 0;
	m.status = "lock " + std::to_string(i);
	return m;
}

/** A DVL message whose definition has one field more than its bytes. */
struct ShortDvl
{
	auvnav_test::DvlData data;
};

const char* const kShortDvlDefinition =
    "Header header\n"
    "float64[4] beam_velocity\n"
    "float32[] ranges\n"
    "Bottom bottom\n"
    "bool valid\n"
    "string status\n"
    "float64 extra\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n"
    "================================================================================\n"
    "MSG: auvnav_test/Bottom\n"
    "geometry_msgs/Vector3 velocity\n"
    "int8 quality\n"
    "duration age\n"
    "================================================================================\n"
    "MSG: geometry_msgs/Vector3\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n";
}  // namespace

namespace ros::message_traits
{
template <>
struct DataType<ShortDvl>
{
	static const char* value() { return "auvnav_test/ShortDvl"; }
	static const char* value(const ShortDvl&) { return value(); }
};
template <>
struct MD5Sum<ShortDvl>
{
	static const char* value() { return "fedcba9876543210fedcba9876543210"; }
	static const char* value(const ShortDvl&) { return value(); }
};
template <>
struct Definition<ShortDvl>
{
	static const char* value() { return kShortDvlDefinition; }
	static const char* value(const ShortDvl&) { return value(); }
};
}  // namespace ros::message_traits

namespace ros::serialization
{
template <>
struct Serializer<ShortDvl>
{
	template <typename Stream, typename T>
	inline static void allInOne(Stream& stream, T m)
	{
		stream.next(m.data);
	}
	ROS_DECLARE_ALLINONE_SERIALIZER
};
}  // namespace ros::serialization

namespace
{
const std::string& ros2Bag();

/** A ROS 1 bag with every supported standard type and the custom DVL type:
 *  3 messages per topic (DVL: 4, with 3, 3, 0, 5 ranges). */
const std::string& ros1Bag()
{
	static const std::string path = []
	{
		const std::string p = scratch("all_types.bag");
		Ros1BagWriter bag(p, 2048);  // small chunks: several chunks per bag
		for (int i = 0; i < 3; ++i)
		{
			bag.write("/imu", recordNs(i), makeImu(i));
			bag.write("/mag", recordNs(i), makeMag(i));
			bag.write("/depth", recordNs(i), makePressure(i));
			bag.write("/gps", recordNs(i), makeFix(i));
			bag.write("/dvl/twist", recordNs(i), makeTwist(i));
			bag.write("/odom", recordNs(i), makeOdom(i));
		}
		const std::size_t ranges[] = {3, 3, 0, 5};
		for (int i = 0; i < 4; ++i) bag.write("/dvl", recordNs(i), makeDvl(i, ranges[i]));
		bag.close();
		return p;
	}();
	return path;
}
}  // namespace

// ================================================================ definitions

TEST(MsgDefinition, FieldsConstantsCommentsAndArrays)
{
	const auto schema = msg::Schema::parse(
	    "pkg/Thing",
	    "# comment line\n"
	    "  int32 FOO=3\n"
	    "string S=abc # with = and # inside\n"
	    "int8 NEG = -1\n"
	    "float64[9] cov   # fixed\n"
	    "uint8[] data\n"
	    "Part[<=3] parts\n"
	    "string<=10 label\n"
	    "string<=4[2] short_names\n"
	    "int32 with_default 5\n"
	    "Header header\n"
	    "other_pkg/Item item\n"
	    "================================================================================\n"
	    "MSG: pkg/Part\n"
	    "time t\n"
	    "duration d\n"
	    "================================================================================\n"
	    "MSG: std_msgs/Header\n"
	    "uint32 seq\n"
	    "time stamp\n"
	    "string frame_id\n"
	    "================================================================================\n"
	    "MSG: other_pkg/Item\n"
	    "byte b\n"
	    "char c\n"
	    "================================================================================\n"
	    "MSG: unused/Broken\n"
	    "this is not a definition\n",
	    msg::Dialect::Ros1);
	const msg::MessageDef& root = schema->root();
	EXPECT_EQ(root.name, "pkg/Thing");
	ASSERT_EQ(root.fields.size(), 8u);
	EXPECT_EQ(root.fields[0].name, "cov");
	EXPECT_EQ(root.fields[0].array, msg::ArrayKind::Fixed);
	EXPECT_EQ(root.fields[0].fixed_size, 9u);
	EXPECT_EQ(root.fields[1].type, msg::FieldType::UInt8);
	EXPECT_EQ(root.fields[1].array, msg::ArrayKind::Sequence);
	EXPECT_EQ(root.fields[2].type_name, "pkg/Part");  // unqualified: the package of pkg/Thing
	EXPECT_EQ(root.fields[2].array, msg::ArrayKind::Sequence);
	ASSERT_NE(root.fields[2].message, nullptr);
	EXPECT_EQ(root.fields[2].message->fields[0].type, msg::FieldType::Time);
	EXPECT_EQ(root.fields[2].message->fields[1].type, msg::FieldType::Duration);
	EXPECT_EQ(root.fields[3].type, msg::FieldType::String);
	EXPECT_EQ(root.fields[4].array, msg::ArrayKind::Fixed);
	EXPECT_EQ(root.fields[4].type, msg::FieldType::String);
	EXPECT_EQ(root.fields[5].name, "with_default");
	EXPECT_EQ(root.fields[6].type_name, "std_msgs/Header");
	ASSERT_NE(root.fields[7].message, nullptr);
	EXPECT_EQ(root.fields[7].message->fields[0].type, msg::FieldType::Int8);  // ROS 1 byte
	EXPECT_EQ(root.fields[7].message->fields[1].type, msg::FieldType::UInt8);
}

TEST(MsgDefinition, Ros2NamesAndBuiltinInterfaces)
{
	const auto schema = msg::Schema::parse(
	    "pkg/msg/Stamped",
	    "std_msgs/Header header\n"
	    "builtin_interfaces/msg/Duration age\n"
	    "byte b\n"
	    "================================================================================\n"
	    "MSG: std_msgs/msg/Header\n"
	    "builtin_interfaces/Time stamp\n"
	    "string frame_id\n",
	    msg::Dialect::Ros2);
	EXPECT_EQ(schema->root().name, "pkg/Stamped");
	const msg::MessageDef* header = schema->root().fields[0].message;
	ASSERT_NE(header, nullptr);
	EXPECT_EQ(header->fields[0].type, msg::FieldType::Time);
	EXPECT_EQ(schema->root().fields[1].type, msg::FieldType::Duration);
	EXPECT_EQ(schema->root().fields[2].type, msg::FieldType::UInt8);  // ROS 2 byte: octet
	EXPECT_EQ(msg::normalizeTypeName("sensor_msgs/msg/Imu"), "sensor_msgs/Imu");
	EXPECT_EQ(msg::normalizeTypeName("sensor_msgs/Imu"), "sensor_msgs/Imu");
}

TEST(MsgDefinition, FallbackSuppliesMissingTypes)
{
	const auto fallback = [](const std::string& name) -> const char*
	{ return name == "geometry_msgs/Vector3" ? "float64 x\nfloat64 y\nfloat64 z\n" : nullptr; };
	const auto schema =
	    msg::Schema::parse("pkg/V", "geometry_msgs/Vector3 v\n", msg::Dialect::Ros2, fallback);
	ASSERT_NE(schema->root().fields[0].message, nullptr);
	EXPECT_EQ(schema->root().fields[0].message->fields.size(), 3u);
}

TEST(MsgDefinition, ErrorsNameTypeAndLine)
{
	const auto error = [](const std::string& text)
	{
		try
		{
			msg::Schema::parse("pkg/Main", text, msg::Dialect::Ros1);
		}
		catch (const msg::DefinitionError& e)
		{
			return std::string(e.what());
		}
		return std::string("no error");
	};
	EXPECT_NE(error("Missing m\n").find("no definition of type pkg/Missing (used by pkg/Main.m)"),
	          std::string::npos);
	EXPECT_NE(error("int32 a\nfloat64[x] b\n").find("line 2: cannot read type 'float64[x]'"),
	          std::string::npos);
	EXPECT_NE(error("int32\n").find("line 1"), std::string::npos);
	EXPECT_NE(error("wstring w\n").find("wstring is not supported"), std::string::npos);
	EXPECT_NE(error("Main again\n").find("contains itself"), std::string::npos);
	EXPECT_NE(error("A a\n===\nMSG: pkg/A\nB b\n===\nMSG: pkg/B\nA a\n").find("contains itself"),
	          std::string::npos);
	EXPECT_NE(error("int32 a\n===\nIDL: pkg/X\n").find("IDL"), std::string::npos);
}

// ================================================================ decoder

namespace
{
const char* const kDecoderDefinition =
    "Header header\n"
    "Beam[] beams\n"
    "uint8[] blob\n"
    "string name\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n"
    "================================================================================\n"
    "MSG: pkg/Beam\n"
    "float32 range\n"
    "int16[2] id\n";

/** ROS 1 bytes of kDecoderDefinition. */
std::vector<uint8_t> decoderMessage(uint32_t beams, uint32_t blob)
{
	std::vector<uint8_t> b;
	const auto put = [&](const void* p, std::size_t n)
	{ b.insert(b.end(), static_cast<const uint8_t*>(p), static_cast<const uint8_t*>(p) + n); };
	const auto u32 = [&](uint32_t v) { put(&v, 4); };
	u32(42);
	u32(kSec0);
	u32(kNsec0);
	u32(3);
	put("map", 3);
	u32(beams);
	for (uint32_t i = 0; i < beams; ++i)
	{
		const float range = 1.5f * static_cast<float>(i);
		put(&range, 4);
		const int16_t id[2] = {static_cast<int16_t>(i), -1};
		put(id, 4);
	}
	u32(blob);
	for (uint32_t i = 0; i < blob; ++i) b.push_back(static_cast<uint8_t>(i));
	u32(2);
	put("ok", 2);
	return b;
}
}  // namespace

TEST(FlatDecoder, FlattensNestedArraysAndTracksLayout)
{
	msg::FlatDecoder decoder(msg::Schema::parse("pkg/Sonar", kDecoderDefinition, msg::Dialect::Ros1),
	                         msg::WireFormat::Ros1);
	Record r;
	const auto two = decoderMessage(2, 3);
	decoder.decode(two.data(), two.size(), r);
	const std::vector<std::string> expected{"header.seq",
	                                        "header.stamp",
	                                        "header.frame_id",
	                                        "beams[]",
	                                        "beams[0].range",
	                                        "beams[0].id[]",
	                                        "beams[0].id[0]",
	                                        "beams[0].id[1]",
	                                        "beams[1].range",
	                                        "beams[1].id[]",
	                                        "beams[1].id[0]",
	                                        "beams[1].id[1]",
	                                        "blob[]",
	                                        "blob[0]",
	                                        "blob[1]",
	                                        "blob[2]",
	                                        "name"};
	EXPECT_EQ(r.names, expected);
	EXPECT_EQ(timeOf(r, "header.stamp"), stampNs(0));
	EXPECT_EQ(num(r, "beams[1].range"), 1.5);
	EXPECT_EQ(num(r, "beams[1].id[1]"), -1.0);
	EXPECT_EQ(num(r, "blob[2]"), 2.0);
	EXPECT_EQ(text(r, "name"), "ok");
	const uint64_t layout = r.layout_id;
	EXPECT_NE(layout, 0u);

	decoder.decode(two.data(), two.size(), r);
	EXPECT_EQ(r.layout_id, layout);  // same lengths, same layout

	// Byte arrays longer than kMaxFlattenedArray give their length only.
	const auto big = decoderMessage(1, static_cast<uint32_t>(kMaxFlattenedArray) + 1);
	decoder.decode(big.data(), big.size(), r);
	EXPECT_NE(r.layout_id, layout);
	EXPECT_EQ(num(r, "blob[]"), static_cast<double>(kMaxFlattenedArray + 1));
	EXPECT_EQ(r.indexOf("blob[0]"), -1);
	EXPECT_EQ(text(r, "name"), "ok");
	EXPECT_EQ(r.names.size(), r.values.size());
}

TEST(FlatDecoder, TruncatedAndCorruptBytesNeverCrash)
{
	msg::FlatDecoder decoder(msg::Schema::parse("pkg/Sonar", kDecoderDefinition, msg::Dialect::Ros1),
	                         msg::WireFormat::Ros1);
	const auto good = decoderMessage(3, 4);
	Record r;
	for (std::size_t n = 0; n < good.size(); ++n)
	{
		try
		{
			decoder.decode(good.data(), n, r);
			ADD_FAILURE() << "no error at " << n << " bytes";
		}
		catch (const msg::DecodeError& e)
		{
			EXPECT_NE(std::string(e.what()).find("message too short"), std::string::npos) << e.what();
		}
	}
	// The field that ends early is named.
	try
	{
		decoder.decode(good.data(), good.size() - 1, r);
	}
	catch (const msg::DecodeError& e)
	{
		EXPECT_NE(std::string(e.what()).find("field 'name' (string)"), std::string::npos) << e.what();
	}
	// A huge count is refused before anything is allocated.
	auto huge = good;
	const uint32_t count = 0xFFFFFFF0u;
	std::memcpy(huge.data() + 19, &count, 4);  // beams[] count
	try
	{
		decoder.decode(huge.data(), huge.size(), r);
		ADD_FAILURE() << "no error";
	}
	catch (const msg::DecodeError& e)
	{
		EXPECT_NE(std::string(e.what()).find("field 'beams' (pkg/Beam[]) has 4294967280 elements"),
		          std::string::npos)
		    << e.what();
	}
	// Random corruption: errors or values, never a crash or a hang.
	std::mt19937 rng(7);
	for (int trial = 0; trial < 3000; ++trial)
	{
		auto bad = good;
		const int flips = 1 + trial % 4;
		for (int k = 0; k < flips; ++k) bad[rng() % bad.size()] = static_cast<uint8_t>(rng());
		try
		{
			decoder.decode(bad.data(), bad.size(), r);
			EXPECT_EQ(r.names.size(), r.values.size());
		}
		catch (const msg::DecodeError&)
		{
		}
	}
	// Leftover bytes mean the definition does not match the data.
	auto longer = good;
	longer.push_back(0);
	try
	{
		decoder.decode(longer.data(), longer.size(), r);
		ADD_FAILURE() << "no error";
	}
	catch (const msg::DecodeError& e)
	{
		EXPECT_NE(std::string(e.what()).find("1 bytes left after the last field"), std::string::npos)
		    << e.what();
	}
}

// ================================================================ ROS 1

TEST(Ros1Bag, ImuFieldNamesValuesAndTimes)
{
	const auto source = openRos1Bag(ros1Bag(), "/imu");
	EXPECT_EQ(source->messageType(), "sensor_msgs/Imu");
	EXPECT_EQ(source->describe(), ros1Bag() + " topic /imu");
	const auto records = readAll(*source);
	ASSERT_EQ(records.size(), 3u);
	for (int i = 0; i < 3; ++i)
	{
		const Record& r = records[static_cast<std::size_t>(i)];
		EXPECT_EQ(r.names, imuNames(true));
		ASSERT_EQ(r.values.size(), r.names.size());
		EXPECT_TRUE(r.has_record_time);
		EXPECT_EQ(r.record_time_ns, recordNs(i));
		EXPECT_EQ(r.where, ros1Bag() + ": topic /imu message #" + std::to_string(i + 1));
		EXPECT_EQ(num(r, "header.seq"), 100 + i);
		EXPECT_EQ(timeOf(r, "header.stamp"), stampNs(i));
		EXPECT_EQ(text(r, "header.frame_id"), "imu_link");
		EXPECT_EQ(num(r, "orientation.x"), 0.1 * i);
		EXPECT_EQ(num(r, "orientation.w"), 0.9);
		EXPECT_EQ(num(r, "orientation_covariance[]"), 9);
		EXPECT_EQ(num(r, "orientation_covariance[8]"), 9.0);
		EXPECT_EQ(num(r, "angular_velocity.z"), 0.03 * i);
		EXPECT_EQ(num(r, "angular_velocity_covariance[0]"), 10.0);
		EXPECT_EQ(num(r, "linear_acceleration.z"), 9.81);
		EXPECT_EQ(num(r, "linear_acceleration_covariance[4]"), 104.0);
	}
	EXPECT_EQ(records[0].layout_id, records[2].layout_id);
}

namespace
{
using Opener = std::function<std::unique_ptr<RecordSource>(const std::string& topic)>;

/** The standard types of ros1Bag() / ros2Bag(): same names and values, except
 *  that ROS 2 headers have no seq. */
void expectStandardTypes(const Opener& open, bool ros1)
{
	const std::vector<std::string> header =
	    ros1 ? std::vector<std::string>{"header.seq", "header.stamp", "header.frame_id"}
	         : std::vector<std::string>{"header.stamp", "header.frame_id"};
	const auto withHeader = [&](std::vector<std::string> rest)
	{
		rest.insert(rest.begin(), header.begin(), header.end());
		return rest;
	};
	{
		const auto r = readAll(*open("/mag"));
		ASSERT_EQ(r.size(), 3u);
		std::vector<std::string> names =
		    withHeader({"magnetic_field.x", "magnetic_field.y", "magnetic_field.z"});
		for (const auto& n : expectedArray("magnetic_field_covariance", 9)) names.push_back(n);
		EXPECT_EQ(r[1].names, names);
		EXPECT_EQ(num(r[1], "magnetic_field.y"), -3.5e-6);
		EXPECT_EQ(num(r[1], "magnetic_field_covariance[4]"), 1e-12);
		EXPECT_EQ(timeOf(r[1], "header.stamp"), stampNs(1));
		EXPECT_EQ(r[1].record_time_ns, recordNs(1));
	}
	{
		const auto r = readAll(*open("/depth"));
		ASSERT_EQ(r.size(), 3u);
		EXPECT_EQ(r[2].names, withHeader({"fluid_pressure", "variance"}));
		EXPECT_EQ(num(r[2], "fluid_pressure"), 103325.0);
		EXPECT_EQ(num(r[2], "variance"), 4.0);
		EXPECT_EQ(text(r[2], "header.frame_id"), "depth");
	}
	{
		const auto r = readAll(*open("/gps"));
		ASSERT_EQ(r.size(), 3u);
		std::vector<std::string> names =
		    withHeader({"status.status", "status.service", "latitude", "longitude", "altitude"});
		for (const auto& n : expectedArray("position_covariance", 9)) names.push_back(n);
		names.push_back("position_covariance_type");
		EXPECT_EQ(r[0].names, names);  // constants are not fields
		EXPECT_EQ(num(r[0], "status.status"), -1.0);
		EXPECT_EQ(num(r[0], "status.service"), 9.0);
		EXPECT_EQ(num(r[0], "latitude"), 43.123456789);
		EXPECT_EQ(num(r[0], "longitude"), -8.987654321);
		EXPECT_EQ(num(r[0], "altitude"), -12.5);
		EXPECT_EQ(num(r[0], "position_covariance[8]"), 9.0);
		EXPECT_EQ(num(r[0], "position_covariance_type"), 2.0);
	}
	{
		const auto r = readAll(*open("/dvl/twist"));
		ASSERT_EQ(r.size(), 3u);
		std::vector<std::string> names =
		    withHeader({"twist.twist.linear.x", "twist.twist.linear.y", "twist.twist.linear.z",
		                "twist.twist.angular.x", "twist.twist.angular.y", "twist.twist.angular.z"});
		for (const auto& n : expectedArray("twist.covariance", 36)) names.push_back(n);
		EXPECT_EQ(r[0].names, names);
		EXPECT_EQ(num(r[0], "twist.twist.linear.x"), 1.25);
		EXPECT_EQ(num(r[0], "twist.twist.linear.y"), -0.125);
		EXPECT_EQ(num(r[0], "twist.twist.linear.z"), 0.0625);
		EXPECT_EQ(num(r[0], "twist.twist.angular.z"), -0.5);
		EXPECT_EQ(num(r[0], "twist.covariance[]"), 36.0);
		EXPECT_EQ(num(r[0], "twist.covariance[35]"), 0.36);
	}
	{
		const auto r = readAll(*open("/odom"));
		ASSERT_EQ(r.size(), 3u);
		std::vector<std::string> names =
		    withHeader({"child_frame_id", "pose.pose.position.x", "pose.pose.position.y",
		                "pose.pose.position.z", "pose.pose.orientation.x", "pose.pose.orientation.y",
		                "pose.pose.orientation.z", "pose.pose.orientation.w"});
		for (const auto& n : expectedArray("pose.covariance", 36)) names.push_back(n);
		for (const char* n : {"twist.twist.linear.x", "twist.twist.linear.y", "twist.twist.linear.z",
		                      "twist.twist.angular.x", "twist.twist.angular.y", "twist.twist.angular.z"})
			names.push_back(n);
		for (const auto& n : expectedArray("twist.covariance", 36)) names.push_back(n);
		EXPECT_EQ(r[0].names, names);
		EXPECT_EQ(text(r[0], "child_frame_id"), "base_link");
		EXPECT_EQ(num(r[0], "pose.pose.position.y"), -20.25);
		EXPECT_EQ(num(r[0], "pose.pose.orientation.w"), 1.0);
		EXPECT_EQ(num(r[0], "pose.covariance[7]"), 0.7);
		EXPECT_EQ(num(r[0], "twist.twist.linear.x"), 1.5);
		EXPECT_EQ(num(r[0], "twist.covariance[35]"), 3.5);
	}
}

/** The DVL records of ros1Bag() / ros2Bag(). */
void expectDvl(const std::vector<Record>& r, bool ros1)
{
	ASSERT_EQ(r.size(), 4u);
	std::vector<std::string> names{"header.stamp", "header.frame_id"};
	if (ros1) names.insert(names.begin(), "header.seq");
	for (const auto& n : expectedArray("beam_velocity", 4)) names.push_back(n);
	for (const auto& n : expectedArray("ranges", 3)) names.push_back(n);
	for (const char* n : {"bottom.velocity.x", "bottom.velocity.y", "bottom.velocity.z", "bottom.quality",
	                      "bottom.age", "valid", "status"})
		names.push_back(n);
	EXPECT_EQ(r[0].names, names);
	EXPECT_EQ(timeOf(r[0], "header.stamp"), stampNs(0));
	EXPECT_EQ(text(r[0], "header.frame_id"), "dvl_link");
	EXPECT_EQ(num(r[0], "beam_velocity[1]"), -0.25);
	EXPECT_EQ(num(r[0], "beam_velocity[3]"), 1.0);
	EXPECT_EQ(num(r[0], "ranges[]"), 3.0);
	EXPECT_EQ(num(r[0], "ranges[2]"), 11.0);
	EXPECT_EQ(num(r[0], "bottom.velocity.x"), 1.5);
	EXPECT_EQ(num(r[0], "bottom.velocity.y"), -0.75);
	EXPECT_EQ(num(r[0], "bottom.velocity.z"), 0.03125);
	EXPECT_EQ(num(r[0], "bottom.quality"), -7.0);
	EXPECT_EQ(timeOf(r[0], "bottom.age"), -1500000000);
	EXPECT_EQ(num(r[0], "valid"), 1.0);
	EXPECT_EQ(num(r[1], "valid"), 0.0);
	EXPECT_EQ(text(r[3], "status"), "lock 3");
	EXPECT_EQ(num(r[3], "beam_velocity[3]"), 4.0);
	EXPECT_EQ(r[3].record_time_ns, recordNs(3));

	// The layout changes with the length of `ranges`, and only then.
	EXPECT_EQ(r[0].layout_id, r[1].layout_id);
	EXPECT_NE(r[1].layout_id, r[2].layout_id);
	EXPECT_NE(r[2].layout_id, r[3].layout_id);
	EXPECT_EQ(num(r[2], "ranges[]"), 0.0);
	EXPECT_EQ(r[2].indexOf("ranges[0]"), -1);
	EXPECT_EQ(num(r[3], "ranges[4]"), 12.0);
	for (const Record& x : r) EXPECT_EQ(x.names.size(), x.values.size());
}
}  // namespace

TEST(Ros1Bag, StandardSensorTypes)
{
	expectStandardTypes([](const std::string& topic) { return openRos1Bag(ros1Bag(), topic); }, true);
}

TEST(Ros1Bag, CustomTypeUsesTheStoredDefinition)
{
	const auto source = openRos1Bag(ros1Bag(), "/dvl");
	EXPECT_EQ(source->messageType(), "auvnav_test/DvlData");
	const auto r = readAll(*source);
	expectDvl(r, true);
	EXPECT_EQ(num(r[0], "header.seq"), 11.0);
	EXPECT_EQ(r[0].indexOf("STATUS_OK"), -1);
	EXPECT_EQ(r[0].indexOf("NOTE"), -1);
}

TEST(Ros1Bag, NumericTimeFieldNeedsAFormat)
{
	// A bag's number has no unit: taking a float64 (here fluid_pressure, 101325
	// + 1000 i) as seconds without time.format would be a silent 1e3..1e9 error.
	const fs::path dir = fs::path(scratch("numeric_time_dir"));
	fs::create_directories(dir);
	auto import = [&](const std::string& time)
	{
		std::ofstream(dir / "spec.yaml") << "sensors:\n  - {label: P, class: pressure, source: {ros1: '" +
		                                        ros1Bag() + "', topic: /depth}, time: " + time +
		                                        ", pressure_reference: absolute}\n";
		ImportOptions opt;
		opt.spec_path = (dir / "spec.yaml").string();
		opt.inputs = {ros1Bag()};
		opt.out_rawlog = (dir / "out.rawlog").string();
		opt.lenient = true;  // a spec error stops the import even so
		ImportReport rep;
		try
		{
			runImport(opt, rep);
		}
		catch (const ImportError& e)
		{
			return std::string(e.what());
		}
		return std::string();
	};
	const std::string err = import("{field: fluid_pressure}");
	EXPECT_NE(err.find("time.format"), std::string::npos) << err;
	EXPECT_NE(err.find("fluid_pressure"), std::string::npos) << err;
	ASSERT_EQ(import("{field: fluid_pressure, format: ms}"), "");
	auvnav::io::RawlogReader r((dir / "out.rawlog").string());
	const auto o = r.next();
	ASSERT_TRUE(o);
	EXPECT_EQ(fromMrptTime(o->timestamp), 101325000000LL);  // 101325 ms
}

TEST(Ros1Bag, CompressedChunks)
{
	for (const auto compression : {rosbag::compression::BZ2, rosbag::compression::LZ4})
	{
		const std::string path =
		    scratch("compressed_" + std::to_string(static_cast<int>(compression)) + ".bag");
		{
			Ros1BagWriter bag(path, 2048, compression);
			const std::size_t ranges[] = {3, 3, 0, 5};
			for (int i = 0; i < 4; ++i) bag.write("/dvl", recordNs(i), makeDvl(i, ranges[i]));
			for (int i = 0; i < 3; ++i) bag.write("/imu", recordNs(i), makeImu(i));
		}
		expectDvl(readAll(*openRos1Bag(path, "/dvl")), true);
		const auto imu = readAll(*openRos1Bag(path, "/imu"));
		ASSERT_EQ(imu.size(), 3u);
		EXPECT_EQ(num(imu[2], "angular_velocity.z"), 0.03 * 2);
	}
}

TEST(Ros1Bag, ListsTopics)
{
	const auto topics = listRos1Topics(ros1Bag());
	const std::vector<std::pair<std::string, std::string>> expected{
	    {"/depth", "sensor_msgs/FluidPressure"},
	    {"/dvl", "auvnav_test/DvlData"},
	    {"/dvl/twist", "geometry_msgs/TwistWithCovarianceStamped"},
	    {"/gps", "sensor_msgs/NavSatFix"},
	    {"/imu", "sensor_msgs/Imu"},
	    {"/mag", "sensor_msgs/MagneticField"},
	    {"/odom", "nav_msgs/Odometry"}};
	EXPECT_EQ(topics, expected);
}

TEST(Ros1Bag, MissingTopicListsTheTopics)
{
	const std::string e = errorOf([] { openRos1Bag(ros1Bag(), "/usbl"); });
	EXPECT_NE(e.find(ros1Bag()), std::string::npos) << e;
	EXPECT_NE(e.find("no topic '/usbl'"), std::string::npos) << e;
	EXPECT_NE(e.find("/imu (sensor_msgs/Imu)"), std::string::npos) << e;
	EXPECT_NE(e.find("/dvl (auvnav_test/DvlData)"), std::string::npos) << e;
}

TEST(Ros1Bag, MissingForeignAndEmptyFiles)
{
	const std::string missing = scratch("no_such.bag");
	std::string e = errorOf([&] { openRos1Bag(missing, "/imu"); });
	EXPECT_NE(e.find(missing + ": cannot open"), std::string::npos) << e;

	const std::string textfile = scratch("notes.bag");
	std::ofstream(textfile) << "time,depth\n0,1\n";
	e = errorOf([&] { openRos1Bag(textfile, "/imu"); });
	EXPECT_NE(e.find(textfile + ": not a ROS 1 bag"), std::string::npos) << e;
	e = errorOf([&] { listRos1Topics(textfile); });
	EXPECT_NE(e.find(textfile + ": not a ROS 1 bag"), std::string::npos) << e;

	const std::string empty = scratch("empty.bag");
	std::ofstream{empty};
	e = errorOf([&] { openRos1Bag(empty, "/imu"); });
	EXPECT_NE(e.find(empty + ": not a ROS 1 bag"), std::string::npos) << e;

	e = errorOf([&] { openRos1Bag(scratchDir().string(), "/imu"); });
	EXPECT_NE(e.find("is a directory"), std::string::npos) << e;

	const std::string old_format = scratch("old.bag");
	std::ofstream(old_format) << "#ROSBAG V1.2\n" << std::string(100, '\0');
	e = errorOf([&] { openRos1Bag(old_format, "/imu"); });
	EXPECT_NE(e.find(old_format + ": ROS bag format 1.2 is not supported"), std::string::npos) << e;

	const std::string& db3 = ros2Bag();
	e = errorOf([&] { openRos1Bag(db3, "/imu"); });
	EXPECT_NE(e.find(db3 + ": not a ROS 1 bag: it is an SQLite database"), std::string::npos) << e;
}

TEST(Ros1Bag, TruncatedBagsAreReportedNotCrashed)
{
	const std::uintmax_t size = fs::file_size(ros1Bag());
	for (const std::uintmax_t keep :
	     {std::uintmax_t{13}, std::uintmax_t{20}, std::uintmax_t{4200}, size / 2, size - 100, size - 1})
	{
		const std::string cut = scratch("cut_" + std::to_string(keep) + ".bag");
		truncateCopy(ros1Bag(), cut, keep);
		const std::string e = drain(cut, "/imu", false);
		EXPECT_NE(e.find(cut + ": "), std::string::npos) << e;
		EXPECT_NE(e.find("truncated"), std::string::npos) << keep << ": " << e;
	}
}

TEST(Ros1Bag, UnindexedBag)
{
	// As left by a recorder that was killed: the header's index_pos is 0.
	const std::string path = scratch("unindexed.bag");
	fs::copy_file(ros1Bag(), path, fs::copy_options::overwrite_existing);
	std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
	std::string head(4096, '\0');
	f.read(head.data(), static_cast<std::streamsize>(head.size()));
	const auto at = head.find("index_pos=");
	ASSERT_NE(at, std::string::npos);
	f.clear();
	f.seekp(static_cast<std::streamoff>(at + 10));
	const char zeros[8] = {};
	f.write(zeros, 8);
	f.close();
	const std::string e = drain(path, "/imu", false);
	EXPECT_NE(e.find(path + ": unindexed ROS 1 bag"), std::string::npos) << e;
}

TEST(Ros1Bag, MessageShorterThanItsDefinition)
{
	const std::string path = scratch("short.bag");
	{
		Ros1BagWriter bag(path);
		for (int i = 0; i < 3; ++i) bag.write("/dvl", recordNs(i), ShortDvl{makeDvl(i, 2)});
	}
	const std::string e = drain(path, "/dvl", false);
	EXPECT_NE(e.find(path + ": topic /dvl message #1"), std::string::npos) << e;
	EXPECT_NE(e.find("field 'extra' (float64)"), std::string::npos) << e;
	EXPECT_NE(e.find("message too short"), std::string::npos) << e;
}

TEST(Ros1Bag, ManySmallMessagesAllDecode)
{
	constexpr int kCount = 100000;
	const std::string path = scratch("many.bag");
	{
		Ros1BagWriter bag(path);
		for (int i = 0; i < kCount; ++i)
		{
			auto m = makePressure(0);
			m.fluid_pressure = i;
			bag.write("/depth", recordNs(0) + i * 10000000LL, m);
		}
	}
	const auto start = std::chrono::steady_clock::now();
	const auto source = openRos1Bag(path, "/depth");
	Record r;
	int n = 0;
	double sum = 0;
	while (source->next(r))
	{
		sum += r.values[3].number;
		EXPECT_EQ(r.record_time_ns, recordNs(0) + n * 10000000LL);
		++n;
	}
	const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
	EXPECT_EQ(n, kCount);
	EXPECT_EQ(sum, 0.5 * kCount * (kCount - 1.0));
	std::printf("ROS 1: %d messages in %.3f s\n", kCount, seconds);
}

TEST(Ros1Bag, DamagedBagsNeverCrash)
{
	// Random bytes changed anywhere: headers, index, connection records,
	// message data. Each case must end in values or an ImportError.
	std::ifstream in(ros1Bag(), std::ios::binary);
	const std::string good((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
	const std::string path = scratch("damaged.bag");
	std::mt19937 rng(11);
	const char* const topics[] = {"/imu", "/dvl", "/odom", "/gps"};
	int errors = 0;
	for (int trial = 0; trial < 300; ++trial)
	{
		std::string bad = good;
		for (int k = 0; k < 1 + trial % 5; ++k) bad[rng() % bad.size()] = static_cast<char>(rng());
		std::ofstream(path, std::ios::binary | std::ios::trunc) << bad;
		try
		{
			const auto source = openRos1Bag(path, topics[trial % 4]);
			Record r;
			while (source->next(r)) EXPECT_EQ(r.names.size(), r.values.size());
		}
		catch (const ImportError& e)
		{
			EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
			++errors;
		}
	}
	EXPECT_GT(errors, 0);
}

// ================================================================ ROS 2

namespace
{
/** A ROS 2 bag (rosbag2 Jazzy layout) with the standard types (no stored
 *  definitions: the bundled ones are used) and the custom DVL type (stored
 *  definition). Messages are written out of time order. */
const std::string& ros2Bag()
{
	static const std::string path = []
	{
		const std::string p = scratch("all_types.db3");
		Ros2BagWriter bag(p);
		bag.addTopic("/imu", "sensor_msgs/msg/Imu");
		bag.addTopic("/mag", "sensor_msgs/msg/MagneticField");
		bag.addTopic("/depth", "sensor_msgs/msg/FluidPressure");
		bag.addTopic("/gps", "sensor_msgs/msg/NavSatFix");
		bag.addTopic("/dvl/twist", "geometry_msgs/msg/TwistWithCovarianceStamped");
		bag.addTopic("/odom", "nav_msgs/msg/Odometry");
		bag.addTopic("/dvl", "auvnav_test/msg/DvlData", auvnav_test::kDvlDataRos2Definition);
		for (int i : {2, 0, 1})
		{
			bag.write("/imu", recordNs(i), toRos2Cdr(makeImu(i)));
			bag.write("/mag", recordNs(i), toRos2Cdr(makeMag(i)));
			bag.write("/depth", recordNs(i), toRos2Cdr(makePressure(i)));
			bag.write("/gps", recordNs(i), toRos2Cdr(makeFix(i)));
			bag.write("/dvl/twist", recordNs(i), toRos2Cdr(makeTwist(i)));
			bag.write("/odom", recordNs(i), toRos2Cdr(makeOdom(i)));
		}
		const std::size_t ranges[] = {3, 3, 0, 5};
		for (int i = 0; i < 4; ++i) bag.write("/dvl", recordNs(i), toRos2Cdr(makeDvl(i, ranges[i])));
		bag.close();
		return p;
	}();
	return path;
}

void sqlExec(const std::string& db3, const std::string& sql)
{
	sqlite3* db = nullptr;
	ASSERT_EQ(sqlite3_open(db3.c_str(), &db), SQLITE_OK);
	EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
	sqlite3_close(db);
}
}  // namespace

TEST(Ros2Bag, ImuFieldNamesValuesAndTimes)
{
	const auto source = openRos2Bag(ros2Bag(), "/imu");
	EXPECT_EQ(source->messageType(), "sensor_msgs/msg/Imu");
	EXPECT_EQ(source->describe(), ros2Bag() + " topic /imu");
	const auto records = readAll(*source);
	ASSERT_EQ(records.size(), 3u);
	for (int i = 0; i < 3; ++i)
	{
		const Record& r = records[static_cast<std::size_t>(i)];
		EXPECT_EQ(r.names, imuNames(false));
		ASSERT_EQ(r.values.size(), r.names.size());
		EXPECT_TRUE(r.has_record_time);
		EXPECT_EQ(r.record_time_ns, recordNs(i));  // sorted by timestamp
		EXPECT_EQ(r.where, ros2Bag() + ": topic /imu message #" + std::to_string(i + 1));
		EXPECT_EQ(timeOf(r, "header.stamp"), stampNs(i));
		EXPECT_EQ(text(r, "header.frame_id"), "imu_link");
		EXPECT_EQ(num(r, "orientation.x"), 0.1 * i);
		EXPECT_EQ(num(r, "orientation.w"), 0.9);
		EXPECT_EQ(num(r, "orientation_covariance[]"), 9);
		EXPECT_EQ(num(r, "orientation_covariance[8]"), 9.0);
		EXPECT_EQ(num(r, "angular_velocity.z"), 0.03 * i);
		EXPECT_EQ(num(r, "angular_velocity_covariance[0]"), 10.0);
		EXPECT_EQ(num(r, "linear_acceleration.z"), 9.81);
		EXPECT_EQ(num(r, "linear_acceleration_covariance[4]"), 104.0);
	}
	EXPECT_EQ(records[0].layout_id, records[2].layout_id);
}

TEST(Ros2Bag, StandardSensorTypesFromBundledDefinitions)
{
	expectStandardTypes([](const std::string& topic) { return openRos2Bag(ros2Bag(), topic); }, false);
}

TEST(Ros2Bag, CustomTypeUsesTheStoredDefinition)
{
	const auto source = openRos2Bag(ros2Bag(), "/dvl");
	EXPECT_EQ(source->messageType(), "auvnav_test/msg/DvlData");
	expectDvl(readAll(*source), false);
}

TEST(Ros2Bag, BigEndianCdr)
{
	const std::string path = scratch("big_endian.db3");
	{
		Ros2BagWriter bag(path);
		bag.addTopic("/dvl", "auvnav_test/msg/DvlData", auvnav_test::kDvlDataRos2Definition);
		const std::size_t ranges[] = {3, 3, 0, 5};
		for (int i = 0; i < 4; ++i) bag.write("/dvl", recordNs(i), toRos2Cdr(makeDvl(i, ranges[i]), false));
	}
	expectDvl(readAll(*openRos2Bag(path, "/dvl")), false);
}

TEST(Ros2Bag, ListsTopics)
{
	const std::vector<std::pair<std::string, std::string>> expected{
	    {"/depth", "sensor_msgs/msg/FluidPressure"},
	    {"/dvl", "auvnav_test/msg/DvlData"},
	    {"/dvl/twist", "geometry_msgs/msg/TwistWithCovarianceStamped"},
	    {"/gps", "sensor_msgs/msg/NavSatFix"},
	    {"/imu", "sensor_msgs/msg/Imu"},
	    {"/mag", "sensor_msgs/msg/MagneticField"},
	    {"/odom", "nav_msgs/msg/Odometry"}};
	EXPECT_EQ(listRos2Topics(ros2Bag()), expected);
}

TEST(Ros2Bag, FolderWithSplitFiles)
{
	// rosbag2 splits as <name>_0.db3, <name>_1.db3, ..., <name>_10.db3: the
	// order is numeric, not by name.
	const fs::path dir = scratchDir() / "split_bag";
	fs::create_directories(dir);
	std::ofstream(dir / "metadata.yaml") << "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n";
	{
		Ros2BagWriter bag((dir / "split_bag_2.db3").string());
		bag.addTopic("/depth", "sensor_msgs/msg/FluidPressure");
		bag.write("/depth", recordNs(0), toRos2Cdr(makePressure(0)));
		bag.write("/depth", recordNs(1), toRos2Cdr(makePressure(1)));
		bag.write("/depth", recordNs(1), toRos2Cdr(makePressure(5)));  // same time: in written order
	}
	{
		Ros2BagWriter bag((dir / "split_bag_10.db3").string());
		bag.addTopic("/imu", "sensor_msgs/msg/Imu");  // other topic ids in this file
		bag.addTopic("/depth", "sensor_msgs/msg/FluidPressure");
		bag.write("/imu", recordNs(2), toRos2Cdr(makeImu(2)));
		bag.write("/depth", recordNs(2), toRos2Cdr(makePressure(2)));
	}
	const auto r = readAll(*openRos2Bag(dir.string(), "/depth"));
	ASSERT_EQ(r.size(), 4u);
	EXPECT_EQ(num(r[0], "fluid_pressure"), 101325.0);
	EXPECT_EQ(num(r[1], "fluid_pressure"), 102325.0);
	EXPECT_EQ(num(r[2], "fluid_pressure"), 106325.0);
	EXPECT_EQ(num(r[3], "fluid_pressure"), 103325.0);
	EXPECT_EQ(r[3].record_time_ns, recordNs(2));
	EXPECT_EQ(r[0].where, (dir / "split_bag_2.db3").string() + ": topic /depth message #1");
	EXPECT_EQ(r[3].where, (dir / "split_bag_10.db3").string() + ": topic /depth message #4");
	EXPECT_EQ(r[0].layout_id, r[3].layout_id);  // one layout across the files
	const std::vector<std::pair<std::string, std::string>> topics{{"/depth", "sensor_msgs/msg/FluidPressure"},
	                                                              {"/imu", "sensor_msgs/msg/Imu"}};
	EXPECT_EQ(listRos2Topics(dir.string()), topics);
	EXPECT_EQ(readAll(*openRos2Bag(dir.string(), "/imu")).size(), 1u);
}

TEST(Ros2Bag, HumbleBagWithoutDefinitionsTable)
{
	const std::string path = scratch("humble.db3");
	{
		Ros2BagWriter bag(path, Ros2BagWriter::Layout::Humble);
		bag.addTopic("/imu", "sensor_msgs/msg/Imu");
		bag.addTopic("/dvl", "auvnav_test/msg/DvlData");
		bag.write("/imu", recordNs(0), toRos2Cdr(makeImu(0)));
		bag.write("/dvl", recordNs(0), toRos2Cdr(makeDvl(0, 1)));
	}
	const auto imu = readAll(*openRos2Bag(path, "/imu"));
	ASSERT_EQ(imu.size(), 1u);
	EXPECT_EQ(imu[0].names, imuNames(false));
	EXPECT_EQ(num(imu[0], "linear_acceleration.z"), 9.81);

	const std::string e = errorOf([&] { openRos2Bag(path, "/dvl"); });
	EXPECT_NE(e.find(path + ": topic /dvl (auvnav_test/msg/DvlData): the bag stores no definition"),
	          std::string::npos)
	    << e;
	EXPECT_NE(e.find("sensor_msgs/Imu"), std::string::npos) << e;  // the bundled types are listed
}

TEST(Ros2Bag, MissingTopicListsTheTopics)
{
	const std::string e = errorOf([] { openRos2Bag(ros2Bag(), "/usbl"); });
	EXPECT_NE(e.find(ros2Bag() + ": no topic '/usbl'"), std::string::npos) << e;
	EXPECT_NE(e.find("/imu (sensor_msgs/msg/Imu)"), std::string::npos) << e;
	EXPECT_NE(e.find("/dvl (auvnav_test/msg/DvlData)"), std::string::npos) << e;
}

TEST(Ros2Bag, MissingForeignAndEmptyFiles)
{
	const std::string missing = scratch("no_such.db3");
	std::string e = errorOf([&] { openRos2Bag(missing, "/imu"); });
	EXPECT_NE(e.find(missing + ": cannot open"), std::string::npos) << e;

	const std::string textfile = scratch("notes.db3");
	std::ofstream(textfile) << "time,depth\n0,1\n" << std::string(2000, 'x');
	e = errorOf([&] { openRos2Bag(textfile, "/imu"); });
	EXPECT_NE(e.find(textfile + ": cannot read the database: not an SQLite database"), std::string::npos)
	    << e;
	e = errorOf([&] { listRos2Topics(textfile); });
	EXPECT_NE(e.find(textfile + ": cannot read the database: not an SQLite database"), std::string::npos)
	    << e;

	e = errorOf([&] { openRos2Bag(ros1Bag(), "/imu"); });
	EXPECT_NE(e.find(ros1Bag() + ": cannot read the database: not an SQLite database"), std::string::npos)
	    << e;

	const std::string other = scratch("other.sqlite");
	fs::remove(other);
	sqlExec(other, "CREATE TABLE samples(t INTEGER, depth REAL)");
	e = errorOf([&] { openRos2Bag(other, "/imu"); });
	EXPECT_NE(e.find(other + ": not a rosbag2 database"), std::string::npos) << e;

	const fs::path empty_dir = scratchDir() / "empty_bag";
	fs::create_directories(empty_dir);
	e = errorOf([&] { openRos2Bag(empty_dir.string(), "/imu"); });
	EXPECT_NE(e.find(empty_dir.string() + ": no .db3 file"), std::string::npos) << e;

	const fs::path mcap_dir = scratchDir() / "mcap_bag";
	fs::create_directories(mcap_dir);
	std::ofstream(mcap_dir / "mcap_bag_0.mcap") << "\x89MCAP0\r\n";
	e = errorOf([&] { openRos2Bag(mcap_dir.string(), "/imu"); });
	EXPECT_NE(e.find(mcap_dir.string() + ": MCAP rosbag2 storage is not supported"), std::string::npos) << e;
}

TEST(Ros2Bag, TruncatedDatabase)
{
	const std::string path = scratch("long.db3");
	{
		Ros2BagWriter bag(path);
		bag.addTopic("/imu", "sensor_msgs/msg/Imu");
		for (int i = 0; i < 3000; ++i) bag.write("/imu", recordNs(0) + i * 10000000LL, toRos2Cdr(makeImu(i)));
	}
	const std::uintmax_t size = fs::file_size(path);
	for (const std::uintmax_t keep : {size / 4, size / 2, size - 4096, size - 1})
	{
		const std::string cut = scratch("cut_" + std::to_string(keep) + ".db3");
		truncateCopy(path, cut, keep);
		const std::string e = drain(cut, "/imu", true);
		EXPECT_NE(e.find(cut + ": "), std::string::npos) << e;
		EXPECT_NE(e.find("truncated or damaged"), std::string::npos) << keep << ": " << e;
	}
}

TEST(Ros2Bag, MessageShorterThanItsDefinition)
{
	const std::string path = scratch("short.db3");
	{
		Ros2BagWriter bag(path);
		bag.addTopic("/imu", "sensor_msgs/msg/Imu");
		bag.write("/imu", recordNs(0), toRos2Cdr(makeImu(0)));
		auto cut = toRos2Cdr(makeImu(1));
		cut.resize(cut.size() - 12);
		bag.write("/imu", recordNs(1), cut);
	}
	const std::string e = drain(path, "/imu", true);
	EXPECT_NE(e.find(path + ": topic /imu message #2 (sensor_msgs/msg/Imu): message too short"),
	          std::string::npos)
	    << e;
	EXPECT_NE(e.find("field 'linear_acceleration_covariance[7]' (float64)"), std::string::npos) << e;
}

TEST(Ros2Bag, UnsupportedEncodings)
{
	const std::string path = scratch("xcdr2.db3");
	{
		Ros2BagWriter bag(path);
		bag.addTopic("/depth", "sensor_msgs/msg/FluidPressure");
		auto bytes = toRos2Cdr(makePressure(0));
		bytes[1] = 0x07;  // XCDR2 little endian
		bag.write("/depth", recordNs(0), bytes);
		bag.addTopic("/json", "sensor_msgs/msg/FluidPressure");
	}
	std::string e = drain(path, "/depth", true);
	EXPECT_NE(e.find(path + ": topic /depth message #1"), std::string::npos) << e;
	EXPECT_NE(e.find("unsupported CDR encapsulation 0x0007"), std::string::npos) << e;

	sqlExec(path, "UPDATE topics SET serialization_format = 'json' WHERE name = '/json'");
	e = errorOf([&] { openRos2Bag(path, "/json"); });
	EXPECT_NE(e.find(path + ": topic /json: serialization format 'json' is not supported"), std::string::npos)
	    << e;
}

TEST(Ros2Bag, CorruptCdrNeverCrashes)
{
	const auto schema = msg::Schema::parse("auvnav_test/msg/DvlData", auvnav_test::kDvlDataRos2Definition,
	                                       msg::Dialect::Ros2);
	msg::FlatDecoder decoder(schema, msg::WireFormat::Cdr);
	const auto good = toRos2Cdr(makeDvl(1, 4));
	Record r;
	decoder.decode(good.data(), good.size(), r);
	EXPECT_EQ(num(r, "ranges[3]"), 11.5);
	for (std::size_t n = 0; n + 4 <= good.size(); ++n)  // every cut that is not padding
	{
		try
		{
			decoder.decode(good.data(), n, r);
			EXPECT_GE(n + 8, good.size()) << "decoded " << n << " of " << good.size() << " bytes";
		}
		catch (const msg::DecodeError&)
		{
		}
	}
	std::mt19937 rng(3);
	for (int trial = 0; trial < 3000; ++trial)
	{
		auto bad = good;
		for (int k = 0; k < 1 + trial % 4; ++k)
			bad[4 + rng() % (bad.size() - 4)] = static_cast<uint8_t>(rng());
		try
		{
			decoder.decode(bad.data(), bad.size(), r);
			EXPECT_EQ(r.names.size(), r.values.size());
		}
		catch (const msg::DecodeError&)
		{
		}
	}
}

TEST(Ros2Bag, ManySmallMessagesAllDecode)
{
	constexpr int kCount = 100000;
	const std::string path = scratch("many.db3");
	{
		Ros2BagWriter bag(path);
		bag.addTopic("/depth", "sensor_msgs/msg/FluidPressure");
		for (int i = 0; i < kCount; ++i)
		{
			auto m = makePressure(0);
			m.fluid_pressure = i;
			bag.write("/depth", recordNs(0) + i * 10000000LL, toRos2Cdr(m));
		}
	}
	const auto start = std::chrono::steady_clock::now();
	const auto source = openRos2Bag(path, "/depth");
	Record r;
	int n = 0;
	double sum = 0;
	while (source->next(r))
	{
		sum += r.values[2].number;
		EXPECT_EQ(r.record_time_ns, recordNs(0) + n * 10000000LL);
		++n;
	}
	const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
	EXPECT_EQ(n, kCount);
	EXPECT_EQ(sum, 0.5 * kCount * (kCount - 1.0));
	std::printf("ROS 2: %d messages in %.3f s\n", kCount, seconds);
}

namespace
{
/** Removes the scratch folder after the last test. */
class ScratchCleanup : public ::testing::Environment
{
 public:
	void TearDown() override
	{
		std::error_code ec;
		fs::remove_all(scratchDir(), ec);
	}
};
const auto* const g_cleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);
}  // namespace
