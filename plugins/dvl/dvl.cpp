#include "dvl.h"

#include <auvnav/obs/CObservationDVL.h>
#include <auvnav/so3.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>

#include "plugin_common.h"

namespace auvnav::plugins
{
DvlModel::DvlModel(const config::Node& cfg, const std::string& label)
	: label_(label),
	  position_b_(cfg.vector3("position_m", Eigen::Vector3d(0.659, -0.141, 0.206))),
	  R_bs_(rotationFromYprDeg(cfg.vector3("orientation_ypr_deg", Eigen::Vector3d(-22.5, 0, 0)))),
	  use_observation_pose_(cfg.boolean("use_observation_pose", false)),
	  sigma_mps_(cfg.positive("sigma_mps", 0.02)),
	  extra_sigma_mps_(cfg.nonNegative("extra_sigma_mps", 0.005)),
	  gate_probability_(gateProbabilityFrom(cfg))
{
	if (position_b_.cwiseAbs().maxCoeff() > 100) cfg.fail("position_m", "lever arm longer than 100 m");
}

PrepareStatus DvlModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& /*ctx*/,
								  std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	const auto* dvl = dynamic_cast<const auvnav::obs::CObservationDVL*>(&obs);
	if (!dvl)
	{
		why = std::string("expected auvnav::obs::CObservationDVL, got ") + obs.GetRuntimeClass()->className;
		return PrepareStatus::Invalid;
	}
	if (!dvl->bottom_lock)
	{
		why = "no bottom lock";
		return PrepareStatus::Skip;
	}
	const Eigen::Vector3d v(dvl->velocity_s_mps[0], dvl->velocity_s_mps[1], dvl->velocity_s_mps[2]);
	if (!v.allFinite())
	{
		why = "non-finite velocity";
		return PrepareStatus::Invalid;
	}

	Eigen::Vector3d r_s = position_b_;
	Eigen::Matrix3d R_bs = R_bs_;
	if (use_observation_pose_)
	{
		r_s = Eigen::Vector3d(dvl->sensorPose.x(), dvl->sensorPose.y(), dvl->sensorPose.z());
		R_bs = dvl->sensorPose.getRotationMatrix().asEigen();
		if (!r_s.allFinite() || !R_bs.allFinite())
		{
			why = "non-finite sensorPose";
			return PrepareStatus::Invalid;
		}
	}

	// The sensor's covariance if it is a usable one (finite, symmetric,
	// positive semi-definite, not all zero), else the configured σ.
	Eigen::Matrix3d C = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(dvl->velocity_cov.data());
	bool cov_ok = C.allFinite() && C.cwiseAbs().maxCoeff() > 0 &&
				  (C - C.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * C.cwiseAbs().maxCoeff();
	if (cov_ok)
	{
		C = 0.5 * (C + C.transpose()).eval();
		const double min_ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C, Eigen::EigenvaluesOnly).eigenvalues()[0];
		cov_ok = min_ev >= 0 && min_ev + extra_sigma_mps_ * extra_sigma_mps_ > 0;
	}
	if (!cov_ok) C = Eigen::Matrix3d::Identity() * (sigma_mps_ * sigma_mps_);

	Measurement m;
	m.z = v;
	m.R = C + Eigen::Matrix3d::Identity() * (extra_sigma_mps_ * extra_sigma_mps_);
	m.label = cov_ok ? "velocity" : "velocity_default_cov";
	const Eigen::Vector3d rotvec = so3::Log(R_bs);
	for (int i = 0; i < 3; ++i)
	{
		m.aux[i] = r_s[i];
		m.aux[3 + i] = rotvec[i];
	}
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

bool DvlModel::doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
						 Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (z_pred.size() != 3) return false;
	const Eigen::Vector3d r_s(m.aux[0], m.aux[1], m.aux[2]);
	const Eigen::Matrix3d R_bs = so3::Exp(Eigen::Vector3d(m.aux[3], m.aux[4], m.aux[5]));
	const Eigen::Matrix3d R_bn = x.R_nb.transpose();
	const Eigen::Vector3d omega_eb_b = ctx.omega_ib_b - x.b_w - R_bn * ctx.omega_ie_n;
	const Eigen::Vector3d v_s_b = R_bn * x.v_n + omega_eb_b.cross(r_s - ctx.imu_position_b);
	z_pred = R_bs.transpose() * v_s_b;
	return true;
}

}  // namespace auvnav::plugins
