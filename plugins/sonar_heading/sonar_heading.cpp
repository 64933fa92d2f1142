#include "sonar_heading.h"

#include <auvnav/sonar/frame.h>
#include <mrpt/obs/CObservationImage.h>

#include <cmath>
#include <filesystem>

namespace auvnav::plugins
{
namespace
{
std::string resolve(const config::Node& cfg, const std::string& key)
{
	const std::filesystem::path p = cfg.string(key);
	if (p.is_absolute()) return p.string();
	return (std::filesystem::path(cfg.string("config_dir", ".")) / p).string();
}
}  // namespace

double predictedBearing(const NavState& x, const Eigen::Vector3d& r_s_b, double mount_yaw_rad,
                        const Eigen::Vector2d& pole_ne)
{
	const Eigen::Vector3d p_s = x.p_n + x.R_nb * r_s_b;
	const Eigen::Vector3d x_s = x.R_nb * Eigen::Vector3d(std::cos(mount_yaw_rad), std::sin(mount_yaw_rad), 0);
	const double psi_s = std::atan2(x_s.y(), x_s.x());
	return auvnav::wrapAngle(std::atan2(pole_ne.y() - p_s.y(), pole_ne.x() - p_s.x()) - psi_s);
}

SonarHeadingModel::SonarHeadingModel(const config::Node& cfg, const std::string& /*label*/) : GatedModel(cfg)
{
	const auto sonar_file = config::Node::load(resolve(cfg, "sonar_config"));
	sonar_ = sonar::SonarConfig::fromConfig(sonar_file);
	sonar_file.checkAllKeysUsed();
	const std::string mode = cfg.string("mode", "validate");
	if (mode != "validate" && mode != "update")
		cfg.fail("mode", "expected 'validate' or 'update', got '" + mode + "'");
	validate_only_ = mode == "validate";
	sigma_floor_rad_ = cfg.inRange("bearing_sigma_floor_deg", 0, 10, 0.5) * kDeg;
	if (cfg.has("validation_csv"))
	{
		const std::string path = resolve(cfg, "validation_csv");
		validation_ = std::make_unique<std::ofstream>(path);
		if (!*validation_) cfg.fail("validation_csv", "cannot write " + path);
		*validation_
		    << "time_s,poles,landmark_heading_deg,landmark_sigma_deg,filter_heading_deg,filter_sigma_deg,"
		       "difference_deg\n";
	}
}

PrepareStatus SonarHeadingModel::doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
                                           std::vector<Measurement>& out, std::string& why)
{
	out.clear();
	const auto* img = dynamic_cast<const mrpt::obs::CObservationImage*>(&obs);
	if (!img)
	{
		why = "not a CObservationImage";
		return PrepareStatus::Invalid;
	}
	auto g = sonar::geometryOf(*img, why);
	if (!g) g = sonar_.geometry;
	if (!g) return PrepareStatus::Invalid;
	const cv::Mat polar = sonar::polarImage(*img);
	if (polar.cols != g->beam_count || polar.rows != g->range_bins)
	{
		why = "image size disagrees with the sonar geometry";
		return PrepareStatus::Invalid;
	}
	if (!ctx.mean || !ctx.covariance)
	{
		why = "filter not initialised";
		return PrepareStatus::Skip;
	}
	const NavState& x = *ctx.mean;
	const Covariance& P = *ctx.covariance;
	const double sigma_heading = std::sqrt(std::max(P(idx::att + 2, idx::att + 2), 0.0));
	const sonar::SonarPose pose =
	    sonar::sonarPose(sonar_, x.p_n, x.R_nb, P.block<2, 2>(idx::pos, idx::pos), sigma_heading);
	const auto r = sonar::analyseFrame(polar, *g, sonar_, pose);
	if (validation_ && r.heading)
	{
		const double filter_heading = std::atan2(x.R_nb(1, 0), x.R_nb(0, 0));
		char line[256];
		std::snprintf(line, sizeof line, "%.3f,%d,%.4f,%.4f,%.4f,%.4f,%.4f\n", ctx.t_s, r.heading->poles,
		              r.heading->heading_rad / kDeg, r.heading->sigma_rad / kDeg, filter_heading / kDeg,
		              sigma_heading / kDeg,
		              auvnav::wrapAngle(r.heading->heading_rad - filter_heading) / kDeg);
		*validation_ << line;
		validation_->flush();
	}
	if (validate_only_)
	{
		// Counted, never applied.
		Measurement m;
		m.skipped = true;
		m.label = "validation";
		out.push_back(m);
		return PrepareStatus::Ok;
	}
	for (const auto& a : r.associations)
	{
		const auto& d = r.detections[static_cast<std::size_t>(a.detection)];
		const auto& pole = sonar_.map.poles[static_cast<std::size_t>(a.pole)];
		Measurement m;
		m.z = Eigen::VectorXd::Constant(1, d.bearing_rad);
		m.R = Eigen::MatrixXd::Constant(
		    1, 1, d.sigma_bearing_rad * d.sigma_bearing_rad + sigma_floor_rad_ * sigma_floor_rad_);
		m.tag = a.pole;
		m.setPayload(PolePosition{pole.ne_m.x(), pole.ne_m.y()});
		m.label = "bearing";
		out.push_back(m);
	}
	return PrepareStatus::Ok;
}

bool SonarHeadingModel::doPredict(const NavState& x, const Measurement& m, const FilterContext& /*ctx*/,
                                  Eigen::Ref<Eigen::VectorXd> z_pred) const
{
	if (z_pred.size() != 1) return false;
	const auto& pole = m.payload<PolePosition>();
	z_pred[0] = predictedBearing(x, sonar_.position_b, sonar_.mount_yaw_rad,
	                             Eigen::Vector2d(pole.north_m, pole.east_m));
	return std::isfinite(z_pred[0]);
}

}  // namespace auvnav::plugins
