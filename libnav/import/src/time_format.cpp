#include <auvnav/import/time_format.h>

#include <cctype>
#include <cstdio>
#include <ctime>
#include <limits>

namespace auvnav::import
{
namespace
{
// MRPT's clock counts 100 ns ticks from its own epoch; this is the UNIX
// epoch on it (fromDouble(0) is exact).
int64_t unixEpochTicks()
{
	static const int64_t ticks = mrpt::Clock::fromDouble(0.0).time_since_epoch().count();
	return ticks;
}

int64_t floorDiv(int64_t a, int64_t b)
{
	int64_t q = a / b;
	if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
	return q;
}

/** Decimal text × 10^scale_exp as an integer (rounded half away from zero).
 *  Overflow-checked: |value| < 9.2e18. */
std::optional<int64_t> decimalToScaledInt(std::string_view s, int scale_exp, std::string& why)
{
	std::size_t i = 0;
	while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
	bool negative = false;
	if (i < s.size() && (s[i] == '+' || s[i] == '-')) negative = s[i++] == '-';
	std::string digits;  // all mantissa digits
	int frac_digits = 0;
	bool seen_point = false, any_digit = false;
	for (; i < s.size(); ++i)
	{
		const char c = s[i];
		if (std::isdigit(static_cast<unsigned char>(c)))
		{
			any_digit = true;
			if (!(digits.empty() && c == '0')) digits.push_back(c);
			if (seen_point) ++frac_digits;
		}
		else if (c == '.' && !seen_point)
			seen_point = true;
		else
			break;
	}
	int exponent = 0;
	if (i < s.size() && (s[i] == 'e' || s[i] == 'E'))
	{
		++i;
		bool eneg = false;
		if (i < s.size() && (s[i] == '+' || s[i] == '-')) eneg = s[i++] == '-';
		bool edigit = false;
		for (; i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])); ++i)
		{
			edigit = true;
			if (exponent < 1000) exponent = exponent * 10 + (s[i] - '0');
		}
		if (!edigit)
		{
			why = "malformed exponent";
			return std::nullopt;
		}
		if (eneg) exponent = -exponent;
	}
	while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
	if (!any_digit || i != s.size())
	{
		why = "not a number";
		return std::nullopt;
	}
	// value = digits × 10^(exponent − frac_digits + scale_exp)
	int shift = exponent - frac_digits + scale_exp;
	if (digits.empty()) return int64_t{0};
	bool round_up = false;
	if (shift < 0)
	{
		const int drop = -shift;
		if (drop > static_cast<int>(digits.size()))
		{
			return int64_t{0};  // below half a unit unless drop == size and first digit >= 5
		}
		const std::size_t keep = digits.size() - static_cast<std::size_t>(drop);
		round_up = digits[keep] >= '5';
		digits.resize(keep);
		shift = 0;
	}
	if (digits.size() + static_cast<std::size_t>(shift) > 19)
	{
		why = "out of range";
		return std::nullopt;
	}
	unsigned long long v = 0;
	for (char c : digits) v = v * 10 + static_cast<unsigned long long>(c - '0');
	for (int k = 0; k < shift; ++k) v *= 10;
	if (round_up) ++v;
	if (v > static_cast<unsigned long long>(std::numeric_limits<int64_t>::max()))
	{
		why = "out of range";
		return std::nullopt;
	}
	const auto r = static_cast<int64_t>(v);
	return negative ? -r : r;
}

bool readInt(std::string_view s, std::size_t& i, int n, int& out)
{
	out = 0;
	for (int k = 0; k < n; ++k, ++i)
	{
		if (i >= s.size() || !std::isdigit(static_cast<unsigned char>(s[i]))) return false;
		out = out * 10 + (s[i] - '0');
	}
	return true;
}

std::optional<TimeNs> parseIso8601(std::string_view s, std::string& why)
{
	why = "not an ISO 8601 time (YYYY-MM-DDThh:mm:ss[.f][Z|+hh:mm])";
	while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
	while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
	std::size_t i = 0;
	int Y, M, D, h, m, sec;
	if (!readInt(s, i, 4, Y) || i >= s.size() || s[i++] != '-' || !readInt(s, i, 2, M) || i >= s.size() ||
	    s[i++] != '-' || !readInt(s, i, 2, D))
		return std::nullopt;
	if (i >= s.size() || (s[i] != 'T' && s[i] != ' ')) return std::nullopt;
	++i;
	if (!readInt(s, i, 2, h) || i >= s.size() || s[i++] != ':' || !readInt(s, i, 2, m) || i >= s.size() ||
	    s[i++] != ':' || !readInt(s, i, 2, sec))
		return std::nullopt;
	if (M < 1 || M > 12 || D < 1 || D > 31 || h > 23 || m > 59 || sec > 60)
	{
		why = "ISO 8601 date/time field out of range";
		return std::nullopt;
	}
	int64_t frac_ns = 0;
	if (i < s.size() && (s[i] == '.' || s[i] == ','))
	{
		++i;
		int64_t scale = 100000000;
		bool any = false, round_up = false;
		int digits = 0;
		for (; i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])); ++i, any = true, ++digits)
		{
			if (digits < 9)
				frac_ns += (s[i] - '0') * scale;
			else if (digits == 9)
				round_up = s[i] >= '5';  // nearest nanosecond, as the decimal formats
			scale /= 10;
		}
		if (!any) return std::nullopt;
		frac_ns += round_up;
	}
	int64_t offset_s = 0;
	if (i < s.size())
	{
		if (s[i] == 'Z')
			++i;
		else if (s[i] == '+' || s[i] == '-')
		{
			const int sign = s[i++] == '-' ? -1 : 1;
			int oh, om = 0;
			if (!readInt(s, i, 2, oh)) return std::nullopt;
			if (i < s.size() && s[i] == ':')
			{
				++i;
				if (!readInt(s, i, 2, om)) return std::nullopt;
			}
			else if (i < s.size() && !readInt(s, i, 2, om))
				return std::nullopt;
			if (oh > 23 || om > 59)
			{
				why = "ISO 8601 zone offset out of range";
				return std::nullopt;
			}
			offset_s = sign * (oh * 3600 + om * 60);
		}
		if (i != s.size()) return std::nullopt;
	}
	std::tm tm{};
	tm.tm_year = Y - 1900;
	tm.tm_mon = M - 1;
	tm.tm_mday = D;
	tm.tm_hour = h;
	tm.tm_min = m;
	tm.tm_sec = sec;
	const int64_t days_s = static_cast<int64_t>(timegm(&tm));  // UTC, no time zone database involved
	// timegm() normalises impossible dates (2016-02-31 -> 03-02): refuse them.
	std::tm back{};
	const time_t tt = static_cast<time_t>(days_s);
	if (!gmtime_r(&tt, &back) || back.tm_mday != D || back.tm_mon != M - 1 || back.tm_year != Y - 1900)
	{
		why = "ISO 8601 date does not exist";
		return std::nullopt;
	}
	int64_t ns = 0;
	if (__builtin_mul_overflow(days_s - offset_s, int64_t{1000000000}, &ns) ||
	    __builtin_add_overflow(ns, frac_ns, &ns))
	{
		why = "out of range";
		return std::nullopt;
	}
	return ns;
}
}  // namespace

TimeFormat timeFormatFromName(const std::string& name, const std::string& what)
{
	if (name == "s") return TimeFormat::Seconds;
	if (name == "ms") return TimeFormat::Milliseconds;
	if (name == "us") return TimeFormat::Microseconds;
	if (name == "ns") return TimeFormat::Nanoseconds;
	if (name == "iso8601") return TimeFormat::Iso8601;
	throw ImportError(what + ": unknown time format '" + name + "' (s, ms, us, ns, iso8601)");
}

std::optional<TimeNs> parseTime(std::string_view text, TimeFormat format, std::string& why)
{
	switch (format)
	{
		case TimeFormat::Seconds:
			return decimalToScaledInt(text, 9, why);
		case TimeFormat::Milliseconds:
			return decimalToScaledInt(text, 6, why);
		case TimeFormat::Microseconds:
			return decimalToScaledInt(text, 3, why);
		case TimeFormat::Nanoseconds:
			return decimalToScaledInt(text, 0, why);
		case TimeFormat::Iso8601:
			return parseIso8601(text, why);
	}
	why = "unknown format";
	return std::nullopt;
}

std::string formatSeconds7(TimeNs t)
{
	const int64_t ticks = floorDiv(t, 100);
	const int64_t sec = floorDiv(ticks, 10000000);
	const int64_t frac = ticks - sec * 10000000;
	char buf[48];
	if (sec < 0 && frac != 0)
		std::snprintf(buf, sizeof buf, "-%lld.%07lld", static_cast<long long>(-(sec + 1)),
		              static_cast<long long>(10000000 - frac));
	else
		std::snprintf(buf, sizeof buf, "%lld.%07lld", static_cast<long long>(sec),
		              static_cast<long long>(frac));
	return buf;
}

mrpt::Clock::time_point toMrptTime(TimeNs t)
{
	// Round to the nearest tick from the floored quotient and its remainder:
	// t + 50 would overflow for stamps within 50 ns of the int64 limit.
	// The remainder from t % 100, not t - ticks * 100: that product overflows
	// for stamps within 100 ns of the int64 minimum (UBSan, import tests).
	int64_t ticks = floorDiv(t, 100);
	const int64_t remainder = (t % 100 + 100) % 100;
	if (remainder >= 50) ++ticks;
	return mrpt::Clock::time_point(mrpt::Clock::duration(unixEpochTicks() + ticks));
}

std::optional<TimeNs> fromMrptTimeChecked(mrpt::Clock::time_point t)
{
	// INVALID_TIMESTAMP (tick 0, 1601) and any time after 2262 have no int64
	// nanosecond count: (ticks - epoch) * 100 would overflow.
	int64_t ticks = 0, ns = 0;
	if (__builtin_sub_overflow(static_cast<int64_t>(t.time_since_epoch().count()), unixEpochTicks(),
	                           &ticks) ||
	    __builtin_mul_overflow(ticks, int64_t{100}, &ns))
		return std::nullopt;
	return ns;
}

TimeNs fromMrptTime(mrpt::Clock::time_point t)
{
	const auto ns = fromMrptTimeChecked(t);
	if (!ns)
		throw ImportError("MRPT time stamp " + std::to_string(t.time_since_epoch().count()) +
		                  " (100 ns ticks) is outside the int64 nanosecond range (1678..2262)");
	return *ns;
}

}  // namespace auvnav::import
