# ROS 1 and ROS 2 bag readers of the importer. Include from libnav/import/CMakeLists.txt:
#
#   include(src/bags.cmake)
#   add_library(auvnav_import ... ${AUVNAV_BAG_SOURCES})
#   target_link_libraries(auvnav_import PRIVATE ${AUVNAV_BAG_LIBS})
#
# Sets
#   AUVNAV_BAG_SOURCES  the ROS 1 and ROS 2 readers, the message-definition parser
#                       and decoder (absolute paths)
#   AUVNAV_BAG_LIBS     auvnav_rosbag_storage;PkgConfig::AUVNAV_SQLITE3
# and defines those two GLOBAL imported targets, so that tests can link them to
# write bags:
#   auvnav_rosbag_storage    rosbag_storage with the include directories and
#                            libraries its headers need (Debian: librosbag-storage-dev)
#   PkgConfig::AUVNAV_SQLITE3  SQLite 3 (Debian: libsqlite3-dev)
#
# find_package(rosbag_storage) is not used: on Debian 12 its config pulls in
# pluginlib's ament config, which runs a Python script that fails outside a ROS 2
# environment and stops the configure step (no QUIET fallback possible).
include_guard(GLOBAL)

# rosbag/bag.h includes pluginlib's headers, which on Debian 12 (ROS 2 pluginlib)
# live one directory down (/usr/include/pluginlib/pluginlib/...) and include
# class_loader, rcpputils, rcutils and ament_index_cpp the same way.
find_path(AUVNAV_ROSBAG_INCLUDE_DIR rosbag/bag.h)
find_library(AUVNAV_ROSBAG_STORAGE_LIBRARY rosbag_storage)
find_library(AUVNAV_ROSCPP_SERIALIZATION_LIBRARY roscpp_serialization)
find_library(AUVNAV_ROSTIME_LIBRARY rostime)
find_library(AUVNAV_CPP_COMMON_LIBRARY cpp_common)
find_library(AUVNAV_CONSOLE_BRIDGE_LIBRARY console_bridge)
set(_auvnav_rosbag_required AUVNAV_ROSBAG_INCLUDE_DIR AUVNAV_ROSBAG_STORAGE_LIBRARY
    AUVNAV_ROSCPP_SERIALIZATION_LIBRARY AUVNAV_ROSTIME_LIBRARY AUVNAV_CPP_COMMON_LIBRARY
    AUVNAV_CONSOLE_BRIDGE_LIBRARY)
foreach(_var IN LISTS _auvnav_rosbag_required)
  if(NOT ${_var})
    message(FATAL_ERROR "ROS 1 bag support: ${_var} not found "
      "(Debian: apt-get install librosbag-storage-dev)")
  endif()
endforeach()

set(_auvnav_rosbag_includes ${AUVNAV_ROSBAG_INCLUDE_DIR})
foreach(_pair
    "PLUGINLIB;pluginlib/class_loader.hpp;pluginlib"
    "CLASS_LOADER;class_loader/class_loader.hpp;class_loader"
    "RCPPUTILS;rcpputils/shared_library.hpp;rcpputils"
    "RCUTILS;rcutils/shared_library.h;rcutils"
    "AMENT_INDEX_CPP;ament_index_cpp/get_resource.hpp;ament_index_cpp")
  list(GET _pair 0 _name)
  list(GET _pair 1 _header)
  list(GET _pair 2 _suffix)
  find_path(AUVNAV_${_name}_INCLUDE_DIR ${_header} PATH_SUFFIXES ${_suffix})
  if(AUVNAV_${_name}_INCLUDE_DIR)
    list(APPEND _auvnav_rosbag_includes ${AUVNAV_${_name}_INCLUDE_DIR})
  endif()
endforeach()
if(NOT AUVNAV_PLUGINLIB_INCLUDE_DIR)
  message(FATAL_ERROR "ROS 1 bag support: pluginlib/class_loader.hpp (needed by rosbag/bag.h) not found "
    "(Debian: apt-get install librosbag-storage-dev)")
endif()
list(REMOVE_DUPLICATES _auvnav_rosbag_includes)

if(NOT TARGET auvnav_rosbag_storage)
  add_library(auvnav_rosbag_storage INTERFACE IMPORTED GLOBAL)
  # Imported include directories are SYSTEM: ROS headers do not trip our warnings.
  set_target_properties(auvnav_rosbag_storage PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${_auvnav_rosbag_includes}"
    INTERFACE_LINK_LIBRARIES "${AUVNAV_ROSBAG_STORAGE_LIBRARY};${AUVNAV_ROSCPP_SERIALIZATION_LIBRARY};${AUVNAV_ROSTIME_LIBRARY};${AUVNAV_CPP_COMMON_LIBRARY};${AUVNAV_CONSOLE_BRIDGE_LIBRARY}")
endif()

find_package(PkgConfig REQUIRED)
pkg_check_modules(AUVNAV_SQLITE3 REQUIRED IMPORTED_TARGET GLOBAL sqlite3)

set(AUVNAV_BAG_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/msg_definition.cpp
  ${CMAKE_CURRENT_LIST_DIR}/msg_decoder.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ros1_bag.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ros1_bag_check.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ros2_bag.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ros2_bag_db.cpp)
set(AUVNAV_BAG_LIBS auvnav_rosbag_storage PkgConfig::AUVNAV_SQLITE3)
