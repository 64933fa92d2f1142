#pragma once
/** @file rawlog.h
 *  Streaming MRPT rawlog reading and writing.
 *
 *  RawlogReader yields one observation at a time (memory does not grow with
 *  the file length). It accepts both rawlog layouts MRPT knows: a plain
 *  sequence of CObservation objects, and CSensoryFrame/CActionCollection pairs
 *  (actions are skipped and counted). Any corrupt, truncated or foreign
 *  content raises RawlogError naming the file, the object index and the
 *  uncompressed byte offset, in one line (MRPT's exception report reduced to
 *  its cause, error_text.h); the reader never crashes on bad bytes.
 *
 *  Hardening (issue 15): each object's class is read from its header and
 *  checked before the object is built: only observations, sensory frames
 *  and action collections (holding observations and actions only) are ever
 *  deserialised. Sensory frames and action collections are read here, one
 *  member at a time (MRPT's readers allocate the claimed count at once), and
 *  delivered all or nothing. auvnav's observation classes bound every count
 *  and length they read; the flag bytes MRPT copies into bools
 *  (CObservationIMU::dataIsPresent, CObservationGPS's flags) are checked
 *  before an observation is returned. Known limit: MRPT's own observation
 *  classes read 32-bit string and vector lengths unchecked, so a damaged IMU
 *  or GPS record can still make MRPT allocate up to 4 GiB once before the
 *  read fails (MRPT cannot be patched here).
 *
 *  RawlogWriter writes a gzip-compressed observation-only rawlog and refuses
 *  observations that go back in time.
 */
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservation.h>

#include <cstdint>
#include <cstring>
#include <deque>
#include <stdexcept>
#include <string>
#include <vector>

namespace auvnav::io
{
class RawlogError : public std::runtime_error
{
 public:
	using std::runtime_error::runtime_error;
};

/** A gzip (or plain) file read through CFileGZInputStream in 4 KiB blocks.
 *  MRPT's readers ask for a few bytes at a time, and every gzread call pays
 *  its set-up before it copies one byte: the block turns those many small
 *  reads into few large ones (issue 16).
 *  Positions count the uncompressed bytes handed out. Read() never returns
 *  more than asked (zlib's error, -1, reads as no bytes). checkEOF() is true
 *  only after a read found the real end of the file, not after a zlib error.
 *  The block is small because zlib drops what one gzread call had
 *  decompressed when it meets damaged data: at most 4 KiB before the damage
 *  is lost that unbuffered reading would have delivered. */
class BufferedGzInput final : public mrpt::io::CStream
{
 public:
	/** Throws (as CFileGZInputStream does) if `path` does not exist. */
	bool open(const std::string& path) { return file_.open(path); }
	size_t Read(void* buf, size_t n) override
	{
		if (n > end_ - pos_) return readAcross(buf, n);
		std::memcpy(buf, block_.data() + pos_, n);  // most reads: a few bytes of the block
		pos_ += n;
		handed_out_ += n;
		return n;
	}
	size_t Write(const void*, size_t) override { return 0; }
	/** Not seekable: throws std::logic_error. */
	uint64_t Seek(int64_t, CStream::TSeekOrigin) override;
	uint64_t getTotalBytesCount() const override { return file_.getTotalBytesCount(); }
	uint64_t getPosition() const override { return handed_out_; }
	bool checkEOF() { return pos_ == end_ && at_end_ && file_.checkEOF(); }

 private:
	/** Reads the next block; false if nothing more could be read. */
	bool refill();
	/** Read() of more bytes than the block holds. */
	size_t readAcross(void* buf, size_t n);

	mrpt::io::CFileGZInputStream file_;
	std::vector<char> block_ = std::vector<char>(std::size_t(1) << 12);
	std::size_t pos_ = 0, end_ = 0;
	uint64_t handed_out_ = 0;
	bool at_end_ = false;  //!< the last refill got 0 bytes, without an error
};

class RawlogReader
{
 public:
	/** Opens `path`; throws RawlogError if it cannot be opened. */
	explicit RawlogReader(const std::string& path);

	/** Next observation in file order, or nullptr at a clean end of file.
	 *  Throws RawlogError on corrupt or truncated content. */
	mrpt::obs::CObservation::Ptr next();

	const std::string& path() const { return path_; }
	std::size_t objectsRead() const { return objects_read_; }
	std::size_t actionsSkipped() const { return actions_skipped_; }

 private:
	/** Reads the object at `offset` into pending_ (an observation, or a
	 *  sensory frame's: possibly none) or skips an action collection.
	 *  Throws on anything else; next() words the error. */
	void readObject(uint64_t offset);

	std::string path_;
	BufferedGzInput file_;
	std::deque<mrpt::obs::CObservation::Ptr> pending_;  // from a CSensoryFrame
	std::size_t objects_read_ = 0;
	std::size_t actions_skipped_ = 0;
};

class RawlogWriter
{
 public:
	/** Creates (truncates) `path`. `compression_level` is zlib's 0..9. */
	explicit RawlogWriter(const std::string& path, int compression_level = 6);

	/** Appends one observation; throws std::invalid_argument if its timestamp
	 *  is earlier than the previous one. */
	void write(const mrpt::obs::CObservation& obs);
	/** Flushes and closes the file (also done by the destructor). */
	void close() { file_.close(); }

	std::size_t count() const { return count_; }

 private:
	std::string path_;
	mrpt::io::CFileGZOutputStream file_;
	mrpt::Clock::time_point last_{};
	std::size_t count_ = 0;
};

}  // namespace auvnav::io
