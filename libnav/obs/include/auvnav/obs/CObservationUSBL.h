#pragma once
/** @file CObservationUSBL.h
 *  An acoustic position fix of a transponder on the vehicle, as a ship's (or a
 *  buoy's) USBL system reports it: the system has already combined its own
 *  GNSS position, attitude and the acoustic range and bearing.
 *
 *  Contract:
 *  - `timestamp` is when the logger received the fix (an acoustic fix arrives
 *    0.5–3 s after it was taken: two-way travel, processing, telemetry);
 *    `measurement_time` is when the fix was taken (the transponder's reply at
 *    the ship), INVALID_TIMESTAMP if the system does not say (the navigator
 *    then uses the timestamp minus the sensor entry's `latency_s`).
 *  - `frame` says what `position` holds: Geodetic: latitude [deg], longitude
 *    [deg], depth [m, positive down]; LocalNed: north, east, down [m] in the
 *    navigation frame at the navigator's origin.
 *  - `covariance_ned_m2`: the fix's covariance in north/east/down [m²],
 *    row-major; all NaN if the system gives none (the consumer then uses its
 *    own error model, e.g. σ growing with slant range).
 *  - `slant_range_m`: transducer to transponder [m], NaN if unknown;
 *    `transponder_id`: the beacon's address.
 *  - `sensorPose`: the transponder's mounting on the vehicle (body FRD).
 *  Serialization is versioned; every version stays readable. Decoding checks
 *  `frame` (no out-of-range enum reaches the consumer).
 */
#include <auvnav/obs/MountedObservation.h>

#include <array>
#include <cstdint>
#include <limits>

namespace auvnav::obs
{
enum class UsblFrame : uint8_t
{
	Geodetic = 0,  //!< latitude [deg], longitude [deg], depth [m]
	LocalNed = 1   //!< north, east, down [m] from the navigation origin
};

class CObservationUSBL : public MountedObservation
{
	DEFINE_SERIALIZABLE(CObservationUSBL, auvnav::obs)

 public:
	static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
	mrpt::Clock::time_point measurement_time = INVALID_TIMESTAMP;  //!< when the fix was taken
	UsblFrame frame = UsblFrame::Geodetic;
	std::array<double, 3> position{kNaN, kNaN, kNaN};  //!< see frame
	std::array<double, 9> covariance_ned_m2{kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN};
	double slant_range_m = kNaN;
	uint16_t transponder_id = 0;

	bool hasCovariance() const;
	void getDescriptionAsText(std::ostream& o) const override;
	bool exportTxtSupported() const override { return true; }
	std::string exportTxtHeader() const override;
	std::string exportTxtDataRow() const override;
};
}  // namespace auvnav::obs
