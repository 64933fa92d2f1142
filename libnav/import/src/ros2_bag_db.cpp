// The .db3 files of a rosbag2 SQLite bag (ros2_bag_db.h): found in its
// folder, checked for truncation, opened read-only, their topics read.
#include "ros2_bag_db.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace auvnav::import::detail
{
namespace
{
namespace fs = std::filesystem;

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
}  // namespace

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

std::vector<BagPart> openParts(const std::string& path)
{
	std::vector<BagPart> parts;
	for (const std::string& file : bagFiles(path)) parts.push_back(openPart(file));
	return parts;
}

}  // namespace auvnav::import::detail
