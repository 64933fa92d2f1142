// Damage inside a compressed rawlog (issue 15): zlib hands back whatever the
// damaged deflate stream decodes to until it notices, so values from a
// broken stretch could reach the filter before the reader gives up (the
// audit's run ended 25.9 m off where the same damage in a plain file left
// 1.1 m). Acceptance: the run stops with an error naming the file, and the
// last estimate is within 2x the clean run's error at that time.
//
// The shipped sample, gzip-compressed by RawlogWriter, damaged in place at
// several points of the compressed bytes (flipped bits over 64 bytes, and
// 512 bytes of noise), run in-process through libnav's run loop.
#include <auvnav/config.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/navigator.h>
#include <auvnav/rawlog_run.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <random>

#include "harness.h"

namespace fs = std::filesystem;
using namespace auvnav;
using namespace auvnav::test;

namespace
{
const std::string kConfig = std::string(AUVNAV_SOURCE_DIR) + "/config/flatfish.yaml";
const fs::path kSample = fs::path(AUVNAV_SOURCE_DIR) / "share/sample";

fs::path scratch(const std::string& name)
{
	// A file `name` in a folder of its own, removed at exit (scratch_dir.h).
	return auvnav::testing::scratchFolder("corrupt", name) / name;
}

std::vector<char> readBytes(const fs::path& p)
{
	std::ifstream in(p, std::ios::binary);
	return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& p, const std::vector<char>& bytes)
{
	std::ofstream out(p, std::ios::binary);
	out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/** The sample re-written gzip-compressed (level 6), once per process. */
const std::vector<char>& compressedSample()
{
	static const std::vector<char> bytes = []
	{
		const fs::path gz = scratch("sample_gz.rawlog");
		{
			io::RawlogReader in((kSample / "sample.rawlog").string());
			io::RawlogWriter out(gz.string(), 6);
			while (auto obs = in.next()) out.write(*obs);
		}
		auto b = readBytes(gz);
		fs::remove(gz);
		return b;
	}();
	return bytes;
}

struct Outcome
{
	double t_end = 0;                                      //!< navigator time at the end of the run
	double error_m = 0;                                    //!< horizontal error there
	double sigma_m = 0;                                    //!< 1-sigma horizontal there
	std::string error;                                     //!< what ended the run ("" if it completed)
	std::vector<std::pair<double, double>> error_by_time;  //!< (t, horizontal error) at every prediction
};

Outcome run(const fs::path& rawlog, bool record)
{
	static const auto truth = readTruth(kSample / "ground_truth.csv");
	const auto cfg = config::Node::load(kConfig);
	PluginHost host;
	Navigator nav(cfg, host);
	Outcome o;
	RunCallbacks cb;
	if (record)
		cb.on_predict = [&](const Navigator& n)
		{
			if (n.initialized()) o.error_by_time.emplace_back(n.time(), horizontalError(n, truth).error_m);
		};
	const RunSummary s = runRawlog(nav, rawlog.string(), cb);
	o.error = s.error;
	o.t_end = nav.time();
	const HorizontalError e = horizontalError(nav, truth);
	o.error_m = e.error_m;
	o.sigma_m = e.two_sigma_m / 2;
	return o;
}

const Outcome& clean()
{
	static const Outcome o = []
	{
		const fs::path p = scratch("clean.rawlog");
		writeBytes(p, compressedSample());
		Outcome c = run(p, true);
		fs::remove(p);
		return c;
	}();
	return o;
}

/** The clean run's error at time t (the last prediction at or before t). */
double cleanErrorAt(double t)
{
	const auto& e = clean().error_by_time;
	auto it = std::upper_bound(e.begin(), e.end(), t, [](double v, const auto& p) { return v < p.first; });
	if (it == e.begin()) return NAN;
	return std::prev(it)->second;
}

void expectWithinTwiceTheCleanError(const std::string& what, const std::vector<char>& damaged)
{
	SCOPED_TRACE(what);
	const fs::path p = scratch("damaged.rawlog");
	writeBytes(p, damaged);
	const Outcome o = run(p, false);
	fs::remove(p);
	const double clean_m = cleanErrorAt(o.t_end);
	std::printf("%-34s stopped at t=%.2f s: error %.3f m (1 sigma %.3f), clean run there %.3f m; %s\n",
	            what.c_str(), o.t_end - clean().error_by_time.front().first, o.error_m, o.sigma_m, clean_m,
	            o.error.empty() ? "completed" : o.error.c_str());
	// The damage is noticed: the run ends with a rawlog error naming the file.
	EXPECT_FALSE(o.error.empty()) << "the damaged log read as complete";
	EXPECT_NE(o.error.find("damaged.rawlog"), std::string::npos) << o.error;
	ASSERT_FALSE(std::isnan(clean_m)) << "the run stopped before the filter initialised";
	EXPECT_TRUE(std::isfinite(o.error_m));
	EXPECT_LE(o.error_m, 2 * clean_m) << "the damaged stretch moved the estimate";
}
}  // namespace

TEST(CorruptCompressedLog, CleanCompressedSampleCompletes)
{
	const Outcome& c = clean();
	EXPECT_TRUE(c.error.empty()) << c.error;
	EXPECT_GT(c.error_by_time.size(), 10000u);
	EXPECT_LT(c.error_m, 3.0);
}

TEST(CorruptCompressedLog, FlippedBitsStopTheRunWithoutMovingTheEstimate)
{
	const auto& good = compressedSample();
	for (double at : {0.1, 0.3, 0.5, 0.7, 0.9})
	{
		auto bad = good;
		const auto from = static_cast<std::size_t>(at * static_cast<double>(good.size()));
		for (std::size_t i = from; i < from + 64; ++i) bad[i] ^= 0x5A;
		expectWithinTwiceTheCleanError("64 bytes flipped at " + std::to_string(int(at * 100)) + " %", bad);
	}
}

TEST(CorruptCompressedLog, NoiseStopsTheRunWithoutMovingTheEstimate)
{
	const auto& good = compressedSample();
	std::mt19937 rng(7);
	for (double at : {0.2, 0.4, 0.6, 0.8})
	{
		auto bad = good;
		const auto from = static_cast<std::size_t>(at * static_cast<double>(good.size()));
		for (std::size_t i = from; i < from + 512; ++i) bad[i] = static_cast<char>(rng() & 0xFF);
		expectWithinTwiceTheCleanError("512 bytes of noise at " + std::to_string(int(at * 100)) + " %", bad);
	}
}
