# auvnav-run without --view loads no GUI library (issue 16): the libraries
# the dynamic loader maps at start (ldd: the whole DT_NEEDED closure) include
# none of MRPT's GUI stack; --view's module is loaded by dlopen only.
#   cmake -DRUN=auvnav-run -DMODULE=libauvnav_live_view.so -P check_headless_libraries.cmake
find_program(LDD ldd REQUIRED)
set(gui_regex "libmrpt-gui|libmrpt-nanogui|libwx_|libQt5|libglfw|libglut|libgtk")
execute_process(COMMAND ${LDD} "${RUN}" OUTPUT_VARIABLE run_libs RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ldd ${RUN} failed (${rc})")
endif()
string(REGEX MATCHALL "[^\n]*(${gui_regex})[^\n]*" gui_libs "${run_libs}")
if(gui_libs)
  message(FATAL_ERROR "auvnav-run loads GUI libraries at start:\n${gui_libs}")
endif()
# The check can fail: the module itself does pull them in.
execute_process(COMMAND ${LDD} "${MODULE}" OUTPUT_VARIABLE module_libs)
if(NOT module_libs MATCHES "libmrpt-gui")
  message(FATAL_ERROR "${MODULE} does not link libmrpt-gui: is it the live view module?\n${module_libs}")
endif()
if(module_libs MATCHES "not found")
  message(FATAL_ERROR "${MODULE} has unresolved libraries:\n${module_libs}")
endif()
string(REGEX MATCHALL "\n" lines "${run_libs}")
list(LENGTH lines n)
message(STATUS "auvnav-run maps ${n} libraries at start, none of them GUI")
