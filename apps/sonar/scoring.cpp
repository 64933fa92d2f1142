#include "scoring.h"

#include <auvnav/sonar/landmarks.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace auvnav::sonarapp
{
namespace
{
constexpr double kDeg = M_PI / 180;
long long key(double t)
{
	return std::llround(t * 1000.0);
}

std::vector<std::string> split(const std::string& line)
{
	std::vector<std::string> out;
	std::stringstream ss(line);
	std::string f;
	while (std::getline(ss, f, ',')) out.push_back(f);
	return out;
}
}  // namespace

SonarTruth SonarTruth::load(const std::string& dir)
{
	SonarTruth t;
	const std::string frames = dir + "/sonar_frames.csv", poles = dir + "/sonar_truth.csv";
	std::ifstream f(frames), p(poles);
	if (!f) throw std::runtime_error("cannot read " + frames);
	if (!p) throw std::runtime_error("cannot read " + poles);
	std::string line;
	std::getline(f, line);
	int n = 1;
	while (std::getline(f, line))
	{
		++n;
		const auto v = split(line);
		if (v.size() != 6) throw std::runtime_error(frames + ":" + std::to_string(n) + ": expected 6 fields");
		t.frames_[key(std::stod(v[0]))].vehicle_yaw_rad = std::stod(v[4]) * kDeg;
	}
	std::getline(p, line);
	n = 1;
	while (std::getline(p, line))
	{
		++n;
		const auto v = split(line);
		if (v.size() != 4) throw std::runtime_error(poles + ":" + std::to_string(n) + ": expected 4 fields");
		auto it = t.frames_.find(key(std::stod(v[0])));
		if (it == t.frames_.end())
			throw std::runtime_error(poles + ":" + std::to_string(n) + ": frame not in " + frames);
		it->second.in_view.push_back({v[1], std::stod(v[2]) * kDeg, std::stod(v[3])});
	}
	return t;
}

const TruthFrame* SonarTruth::at(double unix_time_s) const
{
	const auto it = frames_.find(key(unix_time_s));
	return it == frames_.end() ? nullptr : &it->second;
}

void scoreFrame(const TruthFrame& truth, const std::vector<sonar::Detection>& dets,
                std::optional<double> heading_rad, double heading_sigma_rad, Score& s, double bearing_tol_deg,
                double range_tol_m)
{
	++s.frames;
	std::vector<bool> used(truth.in_view.size(), false);
	std::size_t tp = 0;
	for (const auto& d : dets)
	{
		int best = -1;
		double best_cost = 1e9;
		for (std::size_t j = 0; j < truth.in_view.size(); ++j)
		{
			if (used[j]) continue;
			const double db =
			    std::abs(auvnav::wrapAngle(d.bearing_rad - truth.in_view[j].bearing_rad)) / kDeg;
			const double dr = std::abs(d.range_m - truth.in_view[j].range_m);
			if (db > bearing_tol_deg || dr > range_tol_m) continue;
			const double cost = db / bearing_tol_deg + dr / range_tol_m;
			if (cost < best_cost) best_cost = cost, best = static_cast<int>(j);
		}
		if (best >= 0)
		{
			used[static_cast<std::size_t>(best)] = true;
			++tp;
		}
	}
	s.true_positives += tp;
	s.false_positives += dets.size() - tp;
	s.false_negatives += truth.in_view.size() - tp;
	if (truth.in_view.empty())
	{
		++s.frames_without_poles;
		s.false_in_empty_frames += dets.size();
	}
	if (heading_rad)
	{
		const double e = auvnav::wrapAngle(*heading_rad - truth.vehicle_yaw_rad);
		++s.heading_frames;
		s.heading_sq_sum += e * e;
		s.heading_max_abs = std::max(s.heading_max_abs, std::abs(e));
		s.nees_sum += e * e / (heading_sigma_rad * heading_sigma_rad);
	}
}

double Score::precision() const
{
	const auto n = true_positives + false_positives;
	return n ? static_cast<double>(true_positives) / n : NAN;
}
double Score::recall() const
{
	const auto n = true_positives + false_negatives;
	return n ? static_cast<double>(true_positives) / n : NAN;
}
double Score::headingRms_rad() const
{
	return heading_frames ? std::sqrt(heading_sq_sum / heading_frames) : NAN;
}

std::string Score::markdown() const
{
	char buf[1024];
	std::snprintf(
	    buf, sizeof buf,
	    "| frames | poles in view | detections | precision | recall | false poles per 100 empty frames "
	    "| frames with a heading | heading error RMS | worst | mean NEES |\n"
	    "|---|---|---|---|---|---|---|---|---|---|\n"
	    "| %zu | %zu | %zu | %.1f %% | %.1f %% | %.2f (%zu in %zu) | %zu | %.3f° | %.3f° | %.2f |\n",
	    frames, true_positives + false_negatives, true_positives + false_positives, 100 * precision(),
	    100 * recall(), frames_without_poles ? 100.0 * false_in_empty_frames / frames_without_poles : NAN,
	    false_in_empty_frames, frames_without_poles, heading_frames, headingRms_rad() / kDeg,
	    heading_max_abs / kDeg, heading_frames ? nees_sum / heading_frames : NAN);
	return buf;
}

}  // namespace auvnav::sonarapp
