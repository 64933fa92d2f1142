# GoogleTest of the ROS 1 / ROS 2 bag readers (ctest -R '^import\.'). Include
# from tests/import/CMakeLists.txt (or any directory) after auvnav_import exists:
#
#   include(${CMAKE_CURRENT_SOURCE_DIR}/bags_tests.cmake)
#
# The tests write their own bags: ROS 1 through rosbag_storage with the Debian
# message headers (libsensor-msgs-dev, libgeometry-msgs-dev, libnav-msgs-dev),
# ROS 2 through SQLite. They also test the private definition parser and
# decoder, through auvnav_import_internal (libnav/import/CMakeLists.txt).
# auvnav_rosbag_storage and PkgConfig::AUVNAV_SQLITE3 come from
# libnav/import/src/bags.cmake.
auvnav_add_gtest(test_import_bags
  PREFIX "import."
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_bags.cpp ${CMAKE_CURRENT_LIST_DIR}/bag_writers.cpp
  LIBS auvnav_import auvnav_import_internal auvnav_rosbag_storage PkgConfig::AUVNAV_SQLITE3)
