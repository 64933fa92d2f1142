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
#include <deque>
#include <stdexcept>
#include <string>

namespace auvnav::io
{
class RawlogError : public std::runtime_error
{
 public:
	using std::runtime_error::runtime_error;
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
	mrpt::io::CFileGZInputStream file_;
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

	std::size_t count() const { return count_; }

 private:
	std::string path_;
	mrpt::io::CFileGZOutputStream file_;
	mrpt::Clock::time_point last_{};
	std::size_t count_ = 0;
};

}  // namespace auvnav::io
