// libFuzzer harness: auvnav::io::RawlogReader on a file of arbitrary bytes.
//
// Input: byte 0 selects how the rest becomes the file: even, as is (a plain
// rawlog, or a damaged gzip one: the seeds hold both); odd, gzip-compressed
// first, so that mutations of the objects also travel the compressed path
// (CFileGZInputStream reads both, as auvnav-run does). The reader must end
// cleanly or throw RawlogError, never anything else; every observation it
// returns must describe itself.
#include <auvnav/io/rawlog.h>
#include <zlib.h>

#include <sstream>

#include "fuzz_support.h"

using namespace auvnav::fuzz;

namespace
{
/** `data` as a gzip member (what CFileGZOutputStream writes). */
Bytes gzip(const uint8_t* data, std::size_t size)
{
	z_stream z{};
	// windowBits 15 + 16: a gzip header and trailer, as gzopen() writes.
	if (deflateInit2(&z, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) std::abort();
	Bytes out(deflateBound(&z, size) + 32);
	z.next_in = const_cast<Bytef*>(data);
	z.avail_in = static_cast<uInt>(size);
	z.next_out = out.data();
	z.avail_out = static_cast<uInt>(out.size());
	FUZZ_CHECK(deflate(&z, Z_FINISH) == Z_STREAM_END, "deflate");
	out.resize(z.total_out);
	deflateEnd(&z);
	return out;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size)
{
	if (size < 1) return 0;
	const bool compress = data[0] & 1;
	const Bytes file = compress ? gzip(data + 1, size - 1) : Bytes(data + 1, data + size);
	const MemFile mem(file.data(), file.size());
	try
	{
		auvnav::io::RawlogReader reader(mem.path());
		while (auto o = reader.next())
		{
			std::ostringstream text;
			o->getDescriptionAsText(text);
		}
	}
	catch (const auvnav::io::RawlogError&)
	{
		// refused with a one-line reason: the expected outcome for most inputs
	}
	return 0;
}
