#pragma once
// Internal to the converters: what the per-sensor converters (convert_*.cpp)
// share: the axis map, the mounting, 3-vector reads and array counts.
#include <auvnav/config.h>
#include <auvnav/import/record.h>
#include <mrpt/poses/CPose3D.h>

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

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

/** Reads a 3-vector quantity: Ok (all three), Missing (all three missing), Bad. */
Read readVec3(const std::vector<ScalarSpec>& spec, const Record& r, Columns& cols, Eigen::Vector3d& out,
              std::string& why, const char* name, int index = 0);

bool finiteOrWhy(const Eigen::Vector3d& v, const char* name, std::string& why);

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
