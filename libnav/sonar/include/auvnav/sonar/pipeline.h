#pragma once
/** @file pipeline.h
 *  One sonar frame end to end: detect poles, associate them with the map
 *  from a pose estimate, and derive the vehicle heading they imply. Shared by
 *  auvnav-sonar and the sonar_heading plugin. Configured from YAML
 *  (config/sonar/gemini.yaml documents every key).
 */
#include <auvnav/config.h>
#include <auvnav/sonar/detector.h>
#include <auvnav/sonar/landmarks.h>

#include <optional>

namespace auvnav::sonar
{
struct SonarConfig
{
	std::string label = "SONAR";
	PoleMap map;
	Eigen::Vector3d position_b = Eigen::Vector3d::Zero();  //!< sonar head in the body frame [m]
	double mount_yaw_rad = 0;               //!< bearing-0 direction relative to the body x axis
	std::optional<PolarGeometry> geometry;  //!< for plain images (frames carry their own)
	DetectorParams detector;
	AssociationParams association;
	double position_sigma_m = 1.0;    //!< pose σ when the caller has none (auvnav-sonar)
	double heading_sigma_rad = 0.05;  //!< heading σ when the caller has none

	static SonarConfig fromConfig(const config::Node& n);
};

struct FrameResult
{
	std::vector<Detection> detections;
	std::vector<Association> associations;
	std::optional<FrameHeading> heading;
};

/** Sonar pose from the vehicle's position, yaw and their uncertainty. */
SonarPose sonarPose(const SonarConfig& c, const Eigen::Vector3d& p_n, const Eigen::Matrix3d& R_nb,
                    const Eigen::Matrix2d& P_ne, double sigma_heading_rad);

/** Detect; if `pose` is given, associate and compute the heading. */
FrameResult analyseFrame(const cv::Mat& polar, const PolarGeometry& g, const SonarConfig& c,
                         const std::optional<SonarPose>& pose);

}  // namespace auvnav::sonar
