#include <auvnav/import/exporter.h>
#include <auvnav/import/record.h>
#include <auvnav/import/time_format.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/obs/CObservationUSBL.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/system/filesystem.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>

namespace auvnav::import
{
namespace
{
/** Shortest text that reads back as the same double ("nan" for NaN). */
std::string exact(double v)
{
	if (std::isnan(v)) return "nan";
	if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
	char buf[32];
	std::snprintf(buf, sizeof buf, "%.17g", v);
	return buf;
}

std::string fileSafe(const std::string& label)
{
	std::string s = label;
	for (char& c : s)
		if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) c = '_';
	return s.empty() ? "unnamed" : s;
}

std::string classOf(const mrpt::obs::CObservation& o)
{
	if (dynamic_cast<const mrpt::obs::CObservationIMU*>(&o)) return "imu";
	if (const auto* g = dynamic_cast<const mrpt::obs::CObservationGPS*>(&o))
		return g->has_GGA_datum() ? "gps" : "";
	if (dynamic_cast<const auvnav::obs::CObservationDVL*>(&o)) return "dvl";
	if (dynamic_cast<const auvnav::obs::CObservationADCP*>(&o)) return "adcp";
	if (dynamic_cast<const auvnav::obs::CObservationPressure*>(&o)) return "pressure";
	if (dynamic_cast<const auvnav::obs::CObservationThrusters*>(&o)) return "thrusters";
	if (dynamic_cast<const mrpt::obs::CObservationImage*>(&o)) return "image";
	if (dynamic_cast<const auvnav::obs::CObservationUSBL*>(&o)) return "usbl";
	return "";
}

std::string thrusterUnit(const auvnav::obs::CObservationThrusters& t)
{
	return t.unit == auvnav::obs::EffortUnit::Speed_rpm ? "rpm" : "N";
}

const char* kPoseColumns = "pose_x_m,pose_y_m,pose_z_m,pose_qw,pose_qx,pose_qy,pose_qz";

std::string poseCells(const mrpt::poses::CPose3D& p)
{
	mrpt::math::CQuaternionDouble q;
	p.getAsQuaternion(q);
	return exact(p.x()) + "," + exact(p.y()) + "," + exact(p.z()) + "," + exact(q.r()) + "," + exact(q.x()) +
	       "," + exact(q.y()) + "," + exact(q.z());
}

/** One label's CSV file and what its layout needs to know from pass 1. */
struct LabelOut
{
	std::string cls, file_name, stem;  // stem: file name without .csv (unique per label)
	std::size_t max_array = 0;         // beams, cells or thrusters
	std::string thruster_unit;         // of the label's first row: the spec has one unit per label
	std::unique_ptr<std::ofstream> out;
	std::size_t rows = 0;
};

std::string header(const std::string& cls, std::size_t n)
{
	std::ostringstream h;
	h << "t_s,";
	auto indexed = [&](std::initializer_list<const char*> pattern)
	{
		for (std::size_t i = 0; i < n; ++i)
			for (const char* p : pattern)
			{
				std::string c = p;
				c.replace(c.find('#'), 1, std::to_string(i));
				h << c << ",";
			}
	};
	if (cls == "imu")
		h << "gyro_x_radps,gyro_y_radps,gyro_z_radps,acc_x_mps2,acc_y_mps2,acc_z_mps2,mag_x_G,mag_y_G,mag_z_"
		     "G,"
		     "quat_w,quat_x,quat_y,quat_z,temperature_degC,";
	else if (cls == "gps")
		h << "latitude_deg,longitude_deg,altitude_msl_m,geoid_separation_m,fix_quality,satellites,hdop,";
	else if (cls == "pressure")
		h << "pressure_Pa,temperature_degC,";
	else if (cls == "dvl")
	{
		h << "frame,sign,bottom_lock,vel_x_mps,vel_y_mps,vel_z_mps,cov_00,cov_01,cov_02,cov_10,cov_11,cov_12,"
		     "cov_20,"
		     "cov_21,cov_22,altitude_m,beam_inclination_rad,beam_velocity_sigma_mps,beam_count,";
		indexed({"beam_#_range_m", "beam_#_valid", "beam_#_velocity_mps", "beam_#_azimuth_rad"});
	}
	else if (cls == "adcp")
	{
		h << "blank_distance_m,cell_size_m,velocity_sigma_mps,cell_count,";
		indexed({"cell_#_vx_mps", "cell_#_vy_mps", "cell_#_vz_mps", "cell_#_correlation", "cell_#_valid"});
	}
	else if (cls == "thrusters")
	{
		h << "thruster_count,";
		indexed({"effort_#"});
		std::string s = h.str();
		s.pop_back();  // thrusters have no pose
		return s;
	}
	else if (cls == "image")
		h << "file,ncols,nrows,fx,fy,cx,cy,camera_name,";
	else if (cls == "usbl")
		h << "measurement_time_s,latitude_deg,longitude_deg,depth_m,north_m,east_m,down_m,cov_nn,cov_ne,cov_"
		     "nd,cov_en,"
		     "cov_ee,cov_ed,cov_dn,cov_de,cov_dd,slant_range_m,transponder_id,";
	h << kPoseColumns;
	return h.str();
}

std::string imuRow(const mrpt::obs::CObservationIMU& o)
{
	using namespace mrpt::obs;
	const TIMUDataIndex idx[] = {IMU_WX,         IMU_WY,         IMU_WZ,         IMU_X_ACC,
	                             IMU_Y_ACC,      IMU_Z_ACC,      IMU_MAG_X,      IMU_MAG_Y,
	                             IMU_MAG_Z,      IMU_ORI_QUAT_W, IMU_ORI_QUAT_X, IMU_ORI_QUAT_Y,
	                             IMU_ORI_QUAT_Z, IMU_TEMPERATURE};
	std::string row;
	for (auto i : idx) row += (o.has(i) ? exact(o.get(i)) : std::string()) + ",";
	return row + poseCells(o.sensorPose);
}

/** Geodetic fixes fill latitude/longitude/depth, local ones north/east/down;
 *  the other three cells stay empty (the importer picks the filled set). */
std::string usblRow(const auvnav::obs::CObservationUSBL& o)
{
	const bool geo = o.frame == auvnav::obs::UsblFrame::Geodetic;
	auto cell = [](double v) { return std::isnan(v) ? std::string() : exact(v); };
	std::string row =
	    (o.measurement_time == INVALID_TIMESTAMP ? std::string()
	                                             : formatSeconds7(*fromMrptTimeChecked(o.measurement_time))) +
	    ",";
	for (int i = 0; i < 3; ++i) row += (geo ? cell(o.position[i]) : std::string()) + ",";
	for (int i = 0; i < 3; ++i) row += (geo ? std::string() : cell(o.position[i])) + ",";
	for (double c : o.covariance_ned_m2) row += cell(c) + ",";
	return row + cell(o.slant_range_m) + "," + std::to_string(o.transponder_id) + "," +
	       poseCells(o.sensorPose);
}

std::string gpsRow(const mrpt::obs::CObservationGPS& o)
{
	const auto& f = o.getMsgByClass<mrpt::obs::gnss::Message_NMEA_GGA>().fields;
	return exact(f.latitude_degrees) + "," + exact(f.longitude_degrees) + "," + exact(f.altitude_meters) +
	       "," + exact(f.geoidal_distance) + "," + std::to_string(f.fix_quality) + "," +
	       std::to_string(f.satellitesUsed) + "," + (f.thereis_HDOP ? exact(f.HDOP) : std::string()) + "," +
	       poseCells(o.sensorPose);
}

std::string dvlRow(const auvnav::obs::CObservationDVL& o, std::size_t n)
{
	std::string row = std::string(auvnav::obs::dvlFrameName(o.frame)) + "," +
	                  auvnav::obs::dvlSignName(o.sign) + "," + (o.bottom_lock ? "1" : "0");
	for (double v : o.velocity_s_mps) row += "," + exact(v);
	for (double c : o.velocity_cov) row += "," + exact(c);
	row += "," + exact(o.altitude_m) + "," + exact(o.beam_inclination_rad) + "," +
	       exact(o.beam_velocity_sigma_mps) + "," + std::to_string(o.beams.size());
	for (std::size_t i = 0; i < n; ++i)
	{
		if (i < o.beams.size())
		{
			const auto& b = o.beams[i];
			row += "," + exact(b.range_m) + "," + (b.valid ? "1" : "0") + "," + exact(b.velocity_mps) + "," +
			       exact(b.azimuth_rad);
		}
		else
			row += ",,,,";
	}
	return row + "," + poseCells(o.sensorPose);
}

std::string adcpRow(const auvnav::obs::CObservationADCP& o, std::size_t n)
{
	std::string row = exact(o.blank_distance_m) + "," + exact(o.cell_size_m) + "," +
	                  exact(o.velocity_sigma_mps) + "," + std::to_string(o.cells.size());
	for (std::size_t i = 0; i < n; ++i)
	{
		if (i < o.cells.size())
		{
			const auto& c = o.cells[i];
			row += "," + exact(c.velocity_s_mps[0]) + "," + exact(c.velocity_s_mps[1]) + "," +
			       exact(c.velocity_s_mps[2]) + "," + exact(c.correlation) + "," + (c.valid ? "1" : "0");
		}
		else
			row += ",,,,,";
	}
	return row + "," + poseCells(o.sensorPose);
}

std::string thrusterRow(const auvnav::obs::CObservationThrusters& o, std::size_t n)
{
	std::string row = std::to_string(o.effort.size());
	for (std::size_t i = 0; i < n; ++i)
		row += "," + (i < o.effort.size() ? exact(o.effort[i]) : std::string());
	return row;
}

std::string csvQuoted(const std::string& s)
{
	if (s.find_first_of(",\"\n") == std::string::npos) return s;
	std::string q = "\"";
	for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
	return q + "\"";
}

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

/** The IMU data MRPT can hold that the CSV layout has no column for. */
std::vector<std::string> imuFieldsWithoutColumn(const mrpt::obs::CObservationIMU& o)
{
	using namespace mrpt::obs;
	static const std::pair<TIMUDataIndex, const char*> extra[] = {
	    {IMU_X_VEL, "IMU_X_VEL"},
	    {IMU_Y_VEL, "IMU_Y_VEL"},
	    {IMU_Z_VEL, "IMU_Z_VEL"},
	    {IMU_YAW, "IMU_YAW"},
	    {IMU_PITCH, "IMU_PITCH"},
	    {IMU_ROLL, "IMU_ROLL"},
	    {IMU_X, "IMU_X"},
	    {IMU_Y, "IMU_Y"},
	    {IMU_Z, "IMU_Z"},
	    {IMU_PRESSURE, "IMU_PRESSURE"},
	    {IMU_ALTITUDE, "IMU_ALTITUDE"},
	    {IMU_YAW_VEL_GLOBAL, "IMU_YAW_VEL_GLOBAL"},
	    {IMU_PITCH_VEL_GLOBAL, "IMU_PITCH_VEL_GLOBAL"},
	    {IMU_ROLL_VEL_GLOBAL, "IMU_ROLL_VEL_GLOBAL"},
	    {IMU_X_ACC_GLOBAL, "IMU_X_ACC_GLOBAL"},
	    {IMU_Y_ACC_GLOBAL, "IMU_Y_ACC_GLOBAL"},
	    {IMU_Z_ACC_GLOBAL, "IMU_Z_ACC_GLOBAL"}};
	std::vector<std::string> out;
	for (const auto& [i, name] : extra)
		if (o.has(i)) out.emplace_back(name);
	return out;
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

namespace
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
}  // namespace

std::string exportSpecText(const std::vector<std::pair<std::string, std::string>>& labels_and_classes,
                           const std::map<std::string, std::string>& thruster_units, bool optional_sensors)
{
	return specText(labels_and_classes, {}, thruster_units, optional_sensors);
}

void exportRawlog(const std::string& rawlog, const std::string& out_dir, ExportReport& report)
{
	report = ExportReport{};
	std::map<std::string, LabelOut> labels;
	std::vector<std::string> order;
	// Pass 1: classes and array sizes per label.
	{
		io::RawlogReader in(rawlog);
		while (auto o = in.next())
		{
			const std::string cls = classOf(*o);
			if (!fromMrptTimeChecked(o->timestamp))
			{
				report.skipped_by_reason
				    ["observation without a valid timestamp (invalid, or outside 1678..2262) (" +
				     o->sensorLabel + ")"]++;
				continue;
			}
			if (cls.empty())
			{
				report.skipped_by_reason[std::string("class ") + o->GetRuntimeClass()->className +
				                         " not exported"]++;
				continue;
			}
			auto it = labels.find(o->sensorLabel);
			if (it == labels.end())
			{
				it = labels.emplace(o->sensorLabel, LabelOut{}).first;
				it->second.cls = cls;
				order.push_back(o->sensorLabel);
			}
			LabelOut& l = it->second;
			if (l.cls != cls)
			{
				report.skipped_by_reason["label " + o->sensorLabel + " also used by class " + cls +
				                         ": not exported"]++;
				continue;
			}
			if (const auto* d = dynamic_cast<const auvnav::obs::CObservationDVL*>(o.get()))
				l.max_array = std::max(l.max_array, d->beams.size());
			if (const auto* a = dynamic_cast<const auvnav::obs::CObservationADCP*>(o.get()))
				l.max_array = std::max(l.max_array, a->cells.size());
			if (const auto* t = dynamic_cast<const auvnav::obs::CObservationThrusters*>(o.get()))
			{
				l.max_array = std::max(l.max_array, t->effort.size());
				if (l.thruster_unit.empty()) l.thruster_unit = thrusterUnit(*t);
			}
		}
	}
	// With its parents, as every other program's --out.
	std::error_code ec;
	std::filesystem::create_directories(out_dir, ec);
	if (ec || !std::filesystem::is_directory(out_dir))
		throw ImportError(out_dir + ": cannot create the output folder" +
		                  (ec ? ": " + ec.message() : std::string()));
	std::map<std::string, std::string> units, files;
	std::vector<std::pair<std::string, std::string>> spec_labels;
	std::set<std::string>
	    stems_used;  // lower case: "A B" and "A_B" (or "a_b" on a case-blind disk) share no file
	for (const auto& label : order)
	{
		LabelOut& l = labels[label];
		std::string stem = fileSafe(label);
		auto lower = [](std::string x)
		{
			for (char& c : x) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
			return x;
		};
		for (int k = 2; stems_used.count(lower(stem)); ++k) stem = fileSafe(label) + "_" + std::to_string(k);
		stems_used.insert(lower(stem));
		l.stem = stem;
		l.file_name = stem + ".csv";
		const std::string path = out_dir + "/" + l.file_name;
		l.out = std::make_unique<std::ofstream>(path);
		if (!*l.out) throw ImportError(path + ": cannot write");
		*l.out << header(l.cls, l.max_array) << "\n";
		if (l.cls == "image" && !mrpt::system::directoryExists(out_dir + "/" + stem))
			mrpt::system::createDirectory(out_dir + "/" + stem);
		spec_labels.emplace_back(label, l.cls);
		files[label] = l.file_name;
		if (l.cls == "thrusters") units[label] = l.thruster_unit.empty() ? "N" : l.thruster_unit;
	}
	// Pass 2: the rows.
	io::RawlogReader in(rawlog);
	while (auto o = in.next())
	{
		auto it = labels.find(o->sensorLabel);
		const auto t_ns = fromMrptTimeChecked(o->timestamp);
		if (it == labels.end() || classOf(*o) != it->second.cls || !t_ns) continue;
		LabelOut& l = it->second;
		// What the layout has no column for is counted (exporter.h's contract).
		const auto* th = dynamic_cast<const auvnav::obs::CObservationThrusters*>(o.get());
		if (th && thrusterUnit(*th) != l.thruster_unit)
		{
			// import.yaml has one unit per label: rows in another unit would come back relabelled.
			report
			    .skipped_by_reason["thrusters " + o->sensorLabel + ": rows in " + thrusterUnit(*th) +
			                       " (the label's first rows are in " + l.thruster_unit + ") not exported"]++;
			continue;
		}
		std::string row = formatSeconds7(*t_ns) + ",";
		if (const auto* imu = dynamic_cast<const mrpt::obs::CObservationIMU*>(o.get()))
		{
			row += imuRow(*imu);
			for (const auto& f : imuFieldsWithoutColumn(*imu))
				report
				    .skipped_by_reason["imu " + o->sensorLabel + ": " + f + " has no column, not exported"]++;
		}
		else if (const auto* g = dynamic_cast<const mrpt::obs::CObservationGPS*>(o.get()))
		{
			row += gpsRow(*g);
			for (const auto& [type, msg] : g->messages)
				if (type != mrpt::obs::gnss::NMEA_GGA && msg.get())
					report.skipped_by_reason["gps " + o->sensorLabel + ": message " +
					                         msg->getMessageTypeAsString() + " not exported (only GGA)"]++;
		}
		else if (const auto* p = dynamic_cast<const auvnav::obs::CObservationPressure*>(o.get()))
			row += exact(p->pressure_pa) + "," + exact(p->temperature_c) + "," + poseCells(p->sensorPose);
		else if (const auto* u = dynamic_cast<const auvnav::obs::CObservationUSBL*>(o.get()))
			row += usblRow(*u);
		else if (const auto* d = dynamic_cast<const auvnav::obs::CObservationDVL*>(o.get()))
			row += dvlRow(*d, l.max_array);
		else if (const auto* a = dynamic_cast<const auvnav::obs::CObservationADCP*>(o.get()))
			row += adcpRow(*a, l.max_array);
		else if (const auto* t = dynamic_cast<const auvnav::obs::CObservationThrusters*>(o.get()))
			row += thrusterRow(*t, l.max_array);
		else if (const auto* im = dynamic_cast<const mrpt::obs::CObservationImage*>(o.get()))
		{
			char name[32];
			std::snprintf(name, sizeof name, "%06zu.png", l.rows);
			const std::string rel = l.stem + "/" + name;
			if (!im->image.saveToFile(out_dir + "/" + rel))
				throw ImportError(out_dir + "/" + rel + ": cannot write the image");
			const auto& c = im->cameraParams;
			row += csvQuoted(rel) + "," + std::to_string(c.ncols) + "," + std::to_string(c.nrows) + "," +
			       exact(c.fx()) + "," + exact(c.fy()) + "," + exact(c.cx()) + "," + exact(c.cy()) + "," +
			       csvQuoted(c.cameraName) + "," + poseCells(im->cameraPose);
			if (std::any_of(c.dist.begin(), c.dist.end(), [](double k) { return k != 0; }))
				report.skipped_by_reason["image " + o->sensorLabel +
				                         ": camera distortion (dist) has no column, not exported"]++;
		}
		*l.out << row << "\n";
		l.rows++;
	}
	for (const auto& label : order)
	{
		LabelOut& l = labels[label];
		l.out->flush();
		if (!*l.out) throw ImportError(out_dir + "/" + l.file_name + ": write failed (disk full?)");
		report.sensors.push_back({label, l.cls, l.file_name, l.rows});
	}
	report.spec_file = out_dir + "/import.yaml";
	std::ofstream spec(report.spec_file);
	spec << specText(spec_labels, files, units, false);
	if (!spec) throw ImportError(report.spec_file + ": cannot write");
}

}  // namespace auvnav::import
