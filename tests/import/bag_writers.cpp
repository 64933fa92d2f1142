#include "bag_writers.h"

#include <sqlite3.h>

#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace auvnav_test
{
// Comments, constants (also a string constant with '#' and '=' in its value)
// and an unqualified type name (Bottom: same package) are there on purpose.
const char* const kDvlDataRos1Definition =
    "# A DVL measurement (auvnav bag-reader test type)\n"
    "Header header\n"
    "float64[4] beam_velocity  # along each beam, m/s\n"
    "float32[] ranges\n"
    "Bottom bottom\n"
    "bool valid\n"
    "string status\n"
    "uint8 STATUS_OK=0\n"
    "int32 MAX_BEAMS = 4\n"
    "string NOTE=constants # are = not fields\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "# Standard metadata\n"
    "uint32 seq\n"
    "time stamp\n"
    "string frame_id\n"
    "\n"
    "================================================================================\n"
    "MSG: auvnav_test/Bottom\n"
    "geometry_msgs/Vector3 velocity\n"
    "int8 quality\n"
    "duration age\n"
    "\n"
    "================================================================================\n"
    "MSG: geometry_msgs/Vector3\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n";

// ROS 2 forms: bounded sequence and string, default values, `pkg/msg/Type`
// section names, builtin_interfaces sections (which readers treat as builtins).
const char* const kDvlDataRos2Definition =
    "# A DVL measurement (auvnav bag-reader test type)\n"
    "std_msgs/Header header\n"
    "float64[4] beam_velocity\n"
    "float32[<=16] ranges\n"
    "Bottom bottom\n"
    "bool valid false\n"
    "string<=32 status \"ok # not a comment\"\n"
    "uint8 STATUS_OK=0\n"
    "================================================================================\n"
    "MSG: std_msgs/msg/Header\n"
    "builtin_interfaces/Time stamp\n"
    "string frame_id\n"
    "================================================================================\n"
    "MSG: builtin_interfaces/msg/Time\n"
    "int32 sec\n"
    "uint32 nanosec\n"
    "================================================================================\n"
    "MSG: auvnav_test/msg/Bottom\n"
    "geometry_msgs/Vector3 velocity\n"
    "int8 quality 0\n"
    "builtin_interfaces/Duration age\n"
    "================================================================================\n"
    "MSG: builtin_interfaces/Duration\n"
    "int32 sec\n"
    "uint32 nanosec\n"
    "================================================================================\n"
    "MSG: geometry_msgs/msg/Vector3\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n";
}  // namespace auvnav_test

namespace auvnav::import::testing
{
ros::Time toRosTime(TimeNs ns)
{
	ros::Time t;
	t.sec = static_cast<uint32_t>(ns / 1000000000);
	t.nsec = static_cast<uint32_t>(ns % 1000000000);
	return t;
}

// ---------------------------------------------------------------- ROS 1

Ros1BagWriter::Ros1BagWriter(const std::string& path, uint32_t chunk_bytes,
                             rosbag::compression::CompressionType compression)
{
	bag_.open(path, rosbag::bagmode::Write);
	bag_.setChunkThreshold(chunk_bytes);
	bag_.setCompression(compression);
	open_ = true;
}

Ros1BagWriter::~Ros1BagWriter()
{
	try
	{
		close();
	}
	catch (...)
	{
	}
}

void Ros1BagWriter::close()
{
	if (!open_) return;
	open_ = false;
	bag_.close();
}

// ---------------------------------------------------------------- CDR

CdrWriter::CdrWriter(bool little_endian)
    : bytes_{0x00, static_cast<uint8_t>(little_endian ? 0x01 : 0x00), 0x00, 0x00},
      swap_(little_endian != (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__))
{
}

void CdrWriter::align(std::size_t n)
{
	while ((bytes_.size() - 4) % n != 0) bytes_.push_back(0);
}

void CdrWriter::putRaw(const void* p, std::size_t n)
{
	const auto* b = static_cast<const uint8_t*>(p);
	const std::size_t at = bytes_.size();
	bytes_.insert(bytes_.end(), b, b + n);
	if (swap_)
		for (std::size_t i = 0; i < n / 2; ++i) std::swap(bytes_[at + i], bytes_[at + n - 1 - i]);
}

void CdrWriter::string(const std::string& s)
{
	put<uint32_t>(static_cast<uint32_t>(s.size() + 1));
	bytes_.insert(bytes_.end(), s.begin(), s.end());
	bytes_.push_back(0);
}

void CdrWriter::time(int32_t sec, uint32_t nanosec)
{
	put<int32_t>(sec);
	put<uint32_t>(nanosec);
}

void CdrWriter::header(const std_msgs::Header& h)
{
	time(h.stamp);
	string(h.frame_id);
}

void CdrWriter::vector3(const geometry_msgs::Vector3& v)
{
	put(v.x);
	put(v.y);
	put(v.z);
}

void CdrWriter::quaternion(const geometry_msgs::Quaternion& q)
{
	put(q.x);
	put(q.y);
	put(q.z);
	put(q.w);
}

namespace
{
void point(CdrWriter& w, const geometry_msgs::Point& p)
{
	w.put(p.x);
	w.put(p.y);
	w.put(p.z);
}

void twistWithCovariance(CdrWriter& w, const geometry_msgs::TwistWithCovariance& t)
{
	w.vector3(t.twist.linear);
	w.vector3(t.twist.angular);
	w.fixedArray(t.covariance);
}
}  // namespace

std::vector<uint8_t> toRos2Cdr(const sensor_msgs::Imu& m)
{
	CdrWriter w;
	w.header(m.header);
	w.quaternion(m.orientation);
	w.fixedArray(m.orientation_covariance);
	w.vector3(m.angular_velocity);
	w.fixedArray(m.angular_velocity_covariance);
	w.vector3(m.linear_acceleration);
	w.fixedArray(m.linear_acceleration_covariance);
	return w.bytes();
}

std::vector<uint8_t> toRos2Cdr(const sensor_msgs::MagneticField& m)
{
	CdrWriter w;
	w.header(m.header);
	w.vector3(m.magnetic_field);
	w.fixedArray(m.magnetic_field_covariance);
	return w.bytes();
}

std::vector<uint8_t> toRos2Cdr(const sensor_msgs::FluidPressure& m)
{
	CdrWriter w;
	w.header(m.header);
	w.put(m.fluid_pressure);
	w.put(m.variance);
	return w.bytes();
}

std::vector<uint8_t> toRos2Cdr(const sensor_msgs::NavSatFix& m)
{
	CdrWriter w;
	w.header(m.header);
	w.put<int8_t>(m.status.status);
	w.put<uint16_t>(m.status.service);
	w.put(m.latitude);
	w.put(m.longitude);
	w.put(m.altitude);
	w.fixedArray(m.position_covariance);
	w.put<uint8_t>(m.position_covariance_type);
	return w.bytes();
}

std::vector<uint8_t> toRos2Cdr(const geometry_msgs::TwistWithCovarianceStamped& m)
{
	CdrWriter w;
	w.header(m.header);
	twistWithCovariance(w, m.twist);
	return w.bytes();
}

std::vector<uint8_t> toRos2Cdr(const nav_msgs::Odometry& m)
{
	CdrWriter w;
	w.header(m.header);
	w.string(m.child_frame_id);
	point(w, m.pose.pose.position);
	w.quaternion(m.pose.pose.orientation);
	w.fixedArray(m.pose.covariance);
	twistWithCovariance(w, m.twist);
	return w.bytes();
}

std::vector<uint8_t> toRos2Cdr(const auvnav_test::DvlData& m, bool little_endian)
{
	CdrWriter w(little_endian);
	w.header(m.header);
	w.fixedArray(m.beam_velocity);
	w.sequenceLength(static_cast<uint32_t>(m.ranges.size()));
	for (float r : m.ranges) w.put(r);
	w.vector3(m.bottom.velocity);
	w.put<int8_t>(m.bottom.quality);
	w.time(m.bottom.age.sec, static_cast<uint32_t>(m.bottom.age.nsec));
	w.put<uint8_t>(m.valid);
	w.string(m.status);
	return w.bytes();
}

// ---------------------------------------------------------------- rosbag2

namespace
{
[[noreturn]] void sqliteFailure(sqlite3* db, const std::string& what)
{
	throw std::runtime_error("Ros2BagWriter: " + what + ": " + (db ? sqlite3_errmsg(db) : "out of memory"));
}

void bindText(sqlite3* db, sqlite3_stmt* s, int i, const std::string& v)
{
	if (sqlite3_bind_text(s, i, v.c_str(), static_cast<int>(v.size()), SQLITE_TRANSIENT) != SQLITE_OK)
		sqliteFailure(db, "bind");
}

void stepDone(sqlite3* db, sqlite3_stmt* s, const char* what)
{
	if (sqlite3_step(s) != SQLITE_DONE) sqliteFailure(db, what);
	sqlite3_reset(s);
}
}  // namespace

Ros2BagWriter::Ros2BagWriter(const std::string& db3_path, Layout layout) : layout_(layout)
{
	std::filesystem::remove(db3_path);
	if (sqlite3_open_v2(db3_path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
	    SQLITE_OK)
		sqliteFailure(db_, "cannot create " + db3_path);
	const bool jazzy = layout_ == Layout::Jazzy;
	exec("CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL)");
	exec(std::string("INSERT INTO schema VALUES(") + (jazzy ? "4, 'jazzy'" : "3, 'humble'") + ")");
	exec(std::string("CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
	                 "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL") +
	     (jazzy ? ", type_description_hash TEXT NOT NULL)" : ")"));
	if (jazzy)
		exec(
		    "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY, topic_type TEXT NOT NULL, "
		    "encoding TEXT NOT NULL, encoded_message_definition TEXT NOT NULL, "
		    "type_description_hash TEXT NOT NULL)");
	exec(
	    "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
	    "timestamp INTEGER NOT NULL, data BLOB NOT NULL)");
	exec("CREATE INDEX timestamp_idx ON messages (timestamp ASC)");
	exec("BEGIN");
	if (sqlite3_prepare_v2(db_, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?, ?, ?)", -1,
	                       &insert_, nullptr) != SQLITE_OK)
		sqliteFailure(db_, "prepare");
}

Ros2BagWriter::~Ros2BagWriter()
{
	try
	{
		close();
	}
	catch (...)
	{
	}
}

void Ros2BagWriter::exec(const std::string& sql)
{
	char* err = nullptr;
	if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK)
	{
		const std::string msg = err ? err : "unknown error";
		sqlite3_free(err);
		throw std::runtime_error("Ros2BagWriter: " + sql + ": " + msg);
	}
}

void Ros2BagWriter::addTopic(const std::string& name, const std::string& type, const std::string& definition)
{
	const bool jazzy = layout_ == Layout::Jazzy;
	sqlite3_stmt* s = nullptr;
	const char* sql = jazzy ? "INSERT INTO topics(name, type, serialization_format, offered_qos_profiles, "
	                          "type_description_hash) VALUES(?, ?, 'cdr', '', '')"
	                        : "INSERT INTO topics(name, type, serialization_format, offered_qos_profiles) "
	                          "VALUES(?, ?, 'cdr', '')";
	if (sqlite3_prepare_v2(db_, sql, -1, &s, nullptr) != SQLITE_OK) sqliteFailure(db_, "prepare");
	bindText(db_, s, 1, name);
	bindText(db_, s, 2, type);
	stepDone(db_, s, "insert topic");
	sqlite3_finalize(s);
	topics_.emplace_back(name, sqlite3_last_insert_rowid(db_));
	if (!jazzy) return;

	if (sqlite3_prepare_v2(
	        db_,
	        "INSERT INTO message_definitions(topic_type, encoding, encoded_message_definition, "
	        "type_description_hash) VALUES(?, ?, ?, '')",
	        -1, &s, nullptr) != SQLITE_OK)
		sqliteFailure(db_, "prepare");
	bindText(db_, s, 1, type);
	bindText(db_, s, 2, definition.empty() ? "unknown" : "ros2msg");
	bindText(db_, s, 3, definition);
	stepDone(db_, s, "insert definition");
	sqlite3_finalize(s);
}

int64_t Ros2BagWriter::topicId(const std::string& name) const
{
	for (const auto& t : topics_)
		if (t.first == name) return t.second;
	throw std::runtime_error("Ros2BagWriter: topic " + name + " was not added");
}

void Ros2BagWriter::write(const std::string& topic, TimeNs record_time_ns, const std::vector<uint8_t>& cdr)
{
	sqlite3_bind_int64(insert_, 1, topicId(topic));
	sqlite3_bind_int64(insert_, 2, record_time_ns);
	sqlite3_bind_blob(insert_, 3, cdr.data(), static_cast<int>(cdr.size()), SQLITE_TRANSIENT);
	stepDone(db_, insert_, "insert message");
}

void Ros2BagWriter::close()
{
	if (!db_) return;
	sqlite3_finalize(insert_);
	insert_ = nullptr;
	char* err = nullptr;
	const int rc = sqlite3_exec(db_, "COMMIT", nullptr, nullptr, &err);
	sqlite3_free(err);
	sqlite3_close(db_);
	db_ = nullptr;
	if (rc != SQLITE_OK) throw std::runtime_error("Ros2BagWriter: commit failed");
}

}  // namespace auvnav::import::testing
