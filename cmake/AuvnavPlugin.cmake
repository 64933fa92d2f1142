# auvnav_add_plugin_module(): builds an auvnav sensor-model plugin, a MODULE
# library that the navigator loads at run time (libnav/runtime/include/auvnav/plugin_api.h).
#
# Used in-tree by plugins/CMakeLists.txt (auvnav_add_plugin) and installed with
# the package (lib/cmake/auvnav/), where auvnavConfig.cmake includes it for
# out-of-tree plugin authors:
#
#   find_package(auvnav REQUIRED)
#   auvnav_add_plugin_module(compass SOURCES compass.cpp CONFIG compass.yaml)
#
# auvnav_add_plugin_module(<target> SOURCES <src...>
#                          [NAME <name>]              plugin name; default: <target> without a leading "auvnav_plugin_"
#                          [CONFIG <file.yaml>]       default configuration, copied next to the module as <name>.yaml
#                          [OUTPUT_DIRECTORY <dir>]   default: CMAKE_LIBRARY_OUTPUT_DIRECTORY, else the current binary dir
#                          [INSTALL_DESTINATION <dir>])  install the module (and <name>.yaml) there
#
# auvnav_add_observation_library(<target> SOURCES <src...> [INSTALL_DESTINATION <dir>])
#   a SHARED library lib<target>.so with a plugin's own MRPT observation
#   classes (a CObservation subclass per file, registered by a namespace-scope
#   initialiser: share/examples/compass_plugin): the plugin links it, and the
#   programs that read rawlogs
#   load it with `--obs-lib lib<target>.so` or the sensor's `obs_libs` config
#   key (auvnav/obs_libraries.h). Links auvnav::obs (mrpt::obs) PUBLIC.
#   Install it where the plugin is installed (AUVNAV_PLUGIN_INSTALL_DIR) so
#   that the programs find it by file name in the plugin path.
#
# Install RPATHs (a plugin that links its own observation library must find
# it once installed; CMake's default install RPATH is empty): the module and
# the observation library get "$ORIGIN" (a library installed next to them),
# "$ORIGIN/<relative path to the prefix's libdir>" and the auvnav package's
# library directory. In-tree plugins set their own (plugins/CMakeLists.txt).
#
# The module is lib<...>auvnav_plugin_<name>.so (PREFIX "lib", OUTPUT_NAME
# auvnav_plugin_<name>): the file name the plugin host looks for when a config
# names the plugin `<name>`. It links auvnav::nav, is compiled with hidden
# visibility, linked with --no-undefined and with a version script that exports
# the entry point auvnav_plugin_entry_v1 only (define it with AUVNAV_PLUGIN).
# Against an auvnav built with AUVNAV_SANITIZE, both are built with its
# sanitizers (the plugin fingerprint compares them).
include_guard(GLOBAL)

# The version script sits next to this file both in the source tree (cmake/)
# and in the installed package (lib/cmake/auvnav/). A global property, so that
# the function works whatever directory scope it is called from.
set_property(GLOBAL PROPERTY AUVNAV_PLUGIN_EXPORTS_MAP "${CMAKE_CURRENT_LIST_DIR}/auvnav_plugin_exports.map")

# The install RPATH for a library installed into <destination> (relative to
# the prefix, or absolute): see above.
function(_auvnav_install_rpath out destination)
  set(rpath "$ORIGIN")
  if(destination AND NOT IS_ABSOLUTE "${destination}")
    include(GNUInstallDirs)
    file(RELATIVE_PATH to_libdir "/prefix/${destination}" "/prefix/${CMAKE_INSTALL_LIBDIR}")
    string(REGEX REPLACE "/$" "" to_libdir "${to_libdir}")
    if(to_libdir)
      list(APPEND rpath "$ORIGIN/${to_libdir}")
    endif()
  endif()
  if(AUVNAV_LIBRARY_DIR)  # set by auvnavConfig.cmake (out-of-tree builds)
    list(APPEND rpath "${AUVNAV_LIBRARY_DIR}")
  endif()
  set(${out} "${rpath}" PARENT_SCOPE)
endfunction()

# Out-of-tree builds against a sanitized auvnav (auvnavConfig.cmake sets
# AUVNAV_BUILT_SANITIZED): the same sanitizers as auvnav, and the definition
# that names UBSan in the fingerprint (gcc has no macro for it; plugin_api.h).
# In-tree, the top-level AUVNAV_SANITIZE option sets both for every target.
# --no-undefined, except against clang's sanitizers: clang links their
# runtime into executables only, so every shared library leaves its hooks
# (__asan_report_load8, ...) undefined until the program loads it.
function(_auvnav_no_undefined target)
  if(CMAKE_CXX_COMPILER_ID MATCHES "Clang" AND (AUVNAV_BUILT_SANITIZED OR AUVNAV_SANITIZE OR AUVNAV_FUZZ))
    return()
  endif()
  target_link_options(${target} PRIVATE "LINKER:--no-undefined")
endfunction()

function(_auvnav_match_sanitizers target)
  if(AUVNAV_BUILT_SANITIZED)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
    target_compile_definitions(${target} PRIVATE AUVNAV_BUILT_WITH_UBSAN=1)
  endif()
endfunction()

function(auvnav_add_observation_library target)
  cmake_parse_arguments(ARG "" "INSTALL_DESTINATION" "SOURCES" ${ARGN})
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "auvnav_add_observation_library(${target}): unknown arguments ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "auvnav_add_observation_library(${target}): no SOURCES")
  endif()
  if(NOT TARGET auvnav::obs)
    message(FATAL_ERROR "auvnav_add_observation_library(${target}): target auvnav::obs is missing (find_package(auvnav) first)")
  endif()
  add_library(${target} SHARED ${ARG_SOURCES})
  target_link_libraries(${target} PUBLIC auvnav::obs)
  _auvnav_match_sanitizers(${target})
  # --no-undefined: a missing serialization method is a link error here,
  # not a dlopen failure in the field.
  _auvnav_no_undefined(${target})
  _auvnav_install_rpath(rpath "${ARG_INSTALL_DESTINATION}")
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON INSTALL_RPATH "${rpath}")
  if(ARG_INSTALL_DESTINATION)
    install(TARGETS ${target} LIBRARY DESTINATION "${ARG_INSTALL_DESTINATION}")
  endif()
endfunction()

function(auvnav_add_plugin_module target)
  cmake_parse_arguments(ARG "" "NAME;CONFIG;OUTPUT_DIRECTORY;INSTALL_DESTINATION" "SOURCES" ${ARGN})
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "auvnav_add_plugin_module(${target}): unknown arguments ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "auvnav_add_plugin_module(${target}): no SOURCES")
  endif()
  if(NOT TARGET auvnav::nav)
    message(FATAL_ERROR "auvnav_add_plugin_module(${target}): target auvnav::nav is missing (find_package(auvnav) first)")
  endif()
  set(name "${ARG_NAME}")
  if(NOT name)
    string(REGEX REPLACE "^auvnav_plugin_" "" name "${target}")
  endif()
  if(NOT name MATCHES "^[A-Za-z0-9_]+$")
    message(FATAL_ERROR "auvnav_add_plugin_module(${target}): plugin name '${name}' must be [A-Za-z0-9_]+")
  endif()
  set(out_dir "${ARG_OUTPUT_DIRECTORY}")
  if(NOT out_dir)
    set(out_dir "${CMAKE_LIBRARY_OUTPUT_DIRECTORY}")
  endif()
  if(NOT out_dir)
    set(out_dir "${CMAKE_CURRENT_BINARY_DIR}")
  endif()
  get_property(exports_map GLOBAL PROPERTY AUVNAV_PLUGIN_EXPORTS_MAP)

  add_library(${target} MODULE ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE auvnav::nav)
  _auvnav_match_sanitizers(${target})
  # Hidden visibility for the plugin's code; the version script also hides the
  # template instantiations that libstdc++ headers mark visible: the entry is all.
  target_link_options(${target} PRIVATE "LINKER:--version-script=${exports_map}")
  _auvnav_no_undefined(${target})
  set_target_properties(${target} PROPERTIES
    PREFIX "lib"
    OUTPUT_NAME auvnav_plugin_${name}
    LIBRARY_OUTPUT_DIRECTORY "${out_dir}"
    POSITION_INDEPENDENT_CODE ON
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    LINK_DEPENDS "${exports_map}")
  _auvnav_install_rpath(rpath "${ARG_INSTALL_DESTINATION}")
  set_target_properties(${target} PROPERTIES INSTALL_RPATH "${rpath}")
  set_property(TARGET ${target} PROPERTY AUVNAV_PLUGIN_NAME "${name}")

  if(ARG_CONFIG)
    get_filename_component(config "${ARG_CONFIG}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    configure_file("${config}" "${out_dir}/${name}.yaml" COPYONLY)
  endif()
  if(ARG_INSTALL_DESTINATION)
    install(TARGETS ${target} LIBRARY DESTINATION "${ARG_INSTALL_DESTINATION}")
    if(ARG_CONFIG)
      install(FILES "${config}" DESTINATION "${ARG_INSTALL_DESTINATION}" RENAME "${name}.yaml")
    endif()
  endif()
endfunction()
