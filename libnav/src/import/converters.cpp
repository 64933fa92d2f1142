#include "converters.h"

#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/obs/CObservationThrusters.h>
#include <auvnav/obs/CObservationUSBL.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/system/filesystem.h>

#include <Eigen/Dense>
#include <cmath>

#include "field_spec.h"

namespace auvnav::import::detail
{
namespace
{
constexpr double kDeg = M_PI / 180.0;
constexpr double kGaussPerTesla = 1e4;  // MRPT's CObservationIMU keeps IMU_MAG_* in gauss
constexpr int kMaxArray = 256;
constexpr double kMaxImageSide = 1 << 20;  // pixels; far beyond any camera or sonar image

const std::vector<std::string> kCommonKeys = {"label", "class",    "source",  "time",
                                              "axes",  "mounting", "optional"};

// ---------------------------------------------------------------- axes

/** The matrix taking a source vector to the sensor frame: `axes: [x, -y, -z]`
 *  (signed permutation: sensor axis k = ± source axis), `{rotation_ypr_deg: …}`
 *  or `{matrix: [9 numbers, row-major]}`. */
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

// ---------------------------------------------------------------- mounting

/** Sensor pose on the vehicle: constant (`position_m`, `orientation_ypr_deg`)
 *  or per record (`fields: [x, y, z, qw, qx, qy, qz]`, metres). */
class Mounting
{
 public:
	explicit Mounting(const config::Node& s)
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

	bool poseOf(const Record& r, Columns& cols, mrpt::poses::CPose3D& out, std::string& why) const
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

 private:
	bool per_record_ = false;
	mrpt::poses::CPose3D pose_;
	ScalarSpec fields_[7];
};

/** Reads a 3-vector quantity: Ok (all three), Missing (all three missing), Bad. */
Read readVec3(const std::vector<ScalarSpec>& spec, const Record& r, Columns& cols, Eigen::Vector3d& out,
              std::string& why, const char* name, int index = 0)
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

/** `count:` of an array: a constant or a field (`{field: n}`). */
struct CountSpec
{
	bool is_constant = true;
	int constant = 0;
	ScalarSpec field;

	static CountSpec parse(const config::Node& n, const std::string& key)
	{
		CountSpec c;
		if (!n.has(key)) n.fail(key, "missing (a number, or {field: NAME})");
		if (n.isScalar(key))
		{
			c.constant = n.integer(key);
			if (c.constant < 0 || c.constant > kMaxArray)
				n.fail(key, "expected 0.." + std::to_string(kMaxArray));
			return c;
		}
		c.is_constant = false;
		c.field = parseScalar(n, key, UnitKind::Dimensionless);
		return c;
	}
	bool read(const Record& r, Columns& cols, int& out, std::string& why) const
	{
		if (is_constant)
		{
			out = constant;
			return true;
		}
		double v = 0;
		if (readScalar(field, r, cols, v, why) != Read::Ok || !(v >= 0 && v <= kMaxArray) ||
		    std::floor(v) != v)
		{
			if (why.empty())
				why = "count field '" + field.field + "' missing or not an integer in 0.." +
				      std::to_string(kMaxArray);
			return false;
		}
		out = static_cast<int>(v);
		return true;
	}
	/** A record whose count field names more elements than it has columns is a
	 *  bad record (the count is data), not a spec error: `why` must then not
	 *  start with "no field", which makes the importer stop even with lenient. */
	void explainMissing(int n, std::string& why) const
	{
		if (!is_constant && why.rfind("no field", 0) == 0)
			why = "count field '" + field.field + "' says " + std::to_string(n) + " elements, but there is " +
			      why;
	}
};

// ---------------------------------------------------------------- IMU

class ImuConverter final : public Converter
{
 public:
	ImuConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : label_(label), axes_(parseAxes(s, notes_)), mounting_(s)
	{
		gyro_ = parseVector(q, "angular_velocity", UnitKind::AngularRate, 3);
		acc_ = parseVector(q, "linear_acceleration", UnitKind::Acceleration, 3);
		mag_ = parseVector(q, "magnetic_field", UnitKind::MagneticField, 3);
		quat_ = parseVector(q, "orientation", UnitKind::Dimensionless, 4);
		temp_ = parseScalar(q, "temperature", UnitKind::Temperature);
		if (!gyro_[0].present && !acc_[0].present && !mag_[0].present && !quat_[0].present)
			s.fail("class",
			       "an imu needs at least one of angular_velocity, linear_acceleration, magnetic_field, "
			       "orientation");
		// The quaternion is an attitude of the source frame in the IMU's own world
		// frame: `axes` (possibly a reflection) cannot be applied to it, and leaving
		// it unrotated beside rotated rates would be silently inconsistent.
		if (quat_[0].present && !axes_.isIdentity(1e-12))
			s.fail("axes",
			       "not applicable to orientation (a quaternion of the source frame): give the orientation "
			       "in the sensor frame without axes, or import it as a separate sensor");
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		using namespace mrpt::obs;
		auto o = CObservationIMU::Create();
		o->sensorLabel = label_;
		if (!mounting_.poseOf(r, cols_, o->sensorPose, why)) return nullptr;
		if (!vector(gyro_, r, *o, {IMU_WX, IMU_WY, IMU_WZ}, 1.0, "angular_velocity", why)) return nullptr;
		if (!vector(acc_, r, *o, {IMU_X_ACC, IMU_Y_ACC, IMU_Z_ACC}, 1.0, "linear_acceleration", why))
			return nullptr;
		if (!vector(mag_, r, *o, {IMU_MAG_X, IMU_MAG_Y, IMU_MAG_Z}, kGaussPerTesla, "magnetic_field", why))
			return nullptr;
		if (quat_[0].present)
		{
			double q[4];
			int ok = 0;
			for (int k = 0; k < 4; ++k)
			{
				const Read res = readScalar(quat_[static_cast<std::size_t>(k)], r, cols_, q[k], why);
				if (res == Read::Bad) return nullptr;
				ok += res == Read::Ok;
			}
			if (ok == 4)
			{
				if (!(std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]) &&
				      std::isfinite(q[3])))
				{
					why = "non-finite orientation";
					return nullptr;
				}
				o->set(IMU_ORI_QUAT_W, q[0]);
				o->set(IMU_ORI_QUAT_X, q[1]);
				o->set(IMU_ORI_QUAT_Y, q[2]);
				o->set(IMU_ORI_QUAT_Z, q[3]);
			}
			else if (ok != 0)
			{
				why = "orientation: incomplete quaternion";
				return nullptr;
			}
		}
		double t = 0;
		const Read rt = readScalar(temp_, r, cols_, t, why);
		if (rt == Read::Bad) return nullptr;
		if (rt == Read::Ok) o->set(IMU_TEMPERATURE, t);
		bool any = false;
		for (bool p : o->dataIsPresent) any = any || p;
		if (!any)
		{
			why = "no IMU quantity present";
			return nullptr;
		}
		return o;
	}

 private:
	bool vector(const std::vector<ScalarSpec>& spec, const Record& r, mrpt::obs::CObservationIMU& o,
	            std::array<mrpt::obs::TIMUDataIndex, 3> idx, double scale, const char* name, std::string& why)
	{
		if (!spec[0].present) return true;
		Eigen::Vector3d v;
		const Read res = readVec3(spec, r, cols_, v, why, name);
		if (res == Read::Bad) return false;
		if (res == Read::Missing)
		{
			if (spec[0].optional) return true;
			why = std::string(name) + " missing";
			return false;
		}
		if (!finiteOrWhy(v, name, why)) return false;
		// A field already in gauss is kept as read (no T round trip moving the last bit).
		if (scale == kGaussPerTesla && (spec[0].unit.name == "G" || spec[0].unit.name == "Gauss"))
		{
			for (int k = 0; k < 3; ++k)
				readScalar(spec[static_cast<std::size_t>(k)], r, cols_, v[k], why, 0, &v[k]);
			scale = 1;
		}
		const Eigen::Vector3d v_s = axes_ * v * scale;
		for (int k = 0; k < 3; ++k) o.set(idx[static_cast<std::size_t>(k)], v_s[k]);
		return true;
	}

	std::string label_;
	Eigen::Matrix3d axes_;
	Mounting mounting_;
	std::vector<ScalarSpec> gyro_, acc_, mag_, quat_;
	ScalarSpec temp_;
	Columns cols_;
};

// ---------------------------------------------------------------- DVL

class DvlConverter final : public Converter
{
 public:
	DvlConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : label_(label), axes_(parseAxes(s, notes_)), mounting_(s)
	{
		frame_ = parseText(s, "frame");
		if (!frame_.present)
			s.fail("frame",
			       "required: instrument, vehicle, earth_ned, earth_enu or beam (which one depends on "
			       "the DVL's output setting; a wrong guess is a wrong velocity)");
		sign_ = parseText(s, "sign");
		if (!sign_.present)
			s.fail("sign", "required: vehicle_over_bottom, or bottom_over_instrument (Teledyne RDI PD0)");
		checkText(s, frame_, "frame",
		          [](const std::string& n)
		          {
			          auvnav::obs::DvlFrame f;
			          return auvnav::obs::parseDvlFrame(n, f);
		          });
		checkText(s, sign_, "sign",
		          [](const std::string& n)
		          {
			          auvnav::obs::DvlSign x;
			          return auvnav::obs::parseDvlSign(n, x);
		          });
		if (frame_.is_constant && frame_.constant == "beam" && !axes_.isIdentity(1e-12))
			s.fail("axes",
			       "not applied to beam azimuths with frame: beam (give them in the sensor frame, without "
			       "axes)");
		velocity_ = parseVector(q, "velocity", UnitKind::Velocity, 3);
		cov_ = parseVector(q, "velocity_covariance", UnitKind::VelocitySquared, 9);
		sigma_ = parseScalar(q, "velocity_sigma", UnitKind::Velocity);
		lock_ = parseScalar(q, "bottom_lock", UnitKind::Dimensionless);
		altitude_ = parseScalar(q, "altitude", UnitKind::Length);
		inclination_ = parseScalar(q, "beam_inclination", UnitKind::Angle);
		beam_sigma_ = parseScalar(q, "beam_velocity_sigma", UnitKind::Velocity);
		if (q.has("beams"))
		{
			const config::Node b = q.child("beams");
			b.allowOnly({"count", "range", "range_is", "valid", "velocity", "azimuth"});
			beam_count_ = CountSpec::parse(b, "count");
			range_ = parseScalar(b, "range", UnitKind::Length);
			valid_ = parseScalar(b, "valid", UnitKind::Dimensionless);
			beam_velocity_ = parseScalar(b, "velocity", UnitKind::Velocity);
			azimuth_ = parseScalar(b, "azimuth", UnitKind::Angle);
			const std::string range_is = b.string("range_is", "slant");
			if (range_is != "slant" && range_is != "vertical")
				b.fail("range_is", "expected slant or vertical");
			ranges_vertical_ = range_is == "vertical";
			has_beams_ = true;
		}
		if (!velocity_[0].present && !(has_beams_ && beam_velocity_.present))
			s.fail("velocity", "a dvl needs velocity (3 fields) or beams.velocity");
		// altitude from slant ranges is range × cos(inclination): without the
		// inclination it would be the slant range (15 % high at 30 deg).
		if (has_beams_ && range_.present && !ranges_vertical_ && !inclination_.present && !altitude_.present)
			s.fail("beam_inclination",
			       "required with slant beams.range and no altitude (altitude = range x "
			       "cos(beam_inclination)); or give beams.range_is: vertical");
		if (ranges_vertical_ && !inclination_.present && !altitude_.present)
			notes_.push_back("beams.range_is vertical: altitude = mean of the valid vertical ranges");
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		using namespace auvnav::obs;
		auto o = CObservationDVL::Create();
		o->sensorLabel = label_;
		if (!mounting_.poseOf(r, cols_, o->sensorPose, why)) return nullptr;
		std::string name;
		if (!readText(frame_, r, cols_, name, why)) return nullptr;
		if (!auvnav::obs::parseDvlFrame(name, o->frame))
		{
			why = "frame '" + name + "' unknown";
			return nullptr;
		}
		// Beam azimuths and radial velocities are not rotated by `axes`: a beam-frame
		// record with axes would be silently in the source frame.
		if (o->frame == DvlFrame::Beam && !axes_.isIdentity(1e-12))
		{
			why =
			    "frame beam: axes are not applied to beam azimuths (give them in the sensor frame, without "
			    "axes)";
			return nullptr;
		}
		if (!readText(sign_, r, cols_, name, why)) return nullptr;
		if (!auvnav::obs::parseDvlSign(name, o->sign))
		{
			why = "sign '" + name + "' unknown";
			return nullptr;
		}
		double x = 0;
		inclination_read_ = readScalar(inclination_, r, cols_, x, why) == Read::Ok;
		if (inclination_read_)
			o->beam_inclination_rad = x;
		else if (!why.empty())
			return nullptr;
		if (readScalar(beam_sigma_, r, cols_, x, why) == Read::Ok)
			o->beam_velocity_sigma_mps = x;
		else if (!why.empty())
			return nullptr;
		if (!readBeams(r, *o, why)) return nullptr;

		bool velocity_ok = false;
		if (velocity_[0].present)
		{
			Eigen::Vector3d v(NAN, NAN, NAN);
			const Read res = readVec3(velocity_, r, cols_, v, why, "velocity");
			if (res == Read::Bad) return nullptr;
			// NaN or a declared invalid value is "no velocity" (no bottom lock), not an error.
			velocity_ok = res == Read::Ok && v.allFinite();
			const bool rotate = o->frame == DvlFrame::Instrument || o->frame == DvlFrame::Vehicle;
			const Eigen::Vector3d v_out = velocity_ok ? Eigen::Vector3d(rotate ? axes_ * v : v) : v;
			// An invalid velocity is kept as read (NaN for a missing one), not made up.
			for (int k = 0; k < 3; ++k)
				o->velocity_s_mps[static_cast<std::size_t>(k)] = velocity_ok ? v_out[k] : v[k];
		}
		if (o->frame == DvlFrame::Beam)
		{
			int valid = 0;
			for (const auto& b : o->beams) valid += b.valid;
			velocity_ok = valid >= 3;
		}
		if (!readCovariance(r, *o, why)) return nullptr;

		o->bottom_lock = velocity_ok;
		if (lock_.present)
		{
			const Read res = readScalar(lock_, r, cols_, x, why);
			if (res == Read::Bad) return nullptr;
			o->bottom_lock = velocity_ok && res == Read::Ok && x != 0;
		}
		const Read ra = readScalar(altitude_, r, cols_, x, why);
		if (ra == Read::Bad) return nullptr;
		o->altitude_m = ra == Read::Ok ? x : altitudeFromBeams(*o);
		return o;
	}

 private:
	template <class Valid>
	static void checkText(const config::Node& s, const TextSpec& t, const char* key, Valid valid)
	{
		if (t.is_constant && !valid(t.constant)) s.fail(key, "'" + t.constant + "' is not a valid value");
		for (const auto& [from, to] : t.map)
			if (!valid(to)) s.fail(key, "map value '" + to + "' (for '" + from + "') is not a valid value");
	}

	bool readBeams(const Record& r, auvnav::obs::CObservationDVL& o, std::string& why)
	{
		if (!has_beams_) return true;
		int n = 0;
		if (!beam_count_.read(r, cols_, n, why)) return false;
		o.beams.resize(static_cast<std::size_t>(n));
		for (int i = 0; i < n; ++i)
		{
			auto& b = o.beams[static_cast<std::size_t>(i)];
			double range = NAN, valid = 1, vel = NAN, az = 0;
			const Read rr = readScalar(range_, r, cols_, range, why, i);
			if (rr == Read::Bad) return beam_count_.explainMissing(n, why), false;
			if (rr == Read::Missing) range = NAN;
			const Read rv = readScalar(valid_, r, cols_, valid, why, i);
			if (rv == Read::Bad) return beam_count_.explainMissing(n, why), false;
			const Read rb = readScalar(beam_velocity_, r, cols_, vel, why, i);
			if (rb == Read::Bad) return beam_count_.explainMissing(n, why), false;
			if (rb == Read::Missing) vel = NAN;
			const Read rz = readScalar(azimuth_, r, cols_, az, why, i);
			if (rz == Read::Bad) return beam_count_.explainMissing(n, why), false;
			// Without a validity field a beam is valid when its range (and, in
			// beam mode, its velocity) is a finite positive number.
			bool ok = rv == Read::Ok ? valid != 0 : std::isfinite(range) && range > 0;
			if (beam_velocity_.present) ok = ok && std::isfinite(vel);
			b.range_m = std::isfinite(range) ? range : 0;
			b.valid = ok;
			b.velocity_mps = vel;  // NaN (no radial velocity) stays NaN: 0 would be a measurement
			b.azimuth_rad = az;
		}
		return true;
	}

	bool readCovariance(const Record& r, auvnav::obs::CObservationDVL& o, std::string& why)
	{
		if (cov_[0].present)
		{
			Eigen::Matrix3d C;
			int ok = 0;
			for (int k = 0; k < 9; ++k)
			{
				const Read res =
				    readScalar(cov_[static_cast<std::size_t>(k)], r, cols_, C(k / 3, k % 3), why);
				if (res == Read::Bad) return false;
				ok += res == Read::Ok;
			}
			if (ok == 9)
			{
				// A NaN covariance (beam mode, no 3-D velocity) is kept as read, not made 0.
				const bool rotate =
				    o.frame == auvnav::obs::DvlFrame::Instrument || o.frame == auvnav::obs::DvlFrame::Vehicle;
				if (rotate && C.allFinite()) C = axes_ * C * axes_.transpose();
				for (int k = 0; k < 9; ++k) o.velocity_cov[static_cast<std::size_t>(k)] = C(k / 3, k % 3);
			}
			else if (ok != 0)
			{
				why = "velocity_covariance: only " + std::to_string(ok) + " of 9 components present";
				return false;
			}
			return true;
		}
		double s = 0;
		const Read res = readScalar(sigma_, r, cols_, s, why);
		if (res == Read::Bad) return false;
		if (res == Read::Ok)
			for (int k = 0; k < 3; ++k) o.velocity_cov[static_cast<std::size_t>(4 * k)] = s * s;
		return true;
	}

	double altitudeFromBeams(const auvnav::obs::CObservationDVL& o) const
	{
		double sum = 0;
		int n = 0;
		for (const auto& b : o.beams)
			if (b.valid && b.range_m > 0)
			{
				// Slant ranges without an inclination give no altitude (not the slant range).
				if (!ranges_vertical_ && !inclination_read_) return std::nan("");
				sum += ranges_vertical_ ? b.range_m : b.range_m * std::cos(o.beam_inclination_rad);
				++n;
			}
		return n > 0 ? sum / n : std::nan("");
	}

	std::string label_;
	Eigen::Matrix3d axes_;
	Mounting mounting_;
	TextSpec frame_, sign_;
	std::vector<ScalarSpec> velocity_, cov_;
	ScalarSpec sigma_, lock_, altitude_, inclination_, beam_sigma_;
	bool has_beams_ = false, ranges_vertical_ = false;
	bool inclination_read_ = false;  // this record's beam_inclination was read
	CountSpec beam_count_;
	ScalarSpec range_, valid_, beam_velocity_, azimuth_;
	Columns cols_;
};

// ---------------------------------------------------------------- pressure

class PressureConverter final : public Converter
{
 public:
	PressureConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : label_(label), mounting_(s)
	{
		pressure_ = parseScalar(q, "pressure", UnitKind::Pressure);
		depth_ = parseScalar(q, "depth", UnitKind::Length);
		temp_ = parseScalar(q, "temperature", UnitKind::Temperature);
		if (pressure_.present == depth_.present) s.fail("pressure", "give exactly one of pressure and depth");
		const std::string ref = s.string("pressure_reference", pressure_.present ? "" : "absolute");
		if (ref != "absolute" && ref != "gauge")
			s.fail("pressure_reference",
			       "required with pressure: absolute (atmosphere included) or gauge (relative to the "
			       "atmosphere)");
		gauge_ = ref == "gauge";
		// Converting a gauge reading or a depth to absolute pressure needs the
		// atmosphere (and for a depth the water density and gravity): asked
		// for, never assumed.
		if (gauge_ || depth_.present) atmospheric_pa_ = s.positive("atmospheric_pressure_pa");
		if (depth_.present)
		{
			density_ = s.inRange("density_kg_m3", 900, 1100);
			gravity_ = s.inRange("gravity_mps2", 9.7, 9.9);
			notes_.push_back(
			    "depth converted to absolute pressure with the spec's density, gravity and atmosphere");
		}
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = auvnav::obs::CObservationPressure::Create();
		o->sensorLabel = label_;
		if (!mounting_.poseOf(r, cols_, o->sensorPose, why)) return nullptr;
		double v = 0;
		const ScalarSpec& src = pressure_.present ? pressure_ : depth_;
		const Read res = readScalar(src, r, cols_, v, why);
		if (res == Read::Bad) return nullptr;
		if (res == Read::Missing || !std::isfinite(v))
		{
			why = pressure_.present ? "pressure missing or not finite" : "depth missing or not finite";
			return nullptr;
		}
		if (pressure_.present)
			o->pressure_pa = gauge_ ? v + atmospheric_pa_ : v;
		else
			o->pressure_pa = atmospheric_pa_ + density_ * gravity_ * v;
		double t = NAN;
		if (readScalar(temp_, r, cols_, t, why) == Read::Bad) return nullptr;
		o->temperature_c = t;
		return o;
	}

 private:
	std::string label_;
	Mounting mounting_;
	ScalarSpec pressure_, depth_, temp_;
	bool gauge_ = false;
	double atmospheric_pa_ = 0, density_ = 0, gravity_ = 0;
	Columns cols_;
};

// ---------------------------------------------------------------- USBL

/** An acoustic fix (CObservationUSBL): latitude/longitude/depth or
 *  north/east/down from the navigation origin, chosen per record by which
 *  cells hold numbers, with its optional covariance, slant range,
 *  transponder id and measurement time (UNIX seconds). */
class UsblConverter final : public Converter
{
 public:
	UsblConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : label_(label), mounting_(s)
	{
		lat_ = parseScalar(q, "latitude", UnitKind::Angle);
		lon_ = parseScalar(q, "longitude", UnitKind::Angle);
		depth_ = parseScalar(q, "depth", UnitKind::Length);
		north_ = parseScalar(q, "north", UnitKind::Length);
		east_ = parseScalar(q, "east", UnitKind::Length);
		down_ = parseScalar(q, "down", UnitKind::Length);
		if (lat_.present != lon_.present) s.fail("latitude", "give latitude and longitude together");
		if (north_.present != east_.present) s.fail("north", "give north and east together");
		if (!lat_.present && !north_.present)
			s.fail("latitude", "a usbl fix needs latitude/longitude(/depth) or north/east(/down)");
		if (q.has("position_covariance"))
			cov_ = parseVector(q, "position_covariance", UnitKind::LengthSquared, 9);
		sigma_ = parseScalar(q, "position_sigma", UnitKind::Length);
		if (!cov_.empty() && sigma_.present)
			s.fail("position_sigma", "give position_covariance or position_sigma");
		range_ = parseScalar(q, "slant_range", UnitKind::Length);
		id_ = parseScalar(q, "transponder_id", UnitKind::Dimensionless);
		time_ = parseScalar(q, "measurement_time", UnitKind::Time);
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = auvnav::obs::CObservationUSBL::Create();
		o->sensorLabel = label_;
		if (!mounting_.poseOf(r, cols_, o->sensorPose, why)) return nullptr;
		double a = 0, b = 0, raw_a = 0, raw_b = 0, c = NAN;
		Read ra = lat_.present ? readScalar(lat_, r, cols_, a, why, 0, &raw_a) : Read::Missing;
		Read rb = lat_.present ? readScalar(lon_, r, cols_, b, why, 0, &raw_b) : Read::Missing;
		if (ra == Read::Bad || rb == Read::Bad) return nullptr;
		if (ra == Read::Ok && rb == Read::Ok)
		{
			if (!(std::abs(a) <= M_PI / 2 && std::abs(b) <= 2 * M_PI))
			{
				why = "latitude/longitude not finite or out of range";
				return nullptr;
			}
			o->frame = auvnav::obs::UsblFrame::Geodetic;
			// Degrees in, degrees kept (no rad round trip).
			o->position[0] = lat_.unit.name == "deg" ? raw_a : a / kDeg;
			o->position[1] = lon_.unit.name == "deg" ? raw_b : b / kDeg;
			if (readScalar(depth_, r, cols_, c, why) == Read::Bad) return nullptr;
		}
		else
		{
			ra = north_.present ? readScalar(north_, r, cols_, a, why) : Read::Missing;
			rb = north_.present ? readScalar(east_, r, cols_, b, why) : Read::Missing;
			if (ra != Read::Ok || rb != Read::Ok)
			{
				if (why.empty()) why = "no position (latitude/longitude or north/east)";
				return nullptr;
			}
			o->frame = auvnav::obs::UsblFrame::LocalNed;
			o->position[0] = a;
			o->position[1] = b;
			if (readScalar(down_, r, cols_, c, why) == Read::Bad) return nullptr;
		}
		o->position[2] = c;
		double v = 0;
		for (std::size_t i = 0; i < cov_.size(); ++i)
		{
			const Read res = readScalar(cov_[i], r, cols_, v, why);
			if (res == Read::Bad) return nullptr;
			o->covariance_ned_m2[i] = res == Read::Ok ? v : NAN;
		}
		const Read rs = readScalar(sigma_, r, cols_, v, why);
		if (rs == Read::Bad) return nullptr;
		if (rs == Read::Ok) o->covariance_ned_m2 = {v * v, 0, 0, 0, v * v, 0, 0, 0, v * v};
		const Read rr = readScalar(range_, r, cols_, v, why);
		if (rr == Read::Bad) return nullptr;
		o->slant_range_m = rr == Read::Ok ? v : NAN;
		const Read ri = readScalar(id_, r, cols_, v, why);
		if (ri == Read::Bad) return nullptr;
		if (ri == Read::Ok)
		{
			if (!(v >= 0 && v <= 65535))
			{
				why = "transponder_id not 0..65535";
				return nullptr;
			}
			o->transponder_id = static_cast<uint16_t>(v);
		}
		const Read rt = readScalar(time_, r, cols_, v, why);
		if (rt == Read::Bad) return nullptr;
		if (rt == Read::Ok)
		{
			if (!(v > 0 && v < 1e11))
			{
				why = "measurement_time not a UNIX time";
				return nullptr;
			}
			o->measurement_time = mrpt::Clock::fromDouble(v);
		}
		return o;
	}

 private:
	std::string label_;
	Mounting mounting_;
	ScalarSpec lat_, lon_, depth_, north_, east_, down_, sigma_, range_, id_, time_;
	std::vector<ScalarSpec> cov_;
	Columns cols_;
};

// ---------------------------------------------------------------- GPS

class GpsConverter final : public Converter
{
 public:
	GpsConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : label_(label), mounting_(s)
	{
		lat_ = parseScalar(q, "latitude", UnitKind::Angle);
		lon_ = parseScalar(q, "longitude", UnitKind::Angle);
		alt_ = parseScalar(q, "altitude", UnitKind::Length);
		geoid_ = parseScalar(q, "geoid_separation", UnitKind::Length);
		quality_ = parseScalar(q, "fix_quality", UnitKind::Dimensionless);
		status_ = parseScalar(q, "navsat_status", UnitKind::Dimensionless);
		sats_ = parseScalar(q, "satellites", UnitKind::Dimensionless);
		hdop_ = parseScalar(q, "hdop", UnitKind::Dimensionless);
		if (!lat_.present || !lon_.present) s.fail("latitude", "a gps needs latitude and longitude");
		if (quality_.present && status_.present)
			s.fail("fix_quality", "give fix_quality or navsat_status, not both");
		const std::string ref = s.string("altitude_reference", alt_.present ? "" : "msl");
		if (ref != "msl" && ref != "ellipsoid")
			s.fail("altitude_reference",
			       "required with altitude: msl (NMEA GGA) or ellipsoid (sensor_msgs/NavSatFix)");
		ellipsoid_ = ref == "ellipsoid";
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		using mrpt::obs::gnss::Message_NMEA_GGA;
		double lat = 0, lon = 0, lat_raw = 0, lon_raw = 0;
		if (readScalar(lat_, r, cols_, lat, why, 0, &lat_raw) != Read::Ok ||
		    readScalar(lon_, r, cols_, lon, why, 0, &lon_raw) != Read::Ok)
		{
			if (why.empty()) why = "latitude/longitude missing";
			return nullptr;
		}
		if (!(std::abs(lat) <= M_PI / 2 && std::abs(lon) <= 2 * M_PI))
		{
			why = "latitude/longitude not finite or out of range";
			return nullptr;
		}
		Message_NMEA_GGA gga;
		// Degrees in, degrees kept: no rad round trip that could move the last bit.
		gga.fields.latitude_degrees = lat_.unit.name == "deg" ? lat_raw : lat / kDeg;
		gga.fields.longitude_degrees = lon_.unit.name == "deg" ? lon_raw : lon / kDeg;
		double x = 0;
		Read res = readScalar(alt_, r, cols_, x, why);
		if (res == Read::Bad) return nullptr;
		gga.fields.altitude_meters = res == Read::Ok ? x : NAN;
		res = readScalar(geoid_, r, cols_, x, why);
		if (res == Read::Bad) return nullptr;
		// NavSatFix altitudes are ellipsoidal: GGA altitude + geoid separation
		// must give back the ellipsoidal height, so the separation is 0 here.
		gga.fields.geoidal_distance = (res == Read::Ok && !ellipsoid_) ? x : 0;
		gga.fields.fix_quality = 1;
		if (quality_.present)
		{
			if (readScalar(quality_, r, cols_, x, why) != Read::Ok || !(x >= 0 && x <= 9))
			{
				if (why.empty()) why = "fix_quality missing or not 0..9";
				return nullptr;
			}
			gga.fields.fix_quality = static_cast<uint8_t>(x);
		}
		else if (status_.present)
		{
			// sensor_msgs/NavSatStatus: −1 no fix, 0 fix, 1 SBAS, 2 GBAS.
			if (readScalar(status_, r, cols_, x, why) != Read::Ok)
			{
				if (why.empty()) why = "navsat_status missing";
				return nullptr;
			}
			gga.fields.fix_quality = x < 0 ? 0 : x >= 2 ? 4 : x >= 1 ? 2 : 1;
		}
		res = readScalar(sats_, r, cols_, x, why);
		if (res == Read::Bad) return nullptr;
		gga.fields.satellitesUsed = res == Read::Ok && x >= 0 && x < 256 ? static_cast<uint32_t>(x) : 0;
		res = readScalar(hdop_, r, cols_, x, why);
		if (res == Read::Bad) return nullptr;
		gga.fields.thereis_HDOP = res == Read::Ok;
		gga.fields.HDOP = res == Read::Ok ? static_cast<float>(x) : 0.0f;
		auto o = mrpt::obs::CObservationGPS::Create();
		o->sensorLabel = label_;
		if (!mounting_.poseOf(r, cols_, o->sensorPose, why)) return nullptr;
		o->setMsg(gga);
		return o;
	}

 private:
	std::string label_;
	Mounting mounting_;
	ScalarSpec lat_, lon_, alt_, geoid_, quality_, status_, sats_, hdop_;
	bool ellipsoid_ = false;
	Columns cols_;
};

// ---------------------------------------------------------------- ADCP

class AdcpConverter final : public Converter
{
 public:
	AdcpConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : label_(label), axes_(parseAxes(s, notes_)), mounting_(s)
	{
		blank_ = parseScalar(q, "blank_distance", UnitKind::Length);
		cell_size_ = parseScalar(q, "cell_size", UnitKind::Length);
		sigma_ = parseScalar(q, "velocity_sigma", UnitKind::Velocity);
		if (!blank_.present || !cell_size_.present)
			s.fail("cell_size", "an adcp needs blank_distance and cell_size");
		const config::Node c = q.child("cells");
		c.allowOnly({"count", "velocity", "correlation", "valid"});
		count_ = CountSpec::parse(c, "count");
		velocity_ = parseVector(c, "velocity", UnitKind::Velocity, 3);
		if (!velocity_[0].present) c.fail("velocity", "missing (3 field templates such as cell_{i}_vx)");
		correlation_ = parseScalar(c, "correlation", UnitKind::Dimensionless);
		valid_ = parseScalar(c, "valid", UnitKind::Dimensionless);
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = auvnav::obs::CObservationADCP::Create();
		o->sensorLabel = label_;
		if (!mounting_.poseOf(r, cols_, o->sensorPose, why)) return nullptr;
		if (readScalar(blank_, r, cols_, o->blank_distance_m, why) != Read::Ok ||
		    readScalar(cell_size_, r, cols_, o->cell_size_m, why) != Read::Ok)
		{
			if (why.empty()) why = "blank_distance/cell_size missing";
			return nullptr;
		}
		double x = 0;
		const Read rs = readScalar(sigma_, r, cols_, x, why);
		if (rs == Read::Bad) return nullptr;
		if (rs == Read::Ok) o->velocity_sigma_mps = x;
		int n = 0;
		if (!count_.read(r, cols_, n, why)) return nullptr;
		o->cells.resize(static_cast<std::size_t>(n));
		for (int i = 0; i < n; ++i)
		{
			auto& cell = o->cells[static_cast<std::size_t>(i)];
			Eigen::Vector3d v;
			const Read rv = readVec3(velocity_, r, cols_, v, why, "cell velocity", i);
			if (rv == Read::Bad) return count_.explainMissing(n, why), nullptr;
			double corr = 1, valid = 1;
			const Read rc = readScalar(correlation_, r, cols_, corr, why, i);
			if (rc == Read::Bad) return count_.explainMissing(n, why), nullptr;
			const Read rb = readScalar(valid_, r, cols_, valid, why, i);
			if (rb == Read::Bad) return count_.explainMissing(n, why), nullptr;
			const bool finite = rv == Read::Ok && v.allFinite();
			const Eigen::Vector3d v_s = finite ? Eigen::Vector3d(axes_ * v) : Eigen::Vector3d::Zero();
			for (int k = 0; k < 3; ++k) cell.velocity_s_mps[static_cast<std::size_t>(k)] = v_s[k];
			cell.correlation = rc == Read::Ok ? corr : 0;
			cell.valid = finite && valid != 0;
		}
		return o;
	}

 private:
	std::string label_;
	Eigen::Matrix3d axes_;
	Mounting mounting_;
	ScalarSpec blank_, cell_size_, sigma_;
	CountSpec count_;
	std::vector<ScalarSpec> velocity_;
	ScalarSpec correlation_, valid_;
	Columns cols_;
};

// ---------------------------------------------------------------- thrusters

class ThrustersConverter final : public Converter
{
 public:
	ThrustersConverter(const config::Node& q, const config::Node& s, const std::string& label) : label_(label)
	{
		if (s.has("mounting"))
			s.fail("mounting", "thruster efforts have no mounting (the geometry is vehicle configuration)");
		const config::Node e = q.child("effort");
		e.allowOnly({"count", "field", "unit"});
		count_ = CountSpec::parse(e, "count");
		field_.present = true;
		field_.field = e.string("field");
		field_.where = e.where("field");
		const std::string unit = e.string("unit");
		if (unit == "N")
			unit_ = auvnav::obs::EffortUnit::Force_N;
		else if (unit == "rpm")
			unit_ = auvnav::obs::EffortUnit::Speed_rpm;
		else
			e.fail("unit", "expected N (commanded force) or rpm (shaft speed)");
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = auvnav::obs::CObservationThrusters::Create();
		o->sensorLabel = label_;
		o->unit = unit_;
		int n = 0;
		if (!count_.read(r, cols_, n, why)) return nullptr;
		o->effort.resize(static_cast<std::size_t>(n));
		for (int i = 0; i < n; ++i)
		{
			double& x = o->effort[static_cast<std::size_t>(i)];
			if (readScalar(field_, r, cols_, x, why, i) != Read::Ok || !std::isfinite(x))
			{
				count_.explainMissing(n, why);
				if (why.empty()) why = "effort " + std::to_string(i) + " missing or not finite";
				return nullptr;
			}
		}
		return o;
	}

 private:
	std::string label_;
	CountSpec count_;
	ScalarSpec field_;
	auvnav::obs::EffortUnit unit_ = auvnav::obs::EffortUnit::Force_N;
	Columns cols_;
};

// ---------------------------------------------------------------- image

class ImageConverter final : public Converter
{
 public:
	ImageConverter(const config::Node& q, const config::Node& s, const std::string& label,
	               const std::string& data_dir)
	    : label_(label), data_dir_(data_dir), mounting_(s)
	{
		file_ = parseText(q, "file");
		if (!file_.present || file_.is_constant)
			q.fail("file", "expected {field: NAME} (image file per record)");
		if (q.has("camera"))
		{
			const config::Node c = q.child("camera");
			c.allowOnly({"ncols", "nrows", "fx", "fy", "cx", "cy", "name"});
			const char* keys[6] = {"ncols", "nrows", "fx", "fy", "cx", "cy"};
			for (int i = 0; i < 6; ++i) camera_[i] = parseScalar(c, keys[i], UnitKind::Dimensionless);
			camera_name_ = parseText(c, "name");
			has_camera_ = true;
		}
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		auto o = mrpt::obs::CObservationImage::Create();
		o->sensorLabel = label_;
		if (!mounting_.poseOf(r, cols_, o->cameraPose, why)) return nullptr;
		std::string file;
		if (!readText(file_, r, cols_, file, why)) return nullptr;
		const std::string path = (!file.empty() && file[0] == '/') ? file : data_dir_ + "/" + file;
		// -1: as stored (colour stays colour; 0 would force grayscale). OpenCV may
		// throw on a damaged or empty file: that is this record's rejection.
		bool loaded = false;
		std::string detail;
		try
		{
			loaded = o->image.loadFromFile(path, -1);
		}
		catch (const std::exception& e)
		{
			detail = e.what();
			detail = ": " + detail.substr(0, std::min(detail.find('\n'), std::size_t{200}));
		}
		if (!loaded)
		{
			why = "cannot read image '" + path + "'" + detail;
			return nullptr;
		}
		if (has_camera_)
		{
			double v[6];
			for (int i = 0; i < 6; ++i)
				if (readScalar(camera_[i], r, cols_, v[i], why) != Read::Ok || !std::isfinite(v[i]))
				{
					if (why.empty()) why = "camera parameter missing";
					return nullptr;
				}
			// Casting a negative or huge double to uint32 is undefined behaviour.
			for (int i = 0; i < 2; ++i)
				if (!(v[i] >= 0 && v[i] <= kMaxImageSide) || std::floor(v[i]) != v[i])
				{
					why = std::string("camera ") + (i == 0 ? "ncols" : "nrows") + " " + std::to_string(v[i]) +
					      " is not an integer in 0.." + std::to_string(static_cast<long>(kMaxImageSide));
					return nullptr;
				}
			auto& cam = o->cameraParams;
			cam.ncols = static_cast<uint32_t>(v[0]);
			cam.nrows = static_cast<uint32_t>(v[1]);
			cam.intrinsicParams.setZero();
			cam.fx(v[2]);
			cam.fy(v[3]);
			cam.cx(v[4]);
			cam.cy(v[5]);
			cam.intrinsicParams(2, 2) = 1.0;
			cam.dist.fill(0);
			// An empty name is a name (MRPT's default is ""): the export writes it as an empty cell.
			if (camera_name_.present && !readText(camera_name_, r, cols_, cam.cameraName, why, true))
				return nullptr;
		}
		return o;
	}

 private:
	std::string label_, data_dir_;
	Mounting mounting_;
	TextSpec file_, camera_name_;
	bool has_camera_ = false;
	ScalarSpec camera_[6];
	Columns cols_;
};
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
	if (cls == "imu") return std::make_unique<ImuConverter>(q, s, label);
	if (cls == "dvl") return std::make_unique<DvlConverter>(q, s, label);
	if (cls == "pressure") return std::make_unique<PressureConverter>(q, s, label);
	if (cls == "gps") return std::make_unique<GpsConverter>(q, s, label);
	if (cls == "adcp") return std::make_unique<AdcpConverter>(q, s, label);
	if (cls == "thrusters") return std::make_unique<ThrustersConverter>(q, s, label);
	if (cls == "image") return std::make_unique<ImageConverter>(q, s, label, data_dir);
	if (cls == "usbl") return std::make_unique<UsblConverter>(q, s, label);
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
