#pragma once
// Small helpers shared by the observation classes' serializers.
#include <mrpt/core/exceptions.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdint>
#include <string>

namespace auvnav::obs::detail
{
/** Reads an element count and refuses absurd values, so that a corrupt
 *  file gives a clear error instead of a huge allocation. */
inline uint32_t readCount(mrpt::serialization::CArchive& in, uint32_t max_count, const char* what)
{
	uint32_t n = 0;
	in >> n;
	if (n > max_count)
		THROW_EXCEPTION_FMT(
			"corrupt data: %s count %u exceeds the limit %u", what, static_cast<unsigned>(n),
			static_cast<unsigned>(max_count));
	return n;
}
}  // namespace auvnav::obs::detail
