#pragma once
/** @file logger_clock.h
 *  The logging computer's clock as one sensor sees it: the time stamp a real
 *  logger records is the sample's true time plus an arrival jitter, and now
 *  and then a stamp is repeated or lands before its predecessor. The sensor's
 *  true sampling stays on the simulation grid; only the recorded stamp moves.
 *
 *  Contract (keys read from the sensor's own config block, all optional):
 *  - timestamp_jitter_sigma_s [s], default 0: σ of a zero-mean Gaussian added
 *    to each stamp, clipped to ±0.49 sensor periods so that one sensor's stamps
 *    keep their order; σ is limited to 0.1 period (clipping then touches fewer
 *    than 1e-6 of the stamps, so the σ seen is the σ configured).
 *  - duplicate_stamp_probability [0, 0.5], default 0: the stamp repeats the
 *    previous recorded stamp of this sensor exactly (fresh data, stale stamp).
 *  - out_of_order_probability [0, 0.5], default 0: the stamp is moved 1.5
 *    periods back, i.e. between the stamps of the two previous samples.
 *  Anomalies apply to the jittered stamp. Rawlogs are kept in time order
 *  (io::RawlogWriter refuses an older stamp), so an out-of-order sample is
 *  written where its stamp puts it, before its predecessor, as an importer's
 *  reorder buffer would leave a real log; a duplicate follows the sample whose
 *  stamp it repeats. An anomaly that would put a stamp more than
 *  maxEarly_s() before the sample's true time (a run of duplicates) is not
 *  applied. Each clock owns its random stream; with all keys at their
 *  defaults it draws nothing and returns the true stamp.
 */
#include <auvnav/config.h>
#include <mrpt/core/Clock.h>
#include <mrpt/random/RandomGenerators.h>

#include <cstdint>

namespace auvnav::sim
{
struct StampParams
{
	double jitter_sigma_s = 0;
	double duplicate_probability = 0;
	double out_of_order_probability = 0;
	/** Reads the keys above from `n`; the limits depend on the sensor period. */
	static StampParams fromConfig(const config::Node& n, double period_s);
	bool active() const
	{
		return jitter_sigma_s > 0 || duplicate_probability > 0 || out_of_order_probability > 0;
	}
};

class LoggerClock
{
 public:
	/** A clock that never moves a stamp. */
	LoggerClock() = default;
	LoggerClock(const StampParams& p, double period_s, uint32_t stream_seed);

	struct Stamp
	{
		mrpt::Clock::time_point jittered;  //!< true + jitter
		mrpt::Clock::time_point recorded;  //!< the stamp written (jittered unless an anomaly)
	};
	/** The recorded stamp of a sample taken at `true_stamp`. */
	Stamp stamp(mrpt::Clock::time_point true_stamp);
	/** Largest time a recorded stamp can lie before the true one [s]: what a
	 *  writer keeping time order must wait for. */
	double maxEarly_s() const { return max_early_s_; }
	std::size_t duplicates() const { return duplicates_; }
	std::size_t outOfOrder() const { return out_of_order_; }

 private:
	StampParams p_;
	double period_s_ = 1, clip_s_ = 0, max_early_s_ = 0;
	bool active_ = false, have_previous_ = false;
	mrpt::Clock::time_point previous_{};
	std::size_t duplicates_ = 0, out_of_order_ = 0;
	mrpt::random::CRandomGenerator rng_;
};

}  // namespace auvnav::sim
