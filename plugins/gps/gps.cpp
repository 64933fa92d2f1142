#include "gps.h"

#include <auvnav/earth.h>
#include <mrpt/obs/CObservationGPS.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "plugin_common.h"

namespace auvnav::plugins
{
GpsModel::GpsModel(const config::Node& cfg, const std::string& /*label*/)
    : PositionFixModel(cfg, Eigen::Vector3d(-0.3, 0, -0.6), /*measured_axes=*/2),
      sigma_m_(cfg.positive("sigma_m", 3.0)),
      scale_by_hdop_(cfg.boolean("scale_by_hdop", false)),
      min_interval_(cfg),
      correlated_sigma_m_(cfg.inRange("correlated_sigma_m", 0.0, 1000.0, 0.0)),
      correlation_time_s_(cfg.positive("correlation_time_s", 60.0))
{
	if (bias().enabled() && correlated_sigma_m_ > 0)
		cfg.fail("correlated_sigma_m",
		         "the correlated error is modelled by states.bias already (give one of them, not both)");
}

PrepareStatus GpsModel::decodeFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, GgaFix& fix,
                                  std::string& why) const
{
	using mrpt::obs::gnss::Message_NMEA_GGA;
	const auto* gps = observationAs<mrpt::obs::CObservationGPS>(obs, why);
	if (!gps) return PrepareStatus::Invalid;
	if (!gps->has_GGA_datum())
	{
		why = "no GGA message";
		return PrepareStatus::Skip;
	}
	const auto& f = gps->getMsgByClass<Message_NMEA_GGA>().fields;
	if (f.fix_quality == 0)
	{
		why = "no fix (GGA fix quality 0)";
		return PrepareStatus::Skip;
	}
	if (!std::isfinite(f.latitude_degrees) || !std::isfinite(f.longitude_degrees) ||
	    std::abs(f.latitude_degrees) > 90 || std::abs(f.longitude_degrees) > 180)
	{
		why = "invalid latitude/longitude";
		return PrepareStatus::Invalid;
	}
	if (!ctx.frame)
	{
		why = "no navigation frame in the filter context";
		return PrepareStatus::Invalid;
	}
	earth::Geodetic geo;
	geo.lat_rad = f.latitude_degrees * kDeg;
	geo.lon_rad = f.longitude_degrees * kDeg;
	// GGA altitude is above mean sea level; + geoid separation = ellipsoidal
	// height. It only shifts north/east by ~1e-7 per metre: if it is missing,
	// the origin's height will do.
	const double h = f.altitude_meters + f.geoidal_distance;
	geo.h_m = std::isfinite(h) ? h : ctx.frame->origin().h_m;
	fix.p_n = ctx.frame->toNed(geo);
	if (!fix.p_n.allFinite())
	{
		why = "position conversion failed";
		return PrepareStatus::Invalid;
	}
	fix.hdop = static_cast<double>(f.HDOP);
	return PrepareStatus::Ok;
}

PrepareStatus GpsModel::measureFix(const GgaFix& fix, const mrpt::obs::CObservation& obs,
                                   const FilterContext& ctx, std::vector<Measurement>& out, std::string& why)
{
	// GPS errors are correlated over tens of seconds: using every 1 Hz fix as
	// independent would make the filter overconfident. Use one fix per
	// min_interval_s (the error's correlation time) instead.
	const double t_obs = mrpt::Clock::toDouble(obs.timestamp);
	if (min_interval_.tooSoon(t_obs, "fix", why)) return PrepareStatus::Skip;
	double sigma = sigma_m_;
	if (scale_by_hdop_ && std::isfinite(fix.hdop) && fix.hdop > 0) sigma *= fix.hdop;

	Measurement m;
	m.z = fix.p_n.head<2>();
	m.R = Eigen::Matrix2d::Identity() *
	      (sigma * sigma + correlatedVariance(min_interval_.sinceLastUsed_s(t_obs)));
	// A fix far outside the gate is offered (the filter's gate rejects it and
	// its re-initialisation rule counts it) but does not spend the interval:
	// the next fix is tried, not one min_interval_s later. Else wild fixes at
	// the interval's phase (every 5th of 1 Hz fixes, 30 s apart) would be the
	// only ones ever used.
	if (!likelyOutlier(m, ctx)) min_interval_.markUsed(t_obs);
	m.label = "position";
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

bool GpsModel::likelyOutlier(const Measurement& m, const FilterContext& ctx) const
{
	if (!ctx.mean || !ctx.covariance || ctx.covariance->rows() < idx::pos + 2) return false;
	const NavState& x = *ctx.mean;
	Eigen::Vector2d nu = m.z - pointPosition_n(x, ctx).head<2>();
	// Linearised in position (and bias) alone (the lever arm's attitude share
	// is mm): S ≈ P_pos + R, with the bias H = [I I]; the 2-dof χ² quantile
	// is −2 ln(1 − p).
	Eigen::Matrix2d S = ctx.covariance->block<2, 2>(idx::pos, idx::pos) + m.R;
	const PluginState& bias = this->bias();
	const int b = bias.tangentIndex();
	if (bias.presentIn(x) && ctx.covariance->rows() >= b + 2)
	{
		nu -= bias.segment<2>(x);
		const Eigen::Matrix2d P_pb = ctx.covariance->block<2, 2>(idx::pos, b);
		S += ctx.covariance->block<2, 2>(b, b) + P_pb + P_pb.transpose();
	}
	const double nis = nu.dot(S.ldlt().solve(nu));
	return std::isfinite(nis) && nis > -2 * std::log(1 - std::min(gateProbability(), 1 - 1e-12));
}

double GpsModel::correlatedVariance(double since_last_s) const
{
	if (correlated_sigma_m_ <= 0) return 0.0;
	// A first-order Gauss-Markov error sampled every Δt has lag-one correlation
	// ρ = exp(-Δt/τ). A filter that treats the samples as independent averages
	// them; the variance of such an average is (1+ρ)/(1-ρ) times what it
	// assumes, so that is what each fix is given (effective sample size).
	const double rho = std::exp(-std::max(since_last_s, 0.0) / correlation_time_s_);
	return correlated_sigma_m_ * correlated_sigma_m_ * (1 + rho) / std::max(1 - rho, 1e-6);
}

}  // namespace auvnav::plugins
