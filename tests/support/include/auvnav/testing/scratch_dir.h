#pragma once
/** @file scratch_dir.h
 *  A test's scratch folder. The constructor creates an empty folder under the
 *  system's temporary directory, and the destructor removes it with
 *  everything in it. Removal also happens when an ASSERT fails or an
 *  exception leaves the test, so test runs do not pile files up in /tmp. A
 *  simulated mission with its run is tens of MB: an earlier default test run
 *  left ~130 MB behind each time.
 *
 *  The name is `auvnav_<name>_<pid>_<n>`. The pid keeps ctest's parallel
 *  processes apart, and n keeps apart the folders of one process that share
 *  a name. Set the environment variable AUVNAV_KEEP_TEST_FILES (to anything
 *  but "0") to keep the folders for a post-mortem; the path is then printed
 *  on stderr.
 *
 *  Move-only: the last owner removes the folder. There is no implicit
 *  conversion to a path, and no path from a temporary, because
 *  `fs::path p = makeScratch();` would remove the folder before p is used.
 */
#include <sys/types.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <system_error>
#include <utility>

namespace auvnav::testing
{
class ScratchDir
{
 public:
	explicit ScratchDir(const std::string& name)
	{
		static std::atomic<unsigned> counter{0};
		path_ = std::filesystem::temp_directory_path() /
		        ("auvnav_" + name + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
		std::filesystem::remove_all(path_);  // a folder left by a crashed run with the same pid
		std::filesystem::create_directories(path_);
	}
	~ScratchDir() { release(); }
	ScratchDir(ScratchDir&& other) noexcept : path_(std::exchange(other.path_, {})) {}
	ScratchDir& operator=(ScratchDir&& other) noexcept
	{
		if (this != &other)
		{
			release();
			path_ = std::exchange(other.path_, {});
		}
		return *this;
	}
	ScratchDir(const ScratchDir&) = delete;
	ScratchDir& operator=(const ScratchDir&) = delete;

	const std::filesystem::path& path() const& { return path_; }
	std::filesystem::path operator/(const std::filesystem::path& rel) const& { return path_ / rel; }
	std::string string() const& { return path_.string(); }
	// Not from a temporary: `simulate(…).path()` would name a removed folder.
	const std::filesystem::path& path() const&& = delete;
	std::filesystem::path operator/(const std::filesystem::path& rel) const&& = delete;
	std::string string() const&& = delete;

 private:
	void release() noexcept
	{
		if (path_.empty()) return;
		const char* keep = std::getenv("AUVNAV_KEEP_TEST_FILES");
		if (keep && std::string(keep) != "0")
			std::fprintf(stderr, "kept test files: %s\n", path_.c_str());
		else
		{
			std::error_code ignored;
			std::filesystem::remove_all(path_, ignored);
		}
		path_.clear();
	}

	std::filesystem::path path_;
};
/** A fresh, empty folder `name` inside this process's ScratchDir for
 *  `group`, for tests that hand paths around. The group's folder is
 *  created on first use and removed, with everything in it, at exit.
 *  Safe to call from several threads (one lock around the group map). */
inline std::filesystem::path scratchFolder(const std::string& group, const std::string& name)
{
	static std::mutex lock;
	static std::map<std::string, ScratchDir> groups;  // destroyed at exit: the folders go with them
	const std::lock_guard<std::mutex> hold(lock);
	auto it = groups.find(group);
	if (it == groups.end()) it = groups.emplace(group, ScratchDir(group)).first;
	const std::filesystem::path p = it->second / name;
	std::filesystem::remove_all(p);
	std::filesystem::create_directories(p);
	return p;
}
}  // namespace auvnav::testing
