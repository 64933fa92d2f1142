#pragma once
/** @file time_format.h
 *  Exact time stamps for the importer: text in seconds, milliseconds,
 *  microseconds or nanoseconds (decimal, optional sign, fraction and exponent)
 *  or ISO 8601 (`2016-01-23T22:29:09.123456Z`, `+hh:mm` offsets; no zone =
 *  UTC) to integer nanoseconds since the UNIX epoch, without passing through a
 *  double (UNIX seconds in a double are only good to ~0.2 µs); and the
 *  conversions to and from MRPT's 100 ns clock.
 */
#include <auvnav/import/record.h>
#include <mrpt/core/Clock.h>

#include <optional>
#include <string>
#include <string_view>

namespace auvnav::import
{
enum class TimeFormat
{
	Seconds,
	Milliseconds,
	Microseconds,
	Nanoseconds,
	Iso8601
};

/** "s", "ms", "us", "ns", "iso8601"; throws ImportError otherwise. */
TimeFormat timeFormatFromName(const std::string& name, const std::string& what);

/** Parses `text`; nullopt (and `why`) if it is not a time in that format or
 *  out of the representable range (±292 years around 1970). Fractions finer
 *  than 1 ns are rounded to the nearest nanosecond. */
std::optional<TimeNs> parseTime(std::string_view text, TimeFormat format, std::string& why);

/** Decimal seconds with exactly 7 fractional digits (MRPT's resolution):
 *  parseTime(formatSeconds7(t), Seconds) == t for every t on the 100 ns grid. */
std::string formatSeconds7(TimeNs t);

/** MRPT time point of `t` (rounded to the nearest 100 ns) and back (exact).
 *  fromMrptTime throws ImportError for a time point without an int64
 *  nanosecond count (INVALID_TIMESTAMP, after 2262); the checked form gives
 *  nullopt instead. */
mrpt::Clock::time_point toMrptTime(TimeNs t);
TimeNs fromMrptTime(mrpt::Clock::time_point t);
std::optional<TimeNs> fromMrptTimeChecked(mrpt::Clock::time_point t);

}  // namespace auvnav::import
