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
__extension__ typedef unsigned __int128 u128;  // GCC and Clang on 64-bit targets

constexpr int kMaxFastPrecision = 17;

/** 10^k for k in [0, 38] (10^38 < 2^127). */
u128 pow10(int k)
{
	u128 p = 1;
	for (; k >= 19; k -= 19) p *= UINT64_C(10000000000000000000);
	static constexpr uint64_t kSmall[19] = {1,
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
	                                        1000000000000000000};
	return p * kSmall[k];
}

int bitLength(u128 x)
{
	const auto hi = static_cast<uint64_t>(x >> 64);
	if (hi) return 128 - __builtin_clzll(hi);
	const auto lo = static_cast<uint64_t>(x);
	return lo ? 64 - __builtin_clzll(lo) : 0;
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

/** num / 2^s rounded half to even; 1 <= s <= 127. */
u128 shiftRound(u128 num, int s)
{
	const u128 q = num >> s;
	const u128 r = num - (q << s);
	const u128 half = u128(1) << (s - 1);
	return (r > half || (r == half && (q & 1))) ? q + 1 : q;
}

/** num / den rounded half to even; den < 2^127. */
u128 divRound(u128 num, u128 den)
{
	const u128 q = num / den;
	const u128 r = num - q * den;
	return (2 * r > den || (2 * r == den && (q & 1))) ? q + 1 : q;
}

/** round(m·2^e·10^k) half to even into `n`; false if it does not fit the
 *  fast path's 128-bit arithmetic. */
bool scaledDigits(const Binary& b, int k, u128& n)
{
	if (k >= 0)
	{
		if (k > 22) return false;  // m·10^k < 2^53·2^74
		const u128 num = u128(b.m) * pow10(k);
		if (b.e >= 0)
		{
			if (bitLength(num) + b.e > 127) return false;
			n = num << b.e;
		}
		else if (-b.e > 127)
			return false;
		else
			n = shiftRound(num, -b.e);
		return true;
	}
	const int j = -k;
	if (j > 38) return false;
	const u128 den = pow10(j);
	if (b.e >= 0)
	{
		if (bitLength(b.m) + b.e > 127) return false;
		n = divRound(u128(b.m) << b.e, den);
		return true;
	}
	if (bitLength(den) - b.e > 127) return false;
	n = divRound(b.m, den << -b.e);
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
	return guess + (x >= static_cast<uint64_t>(pow10(guess)) ? 1 : 0);
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
			const u128 num = u128(fraction) * pow10(precision);
			decimals = static_cast<uint64_t>(num >> s);
			const u128 rest = num - (u128(decimals) << s);
			const u128 half = u128(1) << (s - 1);
			// A tie goes to the even last digit: with no decimals, the whole part's.
			const uint64_t last = precision > 0 ? decimals : whole;
			if (rest > half || (rest == half && (last & 1))) ++decimals;
		}
		if (decimals == static_cast<uint64_t>(pow10(precision)))
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
	const auto top = static_cast<uint64_t>(pow10(precision));
	u128 n = 0;
	if (!scaledDigits(b, precision - 1 - x, n))
		return appendWithLibrary(out, v, std::chars_format::general, precision);
	while (n >= top)  // x was one low, or rounding carried to one more digit
	{
		++x;
		if (!scaledDigits(b, precision - 1 - x, n))
			return appendWithLibrary(out, v, std::chars_format::general, precision);
	}
	char digits[kMaxFastPrecision];
	writeDigits(digits, static_cast<uint64_t>(n), precision);
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
