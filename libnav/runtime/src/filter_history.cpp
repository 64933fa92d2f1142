#include <auvnav/filter_history.h>

#include <limits>

namespace auvnav
{
void FilterHistory::trim(double t_s)
{
	// Keep the newest checkpoint at or before t − max_delay and all after it:
	// a measurement up to max_delay_s old finds one before it.
	while (checkpoints_.size() >= 2 && checkpoints_[1].t_s <= t_s - p_.max_delay_s) checkpoints_.pop_front();
	const std::size_t keep_from = checkpoints_.empty() ? end() : checkpoints_.front().event;
	while (first_ < keep_from && !events_.empty())
	{
		events_.pop_front();
		++first_;
	}
}

void FilterHistory::pushImu(double t_s, const Eigen::Vector3d& w)
{
	FilterEvent e;
	e.imu = true;
	e.t = t_s;
	e.w = w;
	events_.push_back(std::move(e));
}

void FilterHistory::insert(std::size_t at, FilterEvent e)
{
	events_.insert(events_.begin() + static_cast<std::ptrdiff_t>(at - first_), std::move(e));
}

std::optional<std::size_t> FilterHistory::rewindFor(double t_m)
{
	std::size_t ins = end();
	while (ins > first_ && !(at(ins - 1).imu && at(ins - 1).t <= t_m)) --ins;
	if (ins == first_) return std::nullopt;  // older than everything kept
	while (ins < end() && !at(ins).imu && at(ins).t_obs <= t_m) ++ins;
	// The last checkpoint before that point; later ones are re-taken.
	std::size_t keep = checkpoints_.size();
	while (keep > 0 && checkpoints_[keep - 1].event > ins) --keep;
	if (keep == 0) return std::nullopt;
	checkpoints_.resize(keep);
	return ins;
}

std::size_t FilterHistory::settledSmootherRecords() const
{
	// Records from before the oldest checkpoint can no longer be rewound.
	if (checkpoints_.empty() || !checkpoints_.front().smoother)
		return std::numeric_limits<std::size_t>::max();
	return checkpoints_.front().smoother->emitted;
}

void FilterHistory::dropSmootherSnapshots()
{
	for (auto& c : checkpoints_) c.smoother.reset();
}

}  // namespace auvnav
