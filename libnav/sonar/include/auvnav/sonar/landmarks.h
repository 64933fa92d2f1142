#pragma once
/** @file landmarks.h
 *  Surveyed pole map, association of sonar detections with it, and the
 *  vehicle heading the associated bearings imply.
 *
 *  Association: each (detection, pole) pair gets an innovation
 *  [bearing (wrapped); range] against the pole predicted from the sonar's
 *  position and heading estimate, with covariance from the detection's σ, the
 *  heading σ and the position covariance (linearised); pairs beyond the
 *  chi-square gate are never associated. Pairs are taken best first, each
 *  detection and pole at most once, and a detection whose second-best pole
 *  is within `ambiguity_ratio` in likelihood of its best is left out.
 *
 *  Heading: pole i at horizontal offset (ΔN, ΔE) from the sonar, seen at
 *  bearing β_i, implies sonar heading atan2(ΔE, ΔN) − β_i; minus the sonar's
 *  mounting yaw this is the vehicle heading. Frame heading = the inverse-
 *  variance weighted circular mean, σ² from β's σ and the position's
 *  cross-bearing uncertainty (σ_pos / range); with two or more poles the
 *  spread of the individual headings may raise σ.
 */
#include <auvnav/angles.h>
#include <auvnav/config.h>
#include <auvnav/sonar/detector.h>

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace auvnav::sonar
{
struct Pole
{
	std::string id;
	Eigen::Vector2d ne_m = Eigen::Vector2d::Zero();  //!< in the mission's NED tangent frame
	double radius_m = 0.1;
};

struct PoleMap
{
	std::vector<Pole> poles;
	/** Reads `poles: [{id, north_m, east_m, radius_m}]`; rejects duplicate ids
	 *  and bad numbers naming the entry. */
	static PoleMap fromConfig(const config::Node& n);
	static PoleMap load(const std::string& file);
};

/** Where the sonar is and looks, with uncertainty (navigation frame). */
struct SonarPose
{
	Eigen::Vector2d ne_m = Eigen::Vector2d::Zero();  //!< sonar head position
	double heading_rad = 0;                          //!< direction of bearing 0 (vehicle yaw + mounting yaw)
	Eigen::Matrix2d P_ne = Eigen::Matrix2d::Identity();  //!< position covariance [m²]
	double sigma_heading_rad = 0.05;
};

struct Association
{
	int detection = -1, pole = -1;
	double predicted_bearing_rad = 0, predicted_range_m = 0;
	double nis = 0;  //!< Mahalanobis² of the innovation (2 dof)
};

struct AssociationParams
{
	double gate_probability = 0.99;  //!< chi-square(2) gate
	double ambiguity_ratio =
	    20;  //!< best pole must be this many times likelier than the second (else dropped)
};

/** Predicted bearing [rad, wrapped] and range of pole `ne` from `pose`. */
void predictPole(const SonarPose& pose, const Eigen::Vector2d& ne, double& bearing_rad, double& range_m);

std::vector<Association> associate(const std::vector<Detection>& dets, const PoleMap& map,
                                   const SonarPose& pose, const AssociationParams& p = {});

struct FrameHeading
{
	double heading_rad = 0;  //!< vehicle heading (wrapped to (−π, π])
	double sigma_rad = 0;
	int poles = 0;
};

/** Vehicle heading implied by the associations (nullopt if none). */
std::optional<FrameHeading> headingFromPoles(const std::vector<Detection>& dets,
                                             const std::vector<Association>& as, const PoleMap& map,
                                             const SonarPose& pose, double mount_yaw_rad);

}  // namespace auvnav::sonar
