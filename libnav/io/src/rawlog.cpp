#include <auvnav/error_text.h>
#include <auvnav/io/rawlog.h>
#include <mrpt/obs/CAction.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>

#include <algorithm>
#include <cstring>
#include <sstream>
#include <vector>

namespace auvnav::io
{
namespace
{
[[noreturn]] void throwTruncated(const std::string& path, std::size_t index, uint64_t offset)
{
	std::ostringstream msg;
	msg << path << ": truncated rawlog: object #" << index << " starting at byte " << offset
	    << " (uncompressed) ends early";
	throw RawlogError(msg.str());
}

/** Most objects one CSensoryFrame or CActionCollection may claim: far above
 *  any real frame, low enough that a damaged count is refused at once. */
constexpr uint32_t kMaxFrameObjects = 65536;
constexpr uint8_t kEndFlag = 0x88;  // MRPT's end-of-object byte

/** MRPT's object header ([0x80|name length][class name][version]), read
 *  and checked before anything of the object is built. */
struct ObjectHeader
{
	std::string raw;  //!< the header's bytes, to hand them to MRPT again
	std::string class_name;
	const mrpt::rtti::TRuntimeClassId* cls = nullptr;  //!< null: not registered
	uint8_t version = 0;
};

/** Reads exactly `n` bytes; throws (a short object) if the stream ends first. */
void readExactly(BufferedGzInput& in, void* buf, std::size_t n, const char* what)
{
	auto* p = static_cast<char*>(buf);
	for (std::size_t done = 0; done < n;)
	{
		const std::size_t got = in.Read(p + done, n - done);
		if (got == 0) throw std::runtime_error(std::string("the file ends inside ") + what);
		done += got;
	}
}

/** The next object's header. Throws CExceptionEOF if not one byte is left
 *  (a clean end, or undecodable compressed data: the caller tells them
 *  apart), std::runtime_error if the header is cut or malformed. */
ObjectHeader readHeader(BufferedGzInput& in)
{
	ObjectHeader h;
	uint8_t len = 0;
	if (in.Read(&len, 1) != 1) throw mrpt::serialization::CExceptionEOF("end of file");
	// MRPT writers since 0.5.5 (2007) set the top bit; the older layout is
	// not read (MRPT's own reader would, with 32-bit version fields).
	if (!(len & 0x80)) throw std::runtime_error("not an MRPT object header (first byte lacks the 0x80 flag)");
	const std::size_t name_len = len & 0x7F;
	if (name_len == 0 || name_len > 120)
		throw std::runtime_error("not an MRPT object header (class name length)");
	h.class_name.resize(name_len);
	readExactly(in, h.class_name.data(), name_len, "an object header");
	if (h.class_name != "nullptr") readExactly(in, &h.version, 1, "an object header");
	h.raw.push_back(static_cast<char>(len));
	h.raw += h.class_name;
	h.raw.push_back(static_cast<char>(h.version));
	h.cls = mrpt::rtti::findRegisteredClass(h.class_name);
	return h;
}

/** A read-only stream serving `head` first, then `rest`: MRPT's ReadObject
 *  reads again the header readHeader() has already checked. */
class ReplayStream : public mrpt::io::CStream
{
 public:
	ReplayStream(const std::string& head, BufferedGzInput& rest) : head_(head), rest_(rest) {}
	size_t Read(void* buf, size_t n) override
	{
		if (used_ == head_.size()) return rest_.Read(buf, n);
		const std::size_t from_head = std::min(n, head_.size() - used_);
		std::memcpy(buf, head_.data() + used_, from_head);
		used_ += from_head;
		return from_head +
		       (n > from_head ? rest_.Read(static_cast<char*>(buf) + from_head, n - from_head) : 0);
	}
	size_t Write(const void*, size_t) override { return 0; }
	uint64_t Seek(int64_t, CStream::TSeekOrigin) override { throw std::logic_error("ReplayStream::Seek"); }
	uint64_t getTotalBytesCount() const override { return rest_.getTotalBytesCount(); }
	uint64_t getPosition() const override { return rest_.getPosition() - (head_.size() - used_); }

 private:
	const std::string& head_;
	BufferedGzInput& rest_;
	std::size_t used_ = 0;
};

/** The object whose header is `h` (already read from `in`), built by its
 *  class's own reader, end flag included. */
mrpt::serialization::CSerializable::Ptr readBody(const ObjectHeader& h, BufferedGzInput& in)
{
	ReplayStream replay(h.raw, in);
	return mrpt::serialization::archiveFrom(replay).ReadObject();
}

/** True unless the byte behind `b` is 0 or 1 (read as a byte: loading a
 *  bool that holds anything else is undefined behaviour). */
bool badFlag(const bool& b)
{
	uint8_t v = 0;
	std::memcpy(&v, &b, 1);
	return v > 1;
}

/** MRPT's IMU and GPS readers copy bytes straight into bools
 *  (CObservationIMU::dataIsPresent, the GPS flags the gps plugin reads); a
 *  damaged byte there would be undefined behaviour in the first plugin that
 *  looks. Such a record is refused whole before anyone reads it. */
void checkMrptFlags(const mrpt::obs::CObservation& o)
{
	if (const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(&o))
	{
		for (const bool& b : imu->dataIsPresent)
			if (badFlag(b))
				throw std::runtime_error(
				    "corrupt data: CObservationIMU dataIsPresent byte is neither 0 nor 1");
	}
	else if (const auto* gps = dynamic_cast<const mrpt::obs::CObservationGPS*>(&o))
	{
		if (badFlag(gps->has_satellite_timestamp))
			throw std::runtime_error(
			    "corrupt data: CObservationGPS has_satellite_timestamp byte is neither 0 nor 1");
		if (gps->has_GGA_datum() &&
		    badFlag(gps->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>().fields.thereis_HDOP))
			throw std::runtime_error(
			    "corrupt data: CObservationGPS GGA thereis_HDOP byte is neither 0 nor 1");
	}
}

/** An observation whose header is `h`, read by its class's reader and
 *  checked (checkMrptFlags). */
mrpt::obs::CObservation::Ptr readObservation(const ObjectHeader& h, BufferedGzInput& in)
{
	auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(readBody(h, in));
	if (!o) throw std::runtime_error("the reader of '" + h.class_name + "' returned no observation");
	checkMrptFlags(*o);
	return o;
}

bool isA(const ObjectHeader& h, const mrpt::rtti::TRuntimeClassId* base)
{
	return h.cls != nullptr && h.cls->derivedFrom(base);
}

/** One object inside a CSensoryFrame or CActionCollection: refused unless
 *  of class `base` before it is built. */
mrpt::serialization::CSerializable::Ptr readMember(BufferedGzInput& in,
                                                   const mrpt::rtti::TRuntimeClassId* base,
                                                   const char* container)
{
	const ObjectHeader h = readHeader(in);
	if (!isA(h, base))
		throw std::runtime_error(std::string("a ") + container + " holds " + base->className +
		                         " objects only, not '" + h.class_name + "'");
	return readBody(h, in);
}

uint32_t readFrameCount(BufferedGzInput& in, const char* container)
{
	uint32_t n = 0;
	readExactly(in, &n, sizeof n, container);
	if (n > kMaxFrameObjects)
		throw std::runtime_error(std::string(container) + " claims " + std::to_string(n) +
		                         " objects (limit " + std::to_string(kMaxFrameObjects) + ")");
	return n;
}

void readEndFlag(BufferedGzInput& in, const char* container)
{
	uint8_t flag = 0;
	readExactly(in, &flag, 1, container);
	if (flag != kEndFlag)
		throw std::runtime_error(std::string(container) + " lacks MRPT's end-of-object flag");
}

/** A CSensoryFrame's observations (MRPT's layout, versions 0..2), read one
 *  by one instead of by MRPT's reader, which allocates the claimed count at
 *  once and accepts an object of any class. All or nothing: a damaged frame
 *  gives none of its observations. */
std::vector<mrpt::obs::CObservation::Ptr> readSensoryFrame(const ObjectHeader& h, BufferedGzInput& in)
{
	constexpr const char* kWhat = "a sensory frame";
	if (h.version > 2)
		throw std::runtime_error("unknown CSensoryFrame serialization version " + std::to_string(h.version));
	uint32_t id = 0;
	if (h.version < 2) readExactly(in, &id, sizeof id, kWhat);  // an ID, dropped in version 2
	int64_t stamp = 0;
	if (h.version == 0) readExactly(in, &stamp, sizeof stamp, kWhat);  // one time for all, version 0
	const uint32_t n = readFrameCount(in, kWhat);
	std::vector<mrpt::obs::CObservation::Ptr> obs;
	for (uint32_t i = 0; i < n; ++i)
	{
		auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(
		    readMember(in, CLASS_ID(mrpt::obs::CObservation), kWhat));
		if (!o) throw std::runtime_error("a sensory frame holds a null observation");
		checkMrptFlags(*o);
		obs.push_back(std::move(o));
		if (h.version == 0) obs.back()->timestamp = mrpt::Clock::time_point(mrpt::Clock::duration(stamp));
	}
	readEndFlag(in, kWhat);
	return obs;
}

/** Reads (and drops) a CActionCollection, checked like a sensory frame. */
void skipActionCollection(const ObjectHeader& h, BufferedGzInput& in)
{
	constexpr const char* kWhat = "an action collection";
	if (h.version != 0)
		throw std::runtime_error("unknown CActionCollection serialization version " +
		                         std::to_string(h.version));
	const uint32_t n = readFrameCount(in, kWhat);
	for (uint32_t i = 0; i < n; ++i) readMember(in, CLASS_ID(mrpt::obs::CAction), kWhat);
	readEndFlag(in, kWhat);
}
}  // namespace

bool BufferedGzInput::refill()
{
	pos_ = end_ = 0;
	const std::size_t got = file_.Read(block_.data(), block_.size());
	// gzread's -1 (a zlib error) arrives as a huge size_t: no bytes.
	at_end_ = got == 0;
	if (got == 0 || got > block_.size()) return false;
	end_ = got;
	return true;
}

size_t BufferedGzInput::readAcross(void* buf, size_t n)
{
	auto* out = static_cast<char*>(buf);
	std::size_t done = 0;
	while (done < n)
	{
		if (pos_ == end_ && !refill()) break;
		const std::size_t k = std::min(n - done, end_ - pos_);
		std::memcpy(out + done, block_.data() + pos_, k);
		pos_ += k;
		done += k;
	}
	handed_out_ += done;
	return done;
}

uint64_t BufferedGzInput::Seek(int64_t, CStream::TSeekOrigin)
{
	throw std::logic_error("BufferedGzInput::Seek");
}

RawlogReader::RawlogReader(const std::string& path) : path_(path)
{
	// CFileGZInputStream::open() throws, rather than returning false, when the
	// file does not exist.
	bool opened = false;
	try
	{
		opened = file_.open(path);
	}
	catch (const std::exception&)
	{
		opened = false;
	}
	if (!opened) throw RawlogError("cannot open rawlog '" + path + "' for reading");
}

mrpt::obs::CObservation::Ptr RawlogReader::next()
{
	while (pending_.empty())
	{
		const uint64_t offset = file_.getPosition();
		try
		{
			readObject(offset);
		}
		catch (const RawlogError&)
		{
			throw;
		}
		catch (const mrpt::serialization::CExceptionEOF&)
		{
			// EOF before any byte of a new object: a clean end of file. zlib
			// reports corrupt compressed data as "no more bytes" too; only
			// gzeof() (checkEOF) tells the real end of the file apart.
			if (file_.getPosition() == offset && file_.checkEOF()) return nullptr;
			if (file_.getPosition() == offset)
			{
				std::ostringstream msg;
				msg << path_ << ": corrupt rawlog: cannot read or decompress object #" << objects_read_
				    << " at byte " << offset << " (uncompressed)";
				throw RawlogError(msg.str());
			}
			throwTruncated(path_, objects_read_, offset);
		}
		catch (const std::exception& e)
		{
			// MRPT reports a short read inside an object as a plain exception,
			// not CExceptionEOF: being at the end of the file means truncation.
			if (file_.checkEOF()) throwTruncated(path_, objects_read_, offset);
			// MRPT's report (call stack, nested reports) stays out: one line.
			std::ostringstream msg;
			msg << path_ << ": corrupt rawlog: cannot read object #" << objects_read_ << " at byte " << offset
			    << " (uncompressed): " << oneLineReason(e.what());
			throw RawlogError(msg.str());
		}
	}
	auto o = pending_.front();
	pending_.pop_front();
	return o;
}

void RawlogReader::readObject(uint64_t offset)
{
	// The class is checked from the header before the object is built, so a
	// damaged or foreign file never runs the reader of a class that has no
	// place in a rawlog (a map, a matrix, a 3-D scene...).
	const ObjectHeader h = readHeader(file_);
	if (h.class_name == "nullptr")
	{
		std::ostringstream msg;
		msg << path_ << ": corrupt rawlog: null object #" << objects_read_ << " at byte " << offset;
		throw RawlogError(msg.str());
	}
	if (!h.cls)
	{
		// Garbage bytes or, far likelier in a well-formed file, a class from
		// an observation library nobody loaded (obs_libraries.h).
		std::ostringstream msg;
		msg << path_ << ": cannot read object #" << objects_read_ << " at byte " << offset
		    << " (uncompressed): class '" << h.class_name << "' is not registered"
		    << " (a corrupt rawlog, or a class whose observation library is not loaded: load it with "
		       "--obs-lib LIB, or obs_libs in the sensor's config entry)";
		throw RawlogError(msg.str());
	}
	if (isA(h, CLASS_ID(mrpt::obs::CObservation)))
	{
		auto o = readObservation(h, file_);
		++objects_read_;
		pending_.push_back(std::move(o));
		return;
	}
	if (h.cls == CLASS_ID(mrpt::obs::CSensoryFrame))
	{
		auto obs = readSensoryFrame(h, file_);
		++objects_read_;
		pending_.insert(pending_.end(), obs.begin(), obs.end());
		return;
	}
	if (h.cls == CLASS_ID(mrpt::obs::CActionCollection))
	{
		skipActionCollection(h, file_);
		++objects_read_;
		++actions_skipped_;
		return;
	}
	std::ostringstream msg;
	msg << path_ << ": unexpected object of class '" << h.class_name << "' (#" << objects_read_ << " at byte "
	    << offset << "); a rawlog holds observations, sensory frames and actions";
	throw RawlogError(msg.str());
}

RawlogWriter::RawlogWriter(const std::string& path, int compression_level) : path_(path)
{
	if (!file_.open(path, compression_level))
		throw RawlogError("cannot open rawlog '" + path + "' for writing");
}

void RawlogWriter::write(const mrpt::obs::CObservation& obs)
{
	if (count_ > 0 && obs.timestamp < last_)
	{
		std::ostringstream msg;
		msg << path_ << ": observation '" << obs.sensorLabel << "' at "
		    << mrpt::system::timeLocalToString(obs.timestamp)
		    << " is older than the previous one; rawlogs are written in time order";
		throw std::invalid_argument(msg.str());
	}
	try
	{
		mrpt::serialization::archiveFrom(file_) << obs;
	}
	catch (const std::exception& e)
	{
		// MRPT says only "Cannot write bytes to stream!" (e.g. a full disk).
		throw RawlogError(path_ + ": cannot write observation #" + std::to_string(count_ + 1) + " ('" +
		                  obs.sensorLabel + "'): " + auvnav::oneLineReason(e.what()));
	}
	last_ = obs.timestamp;
	++count_;
}

}  // namespace auvnav::io
