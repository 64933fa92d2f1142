#include "plot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace auvnav::eval
{
namespace
{
double niceStep(double range, int target_ticks)
{
	const double raw = range / std::max(1, target_ticks);
	const double mag = std::pow(10.0, std::floor(std::log10(raw)));
	for (double m : {1.0, 2.0, 5.0, 10.0})
		if (raw <= m * mag) return m * mag;
	return 10 * mag;
}
std::string fmt(double v)
{
	char b[32];
	std::snprintf(b, sizeof b, "%g", std::abs(v) < 1e-12 ? 0.0 : v);
	return b;
}
}  // namespace

Plot::Plot(std::string title, std::string x_label, std::string y_label, int width, int height)
    : title_(std::move(title)),
      x_label_(std::move(x_label)),
      y_label_(std::move(y_label)),
      w_(width),
      h_(height)
{
}

void Plot::line(const std::vector<double>& x, const std::vector<double>& y, const cv::Scalar& bgr,
                const std::string& label, int thickness)
{
	series_.push_back({Series::Line, x, y, {}, bgr, label, thickness});
}
void Plot::band(const std::vector<double>& x, const std::vector<double>& lo, const std::vector<double>& hi,
                const cv::Scalar& bgr, const std::string& label)
{
	series_.push_back({Series::Band, x, lo, hi, bgr, label, 1});
}
void Plot::hline(double y, const cv::Scalar& bgr, const std::string& label)
{
	series_.push_back({Series::HLine, {}, {y}, {}, bgr, label, 1});
}
void Plot::yRange(double lo, double hi)
{
	fixed_y_ = true;
	y_lo_ = lo;
	y_hi_ = hi;
}
void Plot::xRange(double lo, double hi)
{
	fixed_x_ = true;
	x_lo_ = lo;
	x_hi_ = hi;
}

void Plot::save(const std::string& png) const
{
	double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
	for (const auto& s : series_)
	{
		for (double v : s.x)
			if (std::isfinite(v)) x0 = std::min(x0, v), x1 = std::max(x1, v);
		for (const auto* ys : {&s.y, &s.y2})
			for (double v : *ys)
				if (std::isfinite(v)) y0 = std::min(y0, v), y1 = std::max(y1, v);
	}
	if (!std::isfinite(x0)) x0 = 0, x1 = 1;
	if (!std::isfinite(y0)) y0 = 0, y1 = 1;
	if (fixed_y_) y0 = y_lo_, y1 = y_hi_;
	if (fixed_x_) x0 = x_lo_, x1 = x_hi_;
	if (x1 - x0 < 1e-12) x1 = x0 + 1;
	if (y1 - y0 < 1e-12) y0 -= 0.5, y1 += 0.5;
	const double pad = 0.05 * (y1 - y0);
	if (!fixed_y_) y0 -= pad, y1 += pad;

	cv::Mat img(h_, w_, CV_8UC3, cv::Scalar(255, 255, 255));
	const int L = 80, R = 20, T = 40, B = 60;
	const int pw = w_ - L - R, ph = h_ - T - B;
	auto X = [&](double v) { return L + static_cast<int>(std::lround((v - x0) / (x1 - x0) * pw)); };
	auto Y = [&](double v) { return T + static_cast<int>(std::lround((y1 - v) / (y1 - y0) * ph)); };
	const cv::Scalar grey(200, 200, 200), black(0, 0, 0);
	// Grid and ticks.
	const double xs = niceStep(x1 - x0, 8), ys = niceStep(y1 - y0, 6);
	for (double v = std::ceil(x0 / xs) * xs; v <= x1 + 1e-9; v += xs)
	{
		cv::line(img, {X(v), T}, {X(v), T + ph}, grey, 1);
		cv::putText(img, fmt(v), {X(v) - 12, T + ph + 18}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1,
		            cv::LINE_AA);
	}
	for (double v = std::ceil(y0 / ys) * ys; v <= y1 + 1e-9; v += ys)
	{
		cv::line(img, {L, Y(v)}, {L + pw, Y(v)}, grey, 1);
		cv::putText(img, fmt(v), {8, Y(v) + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
	}
	// Bands first (translucent), then lines.
	for (const auto& s : series_)
	{
		if (s.kind != Series::Band) continue;
		cv::Mat overlay = img.clone();
		for (std::size_t i = 1; i < s.x.size(); ++i)
		{
			if (!(std::isfinite(s.y[i - 1]) && std::isfinite(s.y2[i - 1]) && std::isfinite(s.y[i]) &&
			      std::isfinite(s.y2[i])))
				continue;
			const std::vector<cv::Point> quad = {{X(s.x[i - 1]), Y(s.y[i - 1])},
			                                     {X(s.x[i]), Y(s.y[i])},
			                                     {X(s.x[i]), Y(s.y2[i])},
			                                     {X(s.x[i - 1]), Y(s.y2[i - 1])}};
			cv::fillConvexPoly(overlay, quad, s.bgr, cv::LINE_AA);
		}
		// Blend inside the frame only: a band beyond a fixed y range (the
		// heading's σ in the first minute) must not spill over the labels.
		const cv::Rect frame(L, T, pw + 1, ph + 1);
		cv::Mat inside = img(frame);
		cv::addWeighted(overlay(frame), 0.35, inside, 0.65, 0, inside);
	}
	for (const auto& s : series_)
	{
		if (s.kind == Series::HLine)
		{
			for (int x = L; x < L + pw; x += 12)
				cv::line(img, {x, Y(s.y[0])}, {std::min(x + 6, L + pw), Y(s.y[0])}, s.bgr, 1);
			continue;
		}
		if (s.kind != Series::Line) continue;
		std::vector<cv::Point> pts;
		auto flush = [&]
		{
			if (pts.size() > 1) cv::polylines(img, pts, false, s.bgr, s.thickness, cv::LINE_AA);
			pts.clear();
		};
		for (std::size_t i = 0; i < s.x.size(); ++i)
		{
			if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]))
			{
				flush();
				continue;
			}
			pts.emplace_back(X(s.x[i]), std::clamp(Y(s.y[i]), T, T + ph));
		}
		flush();
	}
	// Frame, labels, legend.
	cv::rectangle(img, {L, T}, {L + pw, T + ph}, black, 1);
	cv::putText(img, title_, {L, 26}, cv::FONT_HERSHEY_SIMPLEX, 0.6, black, 1, cv::LINE_AA);
	cv::putText(img, x_label_, {L + pw / 2 - 40, h_ - 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black, 1,
	            cv::LINE_AA);
	cv::putText(img, y_label_, {8, T - 8}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
	int ly = T + 16;
	for (const auto& s : series_)
	{
		if (s.label.empty()) continue;
		cv::line(img, {L + pw - 230, ly - 4}, {L + pw - 205, ly - 4}, s.bgr, s.kind == Series::Band ? 8 : 2);
		cv::putText(img, s.label, {L + pw - 198, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
		ly += 18;
	}
	if (!cv::imwrite(png, img)) throw std::runtime_error("cannot write " + png);
}

}  // namespace auvnav::eval
