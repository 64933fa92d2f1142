#pragma once
/** @file scene.h
 *  The 3D view of a navigation run (MRPT opengl): estimated trajectory, ground
 *  truth, 2σ position ellipsoids along the way, the vehicle at its last pose,
 *  GPS fixes (accepted and rejected), the seabed.
 *
 *  Display frame: x = east, y = north, z = up (ENU: right-handed with z up, so
 *  the seabed is below), metres from the mission origin; the navigator's NED
 *  positions are converted here only.
 */
#include <mrpt/opengl/COpenGLScene.h>

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace auvnav::view
{
struct TrackPoint
{
	double t = 0;
	Eigen::Vector3d p_ned = Eigen::Vector3d::Zero();
	Eigen::Quaterniond q_nb = Eigen::Quaterniond::Identity();
	Eigen::Vector3d sigma_ned = Eigen::Vector3d::Constant(NAN);  //!< 1σ per axis (states.csv), NaN unknown
	double seabed_depth_m = NAN;                                 //!< truth only
};

/** A position fix offered to the filter by any position sensor (GPS, USBL). */
struct PositionFix
{
	double t = 0;
	std::string label;  //!< the sensor
	Eigen::Vector2d ne_m = Eigen::Vector2d::Zero();
	bool accepted = true;
};

struct RunData
{
	std::vector<TrackPoint> estimate, truth;
	std::vector<TrackPoint> smoothed;  //!< smoothed_states.csv (auvnav-run --smooth), empty if none
	std::vector<PositionFix> fixes;
};

/** Reads DIR/states.csv and, when present, DIR/smoothed_states.csv and
 *  DIR/position_fixes.csv. Throws std::runtime_error naming file and line. */
RunData loadRun(const std::string& dir);
/** Reads an auvnav-sim ground_truth.csv (positions, attitude, seabed depth). */
std::vector<TrackPoint> loadTruth(const std::string& csv);

struct SceneOptions
{
	double ellipsoid_every_s = 60;  //!< spacing of the 2σ ellipsoids
	double ellipsoid_min_sigma_m = 0.05;
};

/** Colours, for tests and the legend: trajectory blue, smoothed orange, truth green,
 *  ellipsoids red, GPS accepted yellow / rejected magenta. */
inline constexpr unsigned char kEstimateRgb[3] = {30, 90, 255};
inline constexpr unsigned char kTruthRgb[3] = {20, 200, 60};
inline constexpr unsigned char kSmoothedRgb[3] = {255, 140, 0};  //!< the smoothed trajectory: orange

mrpt::opengl::COpenGLScene::Ptr buildScene(const RunData& run, const SceneOptions& opt = {});

/** Points an interactive window's camera (mrpt::gui::CDisplayWindow3D keeps
 *  its own, mouse-driven one) the way buildScene framed the scene. */
template <class Window>
void frameWindowLikeScene(Window& window, const mrpt::opengl::COpenGLScene& scene)
{
	const auto& cam = scene.getViewport()->getCamera();
	window.setCameraPointingToPoint(cam.getPointingAtX(), cam.getPointingAtY(), cam.getPointingAtZ());
	window.setCameraZoom(cam.getZoomDistance());
	window.setCameraAzimuthDeg(cam.getAzimuthDegrees());
	window.setCameraElevationDeg(cam.getElevationDegrees());
}

/** Renders `scene` off screen (EGL, no display server) into a PNG. Throws on failure. */
void renderToPng(const mrpt::opengl::COpenGLScene& scene, const std::string& png, unsigned width,
                 unsigned height);

}  // namespace auvnav::view
