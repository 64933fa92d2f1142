// ROS 2 bags (rosbag2, SQLite storage): the messages of a topic come from the
// `messages` table in timestamp order; their CDR bytes are decoded with the
// definition stored in `message_definitions` (rosbag2 since Iron) or, for bags
// without one, with the bundled definitions of the standard types below.
#include <auvnav/import/record.h>

#include "msg_definition.h"

#include <sqlite3.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace auvnav::import
{
namespace
{
namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& path, const std::string& why)
{
	throw ImportError(path + ": " + why);
}

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

// ---------------------------------------------------------------- SQLite

std::string sqliteReason(sqlite3* db, int rc)
{
	switch (rc & 0xff)
	{
		case SQLITE_NOTADB:
			return "not an SQLite database (so not a rosbag2 .db3 file)";
		case SQLITE_CORRUPT:
			return "truncated or damaged database (SQLite: database disk image is malformed)";
		case SQLITE_IOERR:
			return std::string("read error, truncated file? (SQLite: ") + sqlite3_errmsg(db) + ")";
		default:
			return std::string("SQLite: ") + (db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
	}
}

/** A read-only SQLite connection. */
class Database
{
 public:
	explicit Database(std::string path) : path_(std::move(path))
	{
		const int rc = sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr);
		if (rc != SQLITE_OK)
		{
			const std::string why = sqliteReason(db_, rc);
			sqlite3_close(db_);
			db_ = nullptr;
			fail(path_, "cannot open: " + why);
		}
	}
	~Database() { sqlite3_close(db_); }
	Database(const Database&) = delete;
	Database& operator=(const Database&) = delete;

	sqlite3* handle() const { return db_; }
	const std::string& path() const { return path_; }

	[[noreturn]] void failed(int rc, const std::string& doing) const
	{
		fail(path_, doing + ": " + sqliteReason(db_, rc));
	}

 private:
	std::string path_;
	sqlite3* db_ = nullptr;
};

/** A prepared statement; step() throws ImportError on errors. */
class Statement
{
 public:
	Statement(const Database& db, const std::string& sql, std::string doing)
	    : db_(db), doing_(std::move(doing))
	{
		const int rc = sqlite3_prepare_v2(db_.handle(), sql.c_str(), -1, &stmt_, nullptr);
		if (rc != SQLITE_OK) db_.failed(rc, doing_);
	}
	~Statement() { sqlite3_finalize(stmt_); }
	Statement(const Statement&) = delete;
	Statement& operator=(const Statement&) = delete;

	void bind(int i, const std::string& text)
	{
		const int rc =
		    sqlite3_bind_text(stmt_, i, text.c_str(), static_cast<int>(text.size()), SQLITE_TRANSIENT);
		if (rc != SQLITE_OK) db_.failed(rc, doing_);
	}

	/** True with a row, false at the end. */
	bool step()
	{
		const int rc = sqlite3_step(stmt_);
		if (rc == SQLITE_ROW) return true;
		if (rc == SQLITE_DONE) return false;
		db_.failed(rc, doing_);
	}

	int64_t integer(int col) const { return sqlite3_column_int64(stmt_, col); }
	std::string text(int col) const
	{
		const auto* p = sqlite3_column_text(stmt_, col);
		return p ? std::string(reinterpret_cast<const char*>(p),
		                       static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col)))
		         : std::string();
	}
	const uint8_t* blob(int col, std::size_t& size) const
	{
		const auto* p = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, col));
		size = static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col));
		return p;
	}
	bool isNull(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }

 private:
	const Database& db_;
	std::string doing_;
	sqlite3_stmt* stmt_ = nullptr;
};

// ---------------------------------------------------------------- bag files

struct TopicRow
{
	int64_t id = 0;
	std::string name;
	std::string type;
	std::string format;
};

/** One `.db3` file of a bag, opened and checked to be a rosbag2 database. */
struct BagPart
{
	std::unique_ptr<Database> db;
	std::vector<TopicRow> topics;
	bool has_definitions = false;
};

/** Natural order: `bag_2.db3` before `bag_10.db3`. */
bool naturalLess(const std::string& a, const std::string& b)
{
	std::size_t i = 0, j = 0;
	while (i < a.size() && j < b.size())
	{
		if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j])))
		{
			std::size_t ei = i, ej = j;
			while (ei < a.size() && std::isdigit(static_cast<unsigned char>(a[ei]))) ++ei;
			while (ej < b.size() && std::isdigit(static_cast<unsigned char>(b[ej]))) ++ej;
			const std::string na = a.substr(i, ei - i), nb = b.substr(j, ej - j);
			const std::string ta = na.substr(std::min(na.find_first_not_of('0'), na.size()));
			const std::string tb = nb.substr(std::min(nb.find_first_not_of('0'), nb.size()));
			if (ta.size() != tb.size()) return ta.size() < tb.size();
			if (ta != tb) return ta < tb;
			i = ei;
			j = ej;
		}
		else
		{
			if (a[i] != b[j]) return a[i] < b[j];
			++i;
			++j;
		}
	}
	return a.size() - i < b.size() - j;
}

bool endsWith(const std::string& s, const std::string& suffix)
{
	return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/** The `.db3` files of a bag: the file itself, or those in a rosbag2 folder
 *  (split bags: in natural order, which is the recording order). */
std::vector<std::string> bagFiles(const std::string& path)
{
	std::error_code ec;
	if (!fs::exists(path, ec)) fail(path, std::string("cannot open: ") + std::strerror(ENOENT));
	if (!fs::is_directory(path, ec)) return {path};
	std::vector<std::string> files;
	bool mcap = false, compressed = false;
	for (const auto& entry : fs::directory_iterator(path, ec))
	{
		const std::string name = entry.path().filename().string();
		if (endsWith(name, ".db3") && entry.is_regular_file(ec)) files.push_back(entry.path().string());
		mcap = mcap || endsWith(name, ".mcap");
		compressed = compressed || endsWith(name, ".db3.zstd");
	}
	if (files.empty())
	{
		if (compressed)
			fail(path,
			     "compressed rosbag2 files (.db3.zstd) are not supported; decompress them first (zstd -d)");
		if (mcap)
			fail(
			    path,
			    "MCAP rosbag2 storage is not supported, only SQLite (.db3); convert with `ros2 bag convert`");
		fail(path, "no .db3 file in this folder (not a rosbag2 SQLite bag)");
	}
	std::sort(files.begin(), files.end(), naturalLess);
	return files;
}

uint32_t bigEndian(const unsigned char* p, std::size_t n)
{
	uint32_t v = 0;
	for (std::size_t i = 0; i < n; ++i) v = v << 8 | p[i];
	return v;
}

/** SQLite reads a file cut short without complaint as long as the pages it
 *  needs are there; the size the database header records tells. */
void checkDatabaseSize(const std::string& file)
{
	std::ifstream in(file, std::ios::binary);
	unsigned char h[100] = {};
	if (!in.read(reinterpret_cast<char*>(h), sizeof h)) return;  // SQLite reports what is wrong
	if (std::memcmp(h, "SQLite format 3", 16) != 0) return;
	const uint32_t raw_page = bigEndian(h + 16, 2);
	const uint64_t page_size = raw_page == 1 ? 65536 : raw_page;
	const uint32_t pages = bigEndian(h + 28, 4);
	// The page count is valid only when written by the same change as the counter.
	if (pages == 0 || bigEndian(h + 24, 4) != bigEndian(h + 92, 4)) return;
	// With a write-ahead log next to it, the file alone may lag its header.
	std::error_code ec;
	if (fs::exists(file + "-wal", ec)) return;
	const uint64_t size = fs::file_size(file, ec);
	if (ec || size >= pages * page_size) return;
	std::ostringstream msg;
	msg << "truncated or damaged database: its header records " << pages << " pages of " << page_size
	    << " bytes (" << pages * page_size << " bytes) but the file has " << size << " bytes";
	fail(file, msg.str());
}

BagPart openPart(const std::string& file)
{
	checkDatabaseSize(file);
	BagPart part;
	part.db = std::make_unique<Database>(file);
	std::set<std::string> tables;
	{
		// The first read of the file: "not a database" and damage show here.
		Statement s(*part.db, "SELECT name FROM sqlite_master WHERE type = 'table'",
		            "cannot read the database");
		while (s.step()) tables.insert(s.text(0));
	}
	if (!tables.count("topics") || !tables.count("messages"))
		fail(file, "not a rosbag2 database (it has no 'topics' and 'messages' tables)");
	part.has_definitions = tables.count("message_definitions") > 0;
	Statement s(*part.db, "SELECT id, name, type, serialization_format FROM topics ORDER BY id",
	            "cannot read the topics table");
	while (s.step()) part.topics.push_back(TopicRow{s.integer(0), s.text(1), s.text(2), s.text(3)});
	return part;
}

std::vector<BagPart> openParts(const std::string& path)
{
	std::vector<BagPart> parts;
	for (const std::string& file : bagFiles(path)) parts.push_back(openPart(file));
	return parts;
}

using TopicList = std::vector<std::pair<std::string, std::string>>;

TopicList topicsOf(const std::vector<BagPart>& parts)
{
	std::set<std::pair<std::string, std::string>> unique;
	for (const BagPart& p : parts)
		for (const TopicRow& t : p.topics) unique.insert({t.name, t.type});
	return TopicList(unique.begin(), unique.end());
}

std::string describeTopics(const TopicList& topics)
{
	if (topics.empty()) return "the bag has no topics";
	std::string s = "its topics: ";
	for (std::size_t i = 0; i < topics.size(); ++i)
		s += (i ? ", " : "") + topics[i].first + " (" + topics[i].second + ")";
	return s;
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
	bool found = false;
	for (const auto& t : topics) found = found || t.first == topic;
	if (!found) fail(path, "no topic '" + topic + "' in the bag; " + describeTopics(topics));
	return std::make_unique<Ros2Source>(path, topic, std::move(parts));
}

std::vector<std::pair<std::string, std::string>> listRos2Topics(const std::string& path)
{
	return topicsOf(openParts(path));
}

}  // namespace auvnav::import
