#include <auvnav/sonar/pipeline.h>

#include <cmath>

namespace auvnav::sonar
{
namespace
{
constexpr double kDeg = M_PI / 180;
}

SonarConfig SonarConfig::fromConfig(const config::Node& n)
{
	SonarConfig c;
	c.label = n.string("label", c.label);
	c.map = PoleMap::load(n.filePath("pole_map"));
	if (n.has("mount"))
	{
		const auto m = n.child("mount");
		c.position_b = m.vector3("position_m", c.position_b);
		c.mount_yaw_rad = m.inRange("yaw_deg", -180, 180, 0) * kDeg;
	}
	if (n.has("geometry")) c.geometry = PolarGeometry::fromConfig(n.child("geometry"));
	if (n.has("detector"))
	{
		const auto d = n.child("detector");
		auto& p = c.detector;
		p.median_kernel_px = d.integer("median_kernel_px", p.median_kernel_px);
		if (p.median_kernel_px < 1 || p.median_kernel_px % 2 == 0 || p.median_kernel_px > 15)
			d.fail("median_kernel_px", "expected an odd size 1..15");
		p.min_snr = d.positive("min_snr", p.min_snr);
		p.min_area_px = d.integer("min_area_px", p.min_area_px);
		p.max_area_px = d.integer("max_area_px", p.max_area_px);
		if (p.min_area_px < 1 || p.max_area_px < p.min_area_px)
			d.fail("max_area_px", "need 1 <= min_area_px <= max_area_px");
		p.max_extent_m = d.positive("max_extent_m", p.max_extent_m);
		p.max_width_m = d.positive("max_width_m", p.max_width_m);
		p.smooth_sigma_beams = d.positive("smooth_sigma_beams", p.smooth_sigma_beams);
		p.smooth_sigma_m = d.positive("smooth_sigma_m", p.smooth_sigma_m);
		p.shadow_gap_m = d.nonNegative("shadow_gap_m", p.shadow_gap_m);
		p.shadow_length_m = d.positive("shadow_length_m", p.shadow_length_m);
		p.max_shadow_ratio = d.inRange("max_shadow_ratio", 0, 1, p.max_shadow_ratio);
		p.min_background = d.nonNegative("min_background", p.min_background);
		p.min_snr_without_shadow = d.positive("min_snr_without_shadow", p.min_snr_without_shadow);
	}
	if (n.has("association"))
	{
		const auto a = n.child("association");
		c.association.gate_probability =
		    a.inRange("gate_probability", 0.5, 0.999999, c.association.gate_probability);
		c.association.ambiguity_ratio = a.inRange("ambiguity_ratio", 1, 1e6, c.association.ambiguity_ratio);
		c.position_sigma_m = a.positive("position_sigma_m", c.position_sigma_m);
		c.heading_sigma_rad = a.positive("heading_sigma_deg", c.heading_sigma_rad / kDeg) * kDeg;
	}
	return c;
}

SonarPose sonarPose(const SonarConfig& c, const Eigen::Vector3d& p_n, const Eigen::Matrix3d& R_nb,
                    const Eigen::Matrix2d& P_ne, double sigma_heading_rad)
{
	SonarPose s;
	s.ne_m = (p_n + R_nb * c.position_b).head<2>();
	s.heading_rad = wrapAngle(std::atan2(R_nb(1, 0), R_nb(0, 0)) + c.mount_yaw_rad);
	s.P_ne = P_ne;
	s.sigma_heading_rad = sigma_heading_rad;
	return s;
}

FrameResult analyseFrame(const cv::Mat& polar, const PolarGeometry& g, const SonarConfig& c,
                         const std::optional<SonarPose>& pose)
{
	FrameResult r;
	r.detections = detectPoles(polar, g, c.detector);
	if (!pose) return r;
	r.associations = associate(r.detections, c.map, *pose, c.association);
	r.heading = headingFromPoles(r.detections, r.associations, c.map, *pose, c.mount_yaw_rad);
	return r;
}

}  // namespace auvnav::sonar
