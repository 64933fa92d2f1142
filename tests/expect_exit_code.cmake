# Runs COMMAND with ARGS (a ;-list) and fails unless its exit code is
# EXPECTED_EXIT_CODE and its combined stdout+stderr matches EXPECTED_OUTPUT.
#   cmake -DCOMMAND=... -DARGS=... -DEXPECTED_EXIT_CODE=2 -DEXPECTED_OUTPUT=regex -P expect_exit_code.cmake
foreach(var COMMAND EXPECTED_EXIT_CODE EXPECTED_OUTPUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "expect_exit_code.cmake: ${var} is not set")
  endif()
endforeach()

execute_process(
  COMMAND ${COMMAND} ${ARGS}
  RESULT_VARIABLE exit_code
  OUTPUT_VARIABLE out
  ERROR_VARIABLE out)

message("${out}")
if(NOT "${exit_code}" STREQUAL "${EXPECTED_EXIT_CODE}")
  message(FATAL_ERROR "exit code was '${exit_code}', expected ${EXPECTED_EXIT_CODE}")
endif()
# TCLAP wraps usage text at 80 columns, and where it breaks depends on the
# length of the program's path (build/ vs build-san/, the checkout's folder),
# so the pattern may also match the output with every run of whitespace
# collapsed to one space.
string(REGEX REPLACE "[ \t\r\n]+" " " out_one_line "${out}")
if(NOT out MATCHES "${EXPECTED_OUTPUT}" AND NOT out_one_line MATCHES "${EXPECTED_OUTPUT}")
  message(FATAL_ERROR "output does not match the regular expression '${EXPECTED_OUTPUT}'")
endif()
