#pragma once
/** @file record.h
 *  What every importer input yields: records of named fields.
 *
 *  A CSV file gives one record per data row (names from the header row, every
 *  value Text, converted later by the sensor mapping with the unit the spec
 *  names). A bag topic gives one record per message, its fields flattened from
 *  the message definition stored in the bag:
 *
 *  - nested fields are joined with '.':        `header.stamp`, `angular_velocity.x`
 *  - array elements carry their index:          `orientation_covariance[0]`, `beams[2].range`
 *  - every array also gives its length:         `beams[]` (Number)
 *  - ROS `time`/`duration` (ROS 1) and `builtin_interfaces/Time`/`Duration`
 *    (ROS 2) are one Time value in integer nanoseconds (`header.stamp`);
 *    their sec/nsec parts are not listed separately
 *  - numbers and bools are Number, strings are Text; byte/uint8 arrays longer
 *    than `kMaxFlattenedArray` elements (images, raw packets) are skipped
 *    (listed as `name[]` only).
 *
 *  The record time is the time the recorder received the message (ROS bag
 *  record time); CSV records have none.
 *
 *  Errors: a source throws ImportError with a message that names the file and
 *  the line or message index (`where()` of the last record) and what is wrong.
 */
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace auvnav::import
{
/** Integer nanoseconds since the UNIX epoch (exact; doubles of UNIX seconds
 *  lose ~0.2 µs). */
using TimeNs = int64_t;

constexpr std::size_t kMaxFlattenedArray = 256;

class ImportError : public std::runtime_error
{
 public:
	using std::runtime_error::runtime_error;
};

/** A bag without the topic a sensor reads: an optional sensor is then absent. */
class MissingTopicError : public ImportError
{
 public:
	using ImportError::ImportError;
};

struct Value
{
	enum class Kind : uint8_t
	{
		Missing,  //!< empty CSV cell
		Number,
		Time,
		Text
	};
	Kind kind = Kind::Missing;
	double number = 0;   //!< Kind::Number
	TimeNs time_ns = 0;  //!< Kind::Time
	std::string text;    //!< Kind::Text (CSV cells, ROS strings)

	static Value ofNumber(double v)
	{
		Value x;
		x.kind = Kind::Number;
		x.number = v;
		return x;
	}
	static Value ofTime(TimeNs t)
	{
		Value x;
		x.kind = Kind::Time;
		x.time_ns = t;
		return x;
	}
	static Value ofText(std::string s)
	{
		Value x;
		x.kind = Kind::Text;
		x.text = std::move(s);
		return x;
	}
};

/** One row or message. `names` and `values` have the same length. A source
 *  changes `layout_id` whenever `names` changes (a new CSV file, a bag message
 *  whose arrays have another length), so consumers may cache column indices
 *  per layout. */
struct Record
{
	std::vector<std::string> names;
	std::vector<Value> values;
	uint64_t layout_id = 0;
	bool has_record_time = false;
	TimeNs record_time_ns = 0;  //!< bag record time (when has_record_time)
	std::string where;          //!< "imu.csv:17", "run.bag: topic /dvl message #42"
	/** Non-empty when the source could read the record but not make sense of
	 *  it (a CSV row with the wrong number of fields): why. The source goes on
	 *  with the next record; the importer rejects this one (counted, or an
	 *  error without --lenient). */
	std::string defect;

	/** Index of field `name`, or -1. */
	int indexOf(std::string_view name) const
	{
		for (std::size_t i = 0; i < names.size(); ++i)
			if (names[i] == name) return static_cast<int>(i);
		return -1;
	}
};

/** A stream of records from one file or one bag topic. */
class RecordSource
{
 public:
	virtual ~RecordSource() = default;
	/** Fills `out` with the next record; false at the end. Throws ImportError
	 *  on unreadable input (naming file and line/message). */
	virtual bool next(Record& out) = 0;
	/** "imu.csv", "run.bag topic /dvl". */
	virtual std::string describe() const = 0;
	/** The message type ("sensor_msgs/Imu", "sensor_msgs/msg/Imu"), empty for CSV. */
	virtual std::string messageType() const { return {}; }
};

/** ROS 1 bag (rosbag_storage; message layout from the connection records'
 *  definitions). Throws ImportError if the file cannot be opened, is not a bag,
 *  is truncated, or has no topic `topic` (the message lists the topics it has). */
std::unique_ptr<RecordSource> openRos1Bag(const std::string& path, const std::string& topic);

/** ROS 2 bag: a `.db3` file or a rosbag2 folder (SQLite + CDR; message layout
 *  from the bag's `message_definitions` table, else the bundled definitions of
 *  the standard types). Same errors as openRos1Bag. */
std::unique_ptr<RecordSource> openRos2Bag(const std::string& path, const std::string& topic);

/** Topic names and types in a bag, for error messages and `auvnav-import --list`. */
std::vector<std::pair<std::string, std::string>> listRos1Topics(const std::string& path);
std::vector<std::pair<std::string, std::string>> listRos2Topics(const std::string& path);

}  // namespace auvnav::import
