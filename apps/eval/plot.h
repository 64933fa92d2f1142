#pragma once
/** @file plot.h
 *  Minimal line plots drawn with OpenCV (PNG): lines, shaded bands, dashed
 *  reference lines, axes with 1-2-5 ticks, a legend. Enough for auvnav-eval's
 *  figures without a plotting dependency Debian does not ship for C++.
 */
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace auvnav::eval
{
class Plot
{
 public:
	Plot(std::string title, std::string x_label, std::string y_label, int width = 960, int height = 480);
	void line(const std::vector<double>& x, const std::vector<double>& y, const cv::Scalar& bgr,
	          const std::string& label, int thickness = 2);
	void band(const std::vector<double>& x, const std::vector<double>& lo, const std::vector<double>& hi,
	          const cv::Scalar& bgr, const std::string& label);
	void hline(double y, const cv::Scalar& bgr, const std::string& label);
	/** Fixes the y range (otherwise from the data). */
	void yRange(double lo, double hi);
	/** Fixes the x range (otherwise from the data). */
	void xRange(double lo, double hi);
	/** Renders and writes the PNG; throws std::runtime_error on failure. */
	void save(const std::string& png) const;

 private:
	struct Series
	{
		enum Kind
		{
			Line,
			Band,
			HLine
		} kind;
		std::vector<double> x, y, y2;
		cv::Scalar bgr;
		std::string label;
		int thickness;
	};
	std::string title_, x_label_, y_label_;
	int w_, h_;
	bool fixed_y_ = false, fixed_x_ = false;
	double x_lo_ = 0, x_hi_ = 1;
	double y_lo_ = 0, y_hi_ = 1;
	std::vector<Series> series_;
};
}  // namespace auvnav::eval
