// The structural check of ROS 1 bag files (ros1_bag_check.h): bag header,
// index, chunk headers and the wanted topic's message records, bounds-checked.
#include "ros1_bag_check.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bag_common.h"

namespace auvnav::import::detail
{
namespace
{
namespace fs = std::filesystem;

// ---------------------------------------------------------------- structural check
//
// rosbag_storage parses record headers without bounds checks: a damaged bag
// makes it read past its buffers. So before it opens a bag, the records it
// will parse are checked here (bag format 2.0: records of `uint32 header_len,
// header, uint32 data_len, data`; a header is fields of `uint32 len,
// name=value`): the bag header, the connection and chunk-info records at
// index_pos, each chunk's header and the index records after it (offsets within
// the chunk) and, in uncompressed chunks, the records that the index of the
// wanted topic points to. Compressed chunk contents are left to the
// decompressors' checks.

constexpr uint8_t kOpMessageDefinition = 0x01;  // bag 1.2, still skipped by readers
constexpr uint8_t kOpMessage = 0x02;
constexpr uint8_t kOpBagHeader = 0x03;
constexpr uint8_t kOpIndex = 0x04;
constexpr uint8_t kOpChunk = 0x05;
constexpr uint8_t kOpChunkInfo = 0x06;
constexpr uint8_t kOpConnection = 0x07;
constexpr std::string_view kMagic = "#ROSBAG V2.0\n";
// Record headers are a few hundred bytes; connection data holds definitions.
constexpr uint32_t kMaxHeaderBytes = 1u << 20;
// Chunks hold ~768 KiB by default, more only for single large messages.
constexpr uint64_t kMaxChunkBytes = uint64_t{1} << 30;

uint64_t littleEndian(const char* p, std::size_t n)
{
	uint64_t v = 0;
	for (std::size_t i = n; i-- > 0;) v = v << 8 | static_cast<unsigned char>(p[i]);
	return v;
}

/** The bytes of a file by position; reads past the end fail. */
class BagFile
{
 public:
	explicit BagFile(const std::string& path)
	    : fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)), open_errno_(fd_ < 0 ? errno : 0)
	{
		struct stat st = {};
		if (fd_ >= 0 && ::fstat(fd_, &st) == 0) size_ = static_cast<uint64_t>(st.st_size);
	}
	~BagFile()
	{
		if (fd_ >= 0) ::close(fd_);
	}
	BagFile(const BagFile&) = delete;
	BagFile& operator=(const BagFile&) = delete;

	bool isOpen() const { return fd_ >= 0; }
	int openErrno() const { return open_errno_; }
	uint64_t size() const { return size_; }

	bool read(uint64_t pos, std::size_t n, std::string& out) const
	{
		if (pos > size_ || size_ - pos < n) return false;
		out.resize(n);
		std::size_t done = 0;
		while (done < n)
		{
			const ssize_t got = ::pread(fd_, out.data() + done, n - done, static_cast<off_t>(pos + done));
			if (got <= 0) return false;
			done += static_cast<std::size_t>(got);
		}
		return true;
	}

 private:
	int fd_;
	int open_errno_;
	uint64_t size_ = 0;
};

/** `name=value` fields of a record header or of connection data. */
class HeaderFields
{
 public:
	/** False (and `why`) when a field's length overruns the bytes or a field has no '='. */
	bool parse(std::string_view bytes, std::string& why)
	{
		fields_.clear();
		std::size_t pos = 0;
		while (pos < bytes.size())
		{
			if (bytes.size() - pos < 4)
			{
				why = "a header field length is cut off";
				return false;
			}
			const uint64_t len = littleEndian(bytes.data() + pos, 4);
			pos += 4;
			if (len > bytes.size() - pos)
			{
				why = "a header field of " + std::to_string(len) + " bytes overruns its header";
				return false;
			}
			const std::string_view field = bytes.substr(pos, len);
			pos += len;
			const auto eq = field.find('=');
			if (eq == std::string_view::npos)
			{
				why = "a header field has no '='";
				return false;
			}
			fields_.emplace_back(field.substr(0, eq), field.substr(eq + 1));
		}
		return true;
	}

	std::optional<std::string_view> get(std::string_view name) const
	{
		for (const auto& f : fields_)
			if (f.first == name) return f.second;
		return std::nullopt;
	}

	/** A little-endian integer field of exactly `n` bytes. */
	std::optional<uint64_t> integer(std::string_view name, std::size_t n) const
	{
		const auto v = get(name);
		if (!v || v->size() != n) return std::nullopt;
		return littleEndian(v->data(), n);
	}

 private:
	std::vector<std::pair<std::string_view, std::string_view>> fields_;
};

/** Where records are read from: the file, or the bytes of one chunk read at
 *  once (positions are file positions either way). */
class ByteSource
{
 public:
	virtual ~ByteSource() = default;
	/** Up to `n` bytes at `pos` (fewer at the end), valid until the next call. */
	virtual std::string_view view(uint64_t pos, std::size_t n) = 0;
};

class FileBytes final : public ByteSource
{
 public:
	explicit FileBytes(const BagFile& file) : file_(file) {}
	std::string_view view(uint64_t pos, std::size_t n) override
	{
		if (pos >= file_.size()) return {};
		n = static_cast<std::size_t>(std::min<uint64_t>(n, file_.size() - pos));
		if (!file_.read(pos, n, scratch_)) return {};
		return scratch_;
	}

 private:
	const BagFile& file_;
	std::string scratch_;
};

class MemoryBytes final : public ByteSource
{
 public:
	MemoryBytes(uint64_t base, std::string bytes) : base_(base), bytes_(std::move(bytes)) {}
	std::string_view view(uint64_t pos, std::size_t n) override
	{
		if (pos < base_ || pos - base_ >= bytes_.size()) return {};
		return std::string_view(bytes_).substr(static_cast<std::size_t>(pos - base_), n);
	}

 private:
	uint64_t base_;
	std::string bytes_;
};

/** One record's framing, read and checked. Reused between records so that
 *  checking many small records allocates nothing. */
struct RecordInfo
{
	std::string header_bytes;  // the header fields refer to these
	HeaderFields header;
	uint8_t op = 0;
	uint64_t data_pos = 0;
	uint32_t data_len = 0;
	uint64_t end = 0;
};

class BagChecker
{
 public:
	BagChecker(const std::string& path, const BagFile& file) : path_(path), file_(file), file_bytes_(file) {}

	/** The whole check; `topic` empty: the topic-specific part is skipped. */
	void run(const std::string& topic)
	{
		readBagHeader();
		readIndexSection();
		for (const Chunk& c : chunk_infos_) checkChunk(c, topic);
	}

 private:
	struct Chunk
	{
		uint64_t pos = 0;
		uint32_t connections = 0;
	};

	[[noreturn]] void damaged(uint64_t at, const std::string& why) const
	{
		fail(path_, "damaged ROS 1 bag: " + why + " (record at byte " + std::to_string(at) + " of " +
		                std::to_string(file_.size()) + ")");
	}

	[[noreturn]] void truncated(uint64_t at, const std::string& what) const
	{
		std::ostringstream msg;
		msg << "truncated ROS 1 bag: the file ends inside " << what << " at byte " << at << " ("
		    << file_.size()
		    << " bytes; recording interrupted or incomplete copy? `rosbag reindex` may recover it)";
		fail(path_, msg.str());
	}

	/** The record at `pos`, which must end by `limit`, into `r`. */
	void readRecord(ByteSource& in, uint64_t pos, uint64_t limit, const char* what, RecordInfo& r) const
	{
		// Most headers are short: one read for the length, the header and data_len.
		constexpr std::size_t kGuess = 256;
		if (pos > limit || limit - pos < 4) truncated(pos, what);
		std::string_view bytes =
		    in.view(pos, static_cast<std::size_t>(std::min<uint64_t>(kGuess, limit - pos)));
		if (bytes.size() < 4) truncated(pos, what);
		const uint64_t header_len = littleEndian(bytes.data(), 4);
		if (header_len > kMaxHeaderBytes)
			damaged(pos, std::string(what) + " with a header of " + std::to_string(header_len) + " bytes");
		if (limit - pos - 4 < header_len + 4) truncated(pos, what);
		if (bytes.size() < 4 + header_len + 4)
		{
			bytes = in.view(pos, static_cast<std::size_t>(4 + header_len + 4));
			if (bytes.size() < 4 + header_len + 4) truncated(pos, what);
		}
		r.header_bytes.assign(bytes.data() + 4, header_len);
		r.data_len = static_cast<uint32_t>(littleEndian(bytes.data() + 4 + header_len, 4));
		std::string why;
		if (!r.header.parse(r.header_bytes, why)) damaged(pos, std::string(what) + ": " + why);
		const auto op = r.header.integer("op", 1);
		if (!op) damaged(pos, std::string(what) + " without an op field");
		r.op = static_cast<uint8_t>(*op);
		r.data_pos = pos + 4 + header_len + 4;
		if (limit - r.data_pos < r.data_len) truncated(pos, what);
		r.end = r.data_pos + r.data_len;
	}

	uint64_t requireInteger(const RecordInfo& r, uint64_t pos, std::string_view name, std::size_t n) const
	{
		const auto v = r.header.integer(name, n);
		if (!v) damaged(pos, "missing or malformed field '" + std::string(name) + "'");
		return *v;
	}

	void readBagHeader()
	{
		const uint64_t pos = kMagic.size();
		RecordInfo r;
		readRecord(file_bytes_, pos, file_.size(), "the bag header record", r);
		if (r.op != kOpBagHeader) damaged(pos, "the first record is not the bag header");
		index_pos_ = requireInteger(r, pos, "index_pos", 8);
		connection_count_ = static_cast<uint32_t>(requireInteger(r, pos, "conn_count", 4));
		chunk_count_ = static_cast<uint32_t>(requireInteger(r, pos, "chunk_count", 4));
		if (index_pos_ == 0)
			fail(path_, "unindexed ROS 1 bag (the recording was not closed); `rosbag reindex` can repair it");
		if (index_pos_ >= file_.size())
		{
			std::ostringstream msg;
			msg << "truncated ROS 1 bag: its index starts at byte " << index_pos_ << " but the file has only "
			    << file_.size()
			    << " bytes (recording interrupted or incomplete copy; `rosbag reindex` may recover it)";
			fail(path_, msg.str());
		}
		if (index_pos_ < r.end) damaged(pos, "index_pos points into the bag header");
	}

	/** Connection records, then chunk-info records, as rosbag_storage reads them. */
	void readIndexSection()
	{
		uint64_t pos = index_pos_;
		RecordInfo r;
		for (uint32_t i = 0; i < connection_count_; ++i)
		{
			readRecord(file_bytes_, pos, file_.size(), "the connection records of the index", r);
			if (r.op != kOpConnection) damaged(pos, "expected a connection record");
			const uint32_t id = static_cast<uint32_t>(requireInteger(r, pos, "conn", 4));
			const auto topic = r.header.get("topic");
			if (!topic) damaged(pos, "connection record without a topic");
			connection_topics_[id] = std::string(*topic);
			checkConnectionData(file_bytes_, r, pos);
			pos = r.end;
		}
		for (uint32_t i = 0; i < chunk_count_; ++i)
		{
			readRecord(file_bytes_, pos, file_.size(), "the chunk-info records of the index", r);
			if (r.op != kOpChunkInfo) damaged(pos, "expected a chunk-info record");
			Chunk c;
			c.pos = requireInteger(r, pos, "chunk_pos", 8);
			c.connections = static_cast<uint32_t>(requireInteger(r, pos, "count", 4));
			if (uint64_t{c.connections} * 8 != r.data_len)
				damaged(pos, "chunk-info counts do not match its size");
			if (c.pos < kMagic.size() || c.pos >= index_pos_)
				damaged(pos, "chunk-info points outside the chunks");
			chunk_infos_.push_back(c);
			pos = r.end;
		}
	}

	void checkConnectionData(ByteSource& in, const RecordInfo& r, uint64_t pos) const
	{
		if (r.data_len > (64u << 20))
			damaged(pos, "connection data of " + std::to_string(r.data_len) + " bytes");
		const std::string_view data = in.view(r.data_pos, r.data_len);
		if (data.size() != r.data_len) truncated(pos, "a connection record");
		HeaderFields fields;
		std::string why;
		if (!fields.parse(data, why)) damaged(pos, "connection data: " + why);
	}

	/** A chunk's header, the index records after it and (uncompressed, wanted
	 *  topic) the records they point to. */
	void checkChunk(const Chunk& info, const std::string& topic)
	{
		RecordInfo chunk;
		readRecord(file_bytes_, info.pos, index_pos_, "a chunk", chunk);
		if (chunk.op != kOpChunk) damaged(info.pos, "chunk-info points to a record that is not a chunk");
		const auto compression = chunk.header.get("compression");
		if (!compression) damaged(info.pos, "chunk without a compression field");
		const uint64_t size = requireInteger(chunk, info.pos, "size", 4);
		if (size > kMaxChunkBytes) damaged(info.pos, "a chunk of " + std::to_string(size) + " bytes");
		const bool raw = *compression == "none";
		const uint64_t usable = raw ? std::min<uint64_t>(size, chunk.data_len) : size;
		wanted_offsets_.clear();
		uint64_t pos = chunk.end;
		RecordInfo index;
		for (uint32_t i = 0; i < info.connections; ++i)
		{
			readRecord(file_bytes_, pos, index_pos_, "the index records of a chunk", index);
			if (index.op != kOpIndex) damaged(pos, "expected an index record after the chunk");
			const uint32_t connection = static_cast<uint32_t>(requireInteger(index, pos, "conn", 4));
			const uint64_t count = requireInteger(index, pos, "count", 4);
			if (count * 12 != index.data_len) damaged(pos, "index record counts do not match its size");
			const std::string_view entries = file_bytes_.view(index.data_pos, index.data_len);
			if (entries.size() != index.data_len) truncated(pos, "an index record");
			const auto t = connection_topics_.find(connection);
			const bool wanted = raw && !topic.empty() && t != connection_topics_.end() && t->second == topic;
			for (uint64_t k = 0; k < count; ++k)
			{
				const uint64_t offset = littleEndian(entries.data() + k * 12 + 8, 4);
				if (offset >= usable) damaged(pos, "an index entry points past the end of its chunk");
				if (wanted) wanted_offsets_.push_back(offset);
			}
			pos = index.end;
		}
		if (!wanted_offsets_.empty()) checkMessageRecords(chunk.data_pos, usable);
	}

	/** The records that the wanted index entries point to in an uncompressed
	 *  chunk. Many entries: the chunk is read at once (rosbag_storage reads it
	 *  whole too); few (a sparse topic among large messages): one read each. */
	void checkMessageRecords(uint64_t chunk_data, uint64_t usable)
	{
		constexpr uint64_t kBytesPerSmallRead = 4096;
		if (wanted_offsets_.size() * kBytesPerSmallRead < usable)
		{
			for (const uint64_t offset : wanted_offsets_)
				checkMessageRecord(file_bytes_, chunk_data, usable, offset);
			return;
		}
		std::string bytes;
		if (!file_.read(chunk_data, static_cast<std::size_t>(usable), bytes))
			truncated(chunk_data, "a chunk");
		MemoryBytes chunk(chunk_data, std::move(bytes));
		for (const uint64_t offset : wanted_offsets_) checkMessageRecord(chunk, chunk_data, usable, offset);
	}

	/** The message record at `offset` (connection records before it are
	 *  skipped, as readers do). */
	void checkMessageRecord(ByteSource& in, uint64_t chunk_data, uint64_t usable, uint64_t offset)
	{
		const uint64_t chunk_end = chunk_data + usable;
		uint64_t pos = chunk_data + offset;
		for (;;)
		{
			readRecord(in, pos, chunk_end, "a message record", message_);
			if (message_.op == kOpMessage) return;
			if (message_.op != kOpConnection && message_.op != kOpMessageDefinition)
				damaged(pos, "an index entry points to a record that is not a message");
			if (message_.op == kOpConnection) checkConnectionData(in, message_, pos);
			pos = message_.end;
		}
	}

	const std::string& path_;
	const BagFile& file_;
	FileBytes file_bytes_;
	uint64_t index_pos_ = 0;
	uint32_t connection_count_ = 0;
	uint32_t chunk_count_ = 0;
	std::map<uint32_t, std::string> connection_topics_;
	std::vector<Chunk> chunk_infos_;
	std::vector<uint64_t> wanted_offsets_;
	RecordInfo message_;
};
}  // namespace

void checkRos1BagFile(const std::string& path, const std::string& topic)
{
	std::error_code ec;
	if (fs::is_directory(path, ec)) fail(path, "is a directory, not a ROS 1 bag file");
	const BagFile file(path);
	if (!file.isOpen()) fail(path, std::string("cannot open: ") + std::strerror(file.openErrno()));
	std::string head;
	file.read(0, std::min<uint64_t>(file.size(), 16), head);
	if (head.compare(0, kMagic.size(), kMagic) == 0)
	{
		BagChecker(path, file).run(topic);
		return;
	}
	if (head.compare(0, 9, "#ROSBAG V") == 0)
		fail(path, "ROS bag format " + head.substr(9, 3) +
		               " is not supported, only 2.0 (rewrite it with `rosbag filter in.bag out.bag True`)");
	if (head.compare(0, 13, "SQLite format") == 0)
		fail(path, "not a ROS 1 bag: it is an SQLite database (a ROS 2 bag?)");
	fail(path, "not a ROS 1 bag (the file does not start with '#ROSBAG V2.0')");
}

}  // namespace auvnav::import::detail
