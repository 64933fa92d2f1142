#pragma once
// Internal to the ROS 1 bag reader: the structural check of a bag file, run
// before rosbag_storage (which parses record headers without bounds checks)
// opens it.
#include <string>

namespace auvnav::import::detail
{
/** Tells "missing", "not a bag", "unindexed", "truncated" and "damaged" apart
 *  before rosbag_storage, whose messages for these are generic ("Error reading
 *  from file: wanted 4 bytes, read 0 bytes") and which would read past its
 *  buffers on a damaged file. `topic` empty: the topic-specific part (its
 *  message records) is skipped. */
void checkRos1BagFile(const std::string& path, const std::string& topic);

}  // namespace auvnav::import::detail
