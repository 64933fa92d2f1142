// The pieces the per-sensor converters share (converter_support.h): the axis
// map, the mounting, 3-vector reads and array counts.
#include "converter_support.h"

#include <Eigen/Dense>

namespace auvnav::import::detail
{
Eigen::Matrix3d parseAxes(const config::Node& s, std::vector<std::string>& notes)
{
	if (!s.has("axes")) return Eigen::Matrix3d::Identity();
	Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
	if (s.isSequence("axes"))
	{
		const auto names = s.strings("axes");
		if (names.size() != 3) s.fail("axes", "expected 3 signed axis names such as [x, -y, -z]");
		for (int k = 0; k < 3; ++k)
		{
			std::string a = names[static_cast<std::size_t>(k)];
			double sign = 1;
			if (!a.empty() && (a[0] == '-' || a[0] == '+'))
			{
				sign = a[0] == '-' ? -1 : 1;
				a.erase(0, 1);
			}
			const int src = a == "x" ? 0 : a == "y" ? 1 : a == "z" ? 2 : -1;
			if (src < 0)
				s.fail("axes",
				       "'" + names[static_cast<std::size_t>(k)] + "' is not one of x, y, z, -x, -y, -z");
			M(k, src) = sign;
		}
		if ((M.cwiseAbs().colwise().sum().array() != 1).any())
			s.fail("axes", "each source axis must be used exactly once");
	}
	else
	{
		const config::Node a = s.child("axes");
		a.allowOnly({"rotation_ypr_deg", "matrix"});
		if (a.has("rotation_ypr_deg") == a.has("matrix"))
			s.fail("axes", "give a signed axis list, or exactly one of rotation_ypr_deg and matrix");
		if (a.has("matrix"))
		{
			const auto m = a.numbers("matrix");
			if (m.size() != 9) a.fail("matrix", "expected 9 numbers (row-major)");
			for (int i = 0; i < 9; ++i) M(i / 3, i % 3) = m[static_cast<std::size_t>(i)];
			if ((M * M.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6)
				a.fail("matrix", "not orthonormal (|M Mᵀ − I| > 1e-6)");
		}
		else
		{
			const Eigen::Vector3d ypr = a.vector3("rotation_ypr_deg") * kDeg;
			M = mrpt::poses::CPose3D(0, 0, 0, ypr[0], ypr[1], ypr[2]).getRotationMatrix().asEigen();
		}
	}
	if (M.determinant() < 0)
		notes.push_back(
		    "axes: the mapping is a reflection (determinant -1): the source axes are left-handed");
	return M;
}

Mounting::Mounting(const config::Node& s)
{
	if (!s.has("mounting")) return;
	const config::Node m = s.child("mounting");
	m.allowOnly({"position_m", "orientation_ypr_deg", "fields"});
	if (m.has("fields"))
	{
		if (m.has("position_m") || m.has("orientation_ypr_deg"))
			s.fail("mounting", "give either fields or position_m/orientation_ypr_deg");
		const auto names = m.strings("fields");
		if (names.size() != 7) m.fail("fields", "expected [x, y, z, qw, qx, qy, qz]");
		for (std::size_t i = 0; i < 7; ++i)
		{
			fields_[i].present = true;
			fields_[i].field = names[i];
			fields_[i].where = m.where("fields");
		}
		per_record_ = true;
		return;
	}
	const Eigen::Vector3d p = m.vector3("position_m", Eigen::Vector3d::Zero());
	const Eigen::Vector3d ypr = m.vector3("orientation_ypr_deg", Eigen::Vector3d::Zero()) * kDeg;
	if (p.cwiseAbs().maxCoeff() > 100) m.fail("position_m", "lever arm longer than 100 m");
	pose_ = mrpt::poses::CPose3D(p[0], p[1], p[2], ypr[0], ypr[1], ypr[2]);
}

bool Mounting::poseOf(const Record& r, Columns& cols, mrpt::poses::CPose3D& out, std::string& why) const
{
	if (!per_record_)
	{
		out = pose_;
		return true;
	}
	double v[7];
	for (int i = 0; i < 7; ++i)
		if (readScalar(fields_[i], r, cols, v[i], why) != Read::Ok || !std::isfinite(v[i]))
		{
			if (why.empty()) why = "mounting field '" + fields_[i].field + "' missing or not finite";
			return false;
		}
	const double qn = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
	if (std::abs(qn - 1) > 1e-6)
	{
		why = "mounting quaternion is not unit";
		return false;
	}
	out = mrpt::poses::CPose3D(mrpt::math::CQuaternionDouble(v[3], v[4], v[5], v[6]), v[0], v[1], v[2]);
	return true;
}

Read readVec3(const std::vector<ScalarSpec>& spec, const Record& r, Columns& cols, Eigen::Vector3d& out,
              std::string& why, const char* name, int index)
{
	int ok = 0, missing = 0;
	for (int k = 0; k < 3; ++k)
	{
		const Read res = readScalar(spec[static_cast<std::size_t>(k)], r, cols, out[k], why, index);
		if (res == Read::Bad) return Read::Bad;
		(res == Read::Ok ? ok : missing)++;
	}
	if (ok == 3) return Read::Ok;
	if (ok == 0) return Read::Missing;
	why = std::string(name) + ": only " + std::to_string(ok) + " of 3 components present";
	return Read::Bad;
}

bool finiteOrWhy(const Eigen::Vector3d& v, const char* name, std::string& why)
{
	if (v.allFinite()) return true;
	why = std::string("non-finite ") + name;
	return false;
}

LatLonSpec::LatLonSpec(const config::Node& q, const config::Node& s)
    : lat_(parseScalar(q, "latitude", UnitKind::Angle)), lon_(parseScalar(q, "longitude", UnitKind::Angle))
{
	if (lat_.present != lon_.present) s.fail("latitude", "give latitude and longitude together");
}

Read LatLonSpec::read(const Record& r, Columns& cols, double& lat_deg, double& lon_deg,
                      std::string& why) const
{
	double lat_rad = 0, lon_rad = 0, lat_raw = 0, lon_raw = 0;
	const Read lat = readScalar(lat_, r, cols, lat_rad, why, 0, &lat_raw);
	if (lat != Read::Ok) return lat;
	const Read lon = readScalar(lon_, r, cols, lon_rad, why, 0, &lon_raw);
	if (lon != Read::Ok) return lon;
	if (!(std::abs(lat_rad) <= M_PI / 2 && std::abs(lon_rad) <= 2 * M_PI))
	{
		why = "latitude/longitude not finite or out of range";
		return Read::Bad;
	}
	lat_deg = lat_.unit.name == "deg" ? lat_raw : lat_rad / kDeg;
	lon_deg = lon_.unit.name == "deg" ? lon_raw : lon_rad / kDeg;
	return Read::Ok;
}

CountSpec CountSpec::parse(const config::Node& n, const std::string& key)
{
	CountSpec c;
	if (!n.has(key)) n.fail(key, "missing (a number, or {field: NAME})");
	if (n.isScalar(key))
	{
		c.constant = n.integer(key);
		if (c.constant < 0 || c.constant > kMaxArray) n.fail(key, "expected 0.." + std::to_string(kMaxArray));
		return c;
	}
	c.is_constant = false;
	c.field = parseScalar(n, key, UnitKind::Dimensionless);
	return c;
}

bool CountSpec::read(const Record& r, Columns& cols, int& out, std::string& why) const
{
	if (is_constant)
	{
		out = constant;
		return true;
	}
	double v = 0;
	if (readScalar(field, r, cols, v, why) != Read::Ok || !(v >= 0 && v <= kMaxArray) || std::floor(v) != v)
	{
		if (why.empty())
			why = "count field '" + field.field + "' missing or not an integer in 0.." +
			      std::to_string(kMaxArray);
		return false;
	}
	out = static_cast<int>(v);
	return true;
}

void CountSpec::explainMissing(int n, std::string& why) const
{
	if (!is_constant && why.rfind("no field", 0) == 0)
		why =
		    "count field '" + field.field + "' says " + std::to_string(n) + " elements, but there is " + why;
}

}  // namespace auvnav::import::detail
