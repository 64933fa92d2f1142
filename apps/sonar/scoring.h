#pragma once
/** @file scoring.h
 *  Scores sonar detections and landmark headings against auvnav-sim's truth
 *  (sonar_frames.csv: per frame the true sonar heading and vehicle yaw;
 *  sonar_truth.csv: the poles truly in view with bearing and range).
 *  A detection is a true positive when it lies within `bearing_tol_deg` and
 *  `range_tol_m` of a pole truly in view (each pole matched at most once).
 */
#include <auvnav/sonar/detector.h>

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace auvnav::sonarapp
{
struct TruthFrame
{
	double vehicle_yaw_rad = 0;
	struct Pole
	{
		std::string id;
		double bearing_rad = 0, range_m = 0;
	};
	std::vector<Pole> in_view;
};

class SonarTruth
{
 public:
	/** Reads DIR/sonar_frames.csv and DIR/sonar_truth.csv (keys: time in ms). */
	static SonarTruth load(const std::string& dir);
	const TruthFrame* at(double unix_time_s) const;

 private:
	std::map<long long, TruthFrame> frames_;
};

struct Score
{
	std::size_t frames = 0, frames_without_poles = 0, false_in_empty_frames = 0;
	std::size_t true_positives = 0, false_positives = 0, false_negatives = 0;
	std::size_t heading_frames = 0;
	double heading_sq_sum = 0, heading_max_abs = 0, nees_sum = 0;
	double precision() const;
	double recall() const;
	double headingRms_rad() const;
	std::string markdown() const;
};

/** Adds one frame's detections (and landmark heading, if any) to `s`. */
void scoreFrame(const TruthFrame& truth, const std::vector<sonar::Detection>& dets,
                std::optional<double> heading_rad, double heading_sigma_rad, Score& s,
                double bearing_tol_deg = 2.0, double range_tol_m = 0.75);

}  // namespace auvnav::sonarapp
