#include <auvnav/obs_libraries.h>
#include <dlfcn.h>

#include <filesystem>
#include <mutex>
#include <set>

namespace fs = std::filesystem;

namespace auvnav
{
namespace
{
bool isPath(const std::string& lib)
{
	return lib.find('/') != std::string::npos;
}

/** Where `lib` is loaded from: an absolute path, or a bare name for dlopen's own search. */
std::string locate(const std::string& lib, const std::vector<std::string>& search_dirs)
{
	if (isPath(lib))
	{
		if (!fs::exists(lib)) throw ObservationLibraryError("observation library '" + lib + "' not found");
		return fs::absolute(lib).lexically_normal().string();
	}
	for (const auto& dir : search_dirs)
	{
		const fs::path p = fs::path(dir) / lib;
		if (fs::exists(p)) return fs::absolute(p).lexically_normal().string();
	}
	return lib;
}
}  // namespace

std::string loadObservationLibrary(const std::string& lib, const std::vector<std::string>& search_dirs)
{
	if (lib.empty()) throw ObservationLibraryError("observation library: empty name");
	std::string where = locate(lib, search_dirs);
	static std::mutex mutex;
	static std::set<std::string> loaded;
	const std::lock_guard<std::mutex> lock(mutex);
	if (loaded.count(where)) return where;
	// Static initialisers run inside dlopen: the library's registering
	// initialisers (share/examples/compass_plugin) register its classes now.
	if (!dlopen(where.c_str(), RTLD_NOW | RTLD_GLOBAL | RTLD_NODELETE))
	{
		const char* e = dlerror();
		std::string msg = "cannot load observation library '" + lib + "'";
		if (where != lib) msg += " (" + where + ")";
		msg += std::string(": ") + (e ? e : "unknown error");
		if (!isPath(lib) && where == lib && !search_dirs.empty())
		{
			msg += " (also not in";
			for (const auto& d : search_dirs) msg += " " + d;
			msg += ")";
		}
		throw ObservationLibraryError(msg);
	}
	loaded.insert(where);
	return where;
}

void loadObservationLibraries(const std::vector<std::string>& libs,
                              const std::vector<std::string>& search_dirs)
{
	for (const auto& lib : libs) loadObservationLibrary(lib, search_dirs);
}

std::vector<std::string> declaredObservationLibraries(const config::Node& nav_cfg)
{
	std::vector<std::string> out;
	if (!nav_cfg.has("sensors")) return out;
	const fs::path base = nav_cfg.file().empty() ? fs::path() : fs::absolute(nav_cfg.file()).parent_path();
	for (const auto& s : nav_cfg.sequence("sensors"))
	{
		if (!s.has("obs_libs")) continue;
		const auto libs =
		    s.isSequence("obs_libs") ? s.strings("obs_libs") : std::vector<std::string>{s.string("obs_libs")};
		for (const auto& lib : libs)
		{
			if (lib.empty()) s.fail("obs_libs", "empty library name");
			out.push_back(
			    isPath(lib) && fs::path(lib).is_relative() ? (base / lib).lexically_normal().string() : lib);
		}
	}
	return out;
}

}  // namespace auvnav
