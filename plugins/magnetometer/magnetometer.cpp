#include "magnetometer.h"

#include <auvnav/state_block_config.h>

#include <mrpt/obs/CObservationIMU.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <sstream>

#include "level_heading.h"
#include "plugin_common.h"

namespace auvnav::plugins
{
namespace
{
constexpr double kMicroteslaPerGauss = 100.0;  // the contract's unit: IMU_MAG_* in gauss

/** The 3 × 3 matrix under `key` (9 numbers, row-major), or `fallback`. */
Eigen::Matrix3d matrix3(const config::Node& cfg, const std::string& key, const Eigen::Matrix3d& fallback)
{
	if (!cfg.has(key)) return fallback;
	const std::vector<double> v = cfg.numbers(key);
	if (v.size() != 9)
		cfg.fail(key, "expected 9 numbers (a 3x3 matrix, row-major), got " + std::to_string(v.size()));
	Eigen::Matrix3d M;
	for (int i = 0; i < 9; ++i) M(i / 3, i % 3) = v[static_cast<std::size_t>(i)];
	return M;
}
}  // namespace

Eigen::Vector3d earthField_n(double total_ut, double declination_rad, double inclination_rad)
{
	return total_ut * Eigen::Vector3d(std::cos(inclination_rad) * std::cos(declination_rad),
	                                  std::cos(inclination_rad) * std::sin(declination_rad),
	                                  std::sin(inclination_rad));
}

Eigen::Vector3d predictedReading_s(const Eigen::Matrix3d& R_nb, const Eigen::Matrix3d& R_bs,
                                   const Eigen::Vector3d& m_n_ut, const Eigen::Vector3d& b_hard_ut,
                                   const Eigen::Matrix3d& S_soft)
{
	return b_hard_ut + S_soft * (R_bs.transpose() * (R_nb.transpose() * m_n_ut));
}

MagnetometerModel::MagnetometerModel(const config::Node& cfg, const std::string& /*label*/) : GatedModel(cfg)
{
	// A misspelled key must not fall back to its default silently.
	cfg.allowOnly({"mode", "field_ut", "declination_deg", "inclination_deg", "hard_iron_ut", "soft_iron",
	               "noise_ut", "heading_sigma_deg", "norm_tolerance", "dip_tolerance_deg", "gate_probability",
	               "min_interval_s", "states", "config_dir"});
	const std::string mode = cfg.string("mode", "heading");
	if (mode == "heading")
		mode_ = Mode::Heading;
	else if (mode == "vector")
		mode_ = Mode::Vector;
	else
		cfg.fail("mode", "expected 'heading' or 'vector', got '" + mode + "'");

	field_ut_ = cfg.inRange("field_ut", 1.0, 100.0, 49.6);
	declination_rad_ = cfg.inRange("declination_deg", -180.0, 180.0, 3.0) * kDeg;
	inclination_rad_ = cfg.inRange("inclination_deg", -90.0, 90.0, 68.0) * kDeg;
	m_n_ut_ = earthField_n(field_ut_, declination_rad_, inclination_rad_);
	if (mode_ == Mode::Heading && std::abs(inclination_rad_) > 85 * kDeg)
		cfg.fail("inclination_deg", "within 5 deg of vertical the horizontal field cannot give a heading");

	b_hard_ut_ = cfg.vector3("hard_iron_ut", Eigen::Vector3d::Zero());
	if (b_hard_ut_.cwiseAbs().maxCoeff() > 5000)
		cfg.fail("hard_iron_ut", "beyond +-5000 uT (50 G): not a magnetometer offset");

	S_soft_ = matrix3(cfg, "soft_iron", Eigen::Matrix3d::Identity());
	const Eigen::JacobiSVD<Eigen::Matrix3d> svd(S_soft_);
	const Eigen::Vector3d& sv = svd.singularValues();
	// A reflection would be an axis swapped in the mounting, not soft iron; a
	// near-singular or wildly scaling matrix is a units or typing mistake.
	if (!(S_soft_.determinant() > 0))
		cfg.fail("soft_iron", "determinant <= 0 (a reflection or singular matrix)");
	if (!(sv.minCoeff() >= 0.2 && sv.maxCoeff() <= 5.0))
		cfg.fail("soft_iron", "singular values must lie in [0.2, 5] (got " + std::to_string(sv.minCoeff()) +
		                          " .. " + std::to_string(sv.maxCoeff()) + ")");
	S_soft_inv_ = S_soft_.inverse();

	noise_ut_ = cfg.inRange("noise_ut", 1e-3, 100.0, 2.0);
	heading_sigma_rad_ = cfg.inRange("heading_sigma_deg", 1e-3, 90.0, 3.0) * kDeg;
	norm_tolerance_ = cfg.inRange("norm_tolerance", 0.0, 10.0, 0.1);
	if (!(norm_tolerance_ > 0))
		cfg.fail("norm_tolerance", "must be > 0 (use a large value to disable the check)");
	dip_tolerance_rad_ = cfg.inRange("dip_tolerance_deg", 0.0, 180.0, 10.0) * kDeg;
	if (!(dip_tolerance_rad_ > 0))
		cfg.fail("dip_tolerance_deg", "must be > 0 (use 180 to disable the check)");
	if (cfg.has("states"))
	{
		const auto st = cfg.child("states");
		st.allowOnly({"heading_bias"});
		if (st.has("heading_bias"))
		{
			if (mode_ != Mode::Heading) st.fail("heading_bias", "a heading bias state needs mode: heading");
			heading_bias_ = PluginState(
			    stateBlockFromConfig(st.child("heading_bias"), "heading_bias", {""}, "_deg", kDeg));
		}
	}
	min_interval_ = MinInterval(cfg);
}

PrepareStatus MagnetometerModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                           std::vector<Measurement>& out, std::string& why)
{
	using namespace mrpt::obs;
	out.clear();
	const auto* imu = observationAs<CObservationIMU>(obs, why);
	if (!imu) return PrepareStatus::Invalid;
	Eigen::Vector3d m_s_ut;
	const TIMUDataIndex fields[3] = {IMU_MAG_X, IMU_MAG_Y, IMU_MAG_Z};
	const char* names[3] = {"IMU_MAG_X", "IMU_MAG_Y", "IMU_MAG_Z"};
	for (int k = 0; k < 3; ++k)
	{
		if (!imu->has(fields[k]))
		{
			why = std::string("missing ") + names[k];
			return PrepareStatus::Invalid;
		}
		m_s_ut[k] = imu->get(fields[k]) * kMicroteslaPerGauss;
		if (!std::isfinite(m_s_ut[k]))
		{
			why = std::string("non-finite ") + names[k];
			return PrepareStatus::Invalid;
		}
	}
	const Eigen::Matrix3d R_bs = imu->sensorPose.getRotationMatrix().asEigen();
	if (!R_bs.allFinite())
	{
		why = "non-finite sensorPose";
		return PrepareStatus::Invalid;
	}

	// Disturbance gate on the calibrated field: norm first (needs no attitude).
	const Eigen::Vector3d m_c = S_soft_inv_ * (m_s_ut - b_hard_ut_);
	const double norm = m_c.norm();
	if (!(std::abs(norm - field_ut_) <= norm_tolerance_ * field_ut_))
	{
		++disturbed_;
		std::ostringstream s;
		s.precision(3);
		s << "disturbed: calibrated field norm " << norm << " uT vs " << field_ut_ << " uT (tolerance "
		  << 100 * norm_tolerance_ << " %)";
		why = s.str();
		return PrepareStatus::Skip;
	}
	const Eigen::Vector3d m_b = R_bs * m_c;
	if (ctx.mean)
	{
		const Eigen::Vector3d m_n_est = ctx.mean->R_nb * m_b;
		const double dip = std::atan2(m_n_est.z(), m_n_est.head<2>().norm());
		if (!(std::abs(dip - inclination_rad_) <= dip_tolerance_rad_))
		{
			++disturbed_;
			std::ostringstream s;
			s.precision(3);
			s << "disturbed: dip " << dip / kDeg << " deg vs " << inclination_rad_ / kDeg
			  << " deg (tolerance " << dip_tolerance_rad_ / kDeg << " deg)";
			why = s.str();
			return PrepareStatus::Skip;
		}
	}
	else if (mode_ == Mode::Heading)
	{
		why = "heading mode needs the filter's attitude for tilt compensation";
		return PrepareStatus::Skip;
	}

	// Rate limit after the checks, so that a disturbed reading does not hold
	// back the next good one.
	const double t_obs = mrpt::Clock::toDouble(obs.timestamp);
	if (min_interval_.tooSoon(t_obs, "reading", why)) return PrepareStatus::Skip;
	min_interval_.markUsed(t_obs);

	Measurement m;
	if (mode_ == Mode::Vector)
	{
		m.z = m_s_ut;
		m.R = Eigen::Matrix3d::Identity() * (noise_ut_ * noise_ut_);
		const Eigen::Quaterniond q_bs(R_bs);
		m.setPayload(MountingRotation{q_bs.w(), q_bs.x(), q_bs.y(), q_bs.z()});
		m.label = "field";
	}
	else
	{
		const Eigen::Matrix3d& R_ref = ctx.mean->R_nb;
		const Eigen::Vector3d m_n_est = R_ref * m_b;
		const double alpha = std::atan2(m_n_est.y(), m_n_est.x());  // measured field azimuth per the mean
		const Eigen::Vector3d u_b = levelReferenceDirection_b(R_ref);
		// The mean's heading turned by what the field says is missing (D − α).
		m.z = Eigen::VectorXd::Constant(1, wrapAngle(azimuthOf(R_ref, u_b) + declination_rad_ - alpha));
		m.R = Eigen::MatrixXd::Constant(1, 1, heading_sigma_rad_ * heading_sigma_rad_);
		m.setPayload(ReferenceDirection{u_b.x(), u_b.y(), u_b.z()});
		m.label = "heading";
	}
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

bool MagnetometerModel::doPredict(const NavState& x, const Measurement& m, const FilterContext& /*ctx*/,
                                  Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (mode_ == Mode::Vector)
	{
		if (z_pred.size() != 3) return false;
		const auto& q = m.payload<MountingRotation>();
		const Eigen::Quaterniond q_bs(q.w, q.x, q.y, q.z);
		z_pred =
		    predictedReading_s(x.R_nb, q_bs.normalized().toRotationMatrix(), m_n_ut_, b_hard_ut_, S_soft_);
	}
	else
	{
		if (z_pred.size() != 1) return false;
		const auto& u = m.payload<ReferenceDirection>();
		z_pred[0] = azimuthOf(x.R_nb, Eigen::Vector3d(u.x, u.y, u.z));
		z_pred[0] += heading_bias_.valueOr(x, 0.0);
	}
	return z_pred.allFinite();
}

}  // namespace auvnav::plugins
