#pragma once
// End-to-end harness: simulate a mission, run the navigator on its rawlog
// in-process, and line the estimate up with the ground truth.
#include <auvnav/config.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/navigator.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <vector>

namespace auvnav::test
{
struct TruthRow
{
	double t_unix = 0, distance_m = 0, down_m = 0;
	Eigen::Vector3d p_n;
	Eigen::Quaterniond q_nb;
	bool submerged = false;
};

/** Reads ground_truth.csv written by auvnav-sim. */
std::vector<TruthRow> readTruth(const std::filesystem::path& csv);

/** Truth at time t (nearest row; rows are 0.1 s apart). */
const TruthRow& truthAt(const std::vector<TruthRow>& truth, double t_unix);

struct EstimateRow
{
	double t_unix = 0;
	Eigen::Vector3d p_n;	   //!< body origin
	Eigen::Matrix3d R_nb;
	Eigen::Matrix2d P_ne;	   //!< horizontal position covariance
	double heading_sigma = 0;  //!< [rad]
};

struct RunResult
{
	std::vector<EstimateRow> rows;	//!< one per second of data
	std::vector<SensorStats> stats;
	double wall_s = 0, data_s = 0;
	std::size_t repairs = 0;
};

/** Runs the navigator with config `config_file` plus `overrides` (KEY=VALUE). */
RunResult runNavigator(const std::string& config_file, const std::string& rawlog,
					   const std::vector<std::pair<std::string, std::string>>& overrides,
					   const std::vector<DenialWindow>& denials = {});

/** Heading (yaw) of R_nb [rad] and the wrapped difference a − b. */
double yawOf(const Eigen::Matrix3d& R);
double wrapPi(double a);

/** Simulates `mission` (repo-relative) with `seed` into a fresh scratch folder. */
std::filesystem::path simulate(const std::string& mission, unsigned seed);

}  // namespace auvnav::test
