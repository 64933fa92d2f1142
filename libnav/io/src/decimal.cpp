#include <auvnav/io/decimal.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

namespace auvnav::io
{
namespace
{
constexpr int kMaxFastPrecision = 17;

/** 10^k for k in [0, 19] (10^19 < 2^64). */
constexpr uint64_t kPow10[20] = {1,
                                 10,
                                 100,
                                 1000,
                                 10000,
                                 100000,
                                 1000000,
                                 10000000,
                                 100000000,
                                 1000000000,
                                 10000000000,
                                 100000000000,
                                 1000000000000,
                                 10000000000000,
                                 100000000000000,
                                 1000000000000000,
                                 10000000000000000,
                                 100000000000000000,
                                 1000000000000000000,
                                 10000000000000000000u};

int bitLength(uint64_t x)
{
	return x ? 64 - __builtin_clzll(x) : 0;
}

/** An unsigned 128-bit value as two 64-bit words (portable: no compiler
 *  extension, the same on 32- and 64-bit targets). */
struct Wide
{
	uint64_t hi = 0, lo = 0;
};

/** a · b exactly, by 32-bit halves. */
Wide multiply(uint64_t a, uint64_t b)
{
	const uint64_t mask = 0xFFFFFFFFu;
	const uint64_t ll = (a & mask) * (b & mask), lh = (a & mask) * (b >> 32);
	const uint64_t hl = (a >> 32) * (b & mask), hh = (a >> 32) * (b >> 32);
	const uint64_t mid = (ll >> 32) + (lh & mask) + (hl & mask);
	return {hh + (lh >> 32) + (hl >> 32) + (mid >> 32), (mid << 32) | (ll & mask)};
}

/** x / 2^s for s in [1, 127]: the quotient (`fits`: below 2^64) and how
 *  the remainder compares with half of 2^s (−1, 0, +1). */
struct Shifted
{
	uint64_t q = 0;
	bool fits = false;
	int rest_vs_half = 0;
};

Shifted shiftDown(Wide x, int s)
{
	Shifted out;
	const uint64_t q_hi = s >= 64 ? 0 : x.hi >> s;
	out.q = s >= 64 ? x.hi >> (s - 64) : (x.lo >> s) | (x.hi << (64 - s));
	out.fits = q_hi == 0;
	const int h = s - 1;  // the half's bit; the rest lies in bits [0, s)
	const bool half_bit = h >= 64 ? (x.hi >> (h - 64)) & 1 : (x.lo >> h) & 1;
	bool below = false;  // any bit under the half's
	if (h >= 64)
		below = x.lo != 0 || (h > 64 && (x.hi & ((UINT64_C(1) << (h - 64)) - 1)) != 0);
	else if (h > 0)
		below = (x.lo & ((UINT64_C(1) << h) - 1)) != 0;
	out.rest_vs_half = !half_bit ? -1 : (below ? 1 : 0);
	return out;
}

/** |v| = m·2^e exactly; m < 2^53. */
struct Binary
{
	uint64_t m = 0;
	int e = 0;
	bool negative = false;
};

Binary decompose(double v)
{
	uint64_t bits = 0;
	std::memcpy(&bits, &v, sizeof bits);
	Binary b;
	b.negative = (bits >> 63) != 0;
	const int biased = static_cast<int>((bits >> 52) & 0x7FF);
	const uint64_t fraction = bits & ((UINT64_C(1) << 52) - 1);
	b.m = biased ? fraction | (UINT64_C(1) << 52) : fraction;  // subnormal: no hidden bit
	b.e = (biased ? biased : 1) - 1075;
	return b;
}

/** round(m·2^e·10^k) half to even into `n`, for k in [0, 19]; false where
 *  that is not a 64-bit integer (the library then prints the value). */
bool scaledDigits(const Binary& b, int k, uint64_t& n)
{
	if (k < 0 || k > 19) return false;
	const Wide num = multiply(b.m, kPow10[k]);
	if (b.e >= 0)
	{
		if (num.hi != 0 || bitLength(num.lo) + b.e > 63) return false;
		n = num.lo << b.e;
		return true;
	}
	if (-b.e > 127) return false;
	const Shifted d = shiftDown(num, -b.e);
	if (!d.fits || d.q == UINT64_MAX) return false;
	n = d.q + ((d.rest_vs_half > 0 || (d.rest_vs_half == 0 && (d.q & 1))) ? 1 : 0);
	return true;
}

/** "00".."99": two digits per division halves the divisions. */
constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/** Writes x < 10^8 as exactly `width` <= 8 digits (zero-padded), in 32-bit
 *  arithmetic (cheaper divisions than 64-bit). */
void writeDigits32(char* p, uint32_t x, int width)
{
	int i = width;
	for (; i >= 2; i -= 2)
	{
		const uint32_t q = x / 100;
		std::memcpy(p + i - 2, kDigitPairs + 2 * (x - 100 * q), 2);
		x = q;
	}
	if (i == 1) p[0] = static_cast<char>('0' + x);
}

/** Writes x in decimal, exactly `width` digits (zero-padded; width <= 20);
 *  returns the end. Eight digits per 64-bit division. */
char* writeDigits(char* p, uint64_t x, int width)
{
	char* end = p + width;
	char* at = end;
	while (width > 8)
	{
		const uint64_t q = x / 100000000;
		at -= 8;
		writeDigits32(at, static_cast<uint32_t>(x - q * 100000000), 8);
		x = q;
		width -= 8;
	}
	writeDigits32(p, static_cast<uint32_t>(x), width);
	return end;
}

/** Number of decimal digits of x (1 for 0). */
int decimalDigits(uint64_t x)
{
	// floor(log10) from the bit length (1233 / 4096 ≈ log10 2), then one check.
	if (x == 0) return 1;
	const int bits = 64 - __builtin_clzll(x);
	const int guess = (bits * 1233) >> 12;
	return guess + (guess < 20 && x >= kPow10[guess] ? 1 : 0);
}

void appendWithLibrary(std::string& out, double v, std::chars_format format, int precision)
{
	// "%.Pf" of the largest double: a sign, 309 digits, a point and P
	// decimals; "%.Pg" at most P digits, a point and a five-character
	// exponent. Large precisions get a buffer of their size.
	const std::size_t need = 330 + static_cast<std::size_t>(std::max(precision, 0));
	char small[400];
	std::string large;
	char* buf = small;
	if (need > sizeof small)
	{
		large.resize(need);
		buf = large.data();
	}
	const auto r = std::to_chars(buf, buf + need, v, format, precision);
	if (r.ec != std::errc())  // not with the size above; never append a buffer to_chars did not fill
		throw std::length_error("decimal: " + std::to_string(precision) + " digits do not fit the buffer");
	out.append(buf, static_cast<std::size_t>(r.ptr - buf));
}
}  // namespace

void appendFixed(std::string& out, double v, int precision)
{
	const Binary b = decompose(v);
	if (!std::isfinite(v) || precision < 0 || precision > kMaxFastPrecision ||
	    (b.e >= 0 && bitLength(b.m) + b.e > 63))
		return appendWithLibrary(out, v, std::chars_format::fixed, precision);
	uint64_t whole = 0;
	uint64_t decimals = 0;  // round(fraction·10^precision)
	if (b.e >= 0)
		whole = b.m << b.e;
	else
	{
		const int s = -b.e;
		whole = s < 64 ? b.m >> s : 0;
		const uint64_t fraction = s < 64 ? b.m - (whole << s) : b.m;  // over 2^s
		// Past 2^-120, |v|·10^17 < 2^-10: the decimals round to zero.
		if (s <= 120)
		{
			const Shifted d = shiftDown(multiply(fraction, kPow10[precision]), s);
			decimals = d.q;  // below 10^precision: fraction < 2^s
			// A tie goes to the even last digit: with no decimals, the whole part's.
			const uint64_t last = precision > 0 ? decimals : whole;
			if (d.rest_vs_half > 0 || (d.rest_vs_half == 0 && (last & 1))) ++decimals;
		}
		if (decimals == kPow10[precision])
		{
			++whole;
			decimals = 0;
		}
	}
	char buf[48];
	char* p = buf;
	if (b.negative) *p++ = '-';
	p = writeDigits(p, whole, decimalDigits(whole));
	if (precision > 0)
	{
		*p++ = '.';
		p = writeDigits(p, decimals, precision);
	}
	out.append(buf, static_cast<std::size_t>(p - buf));  // (pointer, count): no replace() machinery
}

void appendGeneral(std::string& out, double v, int precision)
{
	if (precision == 0) precision = 1;
	if (!std::isfinite(v) || precision < 0 || precision > kMaxFastPrecision)
		return appendWithLibrary(out, v, std::chars_format::general, precision);
	const Binary b = decompose(v);
	char buf[48];
	char* p = buf;
	if (b.negative) *p++ = '-';
	if (b.m == 0)
	{
		*p++ = '0';
		out.append(buf, static_cast<std::size_t>(p - buf));  // (pointer, count): no replace() machinery
		return;
	}
	// floor(log10 |v|) is x or x + 1: floor(log2 |v|)·log10(2), rounded down
	// (78913 / 2^18 is log10(2) to 1e-7, exact over the double range).
	const int log2_v = bitLength(b.m) - 1 + b.e;
	int x = (log2_v * 78913) >> 18;
	const uint64_t top = kPow10[precision];
	uint64_t n = 0;
	if (!scaledDigits(b, precision - 1 - x, n))
		return appendWithLibrary(out, v, std::chars_format::general, precision);
	while (n >= top)  // x was one low, or rounding carried to one more digit
	{
		++x;
		if (!scaledDigits(b, precision - 1 - x, n))
			return appendWithLibrary(out, v, std::chars_format::general, precision);
	}
	char digits[kMaxFastPrecision];
	writeDigits(digits, n, precision);
	int used = precision;  // significant digits left once trailing zeros go
	if (x < -4 || x >= precision)
	{
		// d.ddde±XX
		while (used > 1 && digits[used - 1] == '0') --used;
		*p++ = digits[0];
		if (used > 1)
		{
			*p++ = '.';
			std::memcpy(p, digits + 1, static_cast<std::size_t>(used - 1));
			p += used - 1;
		}
		*p++ = 'e';
		*p++ = x < 0 ? '-' : '+';
		const int ax = x < 0 ? -x : x;
		p = writeDigits(p, static_cast<uint64_t>(ax), ax < 10 ? 2 : decimalDigits(static_cast<uint64_t>(ax)));
	}
	else
	{
		const int integer_digits = x + 1;  // may be <= 0: "0.000ddd"
		const int min_used = integer_digits > 0 ? integer_digits : 0;
		while (used > min_used && digits[used - 1] == '0') --used;
		if (integer_digits <= 0)
		{
			*p++ = '0';
			if (used > 0)
			{
				*p++ = '.';
				for (int i = 0; i < -integer_digits; ++i) *p++ = '0';
				std::memcpy(p, digits, static_cast<std::size_t>(used));
				p += used;
			}
		}
		else
		{
			std::memcpy(p, digits, static_cast<std::size_t>(integer_digits));
			p += integer_digits;
			if (used > integer_digits)
			{
				*p++ = '.';
				std::memcpy(p, digits + integer_digits, static_cast<std::size_t>(used - integer_digits));
				p += used - integer_digits;
			}
		}
	}
	out.append(buf, static_cast<std::size_t>(p - buf));  // (pointer, count): no replace() machinery
}
}  // namespace auvnav::io
