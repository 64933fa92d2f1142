#pragma once
/** @file enum_names.h
 *  An enum's names written once, as an array indexed by the enumerators'
 *  values (0, 1, … in declaration order), instead of a switch per enum:
 *  nameOf() prints a value, parseName() reads a name back. Where it is
 *  defined, an array is checked with a static_assert against the enum's
 *  last value, so that a new enumerator without a name does not build.
 */
#include <cstddef>
#include <string_view>

namespace auvnav
{
/** The name of `value` in `names`, `fallback` for a value past the end. */
template <class Enum, std::size_t N>
constexpr const char* nameOf(const char* const (&names)[N], Enum value, const char* fallback)
{
	const auto i = static_cast<std::size_t>(value);
	return i < N ? names[i] : fallback;
}

/** The enumerator named `name` (exactly) in `names`; false and `out`
 *  untouched if there is none. */
template <class Enum, std::size_t N>
bool parseName(const char* const (&names)[N], std::string_view name, Enum& out)
{
	for (std::size_t i = 0; i < N; ++i)
		if (name == names[i])
		{
			out = static_cast<Enum>(i);
			return true;
		}
	return false;
}

/** True when `names` has one entry per enumerator up to `last`. */
template <class Enum, std::size_t N>
constexpr bool namesEveryValue(const char* const (&)[N], Enum last)
{
	return N == static_cast<std::size_t>(last) + 1;
}
}  // namespace auvnav
