// auvnav-run's side of --view: finds and loads the live-view module
// (live_view.h), so that the program itself links no GUI library.
#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "live_view.h"

namespace fs = std::filesystem;

namespace auvnav::run
{
namespace
{
constexpr const char* kModuleName = "libauvnav_live_view.so";

/** The installed layout's <libdir>/auvnav (AUVNAV_LIVE_VIEW_RELDIR, relative to
 *  the program's directory), then the build tree's bin/../lib/auvnav. */
std::vector<fs::path> moduleCandidates()
{
	std::error_code ec;
	const fs::path exe_dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
	if (ec) return {};
	std::vector<fs::path> out;
#ifdef AUVNAV_LIVE_VIEW_RELDIR
	out.push_back((exe_dir / AUVNAV_LIVE_VIEW_RELDIR / kModuleName).lexically_normal());
#endif
	const fs::path build_tree = (exe_dir / ".." / "lib" / "auvnav" / kModuleName).lexically_normal();
	if (out.empty() || out.front() != build_tree) out.push_back(build_tree);
	return out;
}
}  // namespace

std::unique_ptr<LiveView> openLiveView(const std::string& title)
{
	// Checked here too, so that a headless machine gets this message rather
	// than the module's loading error.
	if (!std::getenv("DISPLAY"))
		throw std::runtime_error("--view needs a display (DISPLAY is not set; try xvfb-run)");
	const auto candidates = moduleCandidates();
	const fs::path* module = nullptr;
	for (const auto& c : candidates)
		if (fs::exists(c))
		{
			module = &c;
			break;
		}
	if (!module)
	{
		std::string looked;
		for (const auto& c : candidates) looked += (looked.empty() ? "" : ", ") + c.string();
		throw std::runtime_error(std::string("--view: the live view module ") + kModuleName +
		                         " is not installed (looked for " + looked + ")");
	}
	// Never dlclose'd: see live_view.h.
	void* handle = dlopen(module->c_str(), RTLD_NOW | RTLD_LOCAL);
	if (!handle) throw std::runtime_error("--view: cannot load " + module->string() + ": " + dlerror());
	using Create = LiveView* (*)(const char*, std::string*);
	auto create = reinterpret_cast<Create>(dlsym(handle, AUVNAV_LIVE_VIEW_ENTRY_SYMBOL));
	if (!create)
		throw std::runtime_error("--view: " + module->string() +
		                         " has no entry point " AUVNAV_LIVE_VIEW_ENTRY_SYMBOL);
	std::string error;
	std::unique_ptr<LiveView> view(create(title.c_str(), &error));
	if (!view) throw std::runtime_error(error.empty() ? "--view: the live view could not be opened" : error);
	return view;
}
}  // namespace auvnav::run
