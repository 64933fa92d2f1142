// The exporter's CSV layout (export_csv.h): header rows, rows and cells.
#include "export_csv.h"

#include <auvnav/import/time_format.h>
#include <auvnav/obs/CObservationPressure.h>
#include <mrpt/obs/CObservationImage.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

namespace auvnav::import::detail
{
namespace
{
const char* kPoseColumns = "pose_x_m,pose_y_m,pose_z_m,pose_qw,pose_qx,pose_qy,pose_qz";
}  // namespace

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

std::string poseCells(const mrpt::poses::CPose3D& p)
{
	mrpt::math::CQuaternionDouble q;
	p.getAsQuaternion(q);
	return exact(p.x()) + "," + exact(p.y()) + "," + exact(p.z()) + "," + exact(q.r()) + "," + exact(q.x()) +
	       "," + exact(q.y()) + "," + exact(q.z());
}

/** The columns of one class after `t_s`: the fixed ones, then those of each
 *  element (`#`: its index), then the pose unless the class has none. */
struct ClassColumns
{
	const char* cls;
	const char* fixed;
	std::vector<const char*> per_element;
	bool has_pose = true;
};

const ClassColumns kClassColumns[] = {
    {"imu",
     "gyro_x_radps,gyro_y_radps,gyro_z_radps,acc_x_mps2,acc_y_mps2,acc_z_mps2,mag_x_G,mag_y_G,mag_z_G,"
     "quat_w,quat_x,quat_y,quat_z,temperature_degC,",
     {}},
    {"gps", "latitude_deg,longitude_deg,altitude_msl_m,geoid_separation_m,fix_quality,satellites,hdop,", {}},
    {"pressure", "pressure_Pa,temperature_degC,", {}},
    {"dvl",
     "frame,sign,bottom_lock,vel_x_mps,vel_y_mps,vel_z_mps,cov_00,cov_01,cov_02,cov_10,cov_11,cov_12,cov_20,"
     "cov_21,cov_22,altitude_m,beam_inclination_rad,beam_velocity_sigma_mps,beam_count,",
     {"beam_#_range_m", "beam_#_valid", "beam_#_velocity_mps", "beam_#_azimuth_rad"}},
    {"adcp",
     "blank_distance_m,cell_size_m,velocity_sigma_mps,cell_count,",
     {"cell_#_vx_mps", "cell_#_vy_mps", "cell_#_vz_mps", "cell_#_correlation", "cell_#_valid"}},
    {"thrusters", "thruster_count,", {"effort_#"}, false},
    {"image", "file,ncols,nrows,fx,fy,cx,cy,camera_name,", {}},
    {"usbl",
     "measurement_time_s,latitude_deg,longitude_deg,depth_m,north_m,east_m,down_m,"
     "cov_nn,cov_ne,cov_nd,cov_en,cov_ee,cov_ed,cov_dn,cov_de,cov_dd,slant_range_m,transponder_id,",
     {}},
};

std::string header(const std::string& cls, std::size_t n)
{
	std::string h = "t_s,";
	bool has_pose = true;
	for (const ClassColumns& c : kClassColumns)
	{
		if (cls != c.cls) continue;
		h += c.fixed;
		for (std::size_t i = 0; i < n; ++i)
			for (std::string column : c.per_element)
				h += column.replace(column.find('#'), 1, std::to_string(i)) + ",";
		has_pose = c.has_pose;
	}
	if (has_pose)
		h += kPoseColumns;
	else
		h.pop_back();  // the trailing comma
	return h;
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

}  // namespace auvnav::import::detail
