// auvnav-run as a script sees it (issue 15): the exit code and the one-line
// reason of every run that cannot do its job (empty, truncated, corrupt or
// IMU-less log, no valid GPS, YAML errors, clock jumps), and outputs that
// survive a real SIGKILL of the real process (whole lines, a valid
// summary.json). Each test builds its inputs from the sample dataset.
#include <auvnav/cli.h>
#include <auvnav/io/json.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/register.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/serialization/CArchive.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using auvnav::io::Json;

namespace
{
const std::string kRepo = AUVNAV_SOURCE_DIR;
const std::string kSample = kRepo + "/share/sample/sample.rawlog";
const std::string kConfig = kRepo + "/config/flatfish.yaml";

/** A fresh folder per test, under the build tree. */
fs::path workDir()
{
	const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
	const fs::path dir =
	    fs::path(AUVNAV_TEST_WORK_DIR) / "exit" / (std::string(info->test_suite_name()) + "." + info->name());
	fs::remove_all(dir);
	fs::create_directories(dir);
	return dir;
}

struct Outcome
{
	int exit_code = -1;  //!< when it exited
	int signal = 0;      //!< when a signal ended it
	std::string output;  //!< stdout and stderr
	double wall_s = 0;
	long max_rss_kb = 0;  //!< the child's peak resident set (getrusage)
};

/** Runs `exe` with `args` (stdout+stderr to `dir`/output.txt); with
 *  `kill_after_s` > 0, sends it SIGKILL after that long if still running. */
Outcome runProgram(const std::string& exe, const std::vector<std::string>& args, const fs::path& dir,
                   double kill_after_s = 0)
{
	const fs::path log = dir / "output.txt";
	std::vector<std::string> argv_s = {exe};
	argv_s.insert(argv_s.end(), args.begin(), args.end());
	std::vector<char*> argv;
	for (auto& a : argv_s) argv.push_back(a.data());
	argv.push_back(nullptr);
	const auto t0 = std::chrono::steady_clock::now();
	const pid_t pid = fork();
	if (pid == 0)
	{
		const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
		dup2(fd, STDOUT_FILENO);
		dup2(fd, STDERR_FILENO);
		execv(argv[0], argv.data());
		_exit(127);
	}
	Outcome o;
	int status = 0;
	struct rusage usage = {};
	if (kill_after_s > 0)
	{
		// Poll so that a run ending early is seen as such (and not killed late).
		while (wait4(pid, &status, WNOHANG, &usage) == 0)
		{
			if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >= kill_after_s)
			{
				kill(pid, SIGKILL);
				wait4(pid, &status, 0, &usage);
				break;
			}
			std::this_thread::sleep_for(std::chrono::milliseconds(5));
		}
	}
	else
		wait4(pid, &status, 0, &usage);
	o.max_rss_kb = usage.ru_maxrss;
	o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
	if (WIFEXITED(status)) o.exit_code = WEXITSTATUS(status);
	if (WIFSIGNALED(status)) o.signal = WTERMSIG(status);
	std::ifstream in(log);
	std::stringstream ss;
	ss << in.rdbuf();
	o.output = ss.str();
	return o;
}

Outcome runNavigator(const std::vector<std::string>& args, const fs::path& dir, double kill_after_s = 0)
{
	return runProgram(AUVNAV_RUN_EXE, args, dir, kill_after_s);
}

std::vector<std::string> runArgs(const fs::path& dir, const std::string& rawlog,
                                 std::vector<std::string> extra = {}, const std::string& config = kConfig)
{
	std::vector<std::string> a = {"--config", config, "--out", (dir / "out").string(), "--quiet"};
	a.insert(a.end(), extra.begin(), extra.end());
	a.push_back(rawlog);
	return a;
}

/** runNavigator with `args` (writing to dir/out) killed after kill_s; where
 *  the whole run takes less than that here (how soon the navigator gets
 *  through the repeated sample depends on the machine), again, dir/out
 *  emptied first, killed at half its time. */
Outcome runKilledMidway(const std::vector<std::string>& args, const fs::path& dir, double kill_s)
{
	Outcome o = runNavigator(args, dir, kill_s);
	if (o.signal == 0 && o.exit_code >= 0)
	{
		std::printf("the run ended in %.2f s, before the kill at %.2f s: again, killed at %.2f s\n", o.wall_s,
		            kill_s, 0.5 * o.wall_s);
		fs::remove_all(dir / "out");
		o = runNavigator(args, dir, 0.5 * o.wall_s);
	}
	return o;
}

// Under AddressSanitizer (the sanitizer pass, .ci/sanitize) auvnav-run starts
// and runs much slower: at 2 s it has written nothing yet, so the
// short kills come later there, still mid-run, and the limits on a run's wall
// time are wider (still far below blind prediction through an hour).
#if defined(__SANITIZE_ADDRESS__)
#define AUVNAV_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define AUVNAV_TEST_ASAN 1
#endif
#endif
#ifdef AUVNAV_TEST_ASAN
constexpr double kKillDelayScale = 5, kWallLimitScale = 20;
#else
constexpr double kKillDelayScale = 1, kWallLimitScale = 1;
#endif

/** What an edit does to one observation: false drops it. */
using Edit = std::function<bool(mrpt::obs::CObservation&, double t_from_start_s)>;

/** The sample's first `span_s` seconds, each observation passed through
 *  `edit`, as a plain (uncompressed) rawlog. Written with MRPT's archive, not
 *  RawlogWriter: an edit may send the clock backwards. Returns the number
 *  written. */
std::size_t writeEditedSample(const fs::path& out, double span_s, const Edit& edit)
{
	auvnav::obs::registerAllClasses();
	auvnav::io::RawlogReader in(kSample);
	mrpt::io::CFileOutputStream f(out.string());
	auto archive = mrpt::serialization::archiveFrom(f);
	double t0 = -1;
	std::size_t n = 0;
	while (const auto obs = in.next())
	{
		const double t = mrpt::Clock::toDouble(obs->timestamp);
		if (t0 < 0) t0 = t;
		if (t - t0 > span_s) break;
		if (!edit(*obs, t - t0)) continue;
		archive << *obs;
		++n;
	}
	return n;
}

/** The sample played `copies` times, each copy right after the one before
 *  (its stamps shifted by the sample's span plus one IMU period): ~14 minutes
 *  of data per copy, so that a run is still going when killed (on a fast
 *  machine the sample alone can end first). */
void writeSampleRepeated(const fs::path& out, int copies)
{
	auvnav::obs::registerAllClasses();
	mrpt::io::CFileOutputStream f(out.string());
	auto archive = mrpt::serialization::archiveFrom(f);
	double first = -1, last = 0, shift = 0;
	for (int pass = 0; pass < copies; ++pass)
	{
		auvnav::io::RawlogReader in(kSample);
		while (const auto obs = in.next())
		{
			const double t = mrpt::Clock::toDouble(obs->timestamp);
			if (first < 0) first = t;
			if (pass == 0) last = std::max(last, t);
			obs->timestamp = mrpt::Clock::fromDouble(t + shift);
			archive << *obs;
		}
		shift += last - first + 0.01;
	}
}

/** A clock jump of the whole logger: every observation from `at_s` on is stamped `jump_s` later. */
Edit clockJump(double at_s, double jump_s)
{
	return [=](mrpt::obs::CObservation& o, double t)
	{
		if (t >= at_s) o.timestamp = mrpt::Clock::fromDouble(mrpt::Clock::toDouble(o.timestamp) + jump_s);
		return true;
	};
}

std::string slurp(const fs::path& file)
{
	std::ifstream in(file, std::ios::binary);
	std::stringstream ss;
	ss << in.rdbuf();
	return ss.str();
}

Json summaryOf(const fs::path& dir)
{
	const std::string text = slurp(dir / "out" / "summary.json");
	return Json::parse(text);  // throws (fails the test) on a half-written file
}

/** The output's lines that carry an error or a MRPT report. */
std::vector<std::string> errorLines(const std::string& output)
{
	std::vector<std::string> lines;
	std::istringstream in(output);
	for (std::string l; std::getline(in, l);)
		if (l.find("error") != std::string::npos || l.find("MRPT") != std::string::npos ||
		    l.find("Location:") != std::string::npos || l.find("Call stack") != std::string::npos)
			lines.push_back(l);
	return lines;
}

/** The run's reason is exactly one line on stderr, with no MRPT exception report. */
void expectOneLineError(const Outcome& o, const std::string& must_contain)
{
	const auto lines = errorLines(o.output);
	ASSERT_EQ(lines.size(), 1u) << o.output;
	EXPECT_EQ(lines[0].rfind("auvnav-run: error: ", 0), 0u) << lines[0];
	EXPECT_NE(lines[0].find(must_contain), std::string::npos) << lines[0];
}

/** CSV fields, double quotes respected (updates.csv's "why" may hold commas). */
std::vector<std::string> csvFields(const std::string& line)
{
	std::vector<std::string> f(1);
	bool quoted = false;
	for (char c : line)
	{
		if (c == '"')
			quoted = !quoted;
		else if (c == ',' && !quoted)
			f.emplace_back();
		else
			f.back() += c;
	}
	return f;
}

bool isNumber(const std::string& s)
{
	if (s == "null" || s == "nan" || s == "-nan") return true;
	char* end = nullptr;
	std::strtod(s.c_str(), &end);
	return !s.empty() && end == s.c_str() + s.size();
}

/** A killed run's file up to its last newline. SIGKILL can stop the kernel's
 *  write() of a buffer at a page boundary (seen once in CI, on a loaded
 *  machine: the kill at 2 s cut states.csv 1 KB into a row), so the last
 *  line may be partial: it is dropped (run_outputs.h) and said so; every
 *  line before it must be whole. */
std::string wholeLinesOf(const fs::path& file)
{
	std::string text = slurp(file);
	if (!text.empty() && text.back() != '\n')
	{
		const std::size_t cut = text.rfind('\n') + 1;  // npos + 1 = 0: all of it
		std::printf("%s: a partial last line of %zu bytes (the kill cut a write) dropped\n", file.c_str(),
		            text.size() - cut);
		text.erase(cut);
	}
	return text;
}

/** Every line of a killed run's CSV file is whole (but a partial last one,
 *  wholeLinesOf): every row has the header's field count and a number in its
 *  first column (and in `numeric_columns`). Returns the number of rows. */
std::size_t expectWholeCsv(const fs::path& file, const std::vector<std::size_t>& numeric_columns = {})
{
	const std::string text = wholeLinesOf(file);
	EXPECT_FALSE(text.empty()) << file;
	if (text.empty()) return 0;
	std::istringstream in(text);
	std::string header;
	std::getline(in, header);
	const std::size_t n = csvFields(header).size();
	std::size_t rows = 0;
	for (std::string l; std::getline(in, l); ++rows)
	{
		const auto f = csvFields(l);
		EXPECT_EQ(f.size(), n) << file << " row " << rows + 1 << ": " << l.substr(0, 200);
		if (f.size() != n) return rows;
		EXPECT_TRUE(isNumber(f[0])) << file << " row " << rows + 1;
		for (std::size_t c : numeric_columns)
			EXPECT_TRUE(isNumber(f[c])) << file << " row " << rows + 1 << " column " << c;
	}
	return rows;
}

/** The same for trajectory.tum: comment lines, then 8 numbers per line. */
std::size_t expectWholeTum(const fs::path& file)
{
	const std::string text = wholeLinesOf(file);
	EXPECT_FALSE(text.empty());
	if (text.empty()) return 0;
	std::istringstream in(text);
	std::size_t rows = 0;
	for (std::string l; std::getline(in, l);)
	{
		if (l.rfind('#', 0) == 0) continue;
		std::istringstream fields(l);
		std::vector<std::string> f;
		for (std::string x; fields >> x;) f.push_back(x);
		EXPECT_EQ(f.size(), 8u) << file << ": " << l;
		for (const auto& x : f) EXPECT_TRUE(isNumber(x)) << file << ": " << l;
		++rows;
	}
	return rows;
}

/** Rows of a trajectory.tum from time `t_s` on, in file order after the
 *  last row before it (a clock that went back starts a new run of rows). */
std::size_t tumRowsFrom(const fs::path& file, double t_s)
{
	std::istringstream in(slurp(file));
	std::size_t n = 0;
	for (std::string l; std::getline(in, l);)
		if (l.rfind('#', 0) != 0) n = std::stod(l.substr(0, l.find(' '))) >= t_s ? n + 1 : 0;
	return n;
}

double lastTumTime(const fs::path& file)
{
	std::istringstream in(slurp(file));
	double t = 0;
	for (std::string l; std::getline(in, l);)
		if (l.rfind('#', 0) != 0) t = std::stod(l.substr(0, l.find(' ')));
	return t;
}
}  // namespace

// ------------------------------------------------- runs that cannot do their job

TEST(RunExit, AnEmptyRawlogIsBadInput)
{
	const auto dir = workDir();
	std::ofstream(dir / "empty.rawlog").close();
	const Outcome o = runNavigator(runArgs(dir, (dir / "empty.rawlog").string()), dir);
	EXPECT_EQ(o.exit_code, auvnav::cli::kExitBadInput) << o.output;
	expectOneLineError(o, "empty.rawlog: no observations (an empty rawlog)");
	const Json s = summaryOf(dir);
	EXPECT_FALSE(s["completed"].get<bool>());
	EXPECT_NE(s["error"].get<std::string>().find("no observations"), std::string::npos);
}

TEST(RunExit, ARawlogCutTo100BytesIsBadInputInOneLine)
{
	const auto dir = workDir();
	const std::string bytes = slurp(kSample).substr(0, 100);
	std::ofstream(dir / "cut.rawlog", std::ios::binary) << bytes;
	const Outcome o = runNavigator(runArgs(dir, (dir / "cut.rawlog").string()), dir);
	EXPECT_EQ(o.exit_code, auvnav::cli::kExitBadInput) << o.output;
	expectOneLineError(o, "cut.rawlog: no observations in its 100 bytes (an empty rawlog, or one cut short");
}

TEST(RunExit, ACorruptRawlogIsBadInputInOneLineWithoutMrptsReport)
{
	const auto dir = workDir();
	const fs::path plain = dir / "plain.rawlog";
	writeEditedSample(plain, 20, [](auto&, double) { return true; });
	std::string bytes = slurp(plain);
	ASSERT_GT(bytes.size(), 200000u);
	for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 64; ++i)
		bytes[i] = static_cast<char>(0xA5 ^ i);
	std::ofstream(dir / "corrupt.rawlog", std::ios::binary) << bytes;
	const Outcome o = runNavigator(runArgs(dir, (dir / "corrupt.rawlog").string()), dir);
	EXPECT_EQ(o.exit_code, auvnav::cli::kExitBadInput) << o.output;
	expectOneLineError(o, "corrupt.rawlog: ");
	EXPECT_EQ(o.output.find("==== MRPT exception"), std::string::npos) << o.output;
	EXPECT_FALSE(summaryOf(dir)["completed"].get<bool>());
}

TEST(RunExit, ALogWithoutImuIsBadInputNamingTheLabelAndWhatItHas)
{
	const auto dir = workDir();
	const fs::path log = dir / "no_imu.rawlog";
	ASSERT_GT(writeEditedSample(log, 60, [](auto& o, double) { return o.sensorLabel != "IMU"; }), 500u);
	const Outcome o = runNavigator(runArgs(dir, log.string()), dir);
	EXPECT_EQ(o.exit_code, auvnav::cli::kExitBadInput) << o.output;
	expectOneLineError(o, "no IMU observation with label 'IMU' (imu.label) among ");
	EXPECT_NE(o.output.find("DVL "), std::string::npos) << o.output;  // the labels it has
	const Json s = summaryOf(dir);
	EXPECT_FALSE(s["completed"].get<bool>());
	EXPECT_FALSE(s["initialized"].get<bool>());
}

TEST(RunExit, ALogWithoutAValidGpsFixNeverInitialises)
{
	const auto dir = workDir();
	const fs::path log = dir / "no_fix.rawlog";
	std::size_t gps = 0;
	writeEditedSample(log, 60,
	                  [&](mrpt::obs::CObservation& o, double)
	                  {
		                  if (auto* g = dynamic_cast<mrpt::obs::CObservationGPS*>(&o);
		                      g && g->has_GGA_datum())
		                  {
			                  g->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>().fields.fix_quality = 0;
			                  ++gps;
		                  }
		                  return true;
	                  });
	ASSERT_GT(gps, 30u);
	const Outcome o = runNavigator(runArgs(dir, log.string()), dir);
	EXPECT_EQ(o.exit_code, auvnav::cli::kExitNotInitialized) << o.output;
	EXPECT_NE(o.output.find("auvnav-run: not initialised: 5 agreeing GPS fixes on label 'GPS'"),
	          std::string::npos)
	    << o.output;
	const Json s = summaryOf(dir);
	EXPECT_TRUE(s["completed"].get<bool>());  // read to its end: complete, but no result
	EXPECT_EQ(s["status"], "not_initialized");
}

// A YAML error MRPT's reader would take silently (a duplicate key, a second
// document) or report as a multi-line assertion (an alias): exit 2, one line
// naming file, line and key, and no run.
TEST(RunExit, YamlErrorsStopTheRunInOneLine)
{
	const auto dir = workDir();
	fs::copy(kRepo + "/config", dir / "config", fs::copy_options::recursive);
	const std::string text = slurp(kConfig);
	struct Case
	{
		std::string name, append, expected;
	};
	for (const Case& c :
	     {Case{"duplicate", "outputs:\n  rate_hz: 5\n", ": outputs: duplicate key (first at line "},
	      Case{"second_document", "---\noutputs: {rate_hz: 5}\n", ": a second YAML document"},
	      Case{"alias", "extra: *rate\n", ": extra: aliases (*rate) are not supported"}})
	{
		SCOPED_TRACE(c.name);
		const fs::path config = dir / "config" / (c.name + ".yaml");
		std::ofstream(config) << text << c.append;
		const Outcome o = runNavigator(runArgs(dir, kSample, {}, config.string()), dir);
		EXPECT_EQ(o.exit_code, auvnav::cli::kExitBadInput) << o.output;
		expectOneLineError(o, c.name + ".yaml:");
		EXPECT_NE(o.output.find(c.expected), std::string::npos) << o.output;
		EXPECT_LT(o.wall_s, 10.0 * kWallLimitScale);  // refused before reading the log
		EXPECT_FALSE(fs::exists(dir / "out" / "summary.json"));
	}
}

// ------------------------------------------------------------ kill -9

/** Runs the navigator on `rawlog` (100 Hz rows: more bytes per second, more
 *  chances to be cut mid-line; summary every second), SIGKILLs it after
 *  `kill_s` and checks what it left: every text output ends in a whole line
 *  and parses to its last line, summary.json is valid JSON with completed
 *  false, rewritten during the run. */
void expectKilledRunLeftWholeOutputs(const fs::path& base, const fs::path& rawlog, double kill_s,
                                     bool check_progress)
{
	SCOPED_TRACE("killed after " + std::to_string(kill_s) + " s");
	const fs::path dir = base / ("kill_" + std::to_string(int(kill_s)));
	fs::create_directories(dir);
	const Outcome o = runKilledMidway(
	    runArgs(dir, rawlog.string(), {"--set", "outputs.summary_every_s=1", "--set", "outputs.rate_hz=100"}),
	    dir, kill_s);
	ASSERT_EQ(o.signal, SIGKILL) << "the run ended before the kill (exit " << o.exit_code
	                             << "): " << o.output;
	const fs::path out = dir / "out";
	const std::size_t states = expectWholeCsv(out / "states.csv", {1, 2, 3, 4, 5, 6, 7});
	const std::size_t tum = expectWholeTum(out / "trajectory.tum");
	const std::size_t updates = expectWholeCsv(out / "updates.csv", {1, 5});
	const std::size_t nis = expectWholeCsv(out / "nis.csv", {2, 3, 4});
	expectWholeCsv(out / "position_fixes.csv", {2, 3});
	expectWholeCsv(out / "health.csv");
	const Json s = summaryOf(dir);
	EXPECT_FALSE(s["completed"].get<bool>());
	EXPECT_TRUE(s["running"].get<bool>());
	// The kill came mid-run, after rows were written and the summary was
	// rewritten (not checked for the earliest kill: on a loaded machine the run
	// may not have reached its first flush, 1 s of its own clock, by then).
	if (check_progress)
	{
		EXPECT_GT(states, 500u);
		EXPECT_GT(tum, 500u);
		EXPECT_GT(updates, 1000u);
		EXPECT_GT(nis, 10u);
		EXPECT_GT(s["data_duration_s"].get<double>(), 10.0);
		EXPECT_GT(s["predictions"].get<double>(), 1000.0);
	}
	std::printf("killed at %.0f s: %zu state rows, summary at %.0f s of data\n", kill_s, states,
	            s["data_duration_s"].get<double>());
}

// A real SIGKILL of the real process at ~2 s and ~5 s of the sample played
// twice (sooner where the run would end first).
TEST(RunKill, SigkillLeavesWholeLinesAndAValidSummary)
{
	const auto base = workDir();
	const fs::path twice = base / "sample_twice.rawlog";
	writeSampleRepeated(twice, 2);
	expectKilledRunLeftWholeOutputs(base, twice, 2.0 * kKillDelayScale, false);
	expectKilledRunLeftWholeOutputs(base, twice, 5.0 * kKillDelayScale, true);
}

// The same at ~30 s, on the sample played 12 times (~2.8 h of data; sooner
// where the run would end first): buffers that fill and files that grow past
// their first megabytes are cut whole too.
TEST(RunKill, SigkillAfterHalfAMinuteLeavesWholeLinesAndAValidSummary)
{
	const auto base = workDir();
	const fs::path log = base / "sample_12x.rawlog";
	writeSampleRepeated(log, 12);
	expectKilledRunLeftWholeOutputs(base, log, 30.0, true);
	fs::remove(log);
}

// ------------------------------------------------------------ clock jumps

// The first 90 s of the sample, the logger's clock jumping at 60 s. Default
// (clock.on_jump: stop): exit 2 naming the jump, at once.
TEST(RunClockJump, AJumpStopsTheRunNamingIt)
{
	for (double jump : {3600.0, -3600.0, 1e9})
	{
		SCOPED_TRACE("jump " + std::to_string(jump));
		const auto dir = workDir();
		const fs::path log = dir / "jump.rawlog";
		writeEditedSample(log, 90, clockJump(60, jump));
		const Outcome o = runNavigator(runArgs(dir, log.string()), dir);
		EXPECT_EQ(o.exit_code, auvnav::cli::kExitBadInput) << o.output;
		expectOneLineError(o, "IMU 'IMU' clock jumped by ");
		// The jump named with its size (plus the IMU period it replaced) and where.
		const auto at = o.output.find("clock jumped by ");
		ASSERT_NE(at, std::string::npos);
		EXPECT_NEAR(std::stod(o.output.substr(at + 16)), jump, 0.02) << o.output;
		EXPECT_NE(o.output.find(" s at 59.990 s from the start"), std::string::npos) << o.output;
		EXPECT_LT(o.wall_s, 10.0 * kWallLimitScale);
		const Json s = summaryOf(dir);
		EXPECT_FALSE(s["completed"].get<bool>());
		EXPECT_NEAR(s["data_duration_s"].get<double>(), 60.0, 0.1);  // not one step through the jump
	}
}

// clock.on_jump: reinitialize: the run completes, re-initialises once, and the
// 30 s after the jump are navigated, not silently dropped.
TEST(RunClockJump, ReinitialiseCompletesWithTheDataAfterTheJump)
{
	for (double jump : {3600.0, -3600.0, 1e9})
	{
		SCOPED_TRACE("jump " + std::to_string(jump));
		const auto dir = workDir();
		const fs::path log = dir / "jump.rawlog";
		std::size_t imu = 0, imu_after = 0;
		double last_imu_s = 0;
		writeEditedSample(log, 90,
		                  [&, jump_at = clockJump(60, jump)](mrpt::obs::CObservation& o, double t)
		                  {
			                  jump_at(o, t);
			                  if (o.sensorLabel != "IMU") return true;
			                  ++imu;
			                  if (t >= 60) ++imu_after;
			                  last_imu_s = mrpt::Clock::toDouble(o.timestamp);
			                  return true;
		                  });
		ASSERT_GT(imu_after, 2900u);
		const Outcome o =
		    runNavigator(runArgs(dir, log.string(), {"--set", "clock.on_jump=reinitialize"}), dir);
		EXPECT_EQ(o.exit_code, auvnav::cli::kExitOk) << o.output;
		const Json s = summaryOf(dir);
		EXPECT_TRUE(s["completed"].get<bool>());
		EXPECT_EQ(s["clock_jumps"].get<int>(), 1);
		EXPECT_TRUE(s["initialized"].get<bool>());
		// Every IMU sample is accounted for: predicted, or used for levelling
		// while waiting for a fix, at each of the two starts (1 s levelling and
		// a consensus of 5 GPS fixes after it, filter.initial.fix_consensus:
		// ~6.5 s each here, 1304 samples in all).
		const Json& imu_stats = s["sensors"][0];
		ASSERT_EQ(imu_stats["plugin"], "(prediction)");
		EXPECT_EQ(s["predictions"].get<std::size_t>(), imu_stats["accepted"].get<std::size_t>());
		EXPECT_EQ(imu_stats["accepted"].get<std::size_t>() + imu_stats["before_init"].get<std::size_t>(),
		          imu);
		EXPECT_LT(imu_stats["before_init"].get<std::size_t>(), 2 * 800u);
		EXPECT_GT(imu_stats["before_init"].get<std::size_t>(), 2 * 100u);  // levelled twice
		// The 30 s after the jump are in the outputs at 10 Hz from the new start
		// (~6.5 s after the jump) on the new clock, to the last IMU sample (a
		// backward jump included): 243-247 rows measured.
		const double jump_at = last_imu_s - 30;
		EXPECT_GT(tumRowsFrom(dir / "out" / "trajectory.tum", jump_at - 0.5), 225u);
		EXPECT_NEAR(lastTumTime(dir / "out" / "trajectory.tum"), last_imu_s, 0.2);
	}
}

// ------------------------------------------------------------ a day at sea

namespace
{
/** A mission of the sample's kind (surface with GPS, then dives of a 40 m
 *  square at 8 m, each followed by 90 s at the surface), `cycles` dives long:
 *  each cycle ~9 minutes. */
fs::path writeLongMission(const fs::path& dir, int cycles)
{
	std::string text = slurp(kRepo + "/config/missions/sample.yaml");
	text = text.substr(0, text.find("plan:"));
	text.replace(text.find("name: sample"), 12, "name: long");
	// Relative paths in it (vehicle, sensors) stay those of config/missions.
	for (const char* key : {"vehicle: ", "sensors: "})
	{
		const auto at = text.find(key) + std::string(key).size();
		text.insert(at, kRepo + "/config/missions/");
	}
	const auto dur = text.find("max_duration_s:");
	text.replace(dur, text.find('\n', dur) - dur, "max_duration_s: " + std::to_string(600 * cycles + 900));
	text +=
	    "plan:\n"
	    "  - {goto: [140, 40], surface: true, speed_mps: 0.5}\n"
	    "  - repeat: " +
	    std::to_string(cycles) +
	    "\n"
	    "    steps:\n"
	    "      - {wait_s: 50, depth_m: 8}\n"
	    "      - {goto: [180, 40], depth_m: 8, speed_mps: 0.4}\n"
	    "      - {goto: [180, 80], depth_m: 8, speed_mps: 0.4}\n"
	    "      - {goto: [140, 80], depth_m: 8, speed_mps: 0.4}\n"
	    "      - {goto: [140, 40], depth_m: 8, speed_mps: 0.4}\n"
	    "      - {wait_s: 90, surface: true}\n";
	const fs::path file = dir / "long.yaml";
	std::ofstream(file) << text;
	return file;
}

struct LongRun
{
	Outcome run;
	Json summary;
	std::size_t rows = 0;
};

LongRun simulateAndRun(const fs::path& base, const std::string& name, int cycles)
{
	const fs::path dir = base / name;
	fs::create_directories(dir);
	const fs::path mission = writeLongMission(dir, cycles);
	const Outcome sim =
	    runProgram(AUVNAV_SIM_EXE, {mission.string(), "--seed", "1", "--out", (dir / "sim").string()}, dir);
	EXPECT_EQ(sim.exit_code, 0) << sim.output;
	LongRun r;
	// 1 Hz rows: a day of states.csv at 10 Hz would be ~1 GB.
	r.run = runNavigator(runArgs(dir, (dir / "sim" / "long.rawlog").string(), {"--set", "outputs.rate_hz=1"}),
	                     dir);
	fs::remove(dir / "sim" / "long.rawlog");
	fs::remove(dir / "sim" / "ground_truth.csv");
	r.summary = summaryOf(dir);
	r.rows = expectWholeCsv(dir / "out" / "states.csv");
	// Every field a finite number: no NaN or Inf in any state or σ.
	std::ifstream states(dir / "out" / "states.csv");
	std::string line;
	std::getline(states, line);  // header
	std::size_t non_finite = 0;
	for (std::size_t row = 1; std::getline(states, line); ++row)
		for (const auto& f : csvFields(line))
		{
			char* end = nullptr;
			const double v = std::strtod(f.c_str(), &end);
			if (end != f.c_str() + f.size() || !std::isfinite(v))
				if (++non_finite <= 5)
					ADD_FAILURE() << name << ": states.csv row " << row << ": '" << f << "'";
		}
	EXPECT_EQ(non_finite, 0u) << name;
	return r;
}
}  // namespace

// Issue 15: a 24 h mission (slow label): no NaN anywhere in the states, the
// covariance positive definite throughout (no Cholesky repair was needed),
// a healthy end, and a peak RSS within 5 % of a 1 h run's (nothing grows
// with the length of the run).
TEST(RunLongSlow, ADayAtSeaStaysFiniteHealthyAndBoundedInMemory)
{
	const fs::path base = workDir();
	const LongRun hour = simulateAndRun(base, "hour", 6), day = simulateAndRun(base, "day", 162);
	for (const LongRun* r : {&hour, &day})
	{
		EXPECT_EQ(r->run.exit_code, 0) << r->run.output;
		EXPECT_TRUE(r->summary["completed"].get<bool>());
		EXPECT_EQ(r->summary["status"], "ok");
		EXPECT_EQ(r->summary["cholesky_repairs"].get<std::size_t>(), 0u);
	}
	const double day_s = day.summary["data_duration_s"].get<double>();
	EXPECT_GT(day_s, 24 * 3600.0);
	EXPECT_GT(day.rows, 86000u);
	std::printf(
	    "1 h run: %.0f s of data, max RSS %ld kB, %.0f s; 24 h run: %.0f s of data, max RSS %ld kB, %.0f s\n",
	    hour.summary["data_duration_s"].get<double>(), hour.run.max_rss_kb, hour.run.wall_s, day_s,
	    day.run.max_rss_kb, day.run.wall_s);
	EXPECT_LE(day.run.max_rss_kb, 1.05 * hour.run.max_rss_kb);
}

// ------------------------------------------------------------ smoothing (issue 17)

namespace
{
std::string firstLineOf(const fs::path& file)
{
	std::ifstream in(file);
	std::string line;
	std::getline(in, line);
	return line;
}
/** The number printed after `key` in `text` (NaN if absent). */
double numberAfter(const std::string& text, const std::string& key)
{
	const auto at = text.find(key);
	return at == std::string::npos ? NAN : std::strtod(text.c_str() + at + key.size(), nullptr);
}
Outcome evaluate(const fs::path& dir, const fs::path& run, const std::string& truth,
                 std::vector<std::string> extra = {})
{
	std::vector<std::string> a = {"--run",   run.string(), "--truth", truth, "--out", (dir / "eval").string(),
	                              "--every", "5"};
	a.insert(a.end(), extra.begin(), extra.end());
	return runProgram(AUVNAV_EVAL_EXE, a, dir);
}
}  // namespace

// The sample smoothed: the filter's formats, one row per second, a segment
// ending before each of the run's recoveries (20 model-aiding updates applied
// against the gate), every other row smoothed, and closer to the truth over
// the dive: measured 0.95 of the filter's RMS by default, 0.82 with
// smoother.across_recoveries (no segment ends). auvnav-smooth on the
// finished run writes the same file.
TEST(RunSmooth, TheSampleIsSmoothedInTheFiltersFormats)
{
	const auto dir = workDir();
	const Outcome o = runNavigator(runArgs(dir, kSample, {"--smooth"}), dir);
	ASSERT_EQ(o.exit_code, 0) << o.output;
	EXPECT_NE(o.output.find("smoothing: "), std::string::npos) << o.output;
	const fs::path out = dir / "out";
	EXPECT_EQ(firstLineOf(out / "smoothed_states.csv"), firstLineOf(out / "states.csv") + ",smoother");
	const std::size_t rows = expectWholeCsv(out / "smoothed_states.csv");
	EXPECT_GT(rows, 780u);  // ~14 min of data at one kept tick a second, and one row per segment end
	EXPECT_LT(rows, 900u);
	std::ifstream js(out / "smoother.json");
	const Json j = Json::parse(js);
	std::size_t recoveries = 0;
	const Json summary = summaryOf(dir);
	for (const auto& sensor : summary["sensors"]) recoveries += sensor["recovered"].get<std::size_t>();
	EXPECT_GT(recoveries, 0u);
	EXPECT_EQ(j["rows"].get<std::size_t>(), rows);
	EXPECT_EQ(j["segment_ends"].get<std::size_t>(), recoveries + 1);  // and the end of the run
	// A segment's end shares its time with the next one's start: one row each.
	EXPECT_EQ(j["smoothed"].get<std::size_t>(), rows - 1);
	EXPECT_EQ(j["filtered_kept"].get<std::size_t>(), 0u);

	const Outcome ev = evaluate(dir, out, kRepo + "/share/sample/ground_truth.csv");
	ASSERT_EQ(ev.exit_code, 0) << ev.output;
	const double ratio = numberAfter(ev.output, "Smoothed/filtered dive RMS: mean ");
	EXPECT_LT(ratio, 1.0) << ev.output;

	std::ifstream first(out / "smoothed_states.csv");
	const std::string before((std::istreambuf_iterator<char>(first)), std::istreambuf_iterator<char>());
	const Outcome again = runProgram(AUVNAV_SMOOTH_EXE, {out.string()}, dir);
	ASSERT_EQ(again.exit_code, 0) << again.output;
	std::ifstream second(out / "smoothed_states.csv");
	const std::string after((std::istreambuf_iterator<char>(second)), std::istreambuf_iterator<char>());
	EXPECT_EQ(before, after);

	// Across the recoveries: one segment, every row but the last smoothed.
#ifdef AUVNAV_TEST_ASAN
	GTEST_SKIP() << "the second run of the sample (across recoveries) only in the Release pass";
#endif
	const fs::path across = dir / "across";
	fs::create_directories(across);
	const Outcome a = runNavigator(
	    runArgs(across, kSample, {"--smooth", "--set", "smoother.across_recoveries=true"}), across);
	ASSERT_EQ(a.exit_code, 0) << a.output;
	std::ifstream ja(across / "out" / "smoother.json");
	const Json jj = Json::parse(ja);
	EXPECT_EQ(jj["segment_ends"].get<std::size_t>(), 1u);
	const Outcome eva = evaluate(across, across / "out", kRepo + "/share/sample/ground_truth.csv");
	ASSERT_EQ(eva.exit_code, 0) << eva.output;
	const double ratio_across = numberAfter(eva.output, "Smoothed/filtered dive RMS: mean ");
	std::printf("sample: smoothed/filtered dive RMS %.3f (segments at recoveries), %.3f (across them)\n",
	            ratio, ratio_across);
	EXPECT_LT(ratio_across, 0.9) << eva.output;
}

// A run killed (SIGKILL) while recording: auvnav-smooth smooths the whole
// records it left, the last of them as the end.
TEST(RunSmooth, AKilledRunSmoothsWhatWasRecorded)
{
	const auto dir = workDir();
	const fs::path twice = dir / "sample_twice.rawlog";
	writeSampleRepeated(twice, 2);
	// (On a fast machine the sample twice with --smooth can end before a kill
	// at 4 s, so a run that ends first is killed at half its time.)
	const Outcome o = runKilledMidway(runArgs(dir, twice.string(), {"--smooth"}), dir, 4.0 * kKillDelayScale);
	ASSERT_EQ(o.signal, SIGKILL) << "the run ended before the kill; " << o.output;
	const Outcome s = runProgram(AUVNAV_SMOOTH_EXE, {(dir / "out").string()}, dir);
	ASSERT_EQ(s.exit_code, 0) << s.output;
	const std::size_t rows = expectWholeCsv(dir / "out" / "smoothed_states.csv");
	EXPECT_GT(rows, 10u) << s.output;
	EXPECT_NE(s.output.find("estimates"), std::string::npos) << s.output;
	fs::remove(twice);
}

TEST(RunSmooth, NoRecordingIsAOneLineError)
{
	const auto dir = workDir();
	const Outcome s = runProgram(AUVNAV_SMOOTH_EXE, {dir.string()}, dir);
	EXPECT_EQ(s.exit_code, auvnav::cli::kExitBadInput) << s.output;
	EXPECT_NE(s.output.find("stretches.bin: no stretch file (was the run made with auvnav-run --smooth?)"),
	          std::string::npos)
	    << s.output;
	EXPECT_EQ(std::count(s.output.begin(), s.output.end(), '\n'), 1) << s.output;
}

// The paper's denial (adcp_square, seed 1, "Inertial + model + ADCP"): DVL
// and GPS denied for 1000 s after 600 s, then back. The smoother carries the
// DVL's and the surface's return back through the denial. Across the run's
// model-aiding recoveries (smoother.across_recoveries) it measured dive RMS
// 8.28 m filtered, 1.65 m smoothed (0.20), at mid-denial 6.35 -> 2.48 m; by
// default the segments end at them: 0.63, and 6.35 -> 5.74 m.
TEST(RunSmooth, ADenialIsBridgedFromBothEnds)
{
#ifdef AUVNAV_TEST_ASAN
	GTEST_SKIP() << "29 min of data, twice: ~12 min under AddressSanitizer; the Release pass runs it";
#endif
	const auto dir = workDir();
	const Outcome sim = runProgram(
	    AUVNAV_SIM_EXE,
	    {kRepo + "/config/missions/adcp_square.yaml", "--seed", "1", "--out", (dir / "sim").string()}, dir);
	ASSERT_EQ(sim.exit_code, 0) << sim.output;
	const std::string truth = (dir / "sim" / "ground_truth.csv").string();
	struct Figures
	{
		double ratio, mid_f, mid_s;
	};
	auto run = [&](const fs::path& d, std::vector<std::string> extra)
	{
		fs::create_directories(d);
		std::vector<std::string> a = {"--smooth", "--deny", "DVL:600:1600", "--deny", "GPS:600:1600"};
		a.insert(a.end(), extra.begin(), extra.end());
		const Outcome o = runNavigator(runArgs(d, (dir / "sim" / "adcp_square.rawlog").string(), a), d);
		EXPECT_EQ(o.exit_code, 0) << o.output;
		const Outcome f = evaluate(d, d / "out", truth, {"--at", "1100"});
		EXPECT_EQ(f.exit_code, 0) << f.output;
		const Outcome s = evaluate(d, d / "out", truth, {"--at", "1100", "--smoothed"});
		EXPECT_EQ(s.exit_code, 0) << s.output;
		return Figures{numberAfter(f.output, "Smoothed/filtered dive RMS: mean "),
		               numberAfter(f.output, "after the truth's start: "),
		               numberAfter(s.output, "after the truth's start: ")};
	};
	const Figures segmented = run(dir / "default", {});
	const Figures across = run(dir / "across", {"--set", "smoother.across_recoveries=true"});
	std::printf(
	    "denial: smoothed/filtered dive RMS %.3f (%.3f across recoveries); mid-denial error %.2f m filtered, "
	    "%.2f m smoothed (%.2f m across)\n",
	    segmented.ratio, across.ratio, segmented.mid_f, segmented.mid_s, across.mid_s);
	EXPECT_LT(segmented.ratio, 0.8);
	EXPECT_LT(segmented.mid_s, segmented.mid_f);
	EXPECT_LT(across.ratio, 0.35);
	EXPECT_LT(across.mid_s, 0.5 * across.mid_f);
	fs::remove(dir / "sim" / "adcp_square.rawlog");
}
