# The installed package end to end (ctest: package.install_build_run_compass):
#  1. cmake --install the build tree into WORK_DIR/prefix and check the layout
#     (programs, libraries, plugins + YAML, headers, config, CMake package) and
#     that the installed auvnav-run loads the installed libraries;
#  2. configure, build and unit-test share/examples/compass_plugin against it
#     (find_package(auvnav), auvnav_add_observation_library for its own class
#     CObservationCompass, auvnav_add_plugin_module);
#  3. write a 20 s rawlog (IMU, pressure, compass in the example's own class)
#     with the example's make_compass_rawlog; the installed auvnav-info reads
#     it only with --obs-lib;
#  4. run the INSTALLED auvnav-run with the installed default configuration,
#     its core plugins found by name in the installed plugin directory, plus
#     the compass plugin by path (and its observation library through the
#     sensor's obs_libs); expect exit 0, accepted compass updates, the heading
#     pulled to the compass's and, with `states:`, the plugin's own state
#     COMPASS.heading_bias in states.csv;
#  5. install the example into the same prefix (plugin RUNPATH not empty) and
#     run again with `plugin: compass`;
#  6. the hello world of the example's README: the installed auvnav-sim on the
#     installed compass_hello mission (a simulated compass), the installed
#     auvnav-run with the installed compass_hello.yaml: the compass updates.
#   cmake -DBUILD_DIR=<auvnav build> -DSOURCE_DIR=<auvnav source> -DWORK_DIR=<scratch>
#         -DLIBDIR=<CMAKE_INSTALL_LIBDIR> -DCXX_COMPILER=<c++> [-DBUILD_TYPE=Release] -P package_test.cmake
cmake_minimum_required(VERSION 3.22)  # policies of this CMake (IN_LIST in if())
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR LIBDIR CXX_COMPILER)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "package_test.cmake: ${var} is not set")
  endif()
endforeach()
if(NOT BUILD_TYPE)
  set(BUILD_TYPE Release)
endif()
set(prefix "${WORK_DIR}/prefix")
unset(ENV{AUVNAV_PLUGIN_PATH})  # the installed programs must find their plugins on their own
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# run(<what> COMMAND ...): runs a command, fails with its output unless it exits 0.
function(run what)
  cmake_parse_arguments(ARG "" "OUTPUT_VARIABLE" "COMMAND" ${ARGN})
  message(STATUS "${what}: ${ARG_COMMAND}")
  execute_process(COMMAND ${ARG_COMMAND} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}")
  endif()
  if(ARG_OUTPUT_VARIABLE)
    set(${ARG_OUTPUT_VARIABLE} "${out}" PARENT_SCOPE)
  endif()
endfunction()

# --- 1. install
run("install" COMMAND ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}" --config ${BUILD_TYPE})
set(plugin_dir "${prefix}/${LIBDIR}/auvnav/plugins")
foreach(f
    bin/auvnav-run bin/auvnav-sim bin/auvnav-info ${LIBDIR}/auvnav/libauvnav_live_view.so
    ${LIBDIR}/libauvnav_nav.so ${LIBDIR}/libauvnav_obs.so
    ${LIBDIR}/auvnav/plugins/libauvnav_plugin_inertial.so ${LIBDIR}/auvnav/plugins/inertial.yaml
    ${LIBDIR}/auvnav/plugins/libauvnav_plugin_dvl.so ${LIBDIR}/auvnav/plugins/dvl.yaml
    ${LIBDIR}/auvnav/plugins/libauvnav_plugin_pressure.so ${LIBDIR}/auvnav/plugins/pressure.yaml
    ${LIBDIR}/auvnav/plugins/libauvnav_plugin_gps.so ${LIBDIR}/auvnav/plugins/gps.yaml
    ${LIBDIR}/auvnav/plugins/libauvnav_plugin_magnetometer.so ${LIBDIR}/auvnav/plugins/magnetometer.yaml
    ${LIBDIR}/auvnav/plugins/libauvnav_plugin_ahrs.so ${LIBDIR}/auvnav/plugins/ahrs.yaml
    bin/auvnav-calibrate-mag bin/auvnav-export bin/auvnav-import bin/auvnav-sonar bin/auvnav-eval
    bin/auvnav-view bin/auvnav-experiment bin/auvnav-heading-plot bin/auvnav-smooth
    share/auvnav/sample/sample.rawlog share/auvnav/sample/ground_truth.csv share/auvnav/sample/ground_truth.tum
    share/auvnav/config/compass_hello.yaml share/auvnav/config/missions/compass_hello.yaml
    share/auvnav/examples/compass_plugin/CObservationCompass.h
    share/auvnav/examples/compass_plugin/make_compass_rawlog.cpp
    include/auvnav/obs_libraries.h
    include/auvnav/navigator.h include/auvnav/plugin_api.h include/auvnav/plugin_host.h
    include/auvnav/measurement_model.h include/auvnav/obs/CObservationDVL.h include/auvnav/obs/register.h
    include/auvnav/io/rawlog.h include/auvnav/testing/model_checks.h
    share/auvnav/config/flatfish.yaml share/auvnav/config/missions/sample.yaml
    share/auvnav/config/vehicles/flatfish.yaml share/auvnav/config/sensors/flatfish_sensors.yaml
    share/auvnav/examples/compass_plugin/CMakeLists.txt share/auvnav/examples/compass_plugin/compass.cpp
    ${LIBDIR}/cmake/auvnav/auvnavConfig.cmake ${LIBDIR}/cmake/auvnav/auvnavConfigVersion.cmake
    ${LIBDIR}/cmake/auvnav/auvnavTargets.cmake ${LIBDIR}/cmake/auvnav/AuvnavPlugin.cmake
    ${LIBDIR}/cmake/auvnav/auvnav_plugin_exports.map)
  if(NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "not installed: ${prefix}/${f}")
  endif()
endforeach()
file(GLOB installed_plugins RELATIVE "${plugin_dir}" "${plugin_dir}/*.so")
list(SORT installed_plugins)
message(STATUS "installed plugins: ${installed_plugins}")
foreach(p ${installed_plugins})
  if(NOT p MATCHES "^libauvnav_plugin_(inertial|dvl|pressure|gps|adcp|model_aiding|sonar_heading|magnetometer|ahrs|usbl)\\.so$")
    message(FATAL_ERROR "unexpected file in the installed plugin directory (test plugin?): ${p}")
  endif()
endforeach()
# The installed program resolves the installed libraries (RPATH $ORIGIN/..), not the build tree's.
find_program(LDD ldd)
if(LDD)
  run("ldd" COMMAND ${LDD} "${prefix}/bin/auvnav-run" OUTPUT_VARIABLE ldd_out)
  foreach(lib nav obs)
    if(NOT ldd_out MATCHES "libauvnav_${lib}\\.so => ${prefix}/[^\n]*libauvnav_${lib}\\.so")
      message(FATAL_ERROR "installed auvnav-run does not load ${prefix}/${LIBDIR}/libauvnav_${lib}.so:\n${ldd_out}")
    endif()
  endforeach()
  # --view's module (loaded at run time) resolves the installed libauvnav_nav.
  run("ldd live view" COMMAND ${LDD} "${prefix}/${LIBDIR}/auvnav/libauvnav_live_view.so" OUTPUT_VARIABLE ldd_view)
  if(ldd_view MATCHES "not found" OR NOT ldd_view MATCHES "libauvnav_nav\\.so => ${prefix}/")
    message(FATAL_ERROR "installed libauvnav_live_view.so does not resolve its libraries from ${prefix}:\n${ldd_view}")
  endif()
endif()
run("installed auvnav-info --help" COMMAND "${prefix}/bin/auvnav-info" --help)
run("installed auvnav-info on the installed sample" COMMAND "${prefix}/bin/auvnav-info"
  "${prefix}/share/auvnav/sample/sample.rawlog")

# --- 2. the out-of-tree example plugin
set(common_args -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=${BUILD_TYPE}
  -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON)
set(compass_build "${WORK_DIR}/compass")
run("configure the compass example"
  COMMAND ${CMAKE_COMMAND} -S "${SOURCE_DIR}/share/examples/compass_plugin" -B "${compass_build}" ${common_args}
  OUTPUT_VARIABLE out)
if(NOT out MATCHES "auvnav 0\\.[0-9.]+: ${prefix}/${LIBDIR}/cmake/auvnav")
  message(FATAL_ERROR "the example did not find the package in ${prefix}:\n${out}")
endif()
run("build the compass example" COMMAND ${CMAKE_COMMAND} --build "${compass_build}")
set(compass_module "${compass_build}/libauvnav_plugin_compass.so")
if(NOT EXISTS "${compass_module}" OR NOT EXISTS "${compass_build}/compass.yaml")
  message(FATAL_ERROR "no ${compass_module} (or compass.yaml next to it)")
endif()
run("compass unit tests" COMMAND ${CMAKE_CTEST_COMMAND} --test-dir "${compass_build}" --output-on-failure
  OUTPUT_VARIABLE out)
message("${out}")
if(NOT out MATCHES "100% tests passed, 0 tests failed out of ([0-9]+)" OR CMAKE_MATCH_1 LESS 15)
  message(FATAL_ERROR "the compass unit tests did not all run")
endif()

# --- 3. a rawlog with IMU, pressure and compass data in the example's own class
set(compass_obs_lib "${compass_build}/libcompass_obs.so")
set(rawlog "${WORK_DIR}/compass.rawlog")
set(true_heading_deg 20)
run("write the rawlog" COMMAND "${compass_build}/make_compass_rawlog" "${rawlog}" 20 ${true_heading_deg} -12.975)
# The installed auvnav-info cannot read the class without its library (exit 2,
# naming the class and --obs-lib), and lists it with --obs-lib.
execute_process(COMMAND "${prefix}/bin/auvnav-info" "${rawlog}" RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 2 OR NOT out MATCHES "CObservationCompass.*--obs-lib")
  message(FATAL_ERROR "auvnav-info without --obs-lib: exit ${rc}, expected 2 naming the class and --obs-lib:\n${out}")
endif()
run("installed auvnav-info --obs-lib" COMMAND "${prefix}/bin/auvnav-info" --obs-lib "${compass_obs_lib}" "${rawlog}"
  OUTPUT_VARIABLE out)
if(NOT out MATCHES "COMPASS +compass_example::CObservationCompass +200 ")
  message(FATAL_ERROR "auvnav-info --obs-lib does not list the 200 compass observations:\n${out}")
endif()

# --- 4. the installed navigator with the installed default config + the compass by path
# The configs are written into a copy of the installed config directory, so that
# the files flatfish.yaml names relative to itself (vehicles/...) come along.
set(config_dir "${WORK_DIR}/config")
file(COPY "${prefix}/share/auvnav/config/" DESTINATION "${config_dir}")
file(READ "${config_dir}/flatfish.yaml" cfg)
string(FIND "${cfg}" "\nsensors:" at)
if(at EQUAL -1)
  message(FATAL_ERROR "the installed flatfish.yaml has no top-level sensors:")
endif()
math(EXPR at "${at} + 1")
string(SUBSTRING "${cfg}" 0 ${at} head)
string(SUBSTRING "${cfg}" ${at} -1 rest)        # "sensors:\n  - label: ..."
string(REGEX MATCH "\n( *)- " item "${rest}")   # indentation of the items
set(indent "${CMAKE_MATCH_1}")
string(REGEX MATCH "\n[^ \t\n-]" block_end "${rest}")  # first line after the block
if(block_end)
  string(FIND "${rest}" "${block_end}" end)
else()
  string(LENGTH "${rest}" end)
endif()
string(SUBSTRING "${rest}" 0 ${end} sensors)
string(SUBSTRING "${rest}" ${end} -1 tail)
foreach(core inertial pressure)
  if(NOT sensors MATCHES "plugin: ${core}")
    message(FATAL_ERROR "the installed flatfish.yaml's sensors do not list the core plugin ${core}:\n${sensors}")
  endif()
endforeach()
# run_navigator(<tag> <plugin spec in the config> <obs_libs> [WITH_STATE]): writes
# WORK_DIR/config/<tag>.yaml (the installed flatfish.yaml plus a COMPASS sensor
# served by <plugin spec>, declaring <obs_libs>, with the heading-bias state if
# WITH_STATE), runs the installed auvnav-run on the rawlog into WORK_DIR/<tag>/
# and checks the outcome.
function(run_navigator tag plugin_spec obs_libs)
  set(states "")
  if("WITH_STATE" IN_LIST ARGN)
    set(states ", states: {heading_bias: {sigma_deg: 3, process: constant}}")
  endif()
  set(compass_item "\n${indent}- label: COMPASS\n${indent}  plugin: ${plugin_spec}\n${indent}  obs_libs: [${obs_libs}]\n${indent}  config: {sigma_deg: 2, declination_deg: 0${states}}")
  set(config "${config_dir}/${tag}.yaml")
  file(WRITE "${config}" "${head}${sensors}${compass_item}${tail}")
  set(out_dir "${WORK_DIR}/${tag}")
  execute_process(
    COMMAND "${prefix}/bin/auvnav-run" --config "${config}" --out "${out_dir}" --quiet
      --set filter.initial.position=config --set filter.initial.heading_deg=30
      --set navigation_frame.origin.latitude_deg=-12.975 "${rawlog}"
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  message("${out}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${tag}: the installed auvnav-run exited with ${rc}")
  endif()
  file(READ "${out_dir}/summary.json" json)
  string(JSON completed GET "${json}" completed)   # a JSON boolean: ON/OFF
  if(NOT completed)
    message(FATAL_ERROR "${tag}: summary.json: completed is ${completed}")
  endif()
  string(JSON n LENGTH "${json}" sensors)
  math(EXPR last "${n} - 1")
  set(found_compass FALSE)
  foreach(i RANGE ${last})
    string(JSON label GET "${json}" sensors ${i} label)
    string(JSON plugin GET "${json}" sensors ${i} plugin)
    string(JSON accepted GET "${json}" sensors ${i} accepted)
    string(JSON invalid GET "${json}" sensors ${i} invalid)
    message(STATUS "${tag}: sensor ${label} (${plugin}): accepted ${accepted}, invalid ${invalid}")
    if(label STREQUAL "COMPASS")
      set(found_compass TRUE)
      if(NOT plugin STREQUAL "${plugin_spec}" OR NOT accepted GREATER 0 OR NOT invalid EQUAL 0)
        message(FATAL_ERROR "${tag}: summary.json: the compass (${plugin}) has ${accepted} accepted, ${invalid} invalid updates")
      endif()
    elseif(label STREQUAL "PRESSURE" AND NOT accepted GREATER 0)
      message(FATAL_ERROR "${tag}: summary.json: the installed pressure plugin accepted nothing")
    endif()
  endforeach()
  if(NOT found_compass)
    message(FATAL_ERROR "${tag}: summary.json lists no COMPASS sensor:\n${json}")
  endif()

  # The compass pulled the heading from the initial guess of 30 deg to the true 20 deg.
  file(STRINGS "${out_dir}/states.csv" rows)
  list(GET rows 0 header)
  list(GET rows -1 final)
  string(REPLACE "," ";" header "${header}")
  string(REPLACE "," ";" final "${final}")
  list(FIND header yaw_deg yaw_col)
  if(yaw_col EQUAL -1)
    message(FATAL_ERROR "${tag}: states.csv has no yaw_deg column")
  endif()
  list(GET final ${yaw_col} yaw)
  message(STATUS "${tag}: final heading ${yaw} deg (true ${true_heading_deg}, initial guess 30)")
  string(REGEX MATCH "^-?[0-9]+" yaw_int "${yaw}")   # CMake has integer arithmetic only
  if(NOT yaw_int MATCHES "^(18|19|20|21)$")
    message(FATAL_ERROR "${tag}: final heading ${yaw} deg is not within 2 deg of the compass's ${true_heading_deg} deg")
  endif()
  # The plugin's own state: in states.csv, its sigma not above the initial 3 deg.
  if("WITH_STATE" IN_LIST ARGN)
    check_state_column("${tag}" "${out_dir}/states.csv" 0.05236)   # 3 deg
  endif()
endfunction()

# check_state_column(<tag> <states.csv> <max sigma rad>): the compass's
# heading_bias and its sigma are columns, with numbers on the last row, the
# sigma at most the given one (its initial sigma: a constant state's sigma
# never grows).
function(check_state_column tag csv max_sigma_rad)
  file(STRINGS "${csv}" rows)
  list(GET rows 0 header)
  list(GET rows -1 final)
  string(REPLACE "," ";" header "${header}")
  string(REPLACE "," ";" final "${final}")
  list(FIND header "COMPASS.heading_bias" bias_col)
  list(FIND header "sigma_COMPASS.heading_bias" sigma_col)
  if(bias_col EQUAL -1 OR sigma_col EQUAL -1)
    message(FATAL_ERROR "${tag}: states.csv has no COMPASS.heading_bias / sigma_COMPASS.heading_bias column:\n${header}")
  endif()
  list(GET final ${bias_col} bias)
  list(GET final ${sigma_col} sigma)
  message(STATUS "${tag}: final COMPASS.heading_bias ${bias} (sigma ${sigma}) [states.csv units]")
  if(NOT bias MATCHES "^-?[0-9]" OR NOT sigma MATCHES "^[0-9]")
    message(FATAL_ERROR "${tag}: COMPASS.heading_bias '${bias}', sigma '${sigma}' are not numbers")
  endif()
  # states.csv gives plugin states in SI (rad); if() compares numbers as doubles.
  if(sigma GREATER max_sigma_rad)
    message(FATAL_ERROR "${tag}: sigma of COMPASS.heading_bias ${sigma} rad is above its initial ${max_sigma_rad} rad")
  endif()
endfunction()

# By path, straight from the example's build tree, with its observation
# library declared by path, and its own state.
run_navigator(run_by_path "${compass_module}" "${compass_obs_lib}" WITH_STATE)

# --- 5. installed next to the core plugins (the example's INSTALL_DESTINATION),
# the compass is found by name like them.
run("install the compass example" COMMAND ${CMAKE_COMMAND} --install "${compass_build}" --prefix "${prefix}")
foreach(f libauvnav_plugin_compass.so compass.yaml libcompass_obs.so)
  if(NOT EXISTS "${plugin_dir}/${f}")
    message(FATAL_ERROR "the example did not install ${plugin_dir}/${f}")
  endif()
endforeach()
# The installed plugin links its own observation library: its RUNPATH must
# find it there ($ORIGIN), not be empty (CMake's default install RPATH).
find_program(READELF readelf)
if(READELF)
  run("readelf" COMMAND ${READELF} -d "${plugin_dir}/libauvnav_plugin_compass.so" OUTPUT_VARIABLE dyn)
  if(NOT dyn MATCHES "\\((RUNPATH|RPATH)\\)[^\n]*\\[\\$ORIGIN[]:]")
    message(FATAL_ERROR "the installed compass plugin has no \$ORIGIN RUNPATH:\n${dyn}")
  endif()
  if(NOT dyn MATCHES "NEEDED[^\n]*libcompass_obs\\.so")
    message(FATAL_ERROR "the installed compass plugin does not link libcompass_obs.so:\n${dyn}")
  endif()
endif()
if(LDD)
  run("ldd installed plugin" COMMAND ${LDD} "${plugin_dir}/libauvnav_plugin_compass.so" OUTPUT_VARIABLE ldd_out)
  if(NOT ldd_out MATCHES "libcompass_obs\\.so => ${plugin_dir}/libcompass_obs\\.so")
    message(FATAL_ERROR "the installed compass plugin does not resolve its installed libcompass_obs.so:\n${ldd_out}")
  endif()
endif()
# Installed next to the plugins, the library is found by its file name.
run("installed auvnav-info --obs-lib by name" COMMAND "${prefix}/bin/auvnav-info" --obs-lib libcompass_obs.so "${rawlog}")
run_navigator(run_by_name compass libcompass_obs.so)

# --- 6. the hello world (share/examples/compass_plugin/README.md): simulate the
# compass_hello mission with the installed simulator (a compass in
# CObservationIMU IMU_YAW) and run the installed navigator with the installed
# compass_hello.yaml, which names the installed plugin and its state.
set(hello "${WORK_DIR}/hello")
run("installed auvnav-sim compass_hello" COMMAND "${prefix}/bin/auvnav-sim"
  "${prefix}/share/auvnav/config/missions/compass_hello.yaml" --seed 1 --out "${hello}" OUTPUT_VARIABLE out)
message("${out}")
if(NOT out MATCHES "COMPASS +[1-9][0-9]+ observations")
  message(FATAL_ERROR "the simulator wrote no compass observations")
endif()
run("installed auvnav-run compass_hello" COMMAND "${prefix}/bin/auvnav-run" --quiet
  --config "${prefix}/share/auvnav/config/compass_hello.yaml" --out "${hello}/run" "${hello}/compass_hello.rawlog"
  OUTPUT_VARIABLE out)
message("${out}")
if(NOT out MATCHES "COMPASS +compass +[1-9][0-9]+ ")
  message(FATAL_ERROR "hello world: the compass accepted no update")
endif()
check_state_column(hello "${hello}/run/states.csv" 0.05236)   # 3 deg
