// libFuzzer harness: the smoother's stretch file (smoother_stream.h) as
// auvnav-smooth reads it: StretchReader and the backward pass over it.
//
// Input: byte 0 selects how the rest becomes the file: even, as is (headers
// and truncations); odd, after a valid header for the 43 core states, the
// rest repeated to fill up to three records, so that damaged numbers (not
// only damaged headers) reach the backward pass. The pass must end or throw
// std::runtime_error naming the file, never anything else; every estimate
// it hands out has the file's dimension.
#include <auvnav/smoother_stream.h>
#include <sys/mman.h>
#include <unistd.h>

#include <fstream>
#include <iterator>

#include "fuzz_support.h"

using namespace auvnav::fuzz;

namespace
{
/** The bytes StretchWriter writes before the first record, n = core_dim. */
const Bytes& validHeader()
{
	static const Bytes header = []
	{
		const int fd = memfd_create("auvnav-fuzz-header", 0);
		FUZZ_CHECK(fd >= 0, "memfd_create");
		const std::string path = "/proc/self/fd/" + std::to_string(fd);
		auvnav::StretchFileHeader h;
		h.n = auvnav::idx::core_dim;
		h.imu_position_b.setZero();
		for (int i = 0; i < h.n; ++i)
		{
			h.tangent_names.push_back("t" + std::to_string(i));
			h.stored_names.push_back("s" + std::to_string(i));
		}
		{
			auvnav::StretchWriter writer(path, h);
		}
		std::ifstream in(path, std::ios::binary);
		Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
		::close(fd);
		FUZZ_CHECK(!bytes.empty(), "header written");
		return bytes;
	}();
	return header;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size)
{
	if (size < 1) return 0;
	Bytes file;
	if (data[0] & 1)
	{
		// Byte 1: how many records (1–3); the rest, repeated, their bytes.
		if (size < 3) return 0;
		file = validHeader();
		const std::size_t records_bytes =
		    static_cast<std::size_t>(auvnav::stretchRecordBytes(auvnav::idx::core_dim)) * (1 + data[1] % 3);
		for (std::size_t i = 0; i < records_bytes; ++i) file.push_back(data[2 + i % (size - 2)]);
	}
	else
		file.assign(data + 1, data + size);
	const MemFile mem(file.data(), file.size());
	try
	{
		auvnav::smoothStretchFile(
		    mem.path(),
		    [](double, const auvnav::NavState& x, const auvnav::Covariance& P, auvnav::SmoothedKind)
		    {
			    FUZZ_CHECK(x.dim() == auvnav::idx::core_dim && P.rows() == x.dim() && P.cols() == x.dim(),
			               "an estimate of the file's dimension");
		    });
	}
	catch (const std::runtime_error&)
	{
		// refused with a reason naming the file: the expected outcome for most inputs
	}
	return 0;
}
