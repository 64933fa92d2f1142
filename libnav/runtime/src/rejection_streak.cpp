#include <auvnav/rejection_streak.h>
#include <auvnav/ukf.h>

#include <Eigen/Cholesky>

namespace auvnav
{
void RejectionStreak::add(double t_s, const Eigen::VectorXd& nu, const Eigen::MatrixXd& R)
{
	if (size() > 0 && newest().w.size() != nu.size()) clear();
	const Eigen::LLT<Eigen::MatrixXd> llt(R);
	if (llt.info() != Eigen::Success || !nu.allFinite())
	{
		clear();  // nothing to judge a streak by
		return;
	}
	push({t_s, llt.matrixL().solve(nu)});
}

bool RejectionStreak::consistentBias(int count, double probability) const
{
	if (count < 3 || size() < count) return false;
	const int first = size() - count;
	const int m = static_cast<int>(newest().w.size());
	// Least-squares line per whitened component over the last `count` points.
	double t_mean = 0;
	for (int k = first; k < first + count; ++k) t_mean += entry(k).t_s;
	t_mean /= count;
	double stt = 0;
	for (int k = first; k < first + count; ++k) stt += std::pow(entry(k).t_s - t_mean, 2);
	Eigen::VectorXd w_mean = Eigen::VectorXd::Zero(m), slope = Eigen::VectorXd::Zero(m);
	for (int k = first; k < first + count; ++k) w_mean += entry(k).w;
	w_mean /= count;
	if (stt > 0)
	{
		for (int k = first; k < first + count; ++k) slope += (entry(k).t_s - t_mean) * (entry(k).w - w_mean);
		slope /= stt;
	}
	double rss = 0;
	for (int k = first; k < first + count; ++k)
		rss += (entry(k).w - w_mean - slope * (entry(k).t_s - t_mean)).squaredNorm();
	return rss <= ManifoldUkf::chiSquareQuantile((count - 2) * m, probability);
}

}  // namespace auvnav
