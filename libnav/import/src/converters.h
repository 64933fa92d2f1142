#pragma once
// Internal to the importer: one converter per observation class, turning a
// record into an observation as the sensor's spec says (units, axes,
// mounting). Keys and formats: docs/import.md.
#include <auvnav/config.h>
#include <auvnav/import/record.h>
#include <mrpt/obs/CObservation.h>

#include <memory>
#include <string>
#include <vector>

namespace auvnav::import::detail
{
class Converter
{
 public:
	virtual ~Converter() = default;
	/** The observation for `r` (timestamp left to the caller), or nullptr and
	 *  `why` (the rejection reason, without the record's place). */
	virtual mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) = 0;
	/** Facts about the mapping worth a line in the report. */
	const std::vector<std::string>& notes() const { return notes_; }

 protected:
	std::vector<std::string> notes_;
};

/** Completes what depends on the time stamp (GPS: GGA UTC time of day),
 *  after the importer has set `obs.timestamp`. */
void finishObservation(mrpt::obs::CObservation& obs);

/** The class names a spec may give (`class:`). */
const std::vector<std::string>& observationClassNames();
/** The MRPT class an observation class name becomes. */
std::string mrptClassOf(const std::string& cls);
/** Keys a sensor of class `cls` may have besides the common ones. */
std::vector<std::string> classKeys(const std::string& cls);

/** Builds the converter for `cls`. `q` holds the quantity keys (the sensor's
 *  own node, or a preset for a standard message type); `s` the sensor node;
 *  `data_dir` resolves relative image paths. Throws ConfigError. */
std::unique_ptr<Converter> makeConverter(const std::string& cls, const config::Node& q, const config::Node& s,
                                         const std::string& label, const std::string& data_dir);

/** A preset quantity mapping (YAML text) for a standard ROS message type
 *  ("sensor_msgs/Imu" or "sensor_msgs/msg/Imu") and class, or empty. */
std::string presetFor(const std::string& message_type, const std::string& cls);

}  // namespace auvnav::import::detail
