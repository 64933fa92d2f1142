# Replays every file under the directories INPUTS (a list) through the
# libFuzzer binary HARNESS, once each, without fuzzing: the regression check
# of tests/fuzz. Fails if the harness reports anything (crash, leak,
# sanitizer error, timeout, out-of-memory).
set(files "")
foreach(dir ${INPUTS})
  file(GLOB_RECURSE found LIST_DIRECTORIES false "${dir}/*")
  list(APPEND files ${found})
endforeach()
list(FILTER files EXCLUDE REGEX "/README[^/]*$")
if(NOT files)
  message(STATUS "no inputs under ${INPUTS}")
  return()
endif()
list(LENGTH files n)
execute_process(COMMAND ${HARNESS} -rss_limit_mb=2048 -timeout=60 ${files}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${HARNESS} failed on its corpus/regressions (exit ${rc}):\n${out}")
endif()
message(STATUS "${n} inputs replayed through ${HARNESS}")
