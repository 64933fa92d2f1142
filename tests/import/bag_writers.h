#pragma once
/** @file bag_writers.h
 *  Test-only writers of ROS 1 and ROS 2 bags, for the bag-reader tests and the
 *  importer round-trip test. Nothing here is part of auvnav.
 *
 *  - Ros1BagWriter: a ROS 1 bag through rosbag_storage, with any message type
 *    that has ROS 1 C++ traits (sensor_msgs::Imu, ..., auvnav_test::DvlData).
 *  - CdrWriter: the bytes of one ROS 2 message (CDR encapsulation header, then
 *    XCDR1: each primitive aligned to its size, at most 8, counted from the
 *    byte after the header).
 *  - toRos2Cdr(): the ROS 2 CDR of a standard message, filled from the ROS 1
 *    C++ message of the same name (ROS 2 has no `header.seq`, which is dropped;
 *    stamps keep their sec/nsec).
 *  - Ros2BagWriter: a rosbag2 SQLite file (`.db3`).
 *
 *  Every function throws std::runtime_error when writing fails.
 */
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <geometry_msgs/Vector3.h>
#include <nav_msgs/Odometry.h>
#include <ros/duration.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <sensor_msgs/FluidPressure.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>
#include <sensor_msgs/NavSatFix.h>
#include <std_msgs/Header.h>

#include <boost/array.hpp>

#include <cstdint>
#include <string>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

// ---------------------------------------------------------------------------
// A DVL message type that exists only in these tests: a reader that decodes it
// must have used the definition stored in the bag.
namespace auvnav_test
{
struct Bottom
{
	geometry_msgs::Vector3 velocity;
	int8_t quality = 0;
	ros::Duration age;
};

struct DvlData
{
	std_msgs::Header header;
	boost::array<double, 4> beam_velocity{};
	std::vector<float> ranges;
	Bottom bottom;
	uint8_t valid = 0;  //!< ROS 1 bool
	std::string status;
};

/** `auvnav_test/DvlData` as a ROS 1 bag stores it (with its dependencies). */
extern const char* const kDvlDataRos1Definition;
/** `auvnav_test/msg/DvlData` in rosbag2's `ros2msg` encoding (with its dependencies). */
extern const char* const kDvlDataRos2Definition;
}  // namespace auvnav_test

namespace ros::message_traits
{
template <>
struct DataType<auvnav_test::DvlData>
{
	static const char* value() { return "auvnav_test/DvlData"; }
	static const char* value(const auvnav_test::DvlData&) { return value(); }
};
// Not the real MD5 of the definition: readers of the bag do not check it.
template <>
struct MD5Sum<auvnav_test::DvlData>
{
	static const char* value() { return "0123456789abcdef0123456789abcdef"; }
	static const char* value(const auvnav_test::DvlData&) { return value(); }
};
template <>
struct Definition<auvnav_test::DvlData>
{
	static const char* value() { return auvnav_test::kDvlDataRos1Definition; }
	static const char* value(const auvnav_test::DvlData&) { return value(); }
};
template <>
struct HasHeader<auvnav_test::DvlData> : TrueType
{
};
}  // namespace ros::message_traits

namespace ros::serialization
{
template <>
struct Serializer<auvnav_test::Bottom>
{
	template <typename Stream, typename T>
	inline static void allInOne(Stream& stream, T m)
	{
		stream.next(m.velocity);
		stream.next(m.quality);
		stream.next(m.age);
	}
	ROS_DECLARE_ALLINONE_SERIALIZER
};

template <>
struct Serializer<auvnav_test::DvlData>
{
	template <typename Stream, typename T>
	inline static void allInOne(Stream& stream, T m)
	{
		stream.next(m.header);
		stream.next(m.beam_velocity);
		stream.next(m.ranges);
		stream.next(m.bottom);
		stream.next(m.valid);
		stream.next(m.status);
	}
	ROS_DECLARE_ALLINONE_SERIALIZER
};
}  // namespace ros::serialization

namespace auvnav::import::testing
{
using TimeNs = int64_t;

/** Exact: sec = ns / 1e9, nsec = ns % 1e9 (ns >= 0). */
ros::Time toRosTime(TimeNs ns);

/** Writes a ROS 1 bag: chunks of about `chunk_bytes`, compressed or not. */
class Ros1BagWriter
{
 public:
	explicit Ros1BagWriter(
	    const std::string& path, uint32_t chunk_bytes = 768 * 1024,
	    rosbag::compression::CompressionType compression = rosbag::compression::Uncompressed);
	~Ros1BagWriter();
	Ros1BagWriter(const Ros1BagWriter&) = delete;
	Ros1BagWriter& operator=(const Ros1BagWriter&) = delete;

	/** One message on `topic`, recorded at `record_time_ns`. */
	template <class M>
	void write(const std::string& topic, TimeNs record_time_ns, const M& msg)
	{
		bag_.write(topic, toRosTime(record_time_ns), msg);
	}
	/** Writes the index; the bag is unreadable without it. Idempotent. */
	void close();

 private:
	rosbag::Bag bag_;
	bool open_ = false;
};

/** The bytes of one ROS 2 message: encapsulation header (CDR, little or big
 *  endian), then the fields in definition order. */
class CdrWriter
{
 public:
	explicit CdrWriter(bool little_endian = true);

	/** Pads with zeros up to a multiple of `n` (counted after the header). */
	void align(std::size_t n);
	/** A primitive (bool, [u]int8..64, float, double), aligned to its size. */
	template <class T>
	void put(T v)
	{
		align(sizeof(T) > 8 ? 8 : sizeof(T));
		putRaw(&v, sizeof(T));
	}
	/** uint32 length including the NUL, the bytes, the NUL. */
	void string(const std::string& s);
	/** The uint32 element count that precedes a sequence's elements. */
	void sequenceLength(uint32_t n) { put<uint32_t>(n); }
	/** builtin_interfaces/Time or Duration: int32 sec, uint32 nanosec. */
	void time(int32_t sec, uint32_t nanosec);
	void time(const ros::Time& t) { time(static_cast<int32_t>(t.sec), t.nsec); }
	void header(const std_msgs::Header& h);  //!< std_msgs/Header (ROS 2: no seq)
	void vector3(const geometry_msgs::Vector3& v);
	void quaternion(const geometry_msgs::Quaternion& q);
	template <class T, std::size_t N>
	void fixedArray(const boost::array<T, N>& a)
	{
		for (const T& v : a) put<T>(v);
	}

	const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
	void putRaw(const void* p, std::size_t n);
	std::vector<uint8_t> bytes_;
	bool swap_;
};

/** ROS 2 CDR (little endian) of the ROS 2 message with the same name. */
std::vector<uint8_t> toRos2Cdr(const sensor_msgs::Imu& m);
std::vector<uint8_t> toRos2Cdr(const sensor_msgs::MagneticField& m);
std::vector<uint8_t> toRos2Cdr(const sensor_msgs::FluidPressure& m);
std::vector<uint8_t> toRos2Cdr(const sensor_msgs::NavSatFix& m);
std::vector<uint8_t> toRos2Cdr(const geometry_msgs::TwistWithCovarianceStamped& m);
std::vector<uint8_t> toRos2Cdr(const nav_msgs::Odometry& m);
/** `auvnav_test/msg/DvlData` (kDvlDataRos2Definition), little or big endian. */
std::vector<uint8_t> toRos2Cdr(const auvnav_test::DvlData& m, bool little_endian = true);

/** Writes a rosbag2 SQLite file. Layout::Jazzy has the `message_definitions`
 *  table and `type_description_hash` columns (rosbag2 since Iron); Layout::Humble
 *  has neither. Messages are committed by close() (or the destructor). */
class Ros2BagWriter
{
 public:
	enum class Layout
	{
		Jazzy,
		Humble
	};

	/** Creates (replaces) `db3_path`. */
	explicit Ros2BagWriter(const std::string& db3_path, Layout layout = Layout::Jazzy);
	~Ros2BagWriter();
	Ros2BagWriter(const Ros2BagWriter&) = delete;
	Ros2BagWriter& operator=(const Ros2BagWriter&) = delete;

	/** Registers a topic. `definition`: ros2msg text stored for `type` (Jazzy);
	 *  empty stores an 'unknown' empty definition, as rosbag2 does for types it
	 *  cannot find. */
	void addTopic(const std::string& name, const std::string& type, const std::string& definition = "");
	/** One message: `cdr` as from CdrWriter::bytes() or toRos2Cdr(). */
	void write(const std::string& topic, TimeNs record_time_ns, const std::vector<uint8_t>& cdr);
	void close();

 private:
	void exec(const std::string& sql);
	int64_t topicId(const std::string& name) const;

	sqlite3* db_ = nullptr;
	sqlite3_stmt* insert_ = nullptr;
	Layout layout_;
	std::vector<std::pair<std::string, int64_t>> topics_;
};

}  // namespace auvnav::import::testing
