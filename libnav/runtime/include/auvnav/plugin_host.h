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
 *  Refusals (PluginError, one line naming plugin and path): file not found,
 *  not an ELF shared library or truncated (checked before dlopen), a sanitizer
 *  runtime the navigator was not built with among its DT_NEEDED libraries
 *  (checked before dlopen, which would abort the program: ASan's runtime
 *  must come first), not loadable, no entry point, wrong ABI version, newer
 *  API than the host, build fingerprint mismatch (which includes the
 *  sanitizers), factory failure (with the plugin's message).
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

/** The shared libraries the ELF file at `path` asks the dynamic loader for
 *  (its DT_NEEDED entries, in order, e.g. "libasan.so.8"), read from its
 *  program headers without loading it: 32- or 64-bit, this machine's byte
 *  order; none for a file without a dynamic section. Every read is bounded by
 *  the file's size. Throws PluginError "PATH: what" for a file that cannot be
 *  read, is not ELF, or is truncated or inconsistent. */
std::vector<std::string> elfNeededLibraries(const std::string& path);

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
	ModelPtr create(const std::string& plugin, const std::string& config_yaml,
	                const std::string& sensor_label);

	const std::vector<std::string>& searchPaths() const { return paths_; }

 private:
	struct Library;
	std::shared_ptr<Library> open(const std::string& plugin);
	std::vector<std::string> paths_;
	std::vector<std::shared_ptr<Library>> libraries_;
};

}  // namespace auvnav
