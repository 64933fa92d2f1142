#pragma once
// Internal to the ROS 2 bag reader: a rosbag2 SQLite bag's .db3 files, opened
// read-only and checked, with their topics; the SQLite connection and
// statements that read them.
#include <sqlite3.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bag_common.h"

namespace auvnav::import::detail
{
/** Why SQLite returned `rc`, in words for a bag's user. */
std::string sqliteReason(sqlite3* db, int rc);

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

/** The `.db3` files of a bag (the file itself, or those of a rosbag2 folder in
 *  recording order), each opened and checked. Throws ImportError. */
std::vector<BagPart> openParts(const std::string& path);

}  // namespace auvnav::import::detail
