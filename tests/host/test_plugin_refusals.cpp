// The plugin host and the navigator refuse bad plugins and bad numbers with
// messages that say what is wrong and where (plugin_host.h, navigator.h):
// missing file, no entry point, wrong ABI, foreign build fingerprint, failing
// factory; a NaN h and NaN/Inf measurements are counted invalid and never
// reach the state. The bad plugins are built in tests/host/plugins.
#include <auvnav/navigator.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/plugin_host.h>
#include <auvnav/testing/model_checks.h>
#include <gtest/gtest.h>
#include <mrpt/obs/CObservationIMU.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

using namespace auvnav;
namespace at = auvnav::testing;

namespace
{
/** Runs `f`, expecting a PluginError; returns its message ("" if none). */
template <class F>
std::string pluginError(F&& f)
{
	try
	{
		f();
	}
	catch (const PluginError& e)
	{
		return e.what();
	}
	catch (const std::exception& e)
	{
		ADD_FAILURE() << "expected PluginError, got another exception: " << e.what();
		return e.what();
	}
	ADD_FAILURE() << "expected PluginError, nothing was thrown";
	return "";
}

#define EXPECT_CONTAINS(haystack, needle)                            \
	EXPECT_NE(std::string(haystack).find(needle), std::string::npos) \
	    << "'" << (haystack) << "' lacks '" << (needle) << "'"

std::string readFile(const std::string& path)
{
	std::ifstream f(path);
	std::stringstream s;
	s << f.rdbuf();
	return s.str();
}

/** The default navigator configuration (config/flatfish.yaml) with its
 *  top-level `sensors:` block replaced by `sensors_block` (text, with the
 *  `sensors:` line), starting at a configured position (no GPS needed). */
config::Node navigatorConfig(const std::string& sensors_block)
{
	const std::string file = AUVNAV_SOURCE_DIR "/config/flatfish.yaml";
	std::istringstream in(readFile(file));
	std::ostringstream out;
	bool in_sensors = false, replaced = false;
	for (std::string line; std::getline(in, line);)
	{
		if (in_sensors)
		{
			if (line.empty() || line[0] == ' ' || line[0] == '\t' || line[0] == '#' || line[0] == '-')
				continue;
			in_sensors = false;
		}
		if (line.rfind("sensors:", 0) == 0)
		{
			in_sensors = replaced = true;
			out << sensors_block;
			continue;
		}
		out << line << '\n';
	}
	EXPECT_TRUE(replaced) << file << " has no top-level 'sensors:'";
	// Named as the original file: paths in it are relative to its directory.
	auto cfg = config::Node::fromText(out.str(), file);
	cfg.set("filter.initial.position", "config");
	return cfg;
}

constexpr double kT0 = 1.5e9;  // [s, Unix]

/** Feeds `n` stationary, level IMU samples at 100 Hz; returns the last time. */
double feedImu(Navigator& nav, const std::string& label, int n, double t0 = kT0)
{
	double t = t0;
	for (int i = 0; i < n; ++i)
	{
		t = t0 + 0.01 * i;
		auto imu = mrpt::obs::CObservationIMU::Create();
		imu->sensorLabel = label;
		imu->timestamp = mrpt::Clock::fromDouble(t);
		using namespace mrpt::obs;
		imu->set(IMU_WX, 0.0);
		imu->set(IMU_WY, 0.0);
		imu->set(IMU_WZ, 0.0);
		imu->set(IMU_X_ACC, 0.0);
		imu->set(IMU_Y_ACC, 0.0);
		imu->set(IMU_Z_ACC, -9.78);
		nav.process(*imu);
	}
	return t;
}

mrpt::obs::CObservation::Ptr pressureObs(const std::string& label, double t, double value)
{
	auto o = auvnav::obs::CObservationPressure::Create();
	o->sensorLabel = label;
	o->timestamp = mrpt::Clock::fromDouble(t);
	o->pressure_pa = value;
	o->temperature_c = 15;
	return o;
}

SensorStats statsOf(const Navigator& nav, const std::string& label)
{
	for (const auto& s : nav.stats())
		if (s.label == label) return s;
	ADD_FAILURE() << "no statistics for sensor " << label;
	return {};
}

/** A navigator with one sensor `label` served by `plugin` (path) with `config`,
 *  initialised by 1.5 s of IMU data. */
struct NavFixture
{
	PluginHost host;
	std::unique_ptr<Navigator> nav;
	double t = 0;
	std::string imu_label;
	NavFixture(const std::string& label, const std::string& plugin, const std::string& config_flow)
	{
		const auto cfg = navigatorConfig("sensors:\n  - label: " + label + "\n    plugin: " + plugin +
		                                 "\n    config: " + config_flow + "\n");
		imu_label = cfg.child("imu").string("label");
		nav = std::make_unique<Navigator>(cfg, host);
		t = feedImu(*nav, imu_label, 150);
	}
};
}  // namespace

// ------------------------------------------------------------ loading refusals

TEST(PluginRefusal, MissingPluginByNameNamesItAndTheSearchedPaths)
{
	PluginHost host({"/nonexistent/auvnav-plugins"});
	const std::string msg = pluginError([&] { host.create("no_such_sensor", "{}", "X"); });
	EXPECT_CONTAINS(msg, "'no_such_sensor'");
	EXPECT_CONTAINS(msg, "libauvnav_plugin_no_such_sensor.so");
	EXPECT_CONTAINS(msg, "/nonexistent/auvnav-plugins");
	EXPECT_CONTAINS(msg, "AUVNAV_PLUGIN_PATH");
}

TEST(PluginRefusal, MissingPluginFileByPathNamesThePath)
{
	PluginHost host;
	const std::string path = "/nonexistent/dir/libauvnav_plugin_missing.so";
	const std::string msg = pluginError([&] { host.load(path); });
	EXPECT_CONTAINS(msg, "not found");
	EXPECT_CONTAINS(msg, path);
}

TEST(PluginRefusal, MissingPluginThroughTheNavigatorNamesIt)
{
	PluginHost host;
	const auto cfg = navigatorConfig("sensors:\n  - {label: DVL, plugin: no_such_dvl_plugin, config: {}}\n");
	const std::string msg = pluginError([&] { Navigator nav(cfg, host); });
	EXPECT_CONTAINS(msg, "'no_such_dvl_plugin'");
	EXPECT_CONTAINS(msg, "libauvnav_plugin_no_such_dvl_plugin.so");
}

TEST(PluginRefusal, FileThatIsNotALibrary)
{
	const std::string path = ::testing::TempDir() + "libauvnav_plugin_text.so";
	std::ofstream(path) << "not an ELF file\n";
	PluginHost host;
	const std::string msg = pluginError([&] { host.load(path); });
	EXPECT_CONTAINS(msg, "cannot load plugin");
	EXPECT_CONTAINS(msg, path);
	std::filesystem::remove(path);
}

TEST(PluginRefusal, LibraryWithoutEntryPoint)
{
	PluginHost host;
	const std::string msg = pluginError([&] { host.load(AUVNAV_TEST_PLUGIN_NO_ENTRY); });
	EXPECT_CONTAINS(msg, AUVNAV_TEST_PLUGIN_NO_ENTRY);
	EXPECT_CONTAINS(msg, "is not an auvnav plugin");
	EXPECT_CONTAINS(msg, "no entry point auvnav_plugin_entry_v1");
}

TEST(PluginRefusal, WrongAbiVersion)
{
	PluginHost host;
	const std::string msg = pluginError([&] { host.create(AUVNAV_TEST_PLUGIN_WRONG_ABI, "{}", "X"); });
	EXPECT_CONTAINS(msg, "plugin 'wrong_abi'");
	EXPECT_CONTAINS(msg, AUVNAV_TEST_PLUGIN_WRONG_ABI);
	EXPECT_CONTAINS(msg, "has ABI version 99");
	EXPECT_CONTAINS(msg, "needs ABI version " + std::to_string(AUVNAV_PLUGIN_ABI_VERSION));
	EXPECT_CONTAINS(msg, "rebuild the plugin");
}

TEST(PluginRefusal, MismatchingBuildFingerprint)
{
	PluginHost host;
	const std::string msg =
	    pluginError([&] { host.create(AUVNAV_TEST_PLUGIN_WRONG_FINGERPRINT, "{}", "X"); });
	EXPECT_CONTAINS(msg, "plugin 'wrong_fingerprint'");
	EXPECT_CONTAINS(msg, AUVNAV_TEST_PLUGIN_WRONG_FINGERPRINT);
	EXPECT_CONTAINS(msg, "built with 'gcc-0.0 eigen-3.0.0 align-8 mrpt-0x100 state-42'");
	EXPECT_CONTAINS(msg, "'" AUVNAV_BUILD_FINGERPRINT "'");
	EXPECT_CONTAINS(msg, "rebuild the plugin");
}

TEST(PluginRefusal, FailingFactorySurfacesThePluginsMessage)
{
	PluginHost host;
	const std::string msg = pluginError(
	    [&] { host.create(AUVNAV_TEST_PLUGIN_FAILING_FACTORY, "calibration: /etc/cal.bin\n", "BROKEN"); });
	EXPECT_CONTAINS(msg, "plugin 'failing_factory'");
	EXPECT_CONTAINS(msg, AUVNAV_TEST_PLUGIN_FAILING_FACTORY);
	EXPECT_CONTAINS(msg, "refused its configuration for sensor 'BROKEN'");
	EXPECT_CONTAINS(msg, "calibration file '/etc/cal.bin' cannot be read (failing_factory test plugin)");
	// A config the plugin's config reader rejects: the ConfigError text surfaces too.
	const std::string msg2 =
	    pluginError([&] { host.create(AUVNAV_TEST_PLUGIN_PROBE, "mode: sideways\n", "P"); });
	EXPECT_CONTAINS(msg2, "refused its configuration for sensor 'P'");
	EXPECT_CONTAINS(msg2, "mode");
	EXPECT_CONTAINS(msg2, "expected passthrough or nan_h");
}

TEST(PluginRefusal, GoodTestPluginLoads)
{
	// The control: the same build rules make a plugin the host accepts.
	PluginHost host;
	const PluginInfo info = host.load(AUVNAV_TEST_PLUGIN_PROBE);
	EXPECT_EQ(info.name, "probe");
	EXPECT_EQ(info.fingerprint, AUVNAV_BUILD_FINGERPRINT);
	auto m = host.create(AUVNAV_TEST_PLUGIN_PROBE, "mode: passthrough\n", "P");
	ASSERT_TRUE(m);
	EXPECT_EQ(m->uses(), uint32_t(kPosition));
}

// ------------------------------------------------------------ sanitizers and ELF

TEST(PluginRefusal, FingerprintNamesTheSanitizers)
{
	const std::string fp = AUVNAV_BUILD_FINGERPRINT;
#if AUVNAV_SANITIZER_ASAN && AUVNAV_SANITIZER_UBSAN
	EXPECT_CONTAINS(fp, " sanitize-asan-ubsan");
#elif !AUVNAV_SANITIZER_ASAN && !AUVNAV_SANITIZER_UBSAN && !AUVNAV_SANITIZER_TSAN
	EXPECT_EQ(fp.find("sanitize"), std::string::npos) << fp;
#endif
#if defined(__clang__)
	EXPECT_EQ(fp.rfind("clang-", 0), 0u) << fp;
#else
	EXPECT_EQ(fp.rfind("gcc-", 0), 0u) << fp;
#endif
}

#ifdef AUVNAV_TEST_PLUGIN_ASAN_BUILT
// A plugin built with -fsanitize=address passed the fingerprint check (it had
// no sanitizer in it) and dlopen killed the program with "ASan runtime does not
// come first", naming no plugin. Now: refused before dlopen, in one line.
TEST(PluginRefusal, SanitizedPluginIsRefusedBeforeLoading)
{
	const struct
	{
		const char* path;
		const char* runtime;
		const char* sanitizer;
	} cases[] = {{AUVNAV_TEST_PLUGIN_ASAN_BUILT, "libasan.so", "AddressSanitizer"},
	             {AUVNAV_TEST_PLUGIN_UBSAN_BUILT, "libubsan.so", "UndefinedBehaviorSanitizer"}};
	for (const auto& c : cases)
	{
		SCOPED_TRACE(c.path);
		PluginHost host;
		const std::string msg = pluginError([&] { host.create(c.path, "{}", "X"); });
		EXPECT_CONTAINS(msg, std::string("plugin ") + c.path + " needs " + c.runtime);
		EXPECT_CONTAINS(msg, std::string("the ") + c.sanitizer + " runtime");
		EXPECT_CONTAINS(msg, std::string("this navigator is built without ") + c.sanitizer);
		EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
	}
	// By name through the search path: the name as configured, and the file.
	PluginHost host({std::filesystem::path(AUVNAV_TEST_PLUGIN_ASAN_BUILT).parent_path().string()});
	const std::string msg = pluginError([&] { host.load("asan_built"); });
	EXPECT_CONTAINS(
	    msg, std::string("plugin 'asan_built' (") + AUVNAV_TEST_PLUGIN_ASAN_BUILT + ") needs libasan.so");
}
#endif

namespace
{
/** A scratch copy of the first `bytes` bytes of `from`. */
std::string truncatedCopy(const std::string& from, std::size_t bytes, const std::string& name)
{
	const std::string data = readFile(from);
	const std::string path = ::testing::TempDir() + name;
	std::ofstream(path, std::ios::binary) << data.substr(0, std::min(bytes, data.size()));
	return path;
}
}  // namespace

TEST(ElfScan, ListsTheNeededLibrariesOfAPlugin)
{
	const auto needed = elfNeededLibraries(AUVNAV_TEST_PLUGIN_PROBE);
	EXPECT_NE(std::find(needed.begin(), needed.end(), "libauvnav_nav.so"), needed.end());
	EXPECT_NE(std::find_if(needed.begin(), needed.end(),
	                       [](const std::string& n) { return n.rfind("libc.so", 0) == 0; }),
	          needed.end());
#ifdef AUVNAV_TEST_PLUGIN_ASAN_BUILT
	const auto asan = elfNeededLibraries(AUVNAV_TEST_PLUGIN_ASAN_BUILT);
	EXPECT_NE(std::find_if(asan.begin(), asan.end(),
	                       [](const std::string& n) { return n.rfind("libasan.so", 0) == 0; }),
	          asan.end());
#endif
}

TEST(ElfScan, NonElfAndEmptyFilesAreRefusedNamingThem)
{
	const std::string text = ::testing::TempDir() + "elf_scan_text.so";
	std::ofstream(text) << "not an ELF file, but longer than an ELF header would be: 0123456789abcdef\n";
	const std::string empty = ::testing::TempDir() + "elf_scan_empty.so";
	std::ofstream{empty};
	for (const std::string& path : {text, empty})
	{
		const std::string msg = pluginError([&] { elfNeededLibraries(path); });
		EXPECT_EQ(msg, path + ": not an ELF shared library (no ELF header)");
	}
	EXPECT_CONTAINS(pluginError([] { elfNeededLibraries("/nonexistent/x.so"); }),
	                "/nonexistent/x.so: cannot open");
	std::filesystem::remove(text);
	std::filesystem::remove(empty);
}

TEST(ElfScan, TruncatedPluginsAreRefusedNeverCrash)
{
	// Every cut of a real plugin, down to its 16-byte ident: either the needed
	// list (the dynamic section lies before the cut) or a one-line refusal naming
	// the file, and never a read beyond it (the test runs under ASan in .ci/sanitize).
	const std::string from = AUVNAV_TEST_PLUGIN_PROBE;
	const std::size_t size = readFile(from).size();
	std::vector<std::size_t> cuts = {16, 52, 63, 64, 65, 100, 200, 512, 4096};
	for (std::size_t i = 1; i < 64; ++i) cuts.push_back(size * i / 64);
	int refused = 0;
	for (const std::size_t cut : cuts)
	{
		SCOPED_TRACE("cut at " + std::to_string(cut) + " of " + std::to_string(size));
		const std::string path = truncatedCopy(from, cut, "elf_scan_cut.so");
		try
		{
			const auto needed = elfNeededLibraries(path);
			EXPECT_FALSE(needed.empty());
		}
		catch (const PluginError& e)
		{
			++refused;
			EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
			EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
		}
		std::filesystem::remove(path);
	}
	EXPECT_GE(refused, 6);  // at least the cuts inside the headers
	// Through the host: a truncated plugin is "cannot load plugin", naming it.
	const std::string path = truncatedCopy(from, 100, "libauvnav_plugin_cut.so");
	PluginHost host;
	const std::string msg = pluginError([&] { host.load(path); });
	EXPECT_CONTAINS(msg, "cannot load plugin " + path + ": truncated ELF file");
	std::filesystem::remove(path);
}

// ------------------------------------------------------------ bad numbers

TEST(NavigatorRefusal, NanPredictionIsCountedInvalidAndStateUnchanged)
{
	NavFixture f("PROBE", AUVNAV_TEST_PLUGIN_PROBE, "{mode: nan_h}");
	ASSERT_TRUE(f.nav->initialized());
	const NavState before = f.nav->filter().state();
	const Covariance P_before = f.nav->filter().covariance();
	for (int i = 0; i < 3; ++i) f.nav->process(*pressureObs("PROBE", f.t, 0.3));
	const SensorStats st = statsOf(*f.nav, "PROBE");
	EXPECT_EQ(st.invalid, 3u);
	EXPECT_EQ(st.accepted + st.recovered + st.rejected, 0u);
	EXPECT_CONTAINS(st.last_problem, "non-finite h");
	EXPECT_TRUE(at::NavStateIdentical(f.nav->filter().state(), before));
	EXPECT_TRUE(f.nav->filter().covariance() == P_before);
}

TEST(NavigatorRefusal, NanAndInfMeasurementsAreCountedAndNeverReachTheState)
{
	// The probe plugin passes the raw number through unchecked: the navigator's
	// filter must refuse it.
	NavFixture f("PROBE", AUVNAV_TEST_PLUGIN_PROBE, "{mode: passthrough}");
	ASSERT_TRUE(f.nav->initialized());
	const NavState before = f.nav->filter().state();
	const Covariance P_before = f.nav->filter().covariance();
	for (double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL}) f.nav->process(*pressureObs("PROBE", f.t, bad));
	SensorStats st = statsOf(*f.nav, "PROBE");
	EXPECT_EQ(st.invalid, 3u);
	EXPECT_EQ(st.accepted + st.recovered + st.rejected, 0u);
	EXPECT_CONTAINS(st.last_problem, "non-finite");
	EXPECT_TRUE(at::NavStateIdentical(f.nav->filter().state(), before));
	EXPECT_TRUE(f.nav->filter().covariance() == P_before);
	// Control: a finite depth near the state's goes through and moves the state.
	f.nav->process(*pressureObs("PROBE", f.t, before.p_n.z() + 0.05));
	st = statsOf(*f.nav, "PROBE");
	EXPECT_EQ(st.accepted, 1u);
	EXPECT_EQ(st.invalid, 3u);
	EXPECT_NE(f.nav->filter().state().p_n.z(), before.p_n.z());
}

TEST(NavigatorRefusal, NanPressureToTheCorePluginIsCountedAndNeverReachesTheState)
{
	// The core pressure plugin checks its input itself (prepare -> Invalid).
	NavFixture f("PRESSURE", AUVNAV_PRESSURE_PLUGIN, "{}");
	ASSERT_TRUE(f.nav->initialized());
	const NavState before = f.nav->filter().state();
	const Covariance P_before = f.nav->filter().covariance();
	for (double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL}) f.nav->process(*pressureObs("PRESSURE", f.t, bad));
	const SensorStats st = statsOf(*f.nav, "PRESSURE");
	EXPECT_EQ(st.invalid, 3u);
	EXPECT_EQ(st.accepted + st.recovered + st.rejected, 0u);
	EXPECT_CONTAINS(st.last_problem, "non-finite pressure");
	EXPECT_TRUE(at::NavStateIdentical(f.nav->filter().state(), before));
	EXPECT_TRUE(f.nav->filter().covariance() == P_before);
}

TEST(NavigatorRefusal, NonFiniteImuSampleIsCountedAndNeverReachesTheState)
{
	NavFixture f("PROBE", AUVNAV_TEST_PLUGIN_PROBE, "{mode: passthrough}");
	ASSERT_TRUE(f.nav->initialized());
	const NavState before = f.nav->filter().state();
	const std::size_t invalid_before = f.nav->imuStats().invalid;
	auto imu = mrpt::obs::CObservationIMU::Create();
	imu->sensorLabel = f.imu_label;
	imu->timestamp = mrpt::Clock::fromDouble(f.t + 0.01);
	using namespace mrpt::obs;
	for (auto k : {IMU_WX, IMU_WY, IMU_X_ACC, IMU_Y_ACC}) imu->set(k, 0.0);
	imu->set(IMU_WZ, std::nan(""));
	imu->set(IMU_Z_ACC, -9.78);
	f.nav->process(*imu);
	EXPECT_EQ(f.nav->imuStats().invalid, invalid_before + 1);
	EXPECT_CONTAINS(f.nav->imuStats().last_problem, "non-finite");
	EXPECT_TRUE(at::NavStateIdentical(f.nav->filter().state(), before));
}

// ------------------------------------------------------------ unknown configuration keys

namespace
{
/** `key` with two neighbouring letters in its middle swapped ("sigma_pa" -> "sigm_apa"). */
std::string misspelled(std::string key)
{
	for (std::size_t i = key.size() / 2; i + 1 < key.size(); ++i)
		if (key[i] != key[i + 1])
		{
			std::swap(key[i], key[i + 1]);
			return key;
		}
	return key + "x";
}
}  // namespace

class ShippedPlugin : public ::testing::TestWithParam<std::string>
{
};

// Every shipped plugin loads its own default configuration (no key in it goes
// unread) and refuses a misspelled key of it, naming the key and the right one.
TEST_P(ShippedPlugin, RefusesAMisspelledKeyWithTheNearestValidOne)
{
	const std::string name = GetParam();
	const std::string dir = AUVNAV_SOURCE_DIR "/plugins/" + name;
	const std::string text = readFile(dir + "/" + name + ".yaml") + "\nconfig_dir: " + dir + "\n";
	PluginHost host;
	EXPECT_NO_THROW(host.create(name, text, "X")) << name << ".yaml";
	for (const auto& key : config::Node::fromText(text).keys())
	{
		if (key == "config_dir") continue;
		const std::string typo = misspelled(key);
		const std::string msg = pluginError([&] { host.create(name, text + typo + ": 1\n", "X"); });
		// (plugins that also call allowOnly() list the valid keys after the '?')
		EXPECT_CONTAINS(msg, name + " plugin config: " + typo + ": unknown key (did you mean '" + key + "'?");
	}
}

INSTANTIATE_TEST_SUITE_P(Host, ShippedPlugin,
                         ::testing::Values("adcp", "ahrs", "dvl", "gps", "inertial", "magnetometer",
                                           "model_aiding", "pressure", "sonar_heading"));

TEST(PluginConfig, MisspelledKeyThroughTheNavigatorNamesTheFileAndTheEntry)
{
	PluginHost host;
	const auto cfg = navigatorConfig("sensors:\n  - {label: DEPTH, plugin: " AUVNAV_PRESSURE_PLUGIN
	                                 ", config: {sigma_pa: 100, sigmapa: 3}}\n");
	const std::string msg = pluginError([&] { Navigator nav(cfg, host); });
	EXPECT_CONTAINS(msg, "config/flatfish.yaml: sensors[0].config: ");
	EXPECT_CONTAINS(msg, "sigmapa: unknown key (did you mean 'sigma_pa'?)");
}

TEST(NavigatorConfig, MisspelledKeysAreRefusedWithTheNearestValidOne)
{
	PluginHost host;
	const std::string sensors =
	    "sensors:\n  - {label: DEPTH, plugin: " AUVNAV_PRESSURE_PLUGIN ", config: {}}\n";
	{
		const auto cfg = navigatorConfig(sensors);
		EXPECT_NO_THROW({ const Navigator nav(cfg, host); });
	}
	const std::vector<std::pair<std::string, std::string>> cases = {
	    {"filter.initial.heading_dg", "filter.initial.heading_dg: unknown key (did you mean 'heading_deg'?)"},
	    {"imu.max_gap", "imu.max_gap: unknown key (did you mean 'max_gap_s'?)"},
	    {"filter.process_noise.gyro_arw_deg_per_sqrt_hh",
	     "filter.process_noise.gyro_arw_deg_per_sqrt_hh: unknown key (did you mean"},
	    {"gatse.recovery_after_s", "gatse: unknown key (did you mean 'gates'?)"},
	    {"sensors.DEPTH.plugn", "sensors[0].plugn: unknown key (did you mean 'plugin'?)"},
	};
	for (const auto& [key, expected] : cases)
	{
		auto cfg = navigatorConfig(sensors);
		cfg.set(key, "1");
		std::string msg;
		try
		{
			Navigator nav(cfg, host);
		}
		catch (const config::ConfigError& e)
		{
			msg = e.what();
		}
		EXPECT_CONTAINS(msg, "config/flatfish.yaml: " + expected);
	}
}
