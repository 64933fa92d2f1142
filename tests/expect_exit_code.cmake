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
if(NOT out MATCHES "${EXPECTED_OUTPUT}")
  message(FATAL_ERROR "output does not match the regular expression '${EXPECTED_OUTPUT}'")
endif()
