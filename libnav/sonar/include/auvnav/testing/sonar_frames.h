#pragma once
/** @file sonar_frames.h
 *  Synthetic raw polar sonar frames for tests (header only, OpenCV core):
 *  a flat seabed return from `seabed_from_m` on, poles as bright Gaussian
 *  echoes with shadows behind them, Rayleigh speckle of mean 1. Simpler than
 *  auvnav-sim's renderer, with every number in the test's hands.
 */
#include <auvnav/sonar/geometry.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

namespace auvnav::testing
{
struct SyntheticPole
{
	double bearing_rad = 0, range_m = 10, radius_m = 0.15;
};

struct SyntheticScene
{
	double seabed_from_m = 6, seabed_level = 70, water_level = 6, pole_level = 200, shadow_factor = 0.1;
	double beamwidth_rad = 1.0 * M_PI / 180;  //!< FWHM of one beam
};

inline cv::Mat renderPolarFrame(const sonar::PolarGeometry& g, const std::vector<SyntheticPole>& poles,
                                unsigned seed, const SyntheticScene& s = {})
{
	std::mt19937 rng(seed);
	std::uniform_real_distribution<double> u(1e-12, 1.0);
	const double rayleigh = std::sqrt(2.0 / M_PI);
	cv::Mat img(g.range_bins, g.beam_count, CV_8UC1);
	const double sigma_rho = std::max(2 * g.rangeStep_m(), 0.15);
	for (int c = 0; c < g.beam_count; ++c)
	{
		const double theta = g.bearingOfColumn(c);
		double shadow_from = 1e9;
		for (const auto& p : poles)
			if (std::abs(theta - p.bearing_rad) <
			    std::asin(p.radius_m / (p.range_m + p.radius_m)) + 0.5 * g.bearingStep_rad())
				shadow_from = std::min(shadow_from, p.range_m + 0.2);
		for (int r = 0; r < g.range_bins; ++r)
		{
			const double rho = g.rangeOfRow(r);
			double level = s.water_level + (rho >= s.seabed_from_m ? s.seabed_level : 0.0) *
			                                   (rho >= shadow_from ? s.shadow_factor : 1.0);
			for (const auto& p : poles)
			{
				const double half = std::asin(p.radius_m / (p.range_m + p.radius_m));
				const double a = (theta - p.bearing_rad) / std::hypot(s.beamwidth_rad / 2.355, half);
				const double b = (rho - p.range_m) / sigma_rho;
				if (std::abs(a) < 5 && std::abs(b) < 5)
					level += s.pole_level * std::exp(-0.5 * (a * a + b * b));
			}
			level *= rayleigh * std::sqrt(-2.0 * std::log(u(rng)));
			img.at<uchar>(r, c) = static_cast<uchar>(std::clamp(level, 0.0, 255.0));
		}
	}
	return img;
}

/** The Gemini-720i-like geometry of config/sonar/gemini.yaml. */
inline sonar::PolarGeometry geminiGeometry()
{
	sonar::PolarGeometry g;
	g.beam_count = 256;
	g.range_bins = 400;
	g.aperture_rad = 130 * M_PI / 180;
	g.min_range_m = 0.5;
	g.max_range_m = 30;
	return g;
}

}  // namespace auvnav::testing
