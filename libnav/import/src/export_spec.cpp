// The import spec the exporter writes (export_spec.h, exporter.h): one sensor
// entry per label, in the CSV layout of export_csv.h.
#include "export_spec.h"

#include <auvnav/import/exporter.h>

#include <cctype>
#include <sstream>

#include "export_csv.h"

namespace auvnav::import
{
namespace
{
/** `s` as a YAML scalar, single-quoted unless a plain identifier: a label such as `[P1]`, `*P2` or `P3:x`
 *  unquoted would be a list, an alias or a mapping. */
std::string yamlQuoted(const std::string& s)
{
	// Plain identifiers stay plain (config/import/auvnav_export.yaml is this text).
	bool plain = !s.empty() && (std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_');
	for (char c : s)
		plain = plain &&
		        (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == '/');
	std::string lower;
	for (char c : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
	for (const char* word : {"true", "false", "yes", "no", "on", "off", "y", "n", "null", "nan", "inf"})
		plain = plain && lower != word;
	if (plain) return s;
	std::string q = "'";
	for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
	return q + "'";
}

// ---------------------------------------------------------------- spec text

std::string poseSpec()
{
	return "    mounting: {fields: [pose_x_m, pose_y_m, pose_z_m, pose_qw, pose_qx, pose_qy, pose_qz]}   # "
	       "sensorPose per "
	       "row: lever arm [m], unit quaternion (body FRD)\n";
}

std::string sensorSpec(const std::string& label, const std::string& cls, const std::string& file,
                       const std::string& thruster_unit, bool optional)
{
	std::ostringstream s;
	s << "  - label: " << yamlQuoted(label) << "   # sensorLabel in the rawlog\n    class: " << cls
	  << "   # observation class (docs/import.md)\n";
	if (optional) s << "    optional: true   # skipped when the export has no " << file << "\n";
	s << "    source: {csv: " << file << "}   # looked up in the INPUT folder\n"
	  << "    time: {field: t_s, format: s}   # UNIX seconds, 7 decimals (MRPT's 100 ns)\n";
	if (cls == "imu")
		s << "    angular_velocity: {fields: [gyro_x_radps, gyro_y_radps, gyro_z_radps], unit: rad/s, "
		     "optional: true}   "
		     "# gyro, sensor frame\n"
		     "    linear_acceleration: {fields: [acc_x_mps2, acc_y_mps2, acc_z_mps2], unit: 'm/s^2', "
		     "optional: true}   "
		     "# specific force\n"
		     "    magnetic_field: {fields: [mag_x_G, mag_y_G, mag_z_G], unit: G, optional: true}   # MRPT "
		     "keeps gauss\n"
		     "    orientation: {fields: [quat_w, quat_x, quat_y, quat_z], optional: true}   # the IMU's own "
		     "attitude, "
		     "if it gives one\n"
		     "    temperature: {field: temperature_degC, unit: degC, optional: true}   # [degC]\n"
		  << poseSpec();
	else if (cls == "gps")
		s << "    latitude: {field: latitude_deg, unit: deg}   # WGS-84\n"
		     "    longitude: {field: longitude_deg, unit: deg}   # WGS-84\n"
		     "    altitude: {field: altitude_msl_m, unit: m}   # antenna height\n"
		     "    altitude_reference: msl   # GGA: above mean sea level\n"
		     "    geoid_separation: {field: geoid_separation_m, unit: m}   # ellipsoid height = altitude + "
		     "this\n"
		     "    fix_quality: {field: fix_quality}   # GGA fix quality, 0 = no fix\n"
		     "    satellites: {field: satellites}   # satellites used\n"
		     "    hdop: {field: hdop}   # horizontal dilution of precision (empty: none)\n"
		  << poseSpec();
	else if (cls == "pressure")
		s << "    pressure: {field: pressure_Pa, unit: Pa}   # at the sensor\n"
		     "    pressure_reference: absolute   # atmosphere included\n"
		     "    temperature: {field: temperature_degC, unit: degC}   # sensor temperature\n"
		  << poseSpec();
	else if (cls == "dvl")
		s << "    frame: {field: frame}   # instrument | vehicle | earth_ned | earth_enu | beam, per row\n"
		     "    sign: {field: sign}     # vehicle_over_bottom | bottom_over_instrument, per row\n"
		     "    bottom_lock: {field: bottom_lock}   # 1: the velocity is valid\n"
		     "    velocity: {fields: [vel_x_mps, vel_y_mps, vel_z_mps], unit: m/s}   # in `frame`\n"
		     "    velocity_covariance: {fields: [cov_00, cov_01, cov_02, cov_10, cov_11, cov_12, cov_20, "
		     "cov_21, cov_22], "
		     "unit: 'm^2/s^2'}   # row-major\n"
		     "    altitude: {field: altitude_m, unit: m}   # vertical distance to the seabed (nan: unknown)\n"
		     "    beam_inclination: {field: beam_inclination_rad, unit: rad}   # Janus angle from the sensor "
		     "z axis\n"
		     "    beam_velocity_sigma: {field: beam_velocity_sigma_mps, unit: m/s}   # 1-sigma of one beam "
		     "(0: unknown)\n"
		     "    beams:                  # per beam, {i} = 0, 1, ...\n"
		     "      count: {field: beam_count}\n"
		     "      range: {field: 'beam_{i}_range_m', unit: m}   # along the beam\n"
		     "      range_is: slant       # not vertical\n"
		     "      valid: {field: 'beam_{i}_valid'}   # 1: bottom return\n"
		     "      velocity: {field: 'beam_{i}_velocity_mps', unit: m/s}   # radial velocity (beam frame)\n"
		     "      azimuth: {field: 'beam_{i}_azimuth_rad', unit: rad}   # about the sensor z axis, from x\n"
		  << poseSpec();
	else if (cls == "adcp")
		s << "    blank_distance: {field: blank_distance_m, unit: m}   # transducer to the first cell\n"
		     "    cell_size: {field: cell_size_m, unit: m}   # along the profiling axis\n"
		     "    velocity_sigma: {field: velocity_sigma_mps, unit: m/s}   # 1-sigma of one cell\n"
		     "    cells:                  # per cell, {i} = 0, 1, ...\n"
		     "      count: {field: cell_count}\n"
		     "      velocity: {fields: ['cell_{i}_vx_mps', 'cell_{i}_vy_mps', 'cell_{i}_vz_mps'], unit: m/s} "
		     "  # water "
		     "rel. to the sensor\n"
		     "      correlation: {field: 'cell_{i}_correlation'}   # 0..1\n"
		     "      valid: {field: 'cell_{i}_valid'}   # 1: usable\n"
		  << poseSpec();
	else if (cls == "thrusters")
		s << "    effort: {count: {field: thruster_count}, field: 'effort_{i}', unit: " << thruster_unit
		  << "}   # per thruster: N (force) or rpm\n";
	else if (cls == "usbl")
		s << "    measurement_time: {field: measurement_time_s, unit: s, optional: true}   # when the fix "
		     "was taken "
		     "(UNIX; empty: use latency_s)\n"
		     "    latitude: {field: latitude_deg, unit: deg, optional: true}   # geodetic fix, or ...\n"
		     "    longitude: {field: longitude_deg, unit: deg, optional: true}\n"
		     "    depth: {field: depth_m, unit: m, optional: true}\n"
		     "    north: {field: north_m, unit: m, optional: true}   # ... north/east/down from the "
		     "navigation origin\n"
		     "    east: {field: east_m, unit: m, optional: true}\n"
		     "    down: {field: down_m, unit: m, optional: true}\n"
		     "    position_covariance: {fields: [cov_nn, cov_ne, cov_nd, cov_en, cov_ee, cov_ed, cov_dn, "
		     "cov_de, cov_dd], "
		     "unit: 'm^2', optional: true}   # NED, row-major (empty: none)\n"
		     "    slant_range: {field: slant_range_m, unit: m, optional: true}\n"
		     "    transponder_id: {field: transponder_id}\n"
		  << poseSpec();
	else if (cls == "image")
		s << "    file: {field: file}   # PNG, relative to the CSV's folder\n"
		     "    camera: {ncols: {field: ncols}, nrows: {field: nrows}, fx: {field: fx}, fy: {field: fy}, "
		     "cx: {field: cx}, "
		     "cy: {field: cy}, name: {field: camera_name}}   # cameraParams (sonar: polar geometry)\n"
		  << poseSpec();
	return s.str();
}
}  // namespace

std::vector<std::pair<std::string, std::string>> simulatorLabels()
{
	// The simulator's write order at equal stamps (apps/sim/mission.cpp), which
	// the importer keeps for equal stamps.
	return {{"THRUSTERS", "thrusters"}, {"IMU", "imu"},           {"DVL", "dvl"}, {"ADCP", "adcp"},
	        {"SONAR", "image"},         {"PRESSURE", "pressure"}, {"GPS", "gps"}, {"USBL", "usbl"}};
}

namespace detail
{
std::string specText(const std::vector<std::pair<std::string, std::string>>& labels_and_classes,
                     const std::map<std::string, std::string>& files,
                     const std::map<std::string, std::string>& thruster_units, bool optional_sensors)
{
	std::ostringstream s;
	s << "# auvnav-import spec for the CSV layout auvnav-export writes (docs/import.md).\n"
	     "# Every quantity is in the unit its column name says; times are UNIX seconds.\n"
	     "# Rerun: auvnav-import --spec THIS_FILE --out OUT.rawlog THIS_FOLDER\n"
	     "format_version: 1\n"
	     "reorder_window_s: 1.0   # rows are already in time order per file\n"
	     "sensors:\n";
	for (const auto& [label, cls] : labels_and_classes)
	{
		const auto u = thruster_units.find(label);
		const auto f = files.find(label);
		s << sensorSpec(label, cls, f == files.end() ? fileSafe(label) + ".csv" : f->second,
		                u == thruster_units.end() ? "N" : u->second, optional_sensors);
	}
	return s.str();
}
}  // namespace detail

std::string exportSpecText(const std::vector<std::pair<std::string, std::string>>& labels_and_classes,
                           const std::map<std::string, std::string>& thruster_units, bool optional_sensors)
{
	return detail::specText(labels_and_classes, {}, thruster_units, optional_sensors);
}

}  // namespace auvnav::import
