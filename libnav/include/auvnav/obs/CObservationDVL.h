#pragma once
/** @file CObservationDVL.h
 *  Doppler Velocity Log bottom-track observation.
 *
 *  Contract:
 *  - `velocity_s_mps` is the velocity of the sensor over the seabed, expressed
 *    in the sensor frame (sensor pose on the vehicle: `sensorPose`, body FRD).
 *    It is meaningful only when `bottom_lock` is true.
 *  - `velocity_cov` (row-major 3x3, m²/s²) is the covariance of that velocity
 *    as computed from the beam geometry and per-beam noise.
 *  - One entry per acoustic beam in `beams`: slant range to the seabed (m) and
 *    whether that beam had a valid bottom return. `altitude_m` is the vertical
 *    distance sensor→seabed (NaN when no beam returned).
 *  - Serialization is versioned; every version ever written stays readable.
 */
#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <array>
#include <cstdint>
#include <vector>

namespace auvnav::obs
{
struct DvlBeam
{
	double range_m = 0;  //!< slant range along the beam to the seabed [m]
	bool valid = false;  //!< beam had a bottom return inside the lock window
};

class CObservationDVL : public mrpt::obs::CObservation
{
	DEFINE_SERIALIZABLE(CObservationDVL, auvnav::obs)

   public:
	std::array<double, 3> velocity_s_mps{0, 0, 0};  //!< sensor velocity over ground, sensor frame [m/s]
	std::array<double, 9> velocity_cov{};  //!< row-major covariance of velocity_s_mps [m²/s²]
	bool bottom_lock = false;  //!< enough valid beams to solve the 3D velocity
	double altitude_m = 0;	//!< vertical distance to the seabed [m], NaN if unknown
	double beam_inclination_rad = 0;  //!< Janus angle of the beams from the sensor z axis
	std::vector<DvlBeam> beams;	 //!< per-beam range and validity
	mrpt::poses::CPose3D sensorPose;  //!< sensor pose in the body frame (FRD)

	void getSensorPose(mrpt::poses::CPose3D& out) const override { out = sensorPose; }
	void setSensorPose(const mrpt::poses::CPose3D& p) override { sensorPose = p; }
	void getDescriptionAsText(std::ostream& o) const override;
	bool exportTxtSupported() const override { return true; }
	std::string exportTxtHeader() const override;
	std::string exportTxtDataRow() const override;
};
}  // namespace auvnav::obs
