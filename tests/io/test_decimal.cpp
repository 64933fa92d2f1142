// io::appendFixed / appendGeneral against their oracle, std::to_chars with the
// same format and precision (what printf prints in the C locale): byte for
// byte on values chosen to break a decimal formatter (halfway cases, carries
// into a new digit, powers of ten and their neighbours, subnormals, the
// range limits of the 128-bit fast path) and on millions of random doubles.
#include <auvnav/io/decimal.h>
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace
{
std::string oracle(double v, std::chars_format f, int precision)
{
	char buf[512];
	const auto r = std::to_chars(buf, buf + sizeof buf, v, f, precision);
	return std::string(buf, r.ptr);
}

/** Number of mismatches over `values` for the given precisions; prints the first few. */
int mismatches(const std::vector<double>& values, const std::vector<int>& precisions)
{
	int bad = 0;
	for (double v : values)
		for (int p : precisions)
		{
			std::string fixed, general;
			auvnav::io::appendFixed(fixed, v, p);
			auvnav::io::appendGeneral(general, v, p);
			const std::string want_fixed = oracle(v, std::chars_format::fixed, p);
			const std::string want_general = oracle(v, std::chars_format::general, p);
			for (const auto& [got, want, what] :
			     {std::tuple{fixed, want_fixed, "f"}, std::tuple{general, want_general, "g"}})
				if (got != want && ++bad <= 10)
					ADD_FAILURE() << "%." << p << what << " of "
					              << oracle(v, std::chars_format::scientific, 17) << ": got '" << got
					              << "', want '" << want << "'";
		}
	return bad;
}

double fromBits(uint64_t bits)
{
	double v = 0;
	std::memcpy(&v, &bits, sizeof v);
	return v;
}

const std::vector<int> kAllPrecisions{0, 1, 2, 3, 5, 6, 9, 10, 12, 15, 16, 17, 18, 25};
}  // namespace

TEST(Decimal, SpecialValuesMatchToChars)
{
	const double inf = std::numeric_limits<double>::infinity();
	const std::vector<double> values{0.0,
	                                 -0.0,
	                                 1.0,
	                                 -1.0,
	                                 inf,
	                                 -inf,
	                                 std::numeric_limits<double>::quiet_NaN(),
	                                 std::numeric_limits<double>::max(),
	                                 -std::numeric_limits<double>::max(),
	                                 std::numeric_limits<double>::min(),
	                                 std::numeric_limits<double>::denorm_min(),
	                                 -std::numeric_limits<double>::denorm_min(),
	                                 std::numeric_limits<double>::epsilon(),
	                                 9.2233720368547758e18,  // 2^63: the fixed fast path's edge
	                                 9.2233720368547748e18,
	                                 1.8446744073709552e19,
	                                 1492693320.123456,  // a rawlog time
	                                 1492693320.1234565,
	                                 -1e-300,
	                                 1e300,
	                                 1e22,
	                                 1e23};
	EXPECT_EQ(0, mismatches(values, kAllPrecisions));
}

// Exactly representable halves (round half to even on the exact value, not
// on a product), carries (9.99... -> 10.0, 0.0999.. -> 0.1) and the
// neighbours of every power of ten the formats can meet.
TEST(Decimal, HalfwayCasesCarriesAndPowersOfTenMatchToChars)
{
	std::vector<double> values;
	for (int j = 1; j <= 20; ++j)
		for (int k = -40; k <= 40; ++k)
		{
			const double half = (2.0 * k + 1.0) / std::ldexp(1.0, j);  // odd multiples of 2^-j
			values.push_back(half);
			values.push_back(half * 1e-3);
			values.push_back(half * 1e6);
		}
	for (int e = -320; e <= 308; ++e)
	{
		const double p = std::pow(10.0, e);
		for (double x :
		     {p, std::nextafter(p, 0.0), std::nextafter(p, std::numeric_limits<double>::infinity()), 9.5 * p,
		      9.95 * p, 9.9999999995 * p, 9.99999999995 * p, 0.5 * p, 2.5 * p, 1.25 * p, 1.5 * p})
		{
			values.push_back(x);
			values.push_back(-x);
		}
	}
	EXPECT_EQ(0, mismatches(values, kAllPrecisions));
}

// Values of the magnitudes the run writes (times, positions, sigmas,
// quaternions, NIS), many of them decimals near the rounding point.
TEST(Decimal, RandomValuesOfEveryMagnitudeMatchToChars)
{
	std::mt19937_64 rng(20261206);
	std::uniform_int_distribution<uint64_t> any_bits;
	std::uniform_real_distribution<double> unit(-1.0, 1.0);
	std::uniform_int_distribution<int> exponent(-30, 25);
	std::vector<double> values;
	for (int i = 0; i < 200000; ++i)
	{
		values.push_back(fromBits(any_bits(rng)));  // every exponent, NaNs and infinities included
		const double scaled = unit(rng) * std::pow(10.0, exponent(rng));
		values.push_back(scaled);
		// A decimal with 6 or 10 places, plus or minus an ulp or two: the
		// exact value sits a hair from a halfway point.
		const double decimal = std::round(scaled * 1e6) / 1e6 + 5e-7;
		values.push_back(decimal);
		values.push_back(std::nextafter(decimal, std::numeric_limits<double>::infinity()));
		values.push_back(std::nextafter(decimal, -std::numeric_limits<double>::infinity()));
	}
	EXPECT_EQ(0, mismatches(values, {0, 3, 6, 9, 10, 17}));
}

TEST(Decimal, AppendsToWhatTheStringHolds)
{
	std::string s = "t=";
	auvnav::io::appendFixed(s, 2.5, 1);
	s += ",x=";
	auvnav::io::appendGeneral(s, 0.000123456789012, 10);
	EXPECT_EQ("t=2.5,x=0.000123456789", s);
}

// Precisions past the fast path go to std::to_chars with a buffer of their
// size: the largest double with 100 decimals (~410 characters) and 400
// significant digits, against printf.
TEST(Decimal, LargePrecisionsMatchPrintf)
{
	auto printed = [](const char* format, int precision, double v)
	{
		std::vector<char> buf(2000);
		const int n = std::snprintf(buf.data(), buf.size(), format, precision, v);
		return std::string(buf.data(), static_cast<std::size_t>(n));
	};
	for (const double v : {std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(), 1.0 / 3.0,
	                       std::numeric_limits<double>::denorm_min(), -2.5})
		for (const int precision : {18, 80, 100, 400, 760})
		{
			std::string fixed, general;
			auvnav::io::appendFixed(fixed, v, precision);
			auvnav::io::appendGeneral(general, v, precision);
			EXPECT_EQ(printed("%.*f", precision, v), fixed) << v << " at " << precision;
			EXPECT_EQ(printed("%.*g", precision, v), general) << v << " at " << precision;
		}
}
