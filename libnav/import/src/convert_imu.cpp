// The IMU converter: angular rate, specific force, magnetic field, orientation
// and temperature into mrpt::obs::CObservationIMU.
#include <mrpt/obs/CObservationIMU.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>

#include "converter_support.h"
#include "sensor_converters.h"

namespace auvnav::import::detail
{
namespace
{
constexpr double kGaussPerTesla = 1e4;  // MRPT's CObservationIMU keeps IMU_MAG_* in gauss

class ImuConverter final : public AxisMappedConverter
{
 public:
	ImuConverter(const config::Node& q, const config::Node& s, const std::string& label)
	    : AxisMappedConverter(s, label)
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
		if (quat_[0].present && !axes().isIdentity(1e-12))
			s.fail("axes",
			       "not applicable to orientation (a quaternion of the source frame): give the orientation "
			       "in the sensor frame without axes, or import it as a separate sensor");
	}

	mrpt::obs::CObservation::Ptr convert(const Record& r, std::string& why) override
	{
		using namespace mrpt::obs;
		auto o = CObservationIMU::Create();
		if (!labelAndMount(*o, r, why)) return nullptr;
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
		const Eigen::Vector3d v_s = axes() * v * scale;
		for (int k = 0; k < 3; ++k) o.set(idx[static_cast<std::size_t>(k)], v_s[k]);
		return true;
	}

	std::vector<ScalarSpec> gyro_, acc_, mag_, quat_;
	ScalarSpec temp_;
};
}  // namespace

const ConverterFactory makeImuConverter = factoryOf<ImuConverter>;

}  // namespace auvnav::import::detail
