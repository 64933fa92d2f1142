#include "usbl.h"

#include <auvnav/earth.h>
#include <auvnav/obs/CObservationUSBL.h>

#include <cmath>

#include "plugin_common.h"

namespace auvnav::plugins
{
UsblModel::UsblModel(const config::Node& cfg, const std::string& label)
    : label_(label),
      position_b_(cfg.vector3("position_m", Eigen::Vector3d::Zero())),
      sigma_m_(cfg.positive("sigma_m", 2.0)),
      sigma_range_fraction_(cfg.inRange("sigma_range_fraction", 0.0, 1.0, 0.01)),
      depth_sigma_m_(cfg.positive("depth_sigma_m", 1.0)),
      use_reported_covariance_(cfg.boolean("use_reported_covariance", true)),
      use_depth_(cfg.boolean("use_depth", false)),
      gate_probability_(gateProbabilityFrom(cfg))
{
	if (position_b_.cwiseAbs().maxCoeff() > 100) cfg.fail("position_m", "lever arm longer than 100 m");
	bias_ = horizontalFixBias(cfg);
}

double UsblModel::doMeasurementTime(const mrpt::obs::CObservation& obs, double stamp_s) const
{
	const auto* u = dynamic_cast<const obs::CObservationUSBL*>(&obs);
	if (!u || u->measurement_time == INVALID_TIMESTAMP) return stamp_s;
	return mrpt::Clock::toDouble(u->measurement_time);
}

PrepareStatus UsblModel::decodeFix(const mrpt::obs::CObservation& o, const FilterContext& ctx,
                                   Eigen::Vector3d& p_n, Eigen::Matrix3d& C_n, std::string& why) const
{
	const auto* u = observationAs<obs::CObservationUSBL>(o, why);
	if (!u) return PrepareStatus::Invalid;
	if (!ctx.frame)
	{
		why = "no navigation frame in the filter context";
		return PrepareStatus::Invalid;
	}
	const Eigen::Vector3d pos(u->position[0], u->position[1], u->position[2]);
	// Depth is used only with use_depth: a fix without one is still a fix.
	if (!pos.head<2>().allFinite() || (use_depth_ && !std::isfinite(pos.z())))
	{
		why = "non-finite position";
		return PrepareStatus::Invalid;
	}
	if (u->frame == obs::UsblFrame::Geodetic)
	{
		if (std::abs(pos.x()) > 90 || std::abs(pos.y()) > 180)
		{
			why = "latitude/longitude out of range";
			return PrepareStatus::Invalid;
		}
		earth::Geodetic g;
		g.lat_rad = pos.x() * kDeg;
		g.lon_rad = pos.y() * kDeg;
		// Depth below the origin's height (≈ sea level); without a depth the
		// origin's height does (it moves north/east by ~1e-7 per metre).
		g.h_m = ctx.frame->origin().h_m - (std::isfinite(pos.z()) ? pos.z() : 0.0);
		p_n = ctx.frame->toNed(g);
		p_n.z() = pos.z();  // depth, as the pressure sensor's (not the tangent plane's curvature)
	}
	else
		p_n = pos;
	if (!p_n.head<2>().allFinite())
	{
		why = "position conversion failed";
		return PrepareStatus::Invalid;
	}
	if (use_reported_covariance_ && u->hasCovariance())
	{
		C_n = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(u->covariance_ned_m2.data());
		C_n = 0.5 * (C_n + C_n.transpose()).eval();
	}
	else
	{
		const double range = std::isfinite(u->slant_range_m) ? std::max(u->slant_range_m, 0.0) : 0.0;
		const double s = std::hypot(sigma_m_, sigma_range_fraction_ * range);
		C_n = Eigen::Vector3d(s * s, s * s, depth_sigma_m_ * depth_sigma_m_).asDiagonal();
	}
	return PrepareStatus::Ok;
}

bool UsblModel::doInitialFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, InitialFix& out)
{
	Eigen::Vector3d p_n;
	Eigen::Matrix3d C_n;
	std::string why;
	if (decodeFix(obs, ctx, p_n, C_n, why) != PrepareStatus::Ok) return false;
	out.p_n = p_n;
	out.r_b = position_b_;
	return true;
}

PrepareStatus UsblModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                   std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	Eigen::Vector3d p_n;
	Eigen::Matrix3d C_n;
	const PrepareStatus decoded = decodeFix(obs, ctx, p_n, C_n, why);
	if (decoded != PrepareStatus::Ok) return decoded;
	Measurement m;
	const int dim = use_depth_ ? 3 : 2;
	m.z = p_n.head(dim);
	m.R = C_n.topLeftCorner(dim, dim);
	m.label = "fix";
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

bool UsblModel::doPredict(const NavState& x, const Measurement& /*m*/, const FilterContext& ctx,
                          Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	const int dim = use_depth_ ? 3 : 2;
	if (z_pred.size() != dim) return false;
	Eigen::Vector3d p = x.p_n + x.R_nb * (position_b_ - ctx.imu_position_b);
	addFixBias(x, bias_, p);
	z_pred = p.head(dim);
	return true;
}

}  // namespace auvnav::plugins
