#include <auvnav/fix_consensus.h>
#include <auvnav/ukf.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <vector>

namespace auvnav
{
void InitialFixConsensus::add(double t_s, const InitialFix& fix)
{
	fixes_.push_back({t_s, fix});
	while (!fixes_.empty() && fixes_.front().t_s < t_s - params_.window_s) fixes_.pop_front();
}

Eigen::Vector2d InitialFixConsensus::median_ne() const
{
	// Per axis: a minority of wild fixes cannot drag it (unlike the mean).
	Eigen::Vector2d m = Eigen::Vector2d::Zero();
	std::vector<double> v(fixes_.size());
	for (int axis = 0; axis < 2; ++axis)
	{
		for (std::size_t i = 0; i < fixes_.size(); ++i) v[i] = fixes_[i].fix.p_n[axis];
		const std::size_t mid = v.size() / 2;
		std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
		m[axis] = v[mid];
		if (v.size() % 2 == 0)
			m[axis] =
			    0.5 * (m[axis] + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid)));
	}
	return m;
}

bool InitialFixConsensus::agrees(const Entry& e, const Eigen::Vector2d& centre_ne) const
{
	return (e.fix.p_n.head<2>() - centre_ne).norm() <= params_.max_spread_m;
}

int InitialFixConsensus::agreeing() const
{
	if (fixes_.empty()) return 0;
	const Eigen::Vector2d c = median_ne();
	return static_cast<int>(
	    std::count_if(fixes_.begin(), fixes_.end(), [&](const Entry& e) { return agrees(e, c); }));
}

std::optional<InitialFix> InitialFixConsensus::agreed() const
{
	const int n = agreeing();
	if (n < std::max(params_.min_fixes, 1) || 2 * n <= fixes()) return std::nullopt;
	const Eigen::Vector2d c = median_ne();
	for (auto it = fixes_.rbegin(); it != fixes_.rend(); ++it)
		if (agrees(*it, c)) return it->fix;
	return std::nullopt;
}

void RejectedFixRun::add(double t_s, const Eigen::Vector2d& nu_ne_m, const Eigen::Matrix2d& R_m2)
{
	const Eigen::LLT<Eigen::Matrix2d> llt(R_m2);
	if (llt.info() != Eigen::Success || !nu_ne_m.allFinite())
	{
		clear();
		return;
	}
	push({t_s, nu_ne_m, R_m2, llt.solve(Eigen::Matrix2d::Identity())});
}

Eigen::Vector2d RejectedFixRun::meanOffset_m(int count) const
{
	// Weighted least squares of one constant offset: (Σ R⁻¹)⁻¹ Σ R⁻¹ ν.
	Eigen::Matrix2d W = Eigen::Matrix2d::Zero();
	Eigen::Vector2d b = Eigen::Vector2d::Zero();
	for (int k = size() - count; k < size(); ++k)
	{
		W += entry(k).R_inv;
		b += entry(k).R_inv * entry(k).nu;
	}
	return W.ldlt().solve(b);
}

Eigen::Matrix2d RejectedFixRun::meanNoise_m2(int count) const
{
	Eigen::Matrix2d R = Eigen::Matrix2d::Zero();
	for (int k = size() - count; k < size(); ++k) R += entry(k).R;
	return R / count;
}

bool RejectedFixRun::agree(int count, double probability) const
{
	if (count < 2 || size() < count) return false;
	const Eigen::Vector2d mean = meanOffset_m(count);
	double q = 0;
	for (int k = size() - count; k < size(); ++k)
	{
		const Eigen::Vector2d d = entry(k).nu - mean;
		q += d.dot(entry(k).R_inv * d);
	}
	return q <= ManifoldUkf::chiSquareQuantile(2 * (count - 1), probability);
}

}  // namespace auvnav
