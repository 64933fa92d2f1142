#pragma once
/** @file detector.h
 *  Pole detection in raw polar sonar frames (OpenCV).
 *
 *  A surveyed pole standing on the seabed shows in an imaging sonar as a
 *  bright, compact return followed, further out in the same beams, by an
 *  acoustic shadow where the seabed return is missing. The detector:
 *   1. denoises the speckle (median, then a Gaussian about a pole's size);
 *   2. estimates the background per range row (median over the beams, which a
 *      pole a few beams wide does not move) and its spread (MAD);
 *   3. thresholds the signal-to-background ratio, groups pixels into
 *      connected components and keeps compact ones;
 *   4. confirms each by its shadow: the mean level behind it must be well
 *      below the background of those rows; where the background is too dark
 *      to show a shadow (before the seabed return starts), only a much
 *      brighter blob is accepted;
 *   5. reports the intensity-weighted centroid as bearing and range with σ.
 */
#include <auvnav/sonar/geometry.h>

#include <opencv2/core.hpp>
#include <vector>

namespace auvnav::sonar
{
struct DetectorParams
{
	int median_kernel_px = 3;         //!< speckle median filter (odd)
	double smooth_sigma_beams = 1.0;  //!< Gaussian smoothing across beams [columns]
	double smooth_sigma_m = 0.1;      //!< ... and along range [m]
	double min_snr = 4;               //!< (level − background) / background spread to start a blob
	int min_area_px = 4;              //!< smallest blob kept
	int max_area_px = 600;            //!< larger blobs are seabed features, not poles
	double max_extent_m = 1.5;        //!< a blob longer than this in range is not a pole
	double max_width_m = 1.5;         //!< ... or wider than this across the beams
	double shadow_gap_m = 0.4;        //!< start of the shadow window behind the blob's far edge
	double shadow_length_m = 2.0;     //!< length of the shadow window
	double max_shadow_ratio = 0.6;    //!< shadow level / background level to accept
	double min_background = 8;        //!< background level (0–255) needed to see a shadow
	//! Where the background is too dark to show a shadow (near range, before
	//! the seabed), a blob is accepted on brightness alone above this SNR.
	double min_snr_without_shadow = 25;
};

struct Detection
{
	double bearing_rad = 0, range_m = 0;              //!< in the sonar frame
	double sigma_bearing_rad = 0, sigma_range_m = 0;  //!< 1σ
	double column = 0, row = 0;                       //!< centroid in the polar image
	double snr = 0;
	double shadow_ratio = NAN;  //!< NaN: no shadow visible there (accepted on brightness)
	int area_px = 0;
};

/** Detections in `polar` (CV_8UC1, beams × bins) sorted by bearing. */
std::vector<Detection> detectPoles(const cv::Mat& polar, const PolarGeometry& g,
                                   const DetectorParams& p = {});

}  // namespace auvnav::sonar
