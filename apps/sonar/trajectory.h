#pragma once
/** @file trajectory.h
 *  A TUM trajectory (`t x y z qx qy qz qw`, as auvnav-run's trajectory.tum and
 *  auvnav-sim's ground_truth.tum: NED position of the body origin, body-to-NED
 *  attitude) with interpolation in time.
 */
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

namespace auvnav::sonarapp
{
struct TumPose
{
	double t = 0;
	Eigen::Vector3d p_n = Eigen::Vector3d::Zero();
	Eigen::Quaterniond q_nb = Eigen::Quaterniond::Identity();
};

class TumTrajectory
{
   public:
	/** Throws std::runtime_error naming the file and line on bad input. */
	static TumTrajectory load(const std::string& file);
	/** Linear position / slerp attitude at `t`; nullopt outside the span or
	 *  across a gap longer than `max_gap_s`. */
	std::optional<TumPose> at(double t, double max_gap_s = 2.0) const;
	std::size_t size() const { return poses_.size(); }

   private:
	std::vector<TumPose> poses_;
};

}  // namespace auvnav::sonarapp
