#pragma once
// Internal to the converters: what the per-sensor converters (convert_*.cpp)
// share: the axis map, the mounting (and the base of the mounted sensors'
// converters), 3-vector and latitude/longitude reads, array counts.
#include <auvnav/config.h>
#include <auvnav/import/record.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "converters.h"
#include "field_spec.h"

namespace auvnav::import::detail
{
constexpr double kDeg = M_PI / 180.0;
constexpr int kMaxArray = 256;

/** The matrix taking a source vector to the sensor frame: `axes: [x, -y, -z]`
 *  (signed permutation: sensor axis k = ± source axis), `{rotation_ypr_deg: …}`
 *  or `{matrix: [9 numbers, row-major]}`. */
Eigen::Matrix3d parseAxes(const config::Node& s, std::vector<std::string>& notes);

/** Sensor pose on the vehicle: constant (`position_m`, `orientation_ypr_deg`)
 *  or per record (`fields: [x, y, z, qw, qx, qy, qz]`, metres). */
class Mounting
{
 public:
	explicit Mounting(const config::Node& s);

	bool poseOf(const Record& r, Columns& cols, mrpt::poses::CPose3D& out, std::string& why) const;

 private:
	bool per_record_ = false;
	mrpt::poses::CPose3D pose_;
	ScalarSpec fields_[7];
};

/** Base of the converters of a sensor mounted on the vehicle (all but the
 *  thrusters): the sensor's label and mounting, which every observation it
 *  makes gets, and the column cache its reads share. */
class MountedConverter : public Converter
{
 protected:
	MountedConverter(const config::Node& s, const std::string& label) : label_(label), mounting_(s) {}

	/** Gives `o` the sensor's label and its pose for record `r`, through
	 *  setSensorPose (an image's cameraPose); false and `why` if the pose
	 *  cannot be read from `r`. */
	bool labelAndMount(mrpt::obs::CObservation& o, const Record& r, std::string& why)
	{
		o.sensorLabel = label_;
		mrpt::poses::CPose3D pose;
		if (!mounting_.poseOf(r, cols_, pose, why)) return false;
		o.setSensorPose(pose);
		return true;
	}

	Columns cols_;

 private:
	std::string label_;
	Mounting mounting_;
};

/** Base of the converters of a vector sensor (IMU, DVL, ADCP): a mounted
 *  sensor whose source axes map to the sensor frame through `axes:`
 *  (parseAxes). */
class AxisMappedConverter : public MountedConverter
{
 protected:
	AxisMappedConverter(const config::Node& s, const std::string& label)
	    : MountedConverter(s, label), axes_(parseAxes(s, notes_))
	{
	}

	//! Source vector to sensor frame.
	const Eigen::Matrix3d& axes() const { return axes_; }

 private:
	Eigen::Matrix3d axes_;
};

/** Reads a 3-vector quantity: Ok (all three), Missing (all three missing), Bad. */
Read readVec3(const std::vector<ScalarSpec>& spec, const Record& r, Columns& cols, Eigen::Vector3d& out,
              std::string& why, const char* name, int index = 0);

bool finiteOrWhy(const Eigen::Vector3d& v, const char* name, std::string& why);

/** The latitude and longitude of a fix (quantities `latitude` and
 *  `longitude`, angles), given together or not at all. */
class LatLonSpec
{
 public:
	/** Parses them from the quantities `q`; fails on `s` (the sensor entry)
	 *  when only one is given. */
	LatLonSpec(const config::Node& q, const config::Node& s);

	bool present() const { return lat_.present; }

	/** Reads the fix in degrees. A quantity whose unit is deg keeps the
	 *  source's number (no rad round trip that could move its last bit).
	 *  Missing when either cell is empty; Bad and `why` when either is not
	 *  finite or out of range (|latitude| <= 90°, |longitude| <= 360°). */
	Read read(const Record& r, Columns& cols, double& lat_deg, double& lon_deg, std::string& why) const;

 private:
	ScalarSpec lat_, lon_;
};

/** `count:` of an array: a constant or a field (`{field: n}`). */
struct CountSpec
{
	bool is_constant = true;
	int constant = 0;
	ScalarSpec field;

	static CountSpec parse(const config::Node& n, const std::string& key);
	bool read(const Record& r, Columns& cols, int& out, std::string& why) const;
	/** A record whose count field names more elements than it has columns is a
	 *  bad record (the count is data), not a spec error: `why` must then not
	 *  start with "no field", which makes the importer stop even with lenient. */
	void explainMissing(int n, std::string& why) const;
};

}  // namespace auvnav::import::detail
