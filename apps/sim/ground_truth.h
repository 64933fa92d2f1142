#pragma once
/** @file ground_truth.h
 *  Reading auvnav-sim's ground_truth.csv back (for evaluation and tests).
 */
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

namespace auvnav::sim
{
struct TruthRow
{
	double t_unix = 0, distance_m = 0;
	Eigen::Vector3d p_n = Eigen::Vector3d::Zero();	//!< body origin, NED [m]
	Eigen::Quaterniond q_nb = Eigen::Quaterniond::Identity();
	Eigen::Vector2d current_ne = Eigen::Vector2d::Zero();
	bool submerged = false;
};

/** All rows of a ground_truth.csv (throws std::runtime_error naming the file). */
std::vector<TruthRow> readTruth(const std::filesystem::path& csv);

/** The row nearest to time `t_unix` (rows are 0.1 s apart). */
const TruthRow& truthAt(const std::vector<TruthRow>& truth, double t_unix);

}  // namespace auvnav::sim
