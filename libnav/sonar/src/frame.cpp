#include <auvnav/sonar/frame.h>
#include <mrpt/system/datetime.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace auvnav::sonar
{
void setGeometry(mrpt::obs::CObservationImage& obs, const PolarGeometry& g)
{
	g.validate();
	auto& cam = obs.cameraParams;
	cam.ncols = static_cast<uint32_t>(g.beam_count);
	cam.nrows = static_cast<uint32_t>(g.range_bins);
	cam.intrinsicParams.setZero();
	cam.fx(1.0 / g.bearingStep_rad());
	cam.cx(g.columnOfBearing(0.0));
	cam.fy(1.0 / g.rangeStep_m());
	cam.cy(-g.min_range_m / g.rangeStep_m());
	cam.intrinsicParams(2, 2) = 1.0;
	cam.dist.fill(0);
	cam.cameraName = kPolarSonarModel;
}

std::optional<PolarGeometry> geometryOf(const mrpt::obs::CObservationImage& obs, std::string& why)
{
	const auto& cam = obs.cameraParams;
	if (cam.cameraName != kPolarSonarModel)
	{
		why = "camera model '" + cam.cameraName + "' is not '" + kPolarSonarModel + "'";
		return std::nullopt;
	}
	PolarGeometry g;
	g.beam_count = static_cast<int>(cam.ncols);
	g.range_bins = static_cast<int>(cam.nrows);
	const double fx = cam.fx(), fy = cam.fy();
	if (!(std::isfinite(fx) && fx > 0 && std::isfinite(fy) && fy > 0 && std::isfinite(cam.cx()) &&
	      std::isfinite(cam.cy())))
	{
		why = "polar intrinsics not finite and positive";
		return std::nullopt;
	}
	g.aperture_rad = g.beam_count / fx;
	g.min_range_m = -cam.cy() / fy;
	g.max_range_m = g.min_range_m + (g.range_bins - 1) / fy;
	try
	{
		g.validate();
	}
	catch (const std::exception& e)
	{
		why = e.what();
		return std::nullopt;
	}
	if (static_cast<int>(obs.image.getWidth()) != g.beam_count ||
	    static_cast<int>(obs.image.getHeight()) != g.range_bins)
	{
		why = "image " + std::to_string(obs.image.getWidth()) + "x" + std::to_string(obs.image.getHeight()) +
		      " disagrees with the geometry's " + std::to_string(g.beam_count) + " beams x " +
		      std::to_string(g.range_bins) + " bins";
		return std::nullopt;
	}
	return g;
}

cv::Mat polarImage(const mrpt::obs::CObservationImage& obs)
{
	cv::Mat m = obs.image.asCvMat<cv::Mat>(mrpt::img::DEEP_COPY);
	if (m.channels() == 3) cv::cvtColor(m, m, cv::COLOR_BGR2GRAY);
	if (m.depth() != CV_8U) m.convertTo(m, CV_8U);
	return m;
}

mrpt::obs::CObservationImage::Ptr makeFrame(const cv::Mat& polar_u8, const PolarGeometry& g,
                                            const std::string& label, double unix_time_s)
{
	if (polar_u8.type() != CV_8UC1 || polar_u8.cols != g.beam_count || polar_u8.rows != g.range_bins)
		throw std::invalid_argument(
		    "sonar frame: image must be CV_8UC1 with beams x bins matching the geometry");
	auto o = mrpt::obs::CObservationImage::Create();
	o->sensorLabel = label;
	o->timestamp = mrpt::Clock::fromDouble(unix_time_s);
	o->image = mrpt::img::CImage(polar_u8, mrpt::img::DEEP_COPY);
	setGeometry(*o, g);
	return o;
}

cv::Point2d fanPixel(const PolarGeometry& g, double pixels_per_m, double bearing_rad, double range_m)
{
	const double half_width_m = g.max_range_m * std::sin(std::min(0.5 * g.aperture_rad, M_PI / 2));
	const Eigen::Vector2d xy = PolarGeometry::toCartesian(bearing_rad, range_m);
	return {(half_width_m + xy.y()) * pixels_per_m, (g.max_range_m - xy.x()) * pixels_per_m};
}

cv::Mat fanImage(const cv::Mat& polar, const PolarGeometry& g, double pixels_per_m)
{
	const double half_width_m = g.max_range_m * std::sin(std::min(0.5 * g.aperture_rad, M_PI / 2));
	const int width = static_cast<int>(std::ceil(2 * half_width_m * pixels_per_m)) + 1;
	const int height = static_cast<int>(std::ceil(g.max_range_m * pixels_per_m)) + 1;
	cv::Mat map_x(height, width, CV_32FC1), map_y(height, width, CV_32FC1);
	for (int r = 0; r < height; ++r)
		for (int c = 0; c < width; ++c)
		{
			const Eigen::Vector2d xy(g.max_range_m - r / pixels_per_m, c / pixels_per_m - half_width_m);
			double bearing = 0, range = 0;
			PolarGeometry::toPolar(xy, bearing, range);
			const bool in = g.inView(bearing, range);
			map_x.at<float>(r, c) = in ? static_cast<float>(g.columnOfBearing(bearing)) : -1.f;
			map_y.at<float>(r, c) = in ? static_cast<float>(g.rowOfRange(range)) : -1.f;
		}
	cv::Mat fan;
	cv::remap(polar, fan, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
	return fan;
}

}  // namespace auvnav::sonar
