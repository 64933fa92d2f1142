#pragma once
/** @file json.h
 *  The one JSON writer of the programs (auvnav-run's summary.json,
 *  auvnav-info --json, auvnav-import's reports): nlohmann::json from
 *  Debian's nlohmann-json3-dev (header only; a target including this links
 *  nlohmann_json::nlohmann_json).
 *
 *  - Json keeps the keys in insertion order, so files read as before;
 *  - jsonText writes two-space indented text ending in a newline; NaN and
 *    infinities come out as null (JSON has neither; nlohmann's rule), and
 *    bytes that are not UTF-8 (a path or a plugin's message) are replaced by
 *    U+FFFD instead of throwing;
 *  - writeJsonAtomically writes FILE.tmp and renames it over FILE, so a
 *    reader (or a run killed while writing) never sees half a file.
 */
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace auvnav::io
{
using Json = nlohmann::ordered_json;

inline std::string jsonText(const Json& j)
{
	return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

/** Throws std::runtime_error naming the file if it cannot be written. */
inline void writeJsonAtomically(const std::filesystem::path& file, const Json& j)
{
	const std::filesystem::path tmp = file.string() + ".tmp";
	{
		std::ofstream f(tmp);
		f << jsonText(j);
		if (!f.flush()) throw std::runtime_error("cannot write " + tmp.string());
	}
	std::filesystem::rename(tmp, file);
}

}  // namespace auvnav::io
