#include <auvnav/rejection_streak.h>
#include <auvnav/ukf.h>

#include <Eigen/Cholesky>

namespace auvnav
{
void RejectionStreak::add(double t_s, const Eigen::VectorXd& nu, const Eigen::MatrixXd& R)
{
	if (!entries_.empty() && entries_.back().w.size() != nu.size()) entries_.clear();
	const Eigen::LLT<Eigen::MatrixXd> llt(R);
	if (llt.info() != Eigen::Success || !nu.allFinite())
	{
		entries_.clear();  // nothing to judge a streak by
		return;
	}
	entries_.push_back({t_s, llt.matrixL().solve(nu)});
	while (static_cast<int>(entries_.size()) > capacity_) entries_.pop_front();
}

bool RejectionStreak::consistentBias(int count, double probability) const
{
	if (count < 3 || static_cast<int>(entries_.size()) < count) return false;
	const int first = static_cast<int>(entries_.size()) - count;
	const int m = static_cast<int>(entries_.back().w.size());
	// Least-squares line per whitened component over the last `count` points.
	double t_mean = 0;
	for (int k = first; k < first + count; ++k) t_mean += entries_[k].t_s;
	t_mean /= count;
	double stt = 0;
	for (int k = first; k < first + count; ++k) stt += std::pow(entries_[k].t_s - t_mean, 2);
	Eigen::VectorXd w_mean = Eigen::VectorXd::Zero(m), slope = Eigen::VectorXd::Zero(m);
	for (int k = first; k < first + count; ++k) w_mean += entries_[k].w;
	w_mean /= count;
	if (stt > 0)
	{
		for (int k = first; k < first + count; ++k)
			slope += (entries_[k].t_s - t_mean) * (entries_[k].w - w_mean);
		slope /= stt;
	}
	double rss = 0;
	for (int k = first; k < first + count; ++k)
		rss += (entries_[k].w - w_mean - slope * (entries_[k].t_s - t_mean)).squaredNorm();
	return rss <= ManifoldUkf::chiSquareQuantile((count - 2) * m, probability);
}

}  // namespace auvnav
