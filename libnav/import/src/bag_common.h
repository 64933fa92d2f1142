#pragma once
// Internal to the bag readers (ros1_bag*.cpp, ros2_bag*.cpp): what both say
// the same way, their errors ("PATH: why") and their topic lists.
#include <auvnav/import/record.h>

#include <string>
#include <utility>
#include <vector>

namespace auvnav::import::detail
{
[[noreturn]] inline void fail(const std::string& path, const std::string& why)
{
	throw ImportError(path + ": " + why);
}

/** (topic, message type) pairs. */
using TopicList = std::vector<std::pair<std::string, std::string>>;

/** "its topics: /a (pkg/A), ..." for an error message. */
inline std::string describeTopics(const TopicList& topics)
{
	if (topics.empty()) return "the bag has no topics";
	std::string s = "its topics: ";
	for (std::size_t i = 0; i < topics.size(); ++i)
		s += (i ? ", " : "") + topics[i].first + " (" + topics[i].second + ")";
	return s;
}

/** Throws MissingTopicError naming the bag's topics unless `topic` is one. */
inline void requireTopic(const std::string& path, const std::string& topic, const TopicList& topics)
{
	for (const auto& t : topics)
		if (t.first == topic) return;
	throw MissingTopicError(path + ": no topic '" + topic + "' in the bag; " + describeTopics(topics));
}

}  // namespace auvnav::import::detail
