#pragma once
/** @file trajectory.h
 *  The one trajectory / ground-truth reader of the apps and tests, with the
 *  one interpolation rule, so that every program that compares an estimate
 *  with the truth (auvnav-experiment, auvnav-eval, auvnav-sonar, the
 *  integration tests) measures the same error at the same time.
 *
 *  Sources: auvnav-sim's ground_truth.csv (readGroundTruth) and TUM files
 *  `t x y z qx qy qz qw` (readTum: auvnav-run's trajectory.tum, auvnav-sim's
 *  ground_truth.tum). Positions are the body origin in NED [m], attitudes
 *  body-to-NED.
 *
 *  Interpolation between the two points around t: position, current and
 *  distance linear, attitude along the SO(3) geodesic (quaternion slerp),
 *  `submerged` from the nearer point. A point within kTimeTolerance_s of t is
 *  returned as it is.
 */
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <optional>
#include <vector>

namespace auvnav::io
{
struct TrajectoryPoint
{
	double t_unix = 0;                              //!< [s]
	double distance_m = 0;                          //!< travelled so far (ground truth only)
	Eigen::Vector3d p_n = Eigen::Vector3d::Zero();  //!< body origin, NED [m]
	Eigen::Quaterniond q_nb = Eigen::Quaterniond::Identity();
	Eigen::Vector2d current_ne = Eigen::Vector2d::Zero();  //!< water current (ground truth only) [m/s]
	bool submerged = false;                                //!< ground truth only
};

/** Points in strictly increasing time. */
using Trajectory = std::vector<TrajectoryPoint>;

/** Times closer than this are the same instant (CSV text round trip). */
constexpr double kTimeTolerance_s = 1e-6;

/** auvnav-sim's ground_truth.csv (columns by name: unix_time_s, north_m,
 *  east_m, down_m, qw, qx, qy, qz, distance_m, current_n_mps, current_e_mps,
 *  and submerged if present, else false). Throws std::runtime_error naming the file and line on a
 *  missing column, a bad number, a non-unit quaternion, time going backwards
 *  or no rows. */
Trajectory readGroundTruth(const std::filesystem::path& csv);

/** A TUM file; '#' lines and blank lines are skipped, repeated or backward
 *  stamps are dropped (the first point of an instant is kept). Throws
 *  std::runtime_error naming the file and line on bad input or no points. */
Trajectory readTum(const std::filesystem::path& file);

/** The trajectory at t: interpolated between the points around it; nullopt
 *  outside the span or when those two points are more than `max_gap_s`
 *  apart (no interpolation across a data gap). */
std::optional<TrajectoryPoint> interpolate(const Trajectory& tr, double t, double max_gap_s);

/** The same without gap limit, and clamped to the first / last point
 *  outside the span (for a filter time just past the truth's end).
 *  `tr` must not be empty. */
TrajectoryPoint at(const Trajectory& tr, double t);

}  // namespace auvnav::io
