// The importer's converter registry: the observation class names, their keys
// and MRPT classes, the factory over the per-sensor converters (convert_*.cpp),
// ROS message presets, and what is completed once the stamp is known.
#include "converters.h"

#include <mrpt/obs/CObservationGPS.h>

#include <cmath>

#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
const std::vector<std::string> kCommonKeys = {"label", "class",    "source",  "time",
                                              "axes",  "mounting", "optional"};
}  // namespace

void finishObservation(mrpt::obs::CObservation& obs)
{
	// GGA carries the UTC time of day: set once the stamp is known.
	auto* gps = dynamic_cast<mrpt::obs::CObservationGPS*>(&obs);
	if (!gps || !gps->has_GGA_datum()) return;
	auto& f = gps->getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>().fields;
	const double unix_s = mrpt::Clock::toDouble(gps->timestamp);
	const double day_s = std::fmod(unix_s, 86400.0);
	f.UTCTime.hour = static_cast<uint8_t>(day_s / 3600);
	f.UTCTime.minute = static_cast<uint8_t>(std::fmod(day_s, 3600.0) / 60);
	f.UTCTime.sec = std::fmod(day_s, 60.0);
	gps->originalReceivedTimestamp = gps->timestamp;
}

const std::vector<std::string>& observationClassNames()
{
	static const std::vector<std::string> names = {"imu",  "dvl",       "pressure", "gps",
	                                               "adcp", "thrusters", "image",    "usbl"};
	return names;
}

std::string mrptClassOf(const std::string& cls)
{
	if (cls == "imu") return "mrpt::obs::CObservationIMU";
	if (cls == "dvl") return "auvnav::obs::CObservationDVL";
	if (cls == "pressure") return "auvnav::obs::CObservationPressure";
	if (cls == "gps") return "mrpt::obs::CObservationGPS";
	if (cls == "adcp") return "auvnav::obs::CObservationADCP";
	if (cls == "thrusters") return "auvnav::obs::CObservationThrusters";
	if (cls == "image") return "mrpt::obs::CObservationImage";
	if (cls == "usbl") return "auvnav::obs::CObservationUSBL";
	return "?";
}

std::vector<std::string> classKeys(const std::string& cls)
{
	std::vector<std::string> k = kCommonKeys;
	auto add = [&](std::initializer_list<const char*> more)
	{
		for (const char* m : more) k.emplace_back(m);
	};
	if (cls == "imu")
		add({"angular_velocity", "linear_acceleration", "magnetic_field", "orientation", "temperature"});
	if (cls == "dvl")
		add({"frame", "sign", "velocity", "velocity_covariance", "velocity_sigma", "bottom_lock", "altitude",
		     "beam_inclination", "beam_velocity_sigma", "beams"});
	if (cls == "pressure")
		add({"pressure", "depth", "temperature", "pressure_reference", "atmospheric_pressure_pa",
		     "density_kg_m3", "gravity_mps2"});
	if (cls == "gps")
		add({"latitude", "longitude", "altitude", "altitude_reference", "geoid_separation", "fix_quality",
		     "navsat_status", "satellites", "hdop"});
	if (cls == "adcp") add({"blank_distance", "cell_size", "velocity_sigma", "cells"});
	if (cls == "thrusters") add({"effort"});
	if (cls == "image") add({"file", "camera"});
	if (cls == "usbl")
		add({"latitude", "longitude", "depth", "north", "east", "down", "position_covariance",
		     "position_sigma", "slant_range", "transponder_id", "measurement_time"});
	return k;
}

std::unique_ptr<Converter> makeConverter(const std::string& cls, const config::Node& q, const config::Node& s,
                                         const std::string& label, const std::string& data_dir)
{
	if (cls == "imu") return makeImuConverter(q, s, label);
	if (cls == "dvl") return makeDvlConverter(q, s, label);
	if (cls == "pressure") return makePressureConverter(q, s, label);
	if (cls == "gps") return makeGpsConverter(q, s, label);
	if (cls == "adcp") return makeAdcpConverter(q, s, label);
	if (cls == "thrusters") return makeThrustersConverter(q, s, label);
	if (cls == "image") return makeImageConverter(q, s, label, data_dir);
	if (cls == "usbl") return makeUsblConverter(q, s, label);
	std::string list;
	for (const auto& n : observationClassNames()) list += (list.empty() ? "" : ", ") + n;
	s.fail("class", "unknown observation class '" + cls + "' (" + list + ")");
}

std::string presetFor(const std::string& message_type, const std::string& cls)
{
	// "pkg/msg/Type" (ROS 2) → "pkg/Type".
	std::string t = message_type;
	const auto p = t.find("/msg/");
	if (p != std::string::npos) t.erase(p, 4);
	const std::string twist_cov =
	    "velocity_covariance: {fields: ['twist.covariance[0]', 'twist.covariance[1]', 'twist.covariance[2]', "
	    "'twist.covariance[6]', 'twist.covariance[7]', 'twist.covariance[8]', 'twist.covariance[12]', "
	    "'twist.covariance[13]', 'twist.covariance[14]'], unit: 'm^2/s^2'}\n";
	if (cls == "imu" && t == "sensor_msgs/Imu")
		return "angular_velocity: {fields: [angular_velocity.x, angular_velocity.y, angular_velocity.z], "
		       "unit: rad/s}\n"
		       "linear_acceleration: {fields: [linear_acceleration.x, linear_acceleration.y, "
		       "linear_acceleration.z], "
		       "unit: 'm/s^2'}\n";
	if (cls == "imu" && t == "sensor_msgs/MagneticField")
		return "magnetic_field: {fields: [magnetic_field.x, magnetic_field.y, magnetic_field.z], unit: T}\n";
	if (cls == "pressure" && t == "sensor_msgs/FluidPressure")
		return "pressure: {field: fluid_pressure, unit: Pa}\n";
	if (cls == "gps" && t == "sensor_msgs/NavSatFix")
		return "latitude: {field: latitude, unit: deg}\nlongitude: {field: longitude, unit: deg}\n"
		       "altitude: {field: altitude, unit: m}\nnavsat_status: {field: status.status}\n";
	if (cls == "dvl" && t == "geometry_msgs/TwistWithCovarianceStamped")
		return "velocity: {fields: [twist.twist.linear.x, twist.twist.linear.y, twist.twist.linear.z], unit: "
		       "m/s}\n" +
		       twist_cov;
	if (cls == "dvl" && t == "nav_msgs/Odometry")
		return "velocity: {fields: [twist.twist.linear.x, twist.twist.linear.y, twist.twist.linear.z], unit: "
		       "m/s}\n" +
		       twist_cov;
	return {};
}

}  // namespace auvnav::import::detail
