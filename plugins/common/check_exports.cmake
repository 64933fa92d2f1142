# cmake -DNM=<nm> -DMODULE=<lib.so> -P check_exports.cmake
# Fails unless the module's dynamic symbol table defines exactly one symbol,
# the plugin entry point auvnav_plugin_entry_v1 (hidden visibility + version script).
execute_process(COMMAND ${NM} -D --defined-only ${MODULE}
  OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${NM} failed on ${MODULE}: ${err}")
endif()
string(REGEX REPLACE "[0-9a-fA-F]+ [A-Za-z] " "" names "${out}")
string(STRIP "${names}" names)
if(NOT names STREQUAL "auvnav_plugin_entry_v1")
  message(FATAL_ERROR "${MODULE} exports more than the entry point:\n${out}")
endif()
message(STATUS "${MODULE}: exports only auvnav_plugin_entry_v1")
