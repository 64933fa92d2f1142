#include <auvnav/sonar/landmarks.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <set>
#include <stdexcept>

namespace auvnav::sonar
{
PoleMap PoleMap::fromConfig(const config::Node& n)
{
	PoleMap m;
	std::set<std::string> ids;
	for (const auto& p : n.sequence("poles"))
	{
		Pole pole;
		pole.id = p.string("id");
		if (!ids.insert(pole.id).second) p.fail("id", "duplicate pole id '" + pole.id + "'");
		pole.ne_m = {p.number("north_m"), p.number("east_m")};
		if (!pole.ne_m.allFinite()) p.fail("north_m", "pole position must be finite");
		pole.radius_m = p.positive("radius_m", 0.1);
		m.poles.push_back(pole);
	}
	if (m.poles.empty()) n.fail("poles", "the map has no poles");
	return m;
}

PoleMap PoleMap::load(const std::string& file)
{
	const auto n = config::Node::load(file);
	PoleMap m = fromConfig(n);
	n.checkAllKeysUsed();
	return m;
}

void predictPole(const SonarPose& pose, const Eigen::Vector2d& ne, double& bearing_rad, double& range_m)
{
	const Eigen::Vector2d d = ne - pose.ne_m;
	range_m = d.norm();
	bearing_rad = wrapAngle(std::atan2(d.y(), d.x()) - pose.heading_rad);
}

namespace
{
/** Jacobians of bearing and range w.r.t. the sonar position. */
void positionJacobians(const Eigen::Vector2d& d, double range_m, Eigen::RowVector2d& J_b,
                       Eigen::RowVector2d& J_r)
{
	const double r2 = range_m * range_m;
	J_b << d.y() / r2, -d.x() / r2;  // ∂atan2(ΔE, ΔN)/∂(N_s, E_s)
	J_r << -d.x() / range_m, -d.y() / range_m;
}
}  // namespace

std::vector<Association> associate(const std::vector<Detection>& dets, const PoleMap& map,
                                   const SonarPose& pose, const AssociationParams& p)
{
	const double gate = boost::math::quantile(boost::math::chi_squared(2.0), p.gate_probability);
	std::vector<Association> cand;
	std::vector<std::vector<double>> nis_of(dets.size());
	for (std::size_t i = 0; i < dets.size(); ++i)
		for (std::size_t j = 0; j < map.poles.size(); ++j)
		{
			Association a;
			a.detection = static_cast<int>(i);
			a.pole = static_cast<int>(j);
			predictPole(pose, map.poles[j].ne_m, a.predicted_bearing_rad, a.predicted_range_m);
			if (a.predicted_range_m < 1e-6) continue;
			// The return comes from the pole's near face.
			const double r_face = a.predicted_range_m - map.poles[j].radius_m;
			const Eigen::Vector2d nu(wrapAngle(dets[i].bearing_rad - a.predicted_bearing_rad),
			                         dets[i].range_m - r_face);
			Eigen::RowVector2d J_b, J_r;
			positionJacobians(map.poles[j].ne_m - pose.ne_m, a.predicted_range_m, J_b, J_r);
			Eigen::Matrix<double, 2, 2> J;
			J << J_b, J_r;
			Eigen::Matrix2d S = J * pose.P_ne * J.transpose();
			S(0, 0) += std::pow(dets[i].sigma_bearing_rad, 2) + std::pow(pose.sigma_heading_rad, 2);
			S(1, 1) += std::pow(dets[i].sigma_range_m, 2) + std::pow(map.poles[j].radius_m, 2) / 4;
			a.nis = nu.dot(S.ldlt().solve(nu));
			nis_of[i].push_back(a.nis);
			if (a.nis <= gate) cand.push_back(a);
		}
	std::sort(cand.begin(), cand.end(),
	          [](const Association& x, const Association& y) { return x.nis < y.nis; });
	std::vector<Association> out;
	std::vector<bool> det_used(dets.size(), false), pole_used(map.poles.size(), false);
	for (const auto& a : cand)
	{
		if (det_used[static_cast<std::size_t>(a.detection)] || pole_used[static_cast<std::size_t>(a.pole)])
			continue;
		// Ambiguous: another pole explains this detection nearly as well.
		auto& all = nis_of[static_cast<std::size_t>(a.detection)];
		std::sort(all.begin(), all.end());
		det_used[static_cast<std::size_t>(a.detection)] = true;
		// Likelihood ratio of the two best: exp(−(NIS₂ − NIS₁)/2).
		if (all.size() >= 2 && all[1] <= gate && all[1] - all[0] < 2 * std::log(p.ambiguity_ratio)) continue;
		pole_used[static_cast<std::size_t>(a.pole)] = true;
		out.push_back(a);
	}
	return out;
}

std::optional<FrameHeading> headingFromPoles(const std::vector<Detection>& dets,
                                             const std::vector<Association>& as, const PoleMap& map,
                                             const SonarPose& pose, double mount_yaw_rad)
{
	if (as.empty()) return std::nullopt;
	// Circular mean about the first pole's heading: small wrapped offsets.
	double ref = 0, sum_w = 0, sum_wx = 0;
	std::vector<std::pair<double, double>> hv;  // heading, variance
	for (std::size_t k = 0; k < as.size(); ++k)
	{
		const auto& a = as[k];
		const Eigen::Vector2d d = map.poles[static_cast<std::size_t>(a.pole)].ne_m - pose.ne_m;
		const double psi = wrapAngle(std::atan2(d.y(), d.x()) -
		                             dets[static_cast<std::size_t>(a.detection)].bearing_rad - mount_yaw_rad);
		Eigen::RowVector2d J_b, J_r;
		positionJacobians(d, d.norm(), J_b, J_r);
		const double var = std::pow(dets[static_cast<std::size_t>(a.detection)].sigma_bearing_rad, 2) +
		                   (J_b * pose.P_ne * J_b.transpose())(0, 0);
		if (k == 0) ref = psi;
		hv.emplace_back(psi, var);
		const double w = 1.0 / var;
		sum_w += w;
		sum_wx += w * wrapAngle(psi - ref);
	}
	FrameHeading fh;
	const double mean_off = sum_wx / sum_w;
	fh.heading_rad = wrapAngle(ref + mean_off);
	double var = 1.0 / sum_w;
	if (hv.size() >= 2)
	{
		// Spread of the individual headings (weighted), if larger than predicted.
		double s = 0;
		for (const auto& [psi, v] : hv) s += std::pow(wrapAngle(psi - ref) - mean_off, 2) / v;
		var *= std::max(1.0, s / static_cast<double>(hv.size() - 1));
	}
	fh.sigma_rad = std::sqrt(var);
	fh.poles = static_cast<int>(as.size());
	return fh;
}

}  // namespace auvnav::sonar
