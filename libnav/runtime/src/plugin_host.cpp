#include <auvnav/plugin_host.h>
#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace auvnav
{
struct PluginHost::Library
{
	std::string path;
	void* handle = nullptr;
	const AuvnavPluginEntry* entry = nullptr;
	PluginInfo info;
	~Library()
	{
		if (handle) dlclose(handle);
	}
};

namespace
{
std::string executableDir()
{
	std::error_code ec;
	const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
	return ec ? std::string() : exe.parent_path().string();
}

/** A sanitizer's shared runtime, as a plugin's DT_NEEDED names it. */
struct SanitizerRuntime
{
	const char* prefix;  // of the library's file name
	const char* sanitizer;
	bool in_host;  // this navigator is built with it
};

// gcc's runtimes (libasan.so.8, ...) and clang's with -shared-libsan
// (libclang_rt.asan-x86_64.so, ...). Standalone LeakSanitizer is never the
// host's (ASan's leak checker is part of libasan).
const SanitizerRuntime kSanitizerRuntimes[] = {
    {"libasan.so", "AddressSanitizer", AUVNAV_SANITIZER_ASAN},
    {"libclang_rt.asan", "AddressSanitizer", AUVNAV_SANITIZER_ASAN},
    {"libhwasan.so", "HWAddressSanitizer", AUVNAV_SANITIZER_HWASAN},
    {"libclang_rt.hwasan", "HWAddressSanitizer", AUVNAV_SANITIZER_HWASAN},
    {"libtsan.so", "ThreadSanitizer", AUVNAV_SANITIZER_TSAN},
    {"libclang_rt.tsan", "ThreadSanitizer", AUVNAV_SANITIZER_TSAN},
    {"libubsan.so", "UndefinedBehaviorSanitizer", AUVNAV_SANITIZER_UBSAN},
    {"libclang_rt.ubsan", "UndefinedBehaviorSanitizer", AUVNAV_SANITIZER_UBSAN},
    {"liblsan.so", "LeakSanitizer", false},
    {"libclang_rt.lsan", "LeakSanitizer", false},
};

/** "plugin 'dvl' (PATH)", or "plugin PATH" when it was named by its path. */
std::string pluginNamed(const std::string& plugin, const std::string& path)
{
	return plugin.find('/') != std::string::npos ? "plugin " + path
	                                             : "plugin '" + plugin + "' (" + path + ")";
}

/** Refuses, before dlopen runs any of its code, a file that is not an ELF
 *  shared library or that links a sanitizer runtime this navigator lacks
 *  (dlopen would abort the program from inside the runtime's initialiser). */
void checkBeforeLoading(const std::string& plugin, const std::string& path)
{
	std::vector<std::string> needed;
	try
	{
		needed = elfNeededLibraries(path);
	}
	catch (const PluginError& e)
	{
		// e: "PATH: why"; as dlopen's failures: "cannot load plugin 'NAME' from PATH: why".
		const bool by_path = plugin.find('/') != std::string::npos;
		throw PluginError("cannot load plugin " + (by_path ? "" : "'" + plugin + "' from ") + e.what());
	}
	for (const std::string& lib : needed)
		for (const SanitizerRuntime& r : kSanitizerRuntimes)
			if (lib.rfind(r.prefix, 0) == 0 && !r.in_host)
				throw PluginError(pluginNamed(plugin, path) + " needs " + lib + ", the " + r.sanitizer +
				                  " runtime, but this navigator is built without " + r.sanitizer +
				                  " (its runtime cannot be loaded into a program built without it): rebuild "
				                  "the plugin without -fsanitize, or "
				                  "use a navigator built with the same sanitizers");
}

std::vector<std::string> splitPath(const char* s)
{
	std::vector<std::string> out;
	if (!s) return out;
	std::stringstream ss(s);
	for (std::string part; std::getline(ss, part, ':');)
		if (!part.empty()) out.push_back(part);
	return out;
}
}  // namespace

PluginHost::PluginHost(std::vector<std::string> search_paths) : paths_(std::move(search_paths))
{
	for (const auto& p : splitPath(std::getenv("AUVNAV_PLUGIN_PATH"))) paths_.push_back(p);
	const std::string exe_dir = executableDir();
	if (!exe_dir.empty())
	{
		// Installed layout: the plugin directory relative to the program's
		// directory (e.g. ../lib/x86_64-linux-gnu/auvnav/plugins; set by CMake from
		// GNUInstallDirs), then the build tree's bin/../lib/auvnav/plugins.
		std::vector<std::string> defaults;
#ifdef AUVNAV_PLUGIN_RELDIR
		defaults.push_back((fs::path(exe_dir) / AUVNAV_PLUGIN_RELDIR).lexically_normal().string());
#endif
		defaults.push_back(
		    (fs::path(exe_dir) / ".." / "lib" / "auvnav" / "plugins").lexically_normal().string());
		for (const auto& d : defaults)
			if (std::find(paths_.begin(), paths_.end(), d) == paths_.end()) paths_.push_back(d);
	}
}

std::string PluginHost::resolve(const std::string& plugin) const
{
	const bool is_path = plugin.find('/') != std::string::npos ||
	                     (plugin.size() > 3 && plugin.compare(plugin.size() - 3, 3, ".so") == 0);
	if (is_path)
	{
		if (!fs::exists(plugin)) throw PluginError("plugin file not found: " + plugin);
		return fs::absolute(plugin).lexically_normal().string();
	}
	const std::string file = "libauvnav_plugin_" + plugin + ".so";
	for (const auto& dir : paths_)
	{
		const fs::path p = fs::path(dir) / file;
		if (fs::exists(p)) return fs::absolute(p).lexically_normal().string();
	}
	std::string msg = "plugin '" + plugin + "' not found: no " + file + " in";
	for (const auto& dir : paths_) msg += " " + dir;
	if (paths_.empty()) msg += " (no search paths)";
	throw PluginError(msg + " (set plugin_paths in the config or AUVNAV_PLUGIN_PATH)");
}

std::shared_ptr<PluginHost::Library> PluginHost::open(const std::string& plugin)
{
	const std::string path = resolve(plugin);
	for (const auto& lib : libraries_)
		if (lib->path == path) return lib;

	auto lib = std::make_shared<Library>();
	lib->path = path;
	checkBeforeLoading(plugin, path);
	lib->handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
	if (!lib->handle)
	{
		const char* e = dlerror();
		throw PluginError("cannot load plugin '" + plugin + "' from " + path + ": " +
		                  (e ? e : "unknown error"));
	}
	dlerror();
	void* sym = dlsym(lib->handle, AUVNAV_PLUGIN_ENTRY_SYMBOL);
	if (!sym)
		throw PluginError(path +
		                  " is not an auvnav plugin: it has no entry point " AUVNAV_PLUGIN_ENTRY_SYMBOL);
	const auto entry_fn = reinterpret_cast<AuvnavEntryFn>(sym);
	lib->entry = entry_fn();
	if (!lib->entry) throw PluginError(path + ": entry point returned no plugin description");
	const AuvnavPluginHeader& h = lib->entry->header;
	const std::string name = h.name ? h.name : "?";
	if (h.abi_version != AUVNAV_PLUGIN_ABI_VERSION)
		throw PluginError("plugin '" + name + "' (" + path + ") has ABI version " +
		                  std::to_string(h.abi_version) + "; this navigator needs ABI version " +
		                  std::to_string(AUVNAV_PLUGIN_ABI_VERSION) +
		                  ": rebuild the plugin against this auvnav");
	if (h.api_version > AUVNAV_PLUGIN_API_VERSION)
		throw PluginError("plugin '" + name + "' (" + path + ") needs plugin API version " +
		                  std::to_string(h.api_version) + "; this navigator provides " +
		                  std::to_string(AUVNAV_PLUGIN_API_VERSION) + ": update auvnav");
	const std::string fp = h.fingerprint ? h.fingerprint : "";
	if (fp != AUVNAV_BUILD_FINGERPRINT)
		throw PluginError("plugin '" + name + "' (" + path + ") was built with '" + fp +
		                  "' but this navigator with '" AUVNAV_BUILD_FINGERPRINT
		                  "': C++ objects cannot cross safely; rebuild the plugin");
	if (!lib->entry->create || !lib->entry->destroy)
		throw PluginError("plugin '" + name + "' (" + path + ") lacks a factory or destroy function");
	lib->info = {
	    name,         h.version ? h.version : "", h.description ? h.description : "", fp, path, h.abi_version,
	    h.api_version};
	libraries_.push_back(lib);
	return lib;
}

PluginInfo PluginHost::load(const std::string& plugin)
{
	return open(plugin)->info;
}

ModelPtr PluginHost::create(const std::string& plugin, const std::string& config_yaml,
                            const std::string& label)
{
	auto lib = open(plugin);
	char error[1024] = {0};
	MeasurementModel* m = lib->entry->create(config_yaml.c_str(), label.c_str(), error, sizeof error);
	if (!m)
		throw PluginError("plugin '" + lib->info.name + "' (" + lib->path +
		                  ") refused its configuration for sensor '" + label +
		                  "': " + (error[0] ? error : "no reason given"));
	// The deleter keeps the library alive until the model is destroyed.
	return ModelPtr(m, [lib](MeasurementModel* p) { lib->entry->destroy(p); });
}

}  // namespace auvnav
