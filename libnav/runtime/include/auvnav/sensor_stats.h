#pragma once
/** @file sensor_stats.h
 *  What happened to one sensor's observations over a run: the counts
 *  summary.json and auvnav-info report per sensor.
 */
#include <auvnav/ukf.h>

#include <cstddef>
#include <string>

namespace auvnav
{
struct SensorStats
{
	std::string label, plugin;
	std::size_t accepted = 0, recovered = 0, rejected = 0, invalid = 0, skipped = 0, denied = 0, late = 0,
	            before_init = 0;
	//! Observations applied at their measurement time by re-filtering (also
	//! counted by their update status).
	std::size_t delayed = 0;
	//! Position re-initialisations from this sensor's fixes (gates.position_reinit).
	std::size_t reinitialized = 0;
	double nis_sum = 0;      //!< over accepted and recovered updates
	double nis_dim_sum = 0;  //!< Σ dimensions of those updates (E[NIS] = dim)
	std::string last_problem;

	/** Counts one update by its status (its NIS if it was applied). */
	void count(const UpdateResult& r)
	{
		switch (r.status)
		{
			case UpdateStatus::Accepted:
			case UpdateStatus::Recovered:
				++(r.status == UpdateStatus::Accepted ? accepted : recovered);
				nis_sum += r.nis;
				nis_dim_sum += r.dim;
				break;
			case UpdateStatus::Rejected:
				++rejected;
				break;
			case UpdateStatus::Invalid:
				++invalid;
				last_problem = r.why;
				break;
		}
	}
};

}  // namespace auvnav
