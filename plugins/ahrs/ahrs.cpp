#include "ahrs.h"

#include <auvnav/so3.h>
#include <mrpt/obs/CObservationIMU.h>

#include <Eigen/Geometry>
#include <cmath>

#include "level_heading.h"
#include "plugin_common.h"

namespace auvnav::plugins
{
namespace
{
/** From prepare to h: heading only, the level reference direction u_b
 *  (v[0..2]); full attitude, the measured R_nb as a quaternion (w, x, y, z). */
struct AhrsReference
{
	double v[4];
};
}  // namespace

AhrsModel::AhrsModel(const config::Node& cfg, const std::string& /*label*/) : GatedModel(cfg)
{
	// A misspelled key must not fall back to its default silently.
	cfg.allowOnly({"reference_frame", "heading_reference", "declination_deg", "orientation_ypr_deg",
	               "sigma_roll_deg", "sigma_pitch_deg", "sigma_heading_deg", "heading_only",
	               "gate_probability", "min_interval_s", "config_dir"});
	const std::string frame = cfg.string("reference_frame", "ned");
	Eigen::Matrix3d R_n_ref;  // reference axes in a NED frame of the same north
	if (frame == "ned")
		R_n_ref.setIdentity();
	else if (frame == "enu")
		R_n_ref << 0, 1, 0, 1, 0, 0, 0, 0, -1;  // x east, y north, z up → NED
	else
		cfg.fail("reference_frame", "expected 'ned' or 'enu', got '" + frame + "'");

	const std::string heading = cfg.string("heading_reference", "magnetic");
	const double declination_rad = cfg.inRange("declination_deg", -180.0, 180.0, 0.0) * kDeg;
	if (heading == "true")
	{
		if (cfg.has("declination_deg") && declination_rad != 0)
			cfg.fail("declination_deg",
			         "given with heading_reference 'true' (it applies to 'magnetic' only)");
	}
	else if (heading != "magnetic")
		cfg.fail("heading_reference", "expected 'true' or 'magnetic', got '" + heading + "'");
	// Magnetic north lies D east of true north: the magnetic frame is the true
	// one turned by D about down.
	const Eigen::Matrix3d R_true_mag = heading == "magnetic"
	                                       ? so3::Exp(Eigen::Vector3d(0, 0, declination_rad))
	                                       : Eigen::Matrix3d::Identity();
	R_nr_ = R_true_mag * R_n_ref;

	if (cfg.has("orientation_ypr_deg")) R_bs_config_ = rotationFromYprDeg(cfg.vector3("orientation_ypr_deg"));
	sigma_roll_rad_ = cfg.inRange("sigma_roll_deg", 1e-3, 90.0, 0.5) * kDeg;
	sigma_pitch_rad_ = cfg.inRange("sigma_pitch_deg", 1e-3, 90.0, 0.5) * kDeg;
	sigma_heading_rad_ = cfg.inRange("sigma_heading_deg", 1e-3, 180.0, 2.0) * kDeg;
	heading_only_ = cfg.boolean("heading_only", false);
	min_interval_ = MinInterval(cfg);
}

std::optional<Eigen::Matrix3d> AhrsModel::measuredAttitude(const mrpt::obs::CObservation& obs,
                                                           std::string& why) const
{
	using namespace mrpt::obs;
	const auto* imu = observationAs<CObservationIMU>(obs, why);
	if (!imu) return std::nullopt;
	const auto finite = [&](std::initializer_list<TIMUDataIndex> fields, const char* what)
	{
		for (const auto f : fields)
			if (!std::isfinite(imu->get(f)))
			{
				why = std::string("non-finite ") + what;
				return false;
			}
		return true;
	};
	Eigen::Matrix3d R_rs;
	const int quat_fields = imu->has(IMU_ORI_QUAT_W) + imu->has(IMU_ORI_QUAT_X) + imu->has(IMU_ORI_QUAT_Y) +
	                        imu->has(IMU_ORI_QUAT_Z);
	if (quat_fields == 4)
	{
		if (!finite({IMU_ORI_QUAT_W, IMU_ORI_QUAT_X, IMU_ORI_QUAT_Y, IMU_ORI_QUAT_Z}, "quaternion"))
			return std::nullopt;
		Eigen::Quaterniond q(imu->get(IMU_ORI_QUAT_W), imu->get(IMU_ORI_QUAT_X), imu->get(IMU_ORI_QUAT_Y),
		                     imu->get(IMU_ORI_QUAT_Z));
		// Rounded output is renormalised; anything further off is not an attitude.
		if (!(std::abs(q.norm() - 1) <= 0.1))
		{
			why = "quaternion norm " + std::to_string(q.norm()) + " is not 1";
			return std::nullopt;
		}
		R_rs = q.normalized().toRotationMatrix();
	}
	else if (imu->has(IMU_YAW) && imu->has(IMU_PITCH) && imu->has(IMU_ROLL))
	{
		if (!finite({IMU_YAW, IMU_PITCH, IMU_ROLL}, "yaw/pitch/roll")) return std::nullopt;
		// Angles as the device reports them, turned into a rotation once here;
		// the filter model itself never sees them.
		R_rs = (Eigen::AngleAxisd(imu->get(IMU_YAW), Eigen::Vector3d::UnitZ()) *
		        Eigen::AngleAxisd(imu->get(IMU_PITCH), Eigen::Vector3d::UnitY()) *
		        Eigen::AngleAxisd(imu->get(IMU_ROLL), Eigen::Vector3d::UnitX()))
		           .toRotationMatrix();
	}
	else
	{
		why = quat_fields > 0 ? "incomplete quaternion (IMU_ORI_QUAT_W/X/Y/Z)"
		                      : "neither IMU_ORI_QUAT_W/X/Y/Z nor IMU_YAW/IMU_PITCH/IMU_ROLL present";
		return std::nullopt;
	}
	const Eigen::Matrix3d R_bs = R_bs_config_ ? *R_bs_config_ : imu->sensorPose.getRotationMatrix().asEigen();
	if (!R_bs.allFinite())
	{
		why = "non-finite sensorPose";
		return std::nullopt;
	}
	return so3::normalized(R_nr_ * R_rs * R_bs.transpose());
}

PrepareStatus AhrsModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                   std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	const auto R_meas = measuredAttitude(obs, why);
	if (!R_meas) return PrepareStatus::Invalid;
	const double t_obs = mrpt::Clock::toDouble(obs.timestamp);
	if (min_interval_.tooSoon(t_obs, "attitude", why)) return PrepareStatus::Skip;
	min_interval_.markUsed(t_obs);

	Measurement m;
	if (heading_only_)
	{
		// The body direction the mean (or, before there is one, the AHRS
		// itself) places horizontally: no roll/pitch information.
		const Eigen::Vector3d u_b = levelReferenceDirection_b(ctx.mean ? ctx.mean->R_nb : *R_meas);
		m.z = Eigen::VectorXd::Constant(1, azimuthOf(*R_meas, u_b));
		m.R = Eigen::MatrixXd::Constant(1, 1, sigma_heading_rad_ * sigma_heading_rad_);
		m.setPayload(AhrsReference{{u_b.x(), u_b.y(), u_b.z(), 0}});
		m.label = "heading";
	}
	else
	{
		// Euler-angle errors of the device → NED rotation axes:
		// δθ_n = δroll·(body x) + δpitch·(yawed y) + δheading·(down).
		Eigen::Matrix3d J;
		J.col(0) = R_meas->col(0);
		Eigen::Vector3d y_lev(-R_meas->col(0).y(), R_meas->col(0).x(), 0);  // down × body x
		J.col(1) =
		    y_lev.norm() > 1e-9 ? Eigen::Vector3d(y_lev.normalized()) : Eigen::Vector3d(R_meas->col(1));
		J.col(2) = Eigen::Vector3d::UnitZ();
		const Eigen::Vector3d var(sigma_roll_rad_ * sigma_roll_rad_, sigma_pitch_rad_ * sigma_pitch_rad_,
		                          sigma_heading_rad_ * sigma_heading_rad_);
		Eigen::Matrix3d R = J * var.asDiagonal() * J.transpose();
		R += Eigen::Matrix3d::Identity() * (1e-6 * var.maxCoeff());
		m.R = 0.5 * (R + R.transpose());
		m.z = Eigen::Vector3d::Zero();
		const Eigen::Quaterniond q(*R_meas);
		m.setPayload(AhrsReference{{q.w(), q.x(), q.y(), q.z()}});
		m.label = "attitude";
	}
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

bool AhrsModel::doPredict(const NavState& x, const Measurement& m, const FilterContext& /*ctx*/,
                          Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (heading_only_)
	{
		if (z_pred.size() != 1) return false;
		const double* u_b = m.payload<AhrsReference>().v;
		z_pred[0] = azimuthOf(x.R_nb, Eigen::Vector3d(u_b[0], u_b[1], u_b[2]));
	}
	else
	{
		if (z_pred.size() != 3) return false;
		const double* q = m.payload<AhrsReference>().v;
		const Eigen::Matrix3d R_meas =
		    Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
		z_pred = so3::Log(x.R_nb * R_meas.transpose());
	}
	return z_pred.allFinite();
}

}  // namespace auvnav::plugins
