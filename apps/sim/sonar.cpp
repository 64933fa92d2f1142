#include "sonar.h"

#include <auvnav/sonar/frame.h>

#include <algorithm>
#include <cmath>

namespace auvnav::sim
{
namespace
{
constexpr double kDeg = M_PI / 180;
}

SonarSim::SonarSim(const config::Node& n, sonar::PoleMap poles, uint32_t seed)
    : period_s_(1.0 / n.inRange("rate_hz", 0.01, 50)),
      offset_s_(n.nonNegative("time_offset_s", 0.0)),
      mount_(Mounting::fromConfig(n)),
      poles_(std::move(poles)),
      tilt_rad_(n.inRange("tilt_deg", 0, 90) * kDeg),
      vertical_beamwidth_rad_(n.inRange("vertical_beamwidth_deg", 1, 90) * kDeg),
      horizontal_beamwidth_rad_(n.inRange("horizontal_beamwidth_deg", 0.05, 20) * kDeg),
      seabed_level_(n.inRange("seabed_level", 0, 255)),
      pole_level_(n.inRange("pole_level", 0, 255)),
      water_level_(n.inRange("water_level", 0, 255)),
      shadow_factor_(n.inRange("shadow_factor", 0, 1)),
      label_(n.string("label", "SONAR"))
{
	geom_ = sonar::PolarGeometry::fromConfig(n);
	rng_.randomize(seed * 7919u + 101u);
}

double SonarSim::sonarHeading(const Truth& truth) const
{
	const Eigen::Vector3d x_n = truth.x->R_nb() * mount_.R_bs_true * Eigen::Vector3d::UnitX();
	return std::atan2(x_n.y(), x_n.x());
}

mrpt::obs::CObservationImage::Ptr SonarSim::sample(const Truth& truth, const Environment& env,
                                                   std::vector<PoleInView>& in_view)
{
	const auto& x = *truth.x;
	const Eigen::Vector3d p_s = x.p_n + x.R_nb() * mount_.position_b;
	const double psi = sonarHeading(truth);
	const int B = geom_.beam_count, N = geom_.range_bins;

	struct PoleImage
	{
		double bearing, range, half_angle;
	};
	std::vector<PoleImage> visible;
	in_view.clear();
	for (const auto& pole : poles_.poles)
	{
		const Eigen::Vector2d d = pole.ne_m - p_s.head<2>();
		const double dist = d.norm();
		if (dist <= pole.radius_m) continue;
		const double bearing = auvnav::wrapAngle(std::atan2(d.y(), d.x()) - psi);
		const double range = dist - pole.radius_m;
		// Rendered when any of it can reach the image; counted "in view" when
		// its centre is inside the aperture and the range window.
		if (std::abs(bearing) > 0.5 * geom_.aperture_rad + 3 * horizontal_beamwidth_rad_) continue;
		visible.push_back({bearing, range, std::asin(std::min(1.0, pole.radius_m / dist))});
		if (geom_.inView(bearing, range)) in_view.push_back({pole.id, bearing, range});
	}

	cv::Mat img(N, B, CV_8UC1);
	const double sigma_theta = horizontal_beamwidth_rad_ / 2.355;  // FWHM → σ
	// A pole's echo spreads over its face and the pulse: ~0.15 m in range.
	const double sigma_rho = std::max(2 * geom_.rangeStep_m(), 0.15);
	const double rayleigh_sigma = std::sqrt(2.0 / M_PI);  // mean 1
	for (int c = 0; c < B; ++c)
	{
		const double theta = geom_.bearingOfColumn(c);
		const double heading = psi + theta;
		const double ch = std::cos(heading), sh = std::sin(heading);
		// Shadow onset in this beam (nearest pole covering it).
		double shadow_from = std::numeric_limits<double>::infinity();
		for (const auto& v : visible)
			if (std::abs(auvnav::wrapAngle(theta - v.bearing)) < v.half_angle + 0.5 * geom_.bearingStep_rad())
				shadow_from = std::min(shadow_from, v.range + 0.2);
		for (int r = 0; r < N; ++r)
		{
			const double rho = geom_.rangeOfRow(r);
			// Seabed under the ground point this slant range reaches.
			double seabed = 0;
			const double h0 = env.seabedDepth(p_s.x(), p_s.y()) - p_s.z();
			if (rho > h0 && h0 > 0)
			{
				const double ground = std::sqrt(rho * rho - h0 * h0);
				const double h = env.seabedDepth(p_s.x() + ground * ch, p_s.y() + ground * sh) - p_s.z();
				if (h > 0 && rho > h)
				{
					const double phi = std::asin(h / rho);
					const double u = (phi - tilt_rad_) / (0.5 * vertical_beamwidth_rad_);
					seabed = seabed_level_ * std::exp(-0.5 * u * u);
				}
			}
			if (rho >= shadow_from) seabed *= shadow_factor_;
			double pole = 0;
			for (const auto& v : visible)
			{
				const double a = auvnav::wrapAngle(theta - v.bearing) / std::hypot(sigma_theta, v.half_angle);
				const double b = (rho - v.range) / sigma_rho;
				if (std::abs(a) < 5 && std::abs(b) < 5)
					pole += pole_level_ * std::exp(-0.5 * (a * a + b * b));
			}
			const double u1 = std::max(rng_.drawUniform(0.0, 1.0), 1e-12);
			const double speckle = rayleigh_sigma * std::sqrt(-2.0 * std::log(u1));
			const double level = (seabed + water_level_ + pole) * speckle;
			img.at<uchar>(r, c) = static_cast<uchar>(std::clamp(level, 0.0, 255.0));
		}
	}
	auto o = sonar::makeFrame(img, geom_, label_, mrpt::Clock::toDouble(truth.stamp));
	o->cameraPose = mount_.nominalPose();
	return o;
}

}  // namespace auvnav::sim
