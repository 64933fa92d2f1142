// ROS 2 bags (rosbag2, SQLite storage): the messages of a topic come from the
// `messages` table in timestamp order; their CDR bytes are decoded with the
// definition stored in `message_definitions` (rosbag2 since Iron) or, for bags
// without one, with the bundled definitions of the standard types below.
#include <auvnav/import/record.h>

#include "msg_definition.h"

#include <cstring>
#include <map>
#include <set>

#include "bag_common.h"
#include "ros2_bag_db.h"

namespace auvnav::import
{
namespace
{
using detail::BagPart;
using detail::describeTopics;
using detail::fail;
using detail::openParts;
using detail::requireTopic;
using detail::Statement;
using detail::TopicList;
using detail::TopicRow;

// ---------------------------------------------------------------- bundled definitions

struct Bundled
{
	const char* type;
	const char* text;
};

// ROS 2 (Humble .. Jazzy) forms: Header has no seq; Time is int32 sec +
// uint32 nanosec (a builtin for the decoder).
constexpr Bundled kBundled[] = {
    {"std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"},
    {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"},
    {"builtin_interfaces/Duration", "int32 sec\nuint32 nanosec\n"},
    {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"},
    {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
    {"geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"},
    {"geometry_msgs/Pose", "Point position\nQuaternion orientation\n"},
    {"geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"},
    {"geometry_msgs/PoseStamped", "std_msgs/Header header\nPose pose\n"},
    {"geometry_msgs/PoseWithCovarianceStamped", "std_msgs/Header header\nPoseWithCovariance pose\n"},
    {"geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n"},
    {"geometry_msgs/TwistStamped", "std_msgs/Header header\nTwist twist\n"},
    {"geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance\n"},
    {"geometry_msgs/TwistWithCovarianceStamped", "std_msgs/Header header\nTwistWithCovariance twist\n"},
    {"geometry_msgs/Vector3Stamped", "std_msgs/Header header\nVector3 vector\n"},
    {"geometry_msgs/PointStamped", "std_msgs/Header header\nPoint point\n"},
    {"geometry_msgs/QuaternionStamped", "std_msgs/Header header\nQuaternion quaternion\n"},
    {"sensor_msgs/Imu",
     "std_msgs/Header header\n"
     "geometry_msgs/Quaternion orientation\n"
     "float64[9] orientation_covariance\n"
     "geometry_msgs/Vector3 angular_velocity\n"
     "float64[9] angular_velocity_covariance\n"
     "geometry_msgs/Vector3 linear_acceleration\n"
     "float64[9] linear_acceleration_covariance\n"},
    {"sensor_msgs/MagneticField",
     "std_msgs/Header header\ngeometry_msgs/Vector3 magnetic_field\nfloat64[9] magnetic_field_covariance\n"},
    {"sensor_msgs/FluidPressure", "std_msgs/Header header\nfloat64 fluid_pressure\nfloat64 variance\n"},
    {"sensor_msgs/Temperature", "std_msgs/Header header\nfloat64 temperature\nfloat64 variance\n"},
    {"sensor_msgs/NavSatStatus", "int8 status\nuint16 service\n"},
    {"sensor_msgs/NavSatFix",
     "std_msgs/Header header\n"
     "NavSatStatus status\n"
     "float64 latitude\n"
     "float64 longitude\n"
     "float64 altitude\n"
     "float64[9] position_covariance\n"
     "uint8 position_covariance_type\n"},
    {"nav_msgs/Odometry",
     "std_msgs/Header header\n"
     "string child_frame_id\n"
     "geometry_msgs/PoseWithCovariance pose\n"
     "geometry_msgs/TwistWithCovariance twist\n"},
};

const char* bundledDefinition(const std::string& normalized_type)
{
	for (const Bundled& b : kBundled)
		if (normalized_type == b.type) return b.text;
	return nullptr;
}

std::string bundledTypeList()
{
	std::string s;
	for (const Bundled& b : kBundled)
		if (std::strncmp(b.type, "builtin_interfaces/", 19) != 0)
			s += (s.empty() ? "" : ", ") + std::string(b.type);
	return s;
}

TopicList topicsOf(const std::vector<BagPart>& parts)
{
	std::set<std::pair<std::string, std::string>> unique;
	for (const BagPart& p : parts)
		for (const TopicRow& t : p.topics) unique.insert({t.name, t.type});
	return TopicList(unique.begin(), unique.end());
}

// ---------------------------------------------------------------- definitions

struct StoredDefinition
{
	std::string ros2msg;    //!< the definition in .msg syntax, or empty
	bool idl_only = false;  //!< the bag has it in IDL (ros2idl), which is not supported
};

StoredDefinition storedDefinition(const BagPart& part, const std::string& type)
{
	StoredDefinition d;
	if (!part.has_definitions) return d;
	Statement s(*part.db,
	            "SELECT encoding, encoded_message_definition FROM message_definitions WHERE topic_type = ?",
	            "cannot read the message_definitions table");
	s.bind(1, type);
	while (s.step())
	{
		const std::string encoding = s.text(0);
		const std::string text = s.text(1);
		if (text.empty()) continue;
		if (encoding == "ros2msg")
		{
			d.ros2msg = text;
			return d;
		}
		d.idl_only = d.idl_only || encoding == "ros2idl";
	}
	return d;
}

std::shared_ptr<const msg::Schema> schemaFor(const BagPart& part, const std::string& topic,
                                             const std::string& type)
{
	const StoredDefinition definition = storedDefinition(part, type);
	const std::string& stored = definition.ros2msg;
	const std::string normalized = msg::normalizeTypeName(type);
	const char* bundled = bundledDefinition(normalized);
	const msg::DefinitionFallback fallback = bundledDefinition;
	const std::string context = "topic " + topic + " (" + type + "): ";
	if (!stored.empty())
	{
		try
		{
			return msg::Schema::parse(type, stored, msg::Dialect::Ros2, fallback);
		}
		catch (const msg::DefinitionError& e)
		{
			// A standard type is the same everywhere: the bundled form will do.
			if (!bundled)
				fail(part.db->path(),
				     context + "cannot use the message definition stored in the bag: " + e.what());
		}
	}
	if (!bundled && definition.idl_only)
		fail(part.db->path(),
		     context + "the bag stores its definition in IDL (ros2idl), which is not supported, " +
		         "and it is not one of the bundled standard types (" + bundledTypeList() + ")");
	if (!bundled)
		fail(part.db->path(),
		     context + "the bag stores no definition of this type (recorded before ROS 2 Iron?) " +
		         "and it is not one of the bundled standard types (" + bundledTypeList() + ")");
	try
	{
		return msg::Schema::parse(type, bundled, msg::Dialect::Ros2, fallback);
	}
	catch (const msg::DefinitionError& e)
	{
		fail(part.db->path(), context + "bundled definition: " + e.what());
	}
}

// ---------------------------------------------------------------- source

class Ros2Source final : public RecordSource
{
 public:
	Ros2Source(std::string path, std::string topic, std::vector<BagPart> parts)
	    : path_(std::move(path)), topic_(std::move(topic)), parts_(std::move(parts))
	{
		for (std::size_t i = 0; i < parts_.size(); ++i) prepareDecoders(i);
	}

	bool next(Record& out) override
	{
		for (;;)
		{
			if (!statement_)
			{
				if (current_ >= parts_.size()) return false;
				statement_ = queryMessages(current_);
				if (!statement_)
				{
					++current_;
					continue;
				}
			}
			if (statement_->step()) break;
			statement_.reset();
			++current_;
		}
		++index_;
		const BagPart& part = parts_[current_];
		out.where = part.db->path() + ": topic " + topic_ + " message #" + std::to_string(index_);
		out.has_record_time = true;
		out.record_time_ns = statement_->integer(1);
		const auto decoder = decoders_.find({current_, statement_->integer(0)});
		std::size_t size = 0;
		const uint8_t* data = statement_->blob(2, size);
		try
		{
			decoder->second->decode(data, size, out);
		}
		catch (const msg::DecodeError& e)
		{
			throw ImportError(out.where + " (" + types_.at({current_, statement_->integer(0)}) +
			                  "): " + e.what());
		}
		return true;
	}

	std::string describe() const override { return path_ + " topic " + topic_; }
	std::string messageType() const override { return type_; }

 private:
	void prepareDecoders(std::size_t i)
	{
		for (const TopicRow& t : parts_[i].topics)
		{
			if (t.name != topic_) continue;
			if (t.format != "cdr")
				fail(parts_[i].db->path(), "topic " + topic_ + ": serialization format '" + t.format +
				                               "' is not supported (only cdr)");
			if (type_.empty()) type_ = t.type;
			const auto schema = schemaFor(parts_[i], topic_, t.type);
			// Parts that store the same definition share a decoder (and its layout).
			const std::string key = t.type + '\n' + storedDefinition(parts_[i], t.type).ros2msg;
			auto& decoder = shared_[key];
			if (!decoder) decoder = std::make_unique<msg::FlatDecoder>(schema, msg::WireFormat::Cdr);
			decoders_[{i, t.id}] = decoder.get();
			types_[{i, t.id}] = t.type;
		}
	}

	/** The topic's messages in one part, or null if the part lacks the topic. */
	std::unique_ptr<Statement> queryMessages(std::size_t i) const
	{
		std::string ids;
		for (const TopicRow& t : parts_[i].topics)
			if (t.name == topic_) ids += (ids.empty() ? "" : ", ") + std::to_string(t.id);
		if (ids.empty()) return nullptr;
		return std::make_unique<Statement>(
		    *parts_[i].db,
		    "SELECT topic_id, timestamp, data FROM messages WHERE topic_id IN (" + ids +
		        ") ORDER BY timestamp, id",
		    "cannot read the messages of topic " + topic_);
	}

	std::string path_;
	std::string topic_;
	std::string type_;
	std::vector<BagPart> parts_;
	std::map<std::string, std::unique_ptr<msg::FlatDecoder>> shared_;
	std::map<std::pair<std::size_t, int64_t>, msg::FlatDecoder*> decoders_;
	std::map<std::pair<std::size_t, int64_t>, std::string> types_;
	std::size_t current_ = 0;
	std::unique_ptr<Statement> statement_;  // after parts_: it refers to a part's database
	uint64_t index_ = 0;
};

}  // namespace

std::unique_ptr<RecordSource> openRos2Bag(const std::string& path, const std::string& topic)
{
	std::vector<BagPart> parts = openParts(path);
	const TopicList topics = topicsOf(parts);
	requireTopic(path, topic, topics);
	return std::make_unique<Ros2Source>(path, topic, std::move(parts));
}

std::vector<std::pair<std::string, std::string>> listRos2Topics(const std::string& path)
{
	return topicsOf(openParts(path));
}

}  // namespace auvnav::import
