#pragma once
/** @file obs_libraries.h
 *  Observation libraries: shared libraries that define MRPT CObservation
 *  subclasses (a plugin's own sensor data) and register them with MRPT's
 *  class registry when they are loaded (MRPT_INITIALIZER; CMake:
 *  auvnav_add_observation_library). A rawlog holding such a class can be
 *  read only once its library is loaded, so every program that reads rawlogs
 *  loads them before it opens one: those given as `--obs-lib LIB` and those
 *  the navigator config's `sensors:` entries declare under `obs_libs`.
 *
 *  LIB is a path if it contains '/' (relative: to the working directory for
 *  --obs-lib, to the config file's folder for `obs_libs`), else a file name
 *  (`libcompass_obs.so`) looked up first in the plugin search path
 *  (plugin_host.h: plugin_paths, AUVNAV_PLUGIN_PATH, the installed plugin
 *  directory), then by the dynamic loader (LD_LIBRARY_PATH, the installed
 *  library directory through libauvnav_nav's RUNPATH, the system's).
 *
 *  A library is loaded RTLD_NOW | RTLD_GLOBAL, so that a plugin linking the
 *  same library uses this copy, and never unloaded (RTLD_NODELETE): MRPT's
 *  registry keeps pointers into it. Loading the same library twice is a no-op.
 *  A library that cannot be loaded is an ObservationLibraryError naming it
 *  and the loader's reason (programs exit with cli::kExitBadInput, 2).
 */
#include <auvnav/config.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace auvnav
{
class ObservationLibraryError : public std::runtime_error
{
 public:
	using std::runtime_error::runtime_error;
};

/** Loads one observation library; returns the path (or loader name) it was
 *  loaded from. Throws ObservationLibraryError. */
std::string loadObservationLibrary(const std::string& lib, const std::vector<std::string>& search_dirs = {});

/** Loads each of `libs` in order (the first failure throws). */
void loadObservationLibraries(const std::vector<std::string>& libs,
                              const std::vector<std::string>& search_dirs = {});

/** The libraries a navigator config declares: every `sensors:` entry's
 *  optional `obs_libs` (a list of LIB, or one LIB), paths made absolute
 *  against the config file's folder. Reading marks the keys as used, so a
 *  program calls this on the same config::Node before checkAllKeysUsed(). */
std::vector<std::string> declaredObservationLibraries(const config::Node& nav_cfg);

}  // namespace auvnav
