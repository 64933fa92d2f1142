#pragma once
/** @file recent_rejections.h
 *  The newest gate rejections of one aid, oldest first: what RejectionStreak
 *  and RejectedFixRun judge. An entry whose noise cannot whiten its
 *  innovation clears the run (there is nothing to judge it by).
 */
#include <deque>
#include <utility>

namespace auvnav
{
template <class Entry>
class RecentRejections
{
 public:
	/** Keeps at most `capacity` rejections (the newest). */
	explicit RecentRejections(int capacity) : capacity_(capacity) {}

	void clear() { entries_.clear(); }
	int size() const { return static_cast<int>(entries_.size()); }

 protected:
	void push(Entry e)
	{
		entries_.push_back(std::move(e));
		while (size() > capacity_) entries_.pop_front();
	}
	//! Entry k, 0 the oldest kept.
	const Entry& entry(int k) const { return entries_[static_cast<std::size_t>(k)]; }
	const Entry& newest() const { return entries_.back(); }

 private:
	int capacity_;
	std::deque<Entry> entries_;
};
}  // namespace auvnav
