#include "logger_clock.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace auvnav::sim
{
StampParams StampParams::fromConfig(const config::Node& n, double period_s)
{
	StampParams p;
	p.jitter_sigma_s = n.nonNegative("timestamp_jitter_sigma_s", 0.0);
	// Beyond 0.1 period the ±0.49-period clip would visibly shrink the σ.
	if (p.jitter_sigma_s > 0.1 * period_s)
		n.fail("timestamp_jitter_sigma_s",
		       "must be <= 0.1 sensor periods (" + std::to_string(0.1 * period_s) +
		           " s at this rate) so that one sensor's stamps keep their order");
	p.duplicate_probability = n.inRange("duplicate_stamp_probability", 0, 0.5, 0.0);
	p.out_of_order_probability = n.inRange("out_of_order_probability", 0, 0.5, 0.0);
	return p;
}

LoggerClock::LoggerClock(const StampParams& p, double period_s, uint32_t stream_seed)
    : p_(p), period_s_(period_s), clip_s_(0.49 * period_s), active_(p.active())
{
	rng_.randomize(stream_seed);
	// Jitter alone: the clip. An early stamp: 1.5 periods more; a duplicate
	// of an early stamp (or of a jittered one) one period more still.
	if (active_)
	{
		max_early_s_ = clip_s_;
		if (p.out_of_order_probability > 0)
			max_early_s_ += 2.5 * period_s;
		else if (p.duplicate_probability > 0)
			max_early_s_ += period_s;
	}
}

LoggerClock::Stamp LoggerClock::stamp(mrpt::Clock::time_point true_stamp)
{
	if (!active_) return {true_stamp, true_stamp};
	auto seconds = [](double t_s)
	{ return std::chrono::duration_cast<mrpt::Clock::duration>(std::chrono::duration<double>(t_s)); };
	double jitter_s = 0;
	if (p_.jitter_sigma_s > 0)
		jitter_s = std::clamp(p_.jitter_sigma_s * rng_.drawGaussian1D_normalized(), -clip_s_, clip_s_);
	const auto jittered = true_stamp + seconds(jitter_s);
	Stamp s{jittered, jittered};
	// One uniform draw per sample decides the anomaly, so the two
	// probabilities never change each other's stream.
	const double u = rng_.drawUniform(0.0, 1.0);
	if (have_previous_ && u < p_.duplicate_probability)
	{
		// A run of duplicates would drift ever earlier: bounded by maxEarly_s().
		if (previous_ >= true_stamp - seconds(max_early_s_))
		{
			s.recorded = previous_;
			++duplicates_;
		}
	}
	else if (have_previous_ && u < p_.duplicate_probability + p_.out_of_order_probability)
	{
		s.recorded = jittered - seconds(1.5 * period_s_);
		++out_of_order_;
	}
	previous_ = s.recorded;
	have_previous_ = true;
	return s;
}

}  // namespace auvnav::sim
