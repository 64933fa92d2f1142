#pragma once
// End-to-end harness: simulate a mission, run the navigator on its rawlog
// in-process, and line the estimate up with the ground truth.
#include <auvnav/angles.h>
#include <auvnav/config.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/io/trajectory.h>
#include <auvnav/navigator.h>
#include <auvnav/rawlog_run.h>
#include <auvnav/testing/scratch_dir.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace auvnav::test
{
// The ground truth through libnav's one reader (auvnav/io/trajectory.h), as
// auvnav-experiment and auvnav-eval read it.
using TruthRow = io::TrajectoryPoint;
inline std::vector<TruthRow> readTruth(const std::filesystem::path& csv)
{
	return io::readGroundTruth(csv);
}
/** The truth interpolated at t (clamped to the ends). */
inline TruthRow truthAt(const std::vector<TruthRow>& truth, double t)
{
	return io::at(truth, t);
}

struct EstimateRow
{
	double t_unix = 0;
	Eigen::Vector3d p_n;  //!< body origin
	Eigen::Matrix3d R_nb;
	Eigen::Matrix2d P_ne;   //!< horizontal position covariance
	Eigen::Matrix3d P_att;  //!< attitude covariance (NED axes) [rad²]
	double headingSigma() const { return std::sqrt(P_att(2, 2)); }  //!< [rad]
};

struct RunResult
{
	std::vector<EstimateRow> rows;  //!< one per second of data
	std::vector<SensorStats> stats;
	double wall_s = 0, data_s = 0;
	std::size_t repairs = 0;
	NavStatus status = NavStatus::Ok, worst = NavStatus::Ok;  //!< the divergence monitor at the end
	std::string status_reason;
};

/** Runs the navigator with config `config_file` plus `overrides` (KEY=VALUE)
 *  over the rawlog through libnav's run loop (rawlog_run.h); a rawlog or
 *  navigator error is rethrown. */
RunResult runNavigator(const std::string& config_file, const std::string& rawlog,
                       const std::vector<std::pair<std::string, std::string>>& overrides,
                       const std::vector<DenialWindow>& denials = {});

/** Heading (yaw) of R_nb [rad] and the wrapped difference a − b. */
double yawOf(const Eigen::Matrix3d& R);

/** Indices of the first submerged truth row (the dive) and of the first
 *  surfaced row after it (resurfacing; truth.size() if none). */
std::pair<std::size_t, std::size_t> diveAndResurfacing(const std::vector<TruthRow>& truth);

/** Horizontal error of the body origin against the truth at the filter's
 *  time, and twice the σ of the position's major axis. */
struct HorizontalError
{
	double error_m = 0, two_sigma_m = 0;
};
HorizontalError horizontalError(const Navigator& nav, const std::vector<TruthRow>& truth);

/** A test's scratch folder, removed with its contents when it goes out of
 *  scope (auvnav/testing/scratch_dir.h). */
using ScratchDir = auvnav::testing::ScratchDir;

/** Simulates `mission` (repo-relative) with `seed` into a fresh scratch
 *  folder: the rawlog and ground_truth.csv; removed when the returned
 *  object goes out of scope. */
ScratchDir simulate(const std::string& mission, unsigned seed);
/** The same with `sensor_overrides` (KEY=VALUE on the mission's sensor file,
 *  e.g. {"dvl.scale_factor_error", "0.005"}); `tag` keeps variants apart. */
ScratchDir simulate(const std::string& mission, unsigned seed,
                    const std::vector<std::pair<std::string, std::string>>& sensor_overrides,
                    const std::string& tag);

}  // namespace auvnav::test
