// Linked into the harnesses that deserialise MRPT's own observation classes
// (fuzz_rawlog, fuzz_plugin_prepare): operator new refuses (std::bad_alloc)
// any single allocation above kCap instead of making it.
//
// Why: MRPT's readers (CObservationIMU, CObservationGPS, ...) resize strings
// and vectors to whatever 32-bit length the file claims, and MRPT cannot be
// patched here (README "Fuzzing", known limit). Without the cap every run
// would stop within seconds at such an allocation, a finding that cannot be
// fixed, and nothing behind it would be explored. With the cap MRPT's reader
// fails as it does on a real machine that cannot give it 4 GiB, the rawlog
// reader must turn that into a RawlogError, and the fuzzer moves on.
// auvnav's own classes are fuzzed without the cap (fuzz_obs_*): an unbounded
// allocation of theirs is still a finding there.
#include <cstdlib>
#include <new>

namespace
{
constexpr std::size_t kCap = std::size_t(256) << 20;  // 256 MiB: no record of a real rawlog needs more

void* allocate(std::size_t n)
{
	if (n > kCap) throw std::bad_alloc();
	if (void* p = std::malloc(n ? n : 1)) return p;
	throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t n)
{
	return allocate(n);
}
void* operator new[](std::size_t n)
{
	return allocate(n);
}
void operator delete(void* p) noexcept
{
	std::free(p);
}
void operator delete[](void* p) noexcept
{
	std::free(p);
}
void operator delete(void* p, std::size_t) noexcept
{
	std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept
{
	std::free(p);
}

// libFuzzer's own allocations still go through ASan's operator new (its
// runtime is bound to it) and may come back through the operator delete
// above: both end in ASan's malloc/free, but ASan would report the pairing
// as a new/free mismatch. The check is off in these two harnesses only.
extern "C" const char* __asan_default_options()
{
	return "alloc_dealloc_mismatch=0";
}
