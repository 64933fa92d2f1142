#pragma once
/** @file plugin_test_support.h
 *  Test-only helpers of the core plugins' tests (not part of the SDK): the
 *  plugin's default configuration file and a minimal dlopen of the built
 *  MODULE to check its entry point. Loading for real is the host's job
 *  (plugin_host.h); this only checks that the module is what the host expects.
 */
#include <auvnav/config.h>
#include <auvnav/plugin_api.h>
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <string>

namespace auvnav::plugins::test
{
inline std::string readFile(const std::string& path)
{
	std::ifstream f(path);
	std::stringstream s;
	s << f.rdbuf();
	return s.str();
}

/** The plugin's default configuration (plugins/<name>/<name>.yaml). */
inline config::Node defaultConfig()
{
	return config::Node::load(AUVNAV_PLUGIN_DEFAULT_CONFIG);
}

/** A configuration from YAML text (keys not given take their defaults). */
inline config::Node configText(const std::string& yaml)
{
	return config::Node::fromText(yaml, "test config");
}

/** dlopen()s the built module (RTLD_LOCAL) and checks its entry point: name,
 *  ABI/API version and build fingerprint; then creates a model from
 *  `config_yaml`, checks `uses()` and destroys it. */
inline ::testing::AssertionResult ModuleLoadsAndCreates(const std::string& name,
                                                        const std::string& config_yaml,
                                                        uint32_t expected_uses)
{
	using ::testing::AssertionFailure;
	std::unique_ptr<void, int (*)(void*)> h(dlopen(AUVNAV_PLUGIN_MODULE, RTLD_NOW | RTLD_LOCAL), &dlclose);
	if (!h) return AssertionFailure() << "dlopen: " << dlerror();
	auto entry_fn = reinterpret_cast<AuvnavEntryFn>(dlsym(h.get(), AUVNAV_PLUGIN_ENTRY_SYMBOL));
	if (!entry_fn)
		return AssertionFailure() << "no " << AUVNAV_PLUGIN_ENTRY_SYMBOL << " in " << AUVNAV_PLUGIN_MODULE;
	const AuvnavPluginEntry* e = entry_fn();
	if (!e || !e->create || !e->destroy) return AssertionFailure() << "incomplete entry";
	if (e->header.abi_version != AUVNAV_PLUGIN_ABI_VERSION)
		return AssertionFailure() << "ABI version " << e->header.abi_version;
	if (e->header.api_version != AUVNAV_PLUGIN_API_VERSION)
		return AssertionFailure() << "API version " << e->header.api_version;
	if (name != e->header.name) return AssertionFailure() << "name '" << e->header.name << "'";
	if (std::string(AUVNAV_BUILD_FINGERPRINT) != e->header.fingerprint)
		return AssertionFailure() << "fingerprint '" << e->header.fingerprint << "' vs '"
		                          << AUVNAV_BUILD_FINGERPRINT << "'";
	if (!e->header.version || !e->header.description || !*e->header.description)
		return AssertionFailure() << "missing version or description";
	char error[512] = "";
	MeasurementModel* m = e->create(config_yaml.c_str(), "TEST", error, sizeof error);
	if (!m) return AssertionFailure() << "create failed: " << error;
	const uint32_t uses = m->uses();
	e->destroy(m);
	if (uses != expected_uses)
		return AssertionFailure() << "uses() = " << uses << ", expected " << expected_uses;
	return ::testing::AssertionSuccess();
}

/** The factory refuses `config_yaml` with a message containing `expected`. */
inline ::testing::AssertionResult ModuleRefuses(const std::string& config_yaml, const std::string& expected)
{
	using ::testing::AssertionFailure;
	std::unique_ptr<void, int (*)(void*)> h(dlopen(AUVNAV_PLUGIN_MODULE, RTLD_NOW | RTLD_LOCAL), &dlclose);
	if (!h) return AssertionFailure() << "dlopen: " << dlerror();
	auto entry_fn = reinterpret_cast<AuvnavEntryFn>(dlsym(h.get(), AUVNAV_PLUGIN_ENTRY_SYMBOL));
	if (!entry_fn) return AssertionFailure() << "no entry point";
	const AuvnavPluginEntry* e = entry_fn();
	char error[512] = "";
	MeasurementModel* m = e->create(config_yaml.c_str(), "TEST", error, sizeof error);
	if (m)
	{
		e->destroy(m);
		return AssertionFailure() << "accepted config: " << config_yaml;
	}
	if (std::string(error).find(expected) == std::string::npos)
		return AssertionFailure() << "error '" << error << "' does not contain '" << expected << "'";
	return ::testing::AssertionSuccess();
}

}  // namespace auvnav::plugins::test
