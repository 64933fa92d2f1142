#pragma once
/** @file plugin_api.h
 *  The versioned C entry point of an auvnav sensor plugin.
 *
 *  A plugin is a shared library exporting one symbol,
 *  `auvnav_plugin_entry_v1`, an `extern "C"` function returning a pointer to a
 *  static AuvnavPluginEntry: a header the host checks before anything else
 *  (ABI version, API version, name, version, build fingerprint) and a factory.
 *  The factory gets the plugin's YAML configuration as text and returns a new
 *  MeasurementModel, or nullptr with a message in `error`; it never throws
 *  (use AUVNAV_PLUGIN, which wraps it). Objects are destroyed by the plugin's
 *  own `destroy`, so allocation and release stay on one side.
 *
 *  ABI version: changes when this entry layout or the MeasurementModel vtable
 *  changes (the host refuses other values). API version: the version of the
 *  source interface a plugin is written against; a plugin needing a newer one
 *  than the host's is refused, and docs/plugin_sdk_changelog.md says what
 *  each version asks of plugin authors. Build fingerprint: compiler,
 *  Eigen version and alignment, MRPT version, state dimension, sanitizers;
 *  must match the host's exactly (C++ objects cross the boundary).
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>
#include <mrpt/version.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>

// What each version changed for plugin authors: docs/plugin_sdk_changelog.md.
// API 2: MeasurementFunction::structure() replaces affineIn() and
// residualIsDifference() (ABI 9); plugin-owned states are PluginState
// handles returned by states(), every virtual is guarded by
// SafeMeasurementModel's do* methods (ABI 10); FilterContext::alpha_delay_s
// (ABI 11). API 2 is not released yet, so these are one API version.
#define AUVNAV_PLUGIN_ABI_VERSION 11u
#define AUVNAV_PLUGIN_API_VERSION 2u
#define AUVNAV_PLUGIN_ENTRY_SYMBOL "auvnav_plugin_entry_v1"

#define AUVNAV_STR2(x) #x
#define AUVNAV_STR(x) AUVNAV_STR2(x)
#if defined(__clang__)
#define AUVNAV_COMPILER_ID "clang-" AUVNAV_STR(__clang_major__) "." AUVNAV_STR(__clang_minor__)
#elif defined(__GNUC__)
#define AUVNAV_COMPILER_ID "gcc-" AUVNAV_STR(__GNUC__) "." AUVNAV_STR(__GNUC_MINOR__)
#else
#define AUVNAV_COMPILER_ID "unknown-compiler"
#endif
#ifdef _GLIBCXX_USE_CXX11_ABI
#define AUVNAV_STDLIB_ID " libstdc++-cxx11abi-" AUVNAV_STR(_GLIBCXX_USE_CXX11_ABI)
#else
#define AUVNAV_STDLIB_ID " other-stdlib"
#endif
// Sanitizers of this translation unit, each 0 or 1. A sanitized plugin in an
// unsanitized navigator aborts inside dlopen (ASan's runtime must come first)
// and ASan changes object layouts (container annotations), so the set must
// match. gcc defines __SANITIZE_ADDRESS__/__SANITIZE_THREAD__ but nothing for
// UBSan: AUVNAV_BUILT_WITH_UBSAN is defined by the build rules that add
// -fsanitize=undefined (CMakeLists.txt AUVNAV_SANITIZE; for out-of-tree
// plugins auvnav_add_plugin_module, from the installed package's
// AUVNAV_BUILT_SANITIZED). The host also refuses, before dlopen, a plugin that
// links a sanitizer runtime it lacks (plugin_host.h), which catches gcc UBSan
// plugins built by other rules.
#if defined(__has_feature)
#define AUVNAV_HAS_FEATURE(x) __has_feature(x)
#else
#define AUVNAV_HAS_FEATURE(x) 0
#endif
#if defined(__SANITIZE_ADDRESS__) || AUVNAV_HAS_FEATURE(address_sanitizer)
#define AUVNAV_SANITIZER_ASAN 1
#define AUVNAV_ASAN_ID "-asan"
#else
#define AUVNAV_SANITIZER_ASAN 0
#define AUVNAV_ASAN_ID ""
#endif
#if defined(__SANITIZE_HWADDRESS__) || AUVNAV_HAS_FEATURE(hwaddress_sanitizer)
#define AUVNAV_SANITIZER_HWASAN 1
#define AUVNAV_HWASAN_ID "-hwasan"
#else
#define AUVNAV_SANITIZER_HWASAN 0
#define AUVNAV_HWASAN_ID ""
#endif
#if defined(__SANITIZE_THREAD__) || AUVNAV_HAS_FEATURE(thread_sanitizer)
#define AUVNAV_SANITIZER_TSAN 1
#define AUVNAV_TSAN_ID "-tsan"
#else
#define AUVNAV_SANITIZER_TSAN 0
#define AUVNAV_TSAN_ID ""
#endif
#if AUVNAV_HAS_FEATURE(memory_sanitizer)
#define AUVNAV_SANITIZER_MSAN 1
#define AUVNAV_MSAN_ID "-msan"
#else
#define AUVNAV_SANITIZER_MSAN 0
#define AUVNAV_MSAN_ID ""
#endif
#if defined(AUVNAV_BUILT_WITH_UBSAN) || AUVNAV_HAS_FEATURE(undefined_behavior_sanitizer)
#define AUVNAV_SANITIZER_UBSAN 1
#define AUVNAV_UBSAN_ID "-ubsan"
#else
#define AUVNAV_SANITIZER_UBSAN 0
#define AUVNAV_UBSAN_ID ""
#endif
#if AUVNAV_SANITIZER_ASAN || AUVNAV_SANITIZER_HWASAN || AUVNAV_SANITIZER_TSAN || AUVNAV_SANITIZER_MSAN || \
    AUVNAV_SANITIZER_UBSAN
/** e.g. " sanitize-asan-ubsan"; empty for an unsanitized build (its fingerprint as before). */
#define AUVNAV_SANITIZER_ID \
	" sanitize" AUVNAV_ASAN_ID AUVNAV_HWASAN_ID AUVNAV_TSAN_ID AUVNAV_MSAN_ID AUVNAV_UBSAN_ID
#else
#define AUVNAV_SANITIZER_ID ""
#endif

/** Everything that must agree between host and plugin for C++ objects to
 *  cross: compiler (clang and gcc mangle and lay out alike only in part),
 *  the std::string ABI, Eigen's version and alignment, MRPT, the state's
 *  storage (43 + room for plugin states), and the sanitizers. */
#define AUVNAV_BUILD_FINGERPRINT \
	AUVNAV_COMPILER_ID AUVNAV_STDLIB_ID " eigen-" AUVNAV_STR(EIGEN_WORLD_VERSION) "." AUVNAV_STR(          \
		EIGEN_MAJOR_VERSION) "." AUVNAV_STR(EIGEN_MINOR_VERSION) " align-" AUVNAV_STR(EIGEN_MAX_ALIGN_BYTES) \
		" mrpt-" AUVNAV_STR(MRPT_VERSION) " state-43+" AUVNAV_STR(AUVNAV_MAX_EXTRA_STATES) AUVNAV_SANITIZER_ID

extern "C"
{
	struct AuvnavPluginHeader
	{
		uint32_t abi_version;
		uint32_t api_version;
		const char* name;         //!< e.g. "dvl"
		const char* version;      //!< plugin's own version, e.g. "1.0.0"
		const char* fingerprint;  //!< AUVNAV_BUILD_FINGERPRINT at plugin build time
		const char* description;  //!< one line for users
	};

	typedef auvnav::MeasurementModel* (*AuvnavCreateFn)(const char* config_yaml, const char* sensor_label,
	                                                    char* error, size_t error_size);
	typedef void (*AuvnavDestroyFn)(auvnav::MeasurementModel* model);

	struct AuvnavPluginEntry
	{
		AuvnavPluginHeader header;
		AuvnavCreateFn create;
		AuvnavDestroyFn destroy;
	};

	typedef const AuvnavPluginEntry* (*AuvnavEntryFn)();
}

/** The configuration text a plugin receives is its YAML map plus the key
 *  `config_dir`: the absolute folder of the file it came from, against which
 *  the plugin resolves relative file paths in its configuration. */

/** Defines the entry point of a plugin whose model class `ModelClass` has a
 *  constructor `ModelClass(const auvnav::config::Node& cfg, const std::string& label)`.
 *  Exceptions from the constructor become an error message. Once the
 *  constructor is done, every key of `cfg` must have been read (or marked
 *  free-form): a misspelled key is refused with the nearest valid one
 *  (config.h, checkAllKeysUsed). The host's `config_dir` is always allowed.
 *  A model that still declares the deprecated stateBlocks()/bindStates()
 *  builds with a deprecation warning here. */
#define AUVNAV_PLUGIN(ModelClass, plugin_name, plugin_version, plugin_description)                          \
	namespace                                                                                               \
	{                                                                                                       \
	auvnav::MeasurementModel* auvnavCreate_(const char* yaml, const char* label, char* error,               \
	                                        size_t error_size)                                              \
	{                                                                                                       \
		try                                                                                                 \
		{                                                                                                   \
			const auto cfg = auvnav::config::Node::fromText(yaml ? yaml : "{}",                             \
			                                                std::string(plugin_name) + " plugin config");   \
			cfg.markFreeForm("config_dir");                                                                 \
			std::unique_ptr<ModelClass> model(new ModelClass(cfg, label ? label : ""));                     \
			cfg.checkAllKeysUsed();                                                                         \
			return model.release();                                                                         \
		}                                                                                                   \
		catch (const std::exception& e)                                                                     \
		{                                                                                                   \
			std::snprintf(error, error_size, "%s", e.what());                                               \
		}                                                                                                   \
		catch (...)                                                                                         \
		{                                                                                                   \
			std::snprintf(error, error_size, "unknown exception");                                          \
		}                                                                                                   \
		return nullptr;                                                                                     \
	}                                                                                                       \
	void auvnavDestroy_(auvnav::MeasurementModel* m)                                                        \
	{                                                                                                       \
		delete m;                                                                                           \
	}                                                                                                       \
	static_assert(                                                                                          \
	    auvnav::detail::LegacyStatesNotice<auvnav::detail::declaresLegacyStates<ModelClass>()>::value, ""); \
	const AuvnavPluginEntry kAuvnavEntry_ = {                                                               \
	    {AUVNAV_PLUGIN_ABI_VERSION, AUVNAV_PLUGIN_API_VERSION, plugin_name, plugin_version,                 \
	     AUVNAV_BUILD_FINGERPRINT, plugin_description},                                                     \
	    &auvnavCreate_,                                                                                     \
	    &auvnavDestroy_};                                                                                   \
	}                                                                                                       \
	extern "C" __attribute__((visibility("default"))) const AuvnavPluginEntry* auvnav_plugin_entry_v1()     \
	{                                                                                                       \
		return &kAuvnavEntry_;                                                                              \
	}
