// The one JSON writer (auvnav/io/json.h): keys in insertion order, NaN and
// infinities as null, bytes that are not UTF-8 replaced, atomic file writes.
#include <auvnav/io/json.h>
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using auvnav::io::Json;

TEST(Json, KeepsKeyOrderAndWritesNonFiniteNumbersAsNull)
{
	Json j;
	j["zeta"] = 1;
	j["alpha"] = NAN;
	j["mid"] = -INFINITY;
	j["list"] = Json::array();
	const std::string text = auvnav::io::jsonText(j);
	EXPECT_EQ(text, "{\n  \"zeta\": 1,\n  \"alpha\": null,\n  \"mid\": null,\n  \"list\": []\n}\n");
}

TEST(Json, EscapesStringsAndReplacesInvalidUtf8)
{
	Json j;
	j["s"] = std::string("quote \" backslash \\ newline \n bell \x07 latin1 \xe9");
	const std::string text = auvnav::io::jsonText(j);
	EXPECT_NE(text.find(R"(quote \" backslash \\ newline \n bell \u0007 latin1 )"), std::string::npos)
	    << text;
	const Json back = Json::parse(text);  // valid JSON again
	EXPECT_EQ(back["s"].get<std::string>().substr(0, 6), "quote ");
}

TEST(Json, AtomicWriteLeavesNoTemporaryFile)
{
	const auvnav::testing::ScratchDir scratch("json_test");
	const fs::path& dir = scratch.path();
	const fs::path file = dir / "summary.json";
	std::ofstream(file) << "old";
	Json j;
	j["completed"] = true;
	auvnav::io::writeJsonAtomically(file, j);
	std::ifstream f(file);
	std::stringstream ss;
	ss << f.rdbuf();
	EXPECT_EQ(ss.str(), "{\n  \"completed\": true\n}\n");
	EXPECT_FALSE(fs::exists(dir / "summary.json.tmp"));
	EXPECT_THROW(auvnav::io::writeJsonAtomically(dir / "no_such_dir" / "x.json", j), std::exception);
}
