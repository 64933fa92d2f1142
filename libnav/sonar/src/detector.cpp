#include <auvnav/sonar/detector.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace auvnav::sonar
{
namespace
{
/** Per-row median and MAD-based spread over the columns of a float image. */
void rowBackground(const cv::Mat& f, std::vector<float>& level, std::vector<float>& spread)
{
	level.assign(static_cast<std::size_t>(f.rows), 0.f);
	spread.assign(static_cast<std::size_t>(f.rows), 0.f);
	std::vector<float> row(static_cast<std::size_t>(f.cols));
	for (int r = 0; r < f.rows; ++r)
	{
		const float* p = f.ptr<float>(r);
		row.assign(p, p + f.cols);
		auto mid = row.begin() + static_cast<long>(row.size() / 2);
		std::nth_element(row.begin(), mid, row.end());
		const float med = *mid;
		for (auto& v : row) v = std::abs(v - med);
		std::nth_element(row.begin(), mid, row.end());
		level[static_cast<std::size_t>(r)] = med;
		spread[static_cast<std::size_t>(r)] = 1.4826f * *mid;
	}
}
}  // namespace

std::vector<Detection> detectPoles(const cv::Mat& polar, const PolarGeometry& g, const DetectorParams& p)
{
	g.validate();
	if (polar.type() != CV_8UC1 || polar.cols != g.beam_count || polar.rows != g.range_bins)
		throw std::invalid_argument("detectPoles: image must be CV_8UC1, beams x bins as the geometry says");
	cv::Mat denoised, f;
	cv::medianBlur(polar, denoised, p.median_kernel_px | 1);
	denoised.convertTo(f, CV_32F);
	// Matched to a pole's footprint (about a beam wide, ~0.15 m long): averages
	// the speckle down before thresholding.
	cv::GaussianBlur(f, f, cv::Size(0, 0), p.smooth_sigma_beams,
	                 std::max(0.5, p.smooth_sigma_m / g.rangeStep_m()));

	std::vector<float> level, spread;
	rowBackground(f, level, spread);
	// Smooth the profiles over range: one row's median is noisy.
	cv::Mat lv(level, true), sp(spread, true);
	cv::blur(lv, lv, cv::Size(1, 9), cv::Point(-1, -1), cv::BORDER_REPLICATE);
	cv::blur(sp, sp, cv::Size(1, 9), cv::Point(-1, -1), cv::BORDER_REPLICATE);

	// Excess over the row background, and its local maximum over about a pole's
	// footprint: a blob is the part of a return above half its own peak (its
	// core, whatever the background level) and above the noise threshold.
	cv::Mat excess(f.size(), CV_32F), snr(f.size(), CV_32F), mask(f.size(), CV_8U), local_max;
	for (int r = 0; r < f.rows; ++r)
	{
		const float bg = lv.at<float>(r), s = std::max(sp.at<float>(r), 2.0f);  // floor: quantisation
		const float* src = f.ptr<float>(r);
		float* e = excess.ptr<float>(r);
		float* q = snr.ptr<float>(r);
		for (int c = 0; c < f.cols; ++c)
		{
			e[c] = src[c] - bg;
			q[c] = e[c] / s;
		}
	}
	const int half_rows = std::max(2, static_cast<int>(std::lround(p.max_extent_m / g.rangeStep_m() / 2)));
	cv::dilate(excess, local_max, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(9, 2 * half_rows + 1)));
	for (int r = 0; r < f.rows; ++r)
	{
		const float* e = excess.ptr<float>(r);
		const float* q = snr.ptr<float>(r);
		const float* lm = local_max.ptr<float>(r);
		uchar* m = mask.ptr<uchar>(r);
		for (int c = 0; c < f.cols; ++c) m[c] = (q[c] > p.min_snr && e[c] >= 0.5f * lm[c]) ? 255 : 0;
	}
	cv::Mat labels, stats, centroids;
	const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
	const double step_b = g.bearingStep_rad(), step_r = g.rangeStep_m();
	std::vector<Detection> out;
	for (int k = 1; k < n; ++k)
	{
		const int area = stats.at<int>(k, cv::CC_STAT_AREA);
		const int x0 = stats.at<int>(k, cv::CC_STAT_LEFT), y0 = stats.at<int>(k, cv::CC_STAT_TOP);
		const int w = stats.at<int>(k, cv::CC_STAT_WIDTH), h = stats.at<int>(k, cv::CC_STAT_HEIGHT);
		if (area < p.min_area_px || area > p.max_area_px) continue;
		const double blob_range = g.rangeOfRow(y0 + 0.5 * h);
		if (h * step_r > p.max_extent_m || w * step_b * std::max(blob_range, 1.0) > p.max_width_m) continue;
		// Intensity-weighted centroid and spread over the blob.
		double sw = 0, sc = 0, sr = 0, scc = 0, srr = 0, peak = 0;
		for (int r = y0; r < y0 + h; ++r)
			for (int c = x0; c < x0 + w; ++c)
			{
				if (labels.at<int>(r, c) != k) continue;
				const double wt = std::max(0.0, static_cast<double>(f.at<float>(r, c) - lv.at<float>(r)));
				sw += wt;
				sc += wt * c;
				sr += wt * r;
				scc += wt * c * c;
				srr += wt * r * r;
				peak = std::max(peak, static_cast<double>(snr.at<float>(r, c)));
			}
		if (!(sw > 0)) continue;
		Detection d;
		d.column = sc / sw;
		d.row = sr / sw;
		const double var_c = std::max(0.0, scc / sw - d.column * d.column);
		const double var_r = std::max(0.0, srr / sw - d.row * d.row);
		// Shadow window: the blob's beams, from just behind its far edge.
		const int r_from = y0 + h + static_cast<int>(std::ceil(p.shadow_gap_m / step_r));
		// Cut at the image's end; too short a window shows no shadow.
		int r_to = std::min(f.rows, r_from + static_cast<int>(std::ceil(p.shadow_length_m / step_r)));
		if (r_to - r_from < 3) r_to = r_from;
		double shadow = 0, background = 0;
		int count = 0;
		// The shadow is as wide as the pole, narrower than its (beam-widened)
		// echo: look behind the centre column(s) only.
		const int c_mid = static_cast<int>(std::lround(d.column)), c_half = std::max(0, (w - 1) / 4);
		for (int r = r_from; r < r_to; ++r)
			for (int c = std::max(0, c_mid - c_half); c <= std::min(f.cols - 1, c_mid + c_half); ++c)
			{
				shadow += f.at<float>(r, c);
				background += lv.at<float>(r);
				++count;
			}
		if (count > 0 && background / count >= p.min_background)
		{
			d.shadow_ratio = shadow / background;
			if (d.shadow_ratio > p.max_shadow_ratio) continue;
		}
		else if (peak < p.min_snr_without_shadow)
			continue;
		d.bearing_rad = g.bearingOfColumn(d.column);
		d.range_m = g.rangeOfRow(d.row);
		// Centroid precision: the beam/bin quantisation (step/√12) and the blob's spread.
		d.sigma_bearing_rad = step_b * std::sqrt(1.0 / 12 + var_c / std::max(1, area));
		d.sigma_range_m = step_r * std::sqrt(1.0 / 12 + var_r / std::max(1, area));
		d.snr = peak;
		d.area_px = area;
		out.push_back(d);
	}
	std::sort(out.begin(), out.end(),
	          [](const Detection& a, const Detection& b) { return a.bearing_rad < b.bearing_rad; });
	return out;
}

}  // namespace auvnav::sonar
