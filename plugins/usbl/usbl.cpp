#include "usbl.h"

#include <auvnav/earth.h>
#include <auvnav/obs/CObservationUSBL.h>

#include <cmath>

#include "plugin_common.h"

namespace auvnav::plugins
{
UsblModel::UsblModel(const config::Node& cfg, const std::string& /*label*/)
    : PositionFixModel(cfg, Eigen::Vector3d::Zero(),
                       /*measured_axes=*/cfg.boolean("use_depth", false) ? 3 : 2),
      sigma_m_(cfg.positive("sigma_m", 2.0)),
      sigma_range_fraction_(cfg.inRange("sigma_range_fraction", 0.0, 1.0, 0.01)),
      depth_sigma_m_(cfg.positive("depth_sigma_m", 1.0)),
      use_reported_covariance_(cfg.boolean("use_reported_covariance", true))
{
}

double UsblModel::doMeasurementTime(const mrpt::obs::CObservation& obs, double stamp_s) const
{
	const auto* u = dynamic_cast<const obs::CObservationUSBL*>(&obs);
	if (!u || u->measurement_time == INVALID_TIMESTAMP) return stamp_s;
	return mrpt::Clock::toDouble(u->measurement_time);
}

PrepareStatus UsblModel::decodeFix(const mrpt::obs::CObservation& o, const FilterContext& ctx, UsblFix& fix,
                                   std::string& why) const
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
	if (!pos.head<2>().allFinite() || (useDepth() && !std::isfinite(pos.z())))
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
		fix.p_n = ctx.frame->toNed(g);
		fix.p_n.z() = pos.z();  // depth, as the pressure sensor's (not the tangent plane's curvature)
	}
	else
		fix.p_n = pos;
	if (!fix.p_n.head<2>().allFinite())
	{
		why = "position conversion failed";
		return PrepareStatus::Invalid;
	}
	if (use_reported_covariance_ && u->hasCovariance())
	{
		const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> C_n(u->covariance_ned_m2.data());
		fix.C_n = 0.5 * (C_n + C_n.transpose());
	}
	else
	{
		const double range = std::isfinite(u->slant_range_m) ? std::max(u->slant_range_m, 0.0) : 0.0;
		const double s = std::hypot(sigma_m_, sigma_range_fraction_ * range);
		fix.C_n = Eigen::Vector3d(s * s, s * s, depth_sigma_m_ * depth_sigma_m_).asDiagonal();
	}
	return PrepareStatus::Ok;
}

PrepareStatus UsblModel::measureFix(const UsblFix& fix, const mrpt::obs::CObservation& /*obs*/,
                                    const FilterContext& /*ctx*/, std::vector<Measurement>& out,
                                    std::string& /*why*/)
{
	const int axes = measuredAxes();
	return appendMeasurement(out, fix.p_n.head(axes), fix.C_n.topLeftCorner(axes, axes), "fix");
}

}  // namespace auvnav::plugins
