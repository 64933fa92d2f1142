#pragma once
/** @file error_text.h
 *  One line out of an exception's text, for the programs' "PROGRAM: error:
 *  REASON" lines (cli.h) and the messages libnav builds around MRPT's
 *  exceptions (rawlog reading, YAML). Header only.
 *
 *  Why: MRPT's exceptions carry a report of ~10-40 lines ("==== MRPT
 *  exception ====", "Message:", "Location:", a call stack, nested
 *  "Original exception:" reports). A script reading stderr, and a person,
 *  need the cause: our own context (the text before the first report) and
 *  MRPT's innermost non-empty "Message:", which names the root cause.
 *
 *  Contract of oneLineReason(what): the result holds no '\n', '\r' or other
 *  control character (shown as '?'); it is `what` trimmed when `what` is
 *  already one printable line without a report; it is empty only when
 *  `what` is blank.
 */
#include <algorithm>
#include <sstream>
#include <string>

namespace auvnav
{
namespace detail
{
inline std::string trimmedText(const std::string& s)
{
	const auto b = s.find_first_not_of(" \t\r\n");
	const auto e = s.find_last_not_of(" \t\r\n");
	return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}
}  // namespace detail

inline std::string oneLineReason(const std::string& what)
{
	static const std::string kReport = "==== MRPT exception ====";
	const auto report_at = what.find(kReport);
	std::string cause;
	if (report_at != std::string::npos)
	{
		std::istringstream lines(what.substr(report_at));
		for (std::string line; std::getline(lines, line);)
		{
			const auto m = line.find("Message:");
			if (m == std::string::npos) continue;
			const std::string text = detail::trimmedText(line.substr(m + 8));
			if (!text.empty()) cause = text;  // the last one is the innermost
		}
	}
	std::string context = detail::trimmedText(what.substr(0, report_at));
	// Anything after our own first line (another report, a call stack) stays out.
	if (report_at == std::string::npos) context = detail::trimmedText(context.substr(0, context.find('\n')));
	std::string text = context;
	if (!cause.empty()) text += (text.empty() ? "" : " ") + cause;
	for (char& c : text)
	{
		const auto u = static_cast<unsigned char>(c);
		if (c == '\n' || c == '\r' || c == '\t')
			c = ' ';
		else if (u < 0x20 || u == 0x7f)
			c = '?';  // e.g. a class name read from garbage bytes
	}
	return text;
}
}  // namespace auvnav
