#pragma once
/** @file CObservationADCP.h
 *  Acoustic Doppler Current Profiler water-velocity profile.
 *
 *  Contract:
 *  - `cells[i].velocity_s_mps` is the velocity of the water in cell i relative
 *    to the sensor, expressed in the sensor frame (so a vehicle moving through
 *    still water sees −v). Valid only when `cells[i].valid`.
 *  - Cell i is centred at distance `blank_distance_m + (i + 0.5) * cell_size_m`
 *    along the sensor's z axis (the profiling direction).
 *  - `correlation` in [0, 1] is the beam correlation of the cell; consumers may
 *    apply their own threshold on top of `valid`.
 *  - Serialization is versioned; every version ever written stays readable.
 *    Reading refuses a damaged record whole (the object read into is left as
 *    it was): a `valid` byte other than 0/1, more than 4096 cells, a label
 *    longer than 4 KiB or a sensor pose that is no rigid transform.
 */
#include <auvnav/obs/MountedObservation.h>

#include <array>
#include <vector>

namespace auvnav::obs
{
struct AdcpCell
{
	std::array<double, 3> velocity_s_mps{0, 0, 0};  //!< water rel. to sensor, sensor frame [m/s]
	double correlation = 0;                         //!< beam correlation, 0..1
	bool valid = false;  //!< inside the water column and above the correlation floor
};

class CObservationADCP : public MountedObservation
{
	DEFINE_SERIALIZABLE(CObservationADCP, auvnav::obs)

 public:
	double blank_distance_m = 0;    //!< distance from transducer to first cell start [m]
	double cell_size_m = 0;         //!< cell length along the profiling axis [m]
	double velocity_sigma_mps = 0;  //!< per-axis 1σ velocity noise of one cell [m/s]
	std::vector<AdcpCell> cells;

	/** Distance of the centre of cell `i` from the transducer [m]. */
	double cellDistance(std::size_t i) const
	{
		return blank_distance_m + (static_cast<double>(i) + 0.5) * cell_size_m;
	}

	void getDescriptionAsText(std::ostream& o) const override;
	bool exportTxtSupported() const override { return true; }
	std::string exportTxtHeader() const override;
	std::string exportTxtDataRow() const override;
};
}  // namespace auvnav::obs
