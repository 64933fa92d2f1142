#include "adcp.h"

#include <auvnav/obs/CObservationADCP.h>
#include <auvnav/so3.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "plugin_common.h"

namespace auvnav::plugins
{
namespace
{
constexpr double kDefaultSigmaMps = 0.05;  // when neither config nor observation gives one

Measurement skippedCell(std::size_t i, const char* why)
{
	Measurement m;
	m.tag = static_cast<int>(i);
	m.label = why;
	m.skipped = true;
	return m;
}
}  // namespace

double adcpFarWeight(double d_m, double d_max_m)
{
	if (!(d_max_m > 0)) return std::numeric_limits<double>::quiet_NaN();
	return d_m / d_max_m;
}

Eigen::Vector3d adcpCellCurrent(const Eigen::Vector2d& current_vehicle_ne,
                                const Eigen::Vector2d& current_far_ne, double w)
{
	const Eigen::Vector2d c = (1.0 - w) * current_vehicle_ne + w * current_far_ne;
	return {c.x(), c.y(), 0.0};
}

AdcpModel::AdcpModel(const config::Node& cfg, const std::string& /*label*/)
    : GatedModel(cfg),
      position_b_(cfg.vector3("position_m", Eigen::Vector3d(0.659, -0.141, 0.206))),
      R_bs_(rotationFromYprDeg(cfg.vector3("orientation_ypr_deg", Eigen::Vector3d(-22.5, 0, 0)))),
      use_observation_pose_(cfg.boolean("use_observation_pose", false)),
      sigma_mps_(cfg.has("sigma_mps") ? cfg.positive("sigma_mps") : 0.0),
      extra_sigma_mps_(cfg.nonNegative("extra_sigma_mps", 0.02)),
      min_correlation_(cfg.inRange("min_correlation", 0.0, 1.0, 0.5)),
      max_distance_m_(cfg.has("max_distance_m") ? cfg.positive("max_distance_m")
                                                : std::numeric_limits<double>::infinity())
{
	if (position_b_.cwiseAbs().maxCoeff() > 100) cfg.fail("position_m", "lever arm longer than 100 m");
}

PrepareStatus AdcpModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                   std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	const auto* adcp = observationAs<auvnav::obs::CObservationADCP>(obs, why);
	if (!adcp) return PrepareStatus::Invalid;
	if (!(std::isfinite(adcp->cell_size_m) && adcp->cell_size_m > 0))
	{
		why = "cell size not a positive number";
		return PrepareStatus::Invalid;
	}
	if (!(std::isfinite(adcp->blank_distance_m) && adcp->blank_distance_m >= 0))
	{
		why = "blank distance not a non-negative number";
		return PrepareStatus::Invalid;
	}
	if (adcp->cells.empty())
	{
		why = "no cells";
		return PrepareStatus::Skip;
	}
	// The far-current state belongs to the navigator when it fixes its distance
	// (the vehicle current then follows the profile with depth); otherwise the
	// profile's own range.
	const double d_max =
	    ctx.current_far_distance_m > 0
	        ? ctx.current_far_distance_m
	        : adcp->blank_distance_m + static_cast<double>(adcp->cells.size()) * adcp->cell_size_m;
	if (!std::isfinite(d_max))
	{
		why = "profile range not finite";
		return PrepareStatus::Invalid;
	}

	Eigen::Vector3d r_s = position_b_;
	Eigen::Matrix3d R_bs = R_bs_;
	if (use_observation_pose_)
	{
		r_s = Eigen::Vector3d(adcp->sensorPose.x(), adcp->sensorPose.y(), adcp->sensorPose.z());
		R_bs = adcp->sensorPose.getRotationMatrix().asEigen();
		if (!r_s.allFinite() || !R_bs.allFinite())
		{
			why = "non-finite sensorPose";
			return PrepareStatus::Invalid;
		}
	}

	// σ: configured, else the observation's own if usable, else the default;
	// the profile's representation error in quadrature on top.
	double sigma = sigma_mps_;
	if (!(sigma > 0))
		sigma = (std::isfinite(adcp->velocity_sigma_mps) && adcp->velocity_sigma_mps > 0)
		            ? adcp->velocity_sigma_mps
		            : kDefaultSigmaMps;
	const double var = sigma * sigma + extra_sigma_mps_ * extra_sigma_mps_;

	out.reserve(adcp->cells.size());
	for (std::size_t i = 0; i < adcp->cells.size(); ++i)
	{
		const auto& cell = adcp->cells[i];
		const double d = adcp->cellDistance(i);
		if (!cell.valid)
		{
			out.push_back(skippedCell(i, kSkipInvalid));
			continue;
		}
		if (!(cell.correlation >= min_correlation_))  // NaN correlation fails too
		{
			out.push_back(skippedCell(i, kSkipCorrelation));
			continue;
		}
		if (d > max_distance_m_)
		{
			out.push_back(skippedCell(i, kSkipDistance));
			continue;
		}
		const Eigen::Vector3d v(cell.velocity_s_mps[0], cell.velocity_s_mps[1], cell.velocity_s_mps[2]);
		if (!v.allFinite())
		{
			out.push_back(skippedCell(i, kSkipNonFinite));
			continue;
		}
		Measurement m;
		m.z = v;
		m.R = Eigen::Matrix3d::Identity() * var;
		m.tag = static_cast<int>(i);
		m.label = "cell";
		AdcpCell& c = m.setPayload(AdcpCell{d, d_max, {r_s[0], r_s[1], r_s[2]}, {}});
		Eigen::Map<Eigen::Matrix3d>(c.R_bs) = R_bs;
		out.push_back(std::move(m));
	}
	return PrepareStatus::Ok;
}

bool AdcpModel::doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
                          Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (z_pred.size() != 3) return false;
	const AdcpCell& cell = m.payload<AdcpCell>();
	const double w = adcpFarWeight(cell.distance_m, cell.max_distance_m);
	if (!std::isfinite(w)) return false;
	const Eigen::Map<const Eigen::Vector3d> r_s(cell.r_s);
	const Eigen::Map<const Eigen::Matrix3d> R_bs(cell.R_bs);
	const Eigen::Matrix3d R_bn = x.R_nb.transpose();
	const Eigen::Vector3d omega_eb_b = ctx.omega_ib_b - x.b_w - R_bn * ctx.omega_ie_n;
	// Sensor velocity over ground and water current, both in body axes.
	const Eigen::Vector3d v_s_b = R_bn * x.v_n + omega_eb_b.cross(r_s - ctx.imu_position_b);
	const Eigen::Vector3d c_b = R_bn * adcpCellCurrent(x.current_vehicle_ne, x.current_far_ne, w);
	z_pred = R_bs.transpose() * (c_b - v_s_b);
	z_pred[0] += x.b_adcp[0];
	z_pred[1] += x.b_adcp[1];
	return true;
}

bool AdcpModel::doAffineSlopes(const NavState& x, const Measurement& m, const FilterContext& ctx, int from,
                               int to, Eigen::Ref<Eigen::MatrixXd> At) const
{
	if (At.cols() != 3 || At.rows() != to - from) return false;
	const AdcpCell& cell = m.payload<AdcpCell>();
	const double w = adcpFarWeight(cell.distance_m, cell.max_distance_m);
	if (!std::isfinite(w)) return false;
	const Eigen::Map<const Eigen::Vector3d> r_s(cell.r_s);
	const Eigen::Map<const Eigen::Matrix3d> R_bs(cell.R_bs);
	const Eigen::Vector3d lever_b = r_s - ctx.imu_position_b;
	// h = R_sb (R_bn (c(w) − v_n) − (ω_ib − b_w − R_bn ω_ie) × ℓ) + b_adcp, so
	// along b_w,i: R_sb (e_i × ℓ); along v_n,i: −R_sb R_bn e_i; along the
	// currents: (1 − w) and w times R_sb R_bn e_i; along b_adcp,i: e_i.
	const Eigen::Matrix3d R_sn = R_bs.transpose() * x.R_nb.transpose();
	auto put = [&](int i, const Eigen::Vector3d& slope)
	{
		if (i >= from && i < to) At.row(i - from) = slope.transpose();
	};
	for (int i = 0; i < 3; ++i)
	{
		put(idx::gyro_bias + i, R_bs.transpose() * Eigen::Vector3d::Unit(i).cross(lever_b));
		put(idx::vel + i, -R_sn.col(i));
	}
	for (int i = 0; i < 2; ++i)
	{
		put(idx::current_vehicle + i, (1.0 - w) * R_sn.col(i));
		put(idx::current_far + i, w * R_sn.col(i));
		put(idx::adcp_bias + i, Eigen::Vector3d::Unit(i));
	}
	return true;
}

}  // namespace auvnav::plugins
