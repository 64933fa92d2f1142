#pragma once
/** @file decimal.h
 *  printf's "%.<precision>f" and "%.<precision>g" for a double, appended to
 *  a string: the same bytes as std::to_chars with chars_format::fixed /
 *  general and that precision (and as printf in the C locale), at a small
 *  fraction of its cost, which matters for the run's CSV rows (a hundred
 *  values a row, a row an IMU tick).
 *
 *  How: |v| = m·2^e exactly (m < 2^53), and the wanted digits are
 *  round(|v|·10^k) for one integer k ≤ 19, formed exactly in a two-word
 *  (128-bit) product and rounded half to even on the exact remainder, as
 *  the C library rounds. Other values (digits that are not a 64-bit
 *  integer: |v| above 2^63 in fixed form, |v| ≥ 10^precision or tiny in
 *  general form), NaN, infinities and precisions above 17 are handed to
 *  std::to_chars itself. The oracle test (tests/io/test_decimal.cpp)
 *  compares both on millions of values.
 */
#include <string>

namespace auvnav::io
{
/** Appends v as "%.<precision>f" would print it (precision >= 0). */
void appendFixed(std::string& out, double v, int precision);

/** Appends v as "%.<precision>g" would print it (precision 0 reads as 1). */
void appendGeneral(std::string& out, double v, int precision);
}  // namespace auvnav::io
