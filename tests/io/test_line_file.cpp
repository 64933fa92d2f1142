// io::LineFile (whole lines only, one write per flush) and oneLineReason
// (one line out of an MRPT exception report).
#include <auvnav/error_text.h>
#include <auvnav/io/line_file.h>
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using auvnav::io::LineFile;

namespace
{
std::string slurp(const fs::path& f)
{
	std::ifstream in(f, std::ios::binary);
	std::stringstream ss;
	ss << in.rdbuf();
	return ss.str();
}

fs::path scratch(const std::string& name)
{
	// One folder for the process's files, removed at exit.
	static const auvnav::testing::ScratchDir dir("line_file");
	return dir / name;
}
}  // namespace

TEST(LineFile, HoldsBackLinesUntilTheBufferFillsThenWritesThemWhole)
{
	const fs::path f = scratch("a.csv");
	LineFile out(f.string(), 100);   // flush at 100 bytes
	const std::string row(29, 'x');  // 30 bytes with its newline
	for (int i = 0; i < 3; ++i) out.line(row);
	EXPECT_EQ(fs::file_size(f), 0u);  // 90 bytes: still buffered
	out.line(row);
	EXPECT_EQ(fs::file_size(f), 120u);  // crossed 100: all four lines, whole
	out.line("tail");
	out.flush();
	EXPECT_EQ(slurp(f), row + "\n" + row + "\n" + row + "\n" + row + "\ntail\n");
	EXPECT_EQ(out.lines(), 5u);
}

TEST(LineFile, RefusesANewlineInsideALineAndFlushesWhenDestroyedOrMoved)
{
	const fs::path f = scratch("b.csv");
	{
		LineFile out(f.string());
		EXPECT_THROW(out.line("a\nb"), std::invalid_argument);
		out.line("one");
		LineFile moved = std::move(out);
		EXPECT_FALSE(out.isOpen());
		moved.line("two");
	}
	EXPECT_EQ(slurp(f), "one\ntwo\n");
	EXPECT_THROW(LineFile("/nonexistent/dir/x.csv"), std::runtime_error);
}

TEST(OneLineReason, KeepsOurContextAndMrptsInnermostMessage)
{
	const std::string report =
	    "run.rawlog: corrupt rawlog: cannot read object #12 at byte 3456 (uncompressed): ==== MRPT exception "
	    "====\n"
	    "Message:  Error reading object\n"
	    "Location: ./libs/serialization/src/CArchive.cpp:123: [ReadObject]\n"
	    "Call stack backtrace:\n[0 ]     0x7f60fd045437\n"
	    "Original exception:\n==== MRPT exception ====\n"
	    "Message:  Class 'CFoo' is not registered\n"
	    "Location: ./libs/rtti/src/CObject.cpp:77\n";
	EXPECT_EQ(
	    auvnav::oneLineReason(report),
	    "run.rawlog: corrupt rawlog: cannot read object #12 at byte 3456 (uncompressed): Class 'CFoo' is not "
	    "registered");
	EXPECT_EQ(auvnav::oneLineReason(
	              "==== MRPT exception ====\nMessage:  Assert condition failed: x\nLocation: y\n"),
	          "Assert condition failed: x");
	EXPECT_EQ(auvnav::oneLineReason("plain one line"), "plain one line");
	EXPECT_EQ(auvnav::oneLineReason("first line\nsecond line\n"), "first line");
	EXPECT_EQ(auvnav::oneLineReason("  \n"), "");
	EXPECT_EQ(auvnav::oneLineReason("class 'mr\x01\x7fX' is not registered"),
	          "class 'mr??X' is not registered");
}
