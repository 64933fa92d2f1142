# GoogleTest helpers shared by every directory that registers tests (tests/,
# plugins/<name>/). Included from the top-level CMakeLists.txt before any
# add_subdirectory, and only when AUVNAV_BUILD_TESTS is ON, so that plugins can
# register their own tests next to their sources.
include_guard(GLOBAL)

find_package(GTest REQUIRED)
include(GoogleTest)

# Read-only reference data (committed rawlogs). Tests write their scratch files
# elsewhere (see the temporary-directory helpers in each test).
set(AUVNAV_TEST_DATA_DIR "${PROJECT_SOURCE_DIR}/tests/data")

# Helpers only tests use (auvnav/testing/scratch_dir.h): not SDK, not installed.
add_library(auvnav_test_support INTERFACE)
target_include_directories(auvnav_test_support INTERFACE ${PROJECT_SOURCE_DIR}/tests/support/include)

# auvnav_add_gtest(<target> PREFIX <ctest name prefix> SOURCES <src...> LIBS <lib...>)
# One GoogleTest executable; its tests are discovered when CTest runs
# (PRE_TEST), not at build time, so a broken test binary cannot break the build
# and cross-building stays possible.
function(auvnav_add_gtest target)
  cmake_parse_arguments(ARG "" "PREFIX" "SOURCES;LIBS" ${ARGN})
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "auvnav_add_gtest(${target}): no SOURCES")
  endif()
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE GTest::gtest_main auvnav_warnings auvnav_test_support ${ARG_LIBS})
  target_compile_definitions(${target} PRIVATE
    AUVNAV_TEST_DATA_DIR="${AUVNAV_TEST_DATA_DIR}")
  # Test suites named *Slow (e.g. RunLongSlow) carry the ctest label `slow`:
  # left out of the default run (ctest -LE slow), run with ctest -L slow.
  gtest_discover_tests(${target}
    TEST_PREFIX "${ARG_PREFIX}"
    TEST_FILTER "-*Slow.*"
    DISCOVERY_MODE PRE_TEST
    WORKING_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}")
  gtest_discover_tests(${target}
    TEST_PREFIX "${ARG_PREFIX}"
    TEST_FILTER "*Slow.*"
    DISCOVERY_MODE PRE_TEST
    WORKING_DIRECTORY "${CMAKE_CURRENT_BINARY_DIR}"
    PROPERTIES LABELS slow TIMEOUT 5400)
endfunction()
