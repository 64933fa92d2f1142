// ROS 1 bags: rosbag_storage finds the messages of a topic; their bytes are
// decoded with the definition stored in each connection record, so that any
// message type works without its C++ class.
#include <auvnav/import/record.h>

#include "msg_definition.h"

#include <rosbag/bag.h>
#include <rosbag/query.h>
#include <rosbag/view.h>

#include <map>
#include <set>

#include "bag_common.h"
#include "ros1_bag_check.h"

namespace auvnav::import
{
namespace
{
using detail::describeTopics;
using detail::fail;
using detail::requireTopic;
using detail::TopicList;

std::unique_ptr<rosbag::Bag> openBag(const std::string& path, const std::string& topic)
{
	detail::checkRos1BagFile(path, topic);
	auto bag = std::make_unique<rosbag::Bag>();
	try
	{
		bag->open(path, rosbag::bagmode::Read);
	}
	catch (const rosbag::BagUnindexedException&)
	{
		fail(path, "unindexed ROS 1 bag (the recording was not closed); `rosbag reindex` can repair it");
	}
	catch (const std::exception& e)
	{
		fail(path, std::string("cannot read the ROS 1 bag: ") + e.what());
	}
	return bag;
}

TopicList topicsOf(const std::string& path, const rosbag::Bag& bag)
{
	std::set<std::pair<std::string, std::string>> unique;
	try
	{
		rosbag::View all(bag);
		for (const rosbag::ConnectionInfo* c : all.getConnections()) unique.insert({c->topic, c->datatype});
	}
	catch (const std::exception& e)
	{
		fail(path, std::string("cannot read the bag's connections: ") + e.what());
	}
	return TopicList(unique.begin(), unique.end());
}

TimeNs toNs(const ros::Time& t)
{
	return static_cast<TimeNs>(t.sec) * 1000000000 + static_cast<TimeNs>(t.nsec);
}

class Ros1Source final : public RecordSource
{
 public:
	Ros1Source(std::string path, std::string topic, std::unique_ptr<rosbag::Bag> bag)
	    : path_(std::move(path)), topic_(std::move(topic)), bag_(std::move(bag))
	{
		view_ = std::make_unique<rosbag::View>(*bag_, rosbag::TopicQuery(topic_));
		for (const rosbag::ConnectionInfo* c : view_->getConnections())
		{
			if (type_.empty()) type_ = c->datatype;
			by_connection_[&c->md5sum] = &decoderFor(c->datatype, c->md5sum, c->msg_def);
		}
	}

	bool next(Record& out) override
	{
		const rosbag::MessageInstance* m = nullptr;
		try
		{
			if (!started_)
			{
				it_ = view_->begin();
				started_ = true;
			}
			else if (it_ != view_->end())
				++it_;
			if (it_ == view_->end()) return false;
			++index_;
			m = &*it_;
			readBytes(*m);
		}
		catch (const ImportError&)
		{
			throw;
		}
		catch (const std::exception& e)
		{
			throw ImportError(where() + ": cannot read the message from the bag: " + e.what());
		}
		out.where = where();
		out.has_record_time = true;
		out.record_time_ns = toNs(m->getTime());
		try
		{
			decoderOf(*m).decode(buffer_.data(), size_, out);
		}
		catch (const msg::DecodeError& e)
		{
			throw ImportError(out.where + " (" + m->getDataType() + "): " + e.what());
		}
		return true;
	}

	std::string describe() const override { return path_ + " topic " + topic_; }
	std::string messageType() const override { return type_; }

 private:
	std::string where() const { return path_ + ": topic " + topic_ + " message #" + std::to_string(index_); }

	void readBytes(const rosbag::MessageInstance& m)
	{
		size_ = m.size();
		if (buffer_.size() < size_ || buffer_.empty()) buffer_.resize(std::max<std::size_t>(size_, 1));
		ros::serialization::OStream stream(buffer_.data(), static_cast<uint32_t>(size_));
		m.write(stream);
	}

	msg::FlatDecoder& decoderOf(const rosbag::MessageInstance& m)
	{
		// The md5sum string lives in the connection record: its address
		// identifies the connection while the bag is open.
		const auto it = by_connection_.find(&m.getMD5Sum());
		if (it != by_connection_.end()) return *it->second;
		msg::FlatDecoder& d = decoderFor(m.getDataType(), m.getMD5Sum(), m.getMessageDefinition());
		by_connection_[&m.getMD5Sum()] = &d;
		return d;
	}

	/** One decoder per distinct definition (several connections may share one). */
	msg::FlatDecoder& decoderFor(const std::string& type, const std::string& md5,
	                             const std::string& definition)
	{
		const std::string key = type + '\n' + md5 + '\n' + definition;
		auto& slot = decoders_[key];
		if (slot) return *slot;
		if (definition.empty())
			fail(path_, "topic " + topic_ + ": the bag stores no message definition for " + type);
		try
		{
			slot = std::make_unique<msg::FlatDecoder>(
			    msg::Schema::parse(type, definition, msg::Dialect::Ros1), msg::WireFormat::Ros1);
		}
		catch (const msg::DefinitionError& e)
		{
			fail(path_,
			     "topic " + topic_ + ": cannot use the message definition stored in the bag: " + e.what());
		}
		return *slot;
	}

	std::string path_;
	std::string topic_;
	std::string type_;
	std::unique_ptr<rosbag::Bag> bag_;  // before view_: the view refers to it
	std::unique_ptr<rosbag::View> view_;
	rosbag::View::iterator it_;
	bool started_ = false;
	uint64_t index_ = 0;
	std::vector<uint8_t> buffer_;
	std::size_t size_ = 0;
	std::map<std::string, std::unique_ptr<msg::FlatDecoder>> decoders_;
	std::map<const std::string*, msg::FlatDecoder*> by_connection_;
};

}  // namespace

std::unique_ptr<RecordSource> openRos1Bag(const std::string& path, const std::string& topic)
{
	auto bag = openBag(path, topic);
	const TopicList topics = topicsOf(path, *bag);
	requireTopic(path, topic, topics);
	try
	{
		return std::make_unique<Ros1Source>(path, topic, std::move(bag));
	}
	catch (const ImportError&)
	{
		throw;
	}
	catch (const std::exception& e)
	{
		fail(path, "cannot read topic " + topic + ": " + e.what());
	}
}

std::vector<std::pair<std::string, std::string>> listRos1Topics(const std::string& path)
{
	const auto bag = openBag(path, std::string());
	return topicsOf(path, *bag);
}

}  // namespace auvnav::import
