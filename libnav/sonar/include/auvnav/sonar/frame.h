#pragma once
/** @file frame.h
 *  Raw polar sonar frames as mrpt::obs::CObservationImage.
 *
 *  The image is 8-bit grey, beams × range bins (columns × rows, geometry.h).
 *  The geometry travels in the observation's camera model as linear polar
 *  intrinsics: ncols = beams, nrows = bins, fx = columns per radian of
 *  bearing, cx = column of bearing 0, fy = rows per metre, cy = row of range
 *  0, and cameraName = kPolarSonarModel. cameraPose is the sonar head in the
 *  body frame with the sonar's x forward (bearing 0), y starboard, z down.
 */
#include <auvnav/sonar/geometry.h>
#include <mrpt/obs/CObservationImage.h>

#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace auvnav::sonar
{
inline constexpr const char* kPolarSonarModel = "auvnav-polar-sonar";

/** Stores `g` in the observation's camera model (image size included). */
void setGeometry(mrpt::obs::CObservationImage& obs, const PolarGeometry& g);

/** The geometry of a polar sonar frame; nullopt with `why` if `obs` is not one
 *  (wrong camera model, sizes disagreeing with the image, bad numbers). */
std::optional<PolarGeometry> geometryOf(const mrpt::obs::CObservationImage& obs, std::string& why);

/** The frame as a CV_8UC1 matrix (a copy; rows = range bins). */
cv::Mat polarImage(const mrpt::obs::CObservationImage& obs);

/** Wraps a CV_8UC1 polar image and its geometry into an observation. */
mrpt::obs::CObservationImage::Ptr makeFrame(const cv::Mat& polar_u8, const PolarGeometry& g,
                                            const std::string& label, double unix_time_s);

/** Fan (Cartesian) view of a polar frame: `pixels_per_m` scale, the sonar at
 *  the bottom centre, forward up, starboard right (cv::remap, bilinear). */
cv::Mat fanImage(const cv::Mat& polar, const PolarGeometry& g, double pixels_per_m);

/** Pixel of a polar point in fanImage()'s output (same scale). */
cv::Point2d fanPixel(const PolarGeometry& g, double pixels_per_m, double bearing_rad, double range_m);

}  // namespace auvnav::sonar
