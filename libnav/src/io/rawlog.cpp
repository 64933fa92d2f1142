#include <auvnav/error_text.h>
#include <auvnav/io/rawlog.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>

#include <sstream>

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
}  // namespace

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
		mrpt::serialization::CSerializable::Ptr obj;
		try
		{
			obj = mrpt::serialization::archiveFrom(file_).ReadObject();
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
				msg << path_ << ": corrupt rawlog: cannot read or decompress object #"
					<< objects_read_ << " at byte " << offset << " (uncompressed)";
				throw RawlogError(msg.str());
			}
			throwTruncated(path_, objects_read_, offset);
		}
		catch (const std::exception& e)
		{
			// MRPT reports a short read inside an object as a plain exception,
			// not CExceptionEOF: being at the end of the file means truncation.
			if (file_.checkEOF()) throwTruncated(path_, objects_read_, offset);
			std::ostringstream msg;
			const std::string what = e.what();
			if (what.find("not registered") != std::string::npos)
			{
				// Garbage bytes or, far likelier in a well-formed file, a class
				// from an observation library nobody loaded (obs_libraries.h).
				msg << path_ << ": cannot read object #" << objects_read_ << " at byte " << offset
					<< " (uncompressed): " << oneLineReason(what)
					<< " (a corrupt rawlog, or a class whose observation library is not loaded: load it with "
					   "--obs-lib LIB, or obs_libs in the sensor's config entry)";
				throw RawlogError(msg.str());
			}
			// MRPT's report (call stack, nested reports) stays out: one line.
			msg << path_ << ": corrupt rawlog: cannot read object #" << objects_read_
				<< " at byte " << offset << " (uncompressed): " << oneLineReason(what);
			throw RawlogError(msg.str());
		}
		if (!obj)
		{
			std::ostringstream msg;
			msg << path_ << ": corrupt rawlog: null object #" << objects_read_ << " at byte "
				<< offset;
			throw RawlogError(msg.str());
		}
		++objects_read_;
		if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj))
			return o;
		if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj))
		{
			for (const auto& o : *sf) pending_.push_back(o);
			continue;
		}
		if (std::dynamic_pointer_cast<mrpt::obs::CActionCollection>(obj))
		{
			++actions_skipped_;
			continue;
		}
		std::ostringstream msg;
		msg << path_ << ": unexpected object of class '" << obj->GetRuntimeClass()->className
			<< "' (#" << (objects_read_ - 1) << " at byte " << offset
			<< "); a rawlog holds observations, sensory frames and actions";
		throw RawlogError(msg.str());
	}
	auto o = pending_.front();
	pending_.pop_front();
	return o;
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
	mrpt::serialization::archiveFrom(file_) << obs;
	last_ = obs.timestamp;
	++count_;
}

}  // namespace auvnav::io
