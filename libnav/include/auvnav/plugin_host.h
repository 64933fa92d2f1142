#pragma once
/** @file plugin_host.h
 *  Loads sensor-model plugins (shared libraries, see plugin_api.h) at run
 *  time and creates their models.
 *
 *  A plugin named in the config as a bare name `dvl` is searched as
 *  `libauvnav_plugin_dvl.so` in, in order: the directories passed to the
 *  host (the config's `plugin_paths`), the `AUVNAV_PLUGIN_PATH` environment
 *  variable (colon separated), the installed plugin directory relative to the
 *  running program (`<program dir>/../<libdir>/auvnav/plugins`, libdir as
 *  installed, e.g. lib or lib/x86_64-linux-gnu), and
 *  `<dir of the running program>/../lib/auvnav/plugins` (the build tree).
 *  A name containing '/' or ending in ".so" is a path.
 *
 *  Refusals (PluginError, message naming plugin and path): file not found or
 *  not loadable, no entry point, wrong ABI version, newer API than the host,
 *  build fingerprint mismatch, factory failure (with the plugin's message).
 */
#include <auvnav/measurement_model.h>
#include <auvnav/plugin_api.h>

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace auvnav
{
class PluginError : public std::runtime_error
{
   public:
	using std::runtime_error::runtime_error;
};

struct PluginInfo
{
	std::string name, version, description, fingerprint, path;
	uint32_t abi_version = 0, api_version = 0;
};

/** A model created by a plugin; destroying it calls the plugin's destroy and
 *  keeps the library loaded until the last of its models is gone. */
using ModelPtr = std::unique_ptr<MeasurementModel, std::function<void(MeasurementModel*)>>;

class PluginHost
{
   public:
	explicit PluginHost(std::vector<std::string> search_paths = {});

	/** Resolves a plugin name or path to an existing file (throws PluginError). */
	std::string resolve(const std::string& plugin) const;

	/** Loads (once per path), checks and returns the plugin's header. */
	PluginInfo load(const std::string& plugin);

	/** Creates a model from the plugin with its YAML config text. */
	ModelPtr create(const std::string& plugin, const std::string& config_yaml, const std::string& sensor_label);

	const std::vector<std::string>& searchPaths() const { return paths_; }

   private:
	struct Library;
	std::shared_ptr<Library> open(const std::string& plugin);
	std::vector<std::string> paths_;
	std::vector<std::shared_ptr<Library>> libraries_;
};

}  // namespace auvnav
