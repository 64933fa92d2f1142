#pragma once
/** @file rejection_streak.h
 *  Tells a state gone wrong from a sensor gone wrong, from the innovations of
 *  an aid's consecutive gate rejections.
 *
 *  When the state is off (a velocity integrated blind through a DVL gap, a
 *  spike that was accepted), the aid's next measurements are all rejected,
 *  but they agree with each other: their innovations ν_k = z_k − h(x̂_k)
 *  follow a smooth curve (the state error, drifting as the filter
 *  dead-reckons) plus the measurement noise. Outliers (spikes, multipath,
 *  a lock on fish) do not. So over the last n rejected innovations, whitened
 *  by the measurement noise R (not by S: the state's own uncertainty is the
 *  common part being tested for), each component is fitted with a straight
 *  line in time; if the residual sum of squares is inside the χ² quantile of
 *  (n − 2)·m degrees of freedom, the streak is a bias of the state and the
 *  navigator re-acquires the aid at once (ManifoldUkf::update's recovery),
 *  instead of waiting for `gates.recovery_after_s`.
 */
#include <auvnav/recent_rejections.h>

#include <Eigen/Core>

namespace auvnav
{
/** One rejection of a streak: its time [s] and its innovation whitened by
 *  R: L⁻¹ ν, R = L Lᵀ. */
struct WhitenedRejection
{
	double t_s;
	Eigen::VectorXd w;
};

class RejectionStreak : public RecentRejections<WhitenedRejection>
{
 public:
	explicit RejectionStreak(int capacity = 8) : RecentRejections(capacity) {}

	/** One more rejection: time [s], innovation ν, measurement noise R. A
	 *  change of dimension starts a new streak. */
	void add(double t_s, const Eigen::VectorXd& nu, const Eigen::MatrixXd& R);

	/** True when the last `count` (≥ 3) rejections fit a linear drift within
	 *  the χ² quantile at `probability` (see above). */
	bool consistentBias(int count, double probability) const;
};

}  // namespace auvnav
