#include "gps.h"

#include <auvnav/earth.h>
#include <mrpt/obs/CObservationGPS.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "plugin_common.h"

namespace auvnav::plugins
{
GpsModel::GpsModel(const config::Node& cfg, const std::string& label)
    : label_(label),
      position_b_(cfg.vector3("position_m", Eigen::Vector3d(-0.3, 0, -0.6))),
      sigma_m_(cfg.positive("sigma_m", 3.0)),
      scale_by_hdop_(cfg.boolean("scale_by_hdop", false)),
      gate_probability_(gateProbabilityFrom(cfg)),
      min_interval_s_(cfg.inRange("min_interval_s", 0.0, 3600.0, 0.0)),
      correlated_sigma_m_(cfg.inRange("correlated_sigma_m", 0.0, 1000.0, 0.0)),
      correlation_time_s_(cfg.positive("correlation_time_s", 60.0))
{
	if (position_b_.cwiseAbs().maxCoeff() > 100) cfg.fail("position_m", "lever arm longer than 100 m");
	bias_ = horizontalFixBias(cfg);
	if (bias_.enabled() && correlated_sigma_m_ > 0)
		cfg.fail("correlated_sigma_m",
		         "the correlated error is modelled by states.bias already (give one of them, not both)");
}

PrepareStatus GpsModel::decodeFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                  Eigen::Vector3d& p_n, double& hdop, std::string& why) const
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
	p_n = ctx.frame->toNed(geo);
	if (!p_n.allFinite())
	{
		why = "position conversion failed";
		return PrepareStatus::Invalid;
	}
	hdop = static_cast<double>(f.HDOP);
	return PrepareStatus::Ok;
}

bool GpsModel::doInitialFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, InitialFix& out)
{
	Eigen::Vector3d p_n;
	double hdop = 0;
	std::string why;
	if (decodeFix(obs, ctx, p_n, hdop, why) != PrepareStatus::Ok) return false;
	out.p_n = p_n;
	out.r_b = position_b_;
	return true;
}

PrepareStatus GpsModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                  std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	Eigen::Vector3d p_n;
	double hdop = 0;
	const PrepareStatus decoded = decodeFix(obs, ctx, p_n, hdop, why);
	if (decoded != PrepareStatus::Ok) return decoded;
	// GPS errors are correlated over tens of seconds: using every 1 Hz fix as
	// independent would make the filter overconfident. Use one fix per
	// min_interval_s (the error's correlation time) instead.
	const double t_obs = mrpt::Clock::toDouble(obs.timestamp);
	if (t_obs - last_used_s_ < min_interval_s_)
	{
		why = "within min_interval_s of the last fix used";
		return PrepareStatus::Skip;
	}
	const double since_last_s = t_obs - last_used_s_;
	double sigma = sigma_m_;
	if (scale_by_hdop_ && std::isfinite(hdop) && hdop > 0) sigma *= hdop;

	Measurement m;
	m.z = p_n.head<2>();
	m.R = Eigen::Matrix2d::Identity() * (sigma * sigma + correlatedVariance(since_last_s));
	// A fix far outside the gate is offered (the filter's gate rejects it and
	// its re-initialisation rule counts it) but does not spend the interval:
	// the next fix is tried, not one min_interval_s later. Else wild fixes at
	// the interval's phase (every 5th of 1 Hz fixes, 30 s apart) would be the
	// only ones ever used.
	if (!likelyOutlier(m, ctx)) last_used_s_ = t_obs;
	m.label = "position";
	out.push_back(std::move(m));
	return PrepareStatus::Ok;
}

bool GpsModel::likelyOutlier(const Measurement& m, const FilterContext& ctx) const
{
	if (!ctx.mean || !ctx.covariance || ctx.covariance->rows() < idx::pos + 2) return false;
	const NavState& x = *ctx.mean;
	Eigen::Vector2d nu = m.z - (x.p_n + x.R_nb * (position_b_ - ctx.imu_position_b)).head<2>();
	// Linearised in position (and bias) alone (the lever arm's attitude share
	// is mm): S ≈ P_pos + R, with the bias H = [I I]; the 2-dof χ² quantile
	// is −2 ln(1 − p).
	Eigen::Matrix2d S = ctx.covariance->block<2, 2>(idx::pos, idx::pos) + m.R;
	const int b = bias_.tangentIndex();
	if (bias_.presentIn(x) && ctx.covariance->rows() >= b + 2)
	{
		nu -= bias_.segment<2>(x);
		const Eigen::Matrix2d P_pb = ctx.covariance->block<2, 2>(idx::pos, b);
		S += ctx.covariance->block<2, 2>(b, b) + P_pb + P_pb.transpose();
	}
	const double nis = nu.dot(S.ldlt().solve(nu));
	return std::isfinite(nis) && nis > -2 * std::log(1 - std::min(gate_probability_, 1 - 1e-12));
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

bool GpsModel::doPredict(const NavState& x, const Measurement& /*m*/, const FilterContext& ctx,
                         Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (z_pred.size() != 2) return false;
	z_pred = (x.p_n + x.R_nb * (position_b_ - ctx.imu_position_b)).head<2>();
	addFixBias(x, bias_, z_pred);
	return true;
}

}  // namespace auvnav::plugins
