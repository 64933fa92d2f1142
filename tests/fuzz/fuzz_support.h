#pragma once
/** @file fuzz_support.h
 *  Helpers shared by the libFuzzer harnesses of tests/fuzz (not installed).
 *
 *  Contract: a harness feeds the bytes to the project's own reader and
 *  returns normally whatever the reader decides (a clean refusal is an
 *  expected outcome); only a sanitizer report, an uncaught exception, an
 *  allocation beyond -malloc_limit_mb, a timeout or a broken invariant
 *  checked with FUZZ_CHECK (abort) counts as a finding.
 */
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/serialization/CSerializable.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace auvnav::fuzz
{
using Bytes = std::vector<uint8_t>;

/** Aborts (a finding) with `what` when `cond` is false. */
#define FUZZ_CHECK(cond, what)                                                     \
	do                                                                             \
	{                                                                              \
		if (!(cond))                                                               \
		{                                                                          \
			std::fprintf(stderr, "fuzz invariant broken: %s (%s)\n", what, #cond); \
			std::abort();                                                          \
		}                                                                          \
	} while (0)

/** One MRPT object from `bytes` (header, data, end flag); throws on refusal. */
inline mrpt::serialization::CSerializable::Ptr readObject(const uint8_t* data, std::size_t size)
{
	mrpt::io::CMemoryStream buf;
	buf.assignMemoryNotOwn(data, size);
	return mrpt::serialization::archiveFrom(buf).ReadObject();
}

/** An object's serialisation (header, data, end flag). */
inline Bytes writeObject(const mrpt::serialization::CSerializable& obj)
{
	mrpt::io::CMemoryStream buf;
	mrpt::serialization::archiveFrom(buf) << obj;
	const auto* p = static_cast<const uint8_t*>(buf.getRawBufferData());
	return Bytes(p, p + buf.getTotalBytesCount());
}

/** MRPT's object header for `class_name` at `version`: what ReadObject
 *  expects before the class's own data. */
inline Bytes objectHeader(const std::string& class_name, uint8_t version)
{
	Bytes h;
	h.push_back(static_cast<uint8_t>(0x80 | class_name.size()));
	h.insert(h.end(), class_name.begin(), class_name.end());
	h.push_back(version);
	return h;
}

/** An anonymous in-memory file (memfd) holding `bytes`, reachable by path
 *  (/proc/self/fd/N) for readers that open files by name: no disk I/O and
 *  nothing left behind. */
class MemFile
{
 public:
	MemFile(const void* data, std::size_t size)
	{
		fd_ = memfd_create("auvnav-fuzz", 0);
		if (fd_ < 0) throw std::runtime_error("memfd_create failed");
		const auto* p = static_cast<const char*>(data);
		for (std::size_t done = 0; done < size;)
		{
			const ssize_t n = ::write(fd_, p + done, size - done);
			if (n <= 0) throw std::runtime_error("memfd write failed");
			done += static_cast<std::size_t>(n);
		}
	}
	~MemFile() { ::close(fd_); }
	MemFile(const MemFile&) = delete;
	MemFile& operator=(const MemFile&) = delete;
	std::string path() const { return "/proc/self/fd/" + std::to_string(fd_); }

 private:
	int fd_ = -1;
};
}  // namespace auvnav::fuzz
