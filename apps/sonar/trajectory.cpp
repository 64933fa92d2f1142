#include "trajectory.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace auvnav::sonarapp
{
TumTrajectory TumTrajectory::load(const std::string& file)
{
	std::ifstream f(file);
	if (!f) throw std::runtime_error("cannot read trajectory " + file);
	TumTrajectory tr;
	std::string line;
	int n = 0;
	while (std::getline(f, line))
	{
		++n;
		if (line.empty() || line[0] == '#') continue;
		std::istringstream ss(line);
		TumPose p;
		double qx, qy, qz, qw;
		if (!(ss >> p.t >> p.p_n.x() >> p.p_n.y() >> p.p_n.z() >> qx >> qy >> qz >> qw))
			throw std::runtime_error(file + ":" + std::to_string(n) + ": expected 't x y z qx qy qz qw'");
		p.q_nb = Eigen::Quaterniond(qw, qx, qy, qz);
		if (!std::isfinite(p.t) || !p.p_n.allFinite() || !(std::abs(p.q_nb.norm() - 1) < 1e-3))
			throw std::runtime_error(file + ":" + std::to_string(n) + ": non-finite value or non-unit quaternion");
		p.q_nb.normalize();
		if (!tr.poses_.empty() && p.t <= tr.poses_.back().t) continue;	// keep it strictly increasing
		tr.poses_.push_back(p);
	}
	if (tr.poses_.empty()) throw std::runtime_error(file + ": no poses");
	return tr;
}

std::optional<TumPose> TumTrajectory::at(double t, double max_gap_s) const
{
	if (poses_.empty() || t < poses_.front().t || t > poses_.back().t) return std::nullopt;
	auto it = std::lower_bound(poses_.begin(), poses_.end(), t, [](const TumPose& p, double v) { return p.t < v; });
	if (it == poses_.begin()) return *it;
	const TumPose& b = *it;
	const TumPose& a = *(it - 1);
	if (b.t - a.t > max_gap_s) return std::nullopt;
	const double s = (t - a.t) / (b.t - a.t);
	TumPose p;
	p.t = t;
	p.p_n = (1 - s) * a.p_n + s * b.p_n;
	p.q_nb = a.q_nb.slerp(s, b.q_nb);
	return p;
}

}  // namespace auvnav::sonarapp
