#pragma once
/** @file eval.h
 *  A navigator run (auvnav-run's states.csv, nis.csv) against the simulator's
 *  ground truth (ground_truth.csv): errors, their σ, NEES of position and
 *  attitude (3 dof each, full covariance blocks), NIS per sensor.
 *  Attitude error δθ = Log(R_est R_trueᵀ) in the navigation frame (the
 *  filter's left perturbation, so the covariance applies as is).
 */
#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace auvnav::eval
{
struct Sample
{
	double t = 0;  //!< Unix time [s]
	Eigen::Vector3d pos_err_ned = Eigen::Vector3d::Zero();
	Eigen::Matrix3d P_pos = Eigen::Matrix3d::Identity();
	Eigen::Vector3d att_err = Eigen::Vector3d::Zero();  //!< δθ [rad]
	Eigen::Matrix3d P_att = Eigen::Matrix3d::Identity();
	double heading_err_rad = 0, heading_sigma_rad = 0;
	Eigen::Vector2d current_est = Eigen::Vector2d::Zero(), current_true = Eigen::Vector2d::Zero(),
	                current_sigma = Eigen::Vector2d::Zero();
	//! Physical damping estimates (exp of the stored logs) and their 2σ bounds: D_l,xx, D_l,yy, D_q,xx,
	//! D_q,yy.
	Eigen::Vector4d damping = Eigen::Vector4d::Zero(), damping_lo = Eigen::Vector4d::Zero(),
	                damping_hi = Eigen::Vector4d::Zero();
	double distance_m = 0;    //!< travelled so far (truth)
	double depth_true_m = 0;  //!< truth's depth (dive: > 0.5 m)
	double nees_pos = 0, nees_att = 0;
	double nees_hpos = 0;  //!< horizontal position only (2 dof)
};

struct NisBin
{
	double t = 0;
	std::size_t updates = 0, dim = 0;
	double nis = 0;
};

struct Evaluation
{
	std::vector<Sample> samples;
	std::map<std::string, std::vector<NisBin>> nis;  //!< per sensor label
};

/** Reads RUN/states.csv (or `states_file`: smoothed_states.csv) and
 *  RUN/nis.csv if present, and the truth CSV; keeps one sample per
 *  `every_s`. Throws std::runtime_error naming file/line. */
Evaluation evaluate(const std::string& run_dir, const std::string& truth_csv, double every_s = 1.0,
                    const std::string& states_file = "states.csv");

/** The sample of the first state at or after `after_truth_start_s` seconds
 *  after the truth's first row (every state, no subsampling); nullopt if
 *  there is none or no truth there. auvnav-experiment takes its error at the
 *  same instant (the first prediction at or after the end of the denial). */
std::optional<Sample> sampleAt(const std::string& run_dir, const std::string& truth_csv,
                               double after_truth_start_s, const std::string& states_file = "states.csv");

/** Two-sided 95 % bounds of the mean of `runs` independent χ²(dof) values. */
std::pair<double, double> chi2MeanBounds(int dof, int runs, double probability = 0.95);

}  // namespace auvnav::eval
