#pragma once
/** @file CObservationDVL.h
 *  Doppler Velocity Log bottom-track observation.
 *
 *  Contract:
 *  - `velocity_s_mps` is the velocity of the sensor over the seabed, in the
 *    coordinates named by `frame` and with the sign named by `sign`:
 *    - Instrument: the sensor frame (sensor pose on the vehicle: `sensorPose`,
 *      body FRD); the default and the only mode of serialization version 0.
 *    - Vehicle: the body frame (FRD), already rotated by the DVL's own
 *      mounting setting; still the velocity of the DVL point.
 *    - EarthNed / EarthEnu: the navigation frame (north-east-down or
 *      east-north-up), rotated by the DVL with its own heading and tilt.
 *    - Beam: no 3-D velocity (`velocity_s_mps`, `velocity_cov` unused; the
 *      simulator writes NaN there);
 *      `beams[i].velocity_mps` are the radial velocities along each beam's
 *      unit vector (see DvlBeam), `beam_velocity_sigma_mps` their 1σ.
 *    - sign VehicleOverBottom: the sensor's velocity over the seabed;
 *      BottomOverInstrument: the seabed's velocity relative to the instrument,
 *      i.e. minus the sensor's (Teledyne RDI PD0: "the instrument is
 *      stationary and the bottom is moving").
 *    It is meaningful only when `bottom_lock` is true.
 *  - `velocity_cov` (row-major 3x3, m²/s²) is the covariance of that velocity,
 *    in the same coordinates, as computed from the beam geometry and per-beam
 *    noise (all zero: unknown).
 *  - One entry per acoustic beam in `beams`: slant range to the seabed (m) and
 *    whether that beam had a valid bottom return. `altitude_m` is the vertical
 *    distance sensor→seabed (NaN when no beam returned).
 *  - Serialization is versioned; every version ever written stays readable.
 *    Version 0: instrument frame and sign only (read back as Instrument,
 *    VehicleOverBottom, beam velocity, azimuth and σ 0). Version 1 adds
 *    `frame`, `sign`, `beam_velocity_sigma_mps` and per-beam velocity and
 *    azimuth. Enums and flags travel as uint8; a value out of range is
 *    refused as corrupt data.
 */
#include <auvnav/obs/MountedObservation.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace auvnav::obs
{
/** Coordinates of `CObservationDVL::velocity_s_mps` (serialized as uint8). */
enum class DvlFrame : uint8_t
{
	Instrument = 0,
	Vehicle = 1,
	EarthNed = 2,
	EarthEnu = 3,
	Beam = 4
};

/** Sign convention of the reported velocities (serialized as uint8). */
enum class DvlSign : uint8_t
{
	VehicleOverBottom = 0,    //!< velocity of the sensor over the seabed
	BottomOverInstrument = 1  //!< velocity of the seabed seen from the sensor (RDI PD0): minus the above
};

/** Names of the enumerators as used in configuration files and text output:
 *  "instrument", "vehicle", "earth_ned", "earth_enu", "beam";
 *  "vehicle_over_bottom", "bottom_over_instrument". */
const char* dvlFrameName(DvlFrame f);
const char* dvlSignName(DvlSign s);
/** Parses those names (exact, lower case); false and `out` untouched if unknown. */
bool parseDvlFrame(const std::string& name, DvlFrame& out);
bool parseDvlSign(const std::string& name, DvlSign& out);

/** One acoustic beam. Its unit vector in the sensor frame, pointing from the
 *  transducer towards the seabed, is
 *      u = [sin(i) cos(a), sin(i) sin(a), cos(i)],
 *  i = `CObservationDVL::beam_inclination_rad`, a = `azimuth_rad`. In Beam
 *  mode `velocity_mps` is uᵀ v_s (v_s: sensor velocity over the seabed, sensor
 *  frame), negated under BottomOverInstrument. */
struct DvlBeam
{
	double range_m = 0;       //!< slant range along the beam to the seabed [m]
	bool valid = false;       //!< beam had a bottom return inside the lock window
	double velocity_mps = 0;  //!< radial velocity along u [m/s] (Beam mode; version >= 1)
	double azimuth_rad = 0;   //!< beam azimuth about the sensor z axis, from sensor x [rad] (version >= 1)
};

class CObservationDVL : public MountedObservation
{
	DEFINE_SERIALIZABLE(CObservationDVL, auvnav::obs)

 public:
	std::array<double, 3> velocity_s_mps{0, 0, 0};  //!< sensor velocity over ground, sensor frame [m/s]
	std::array<double, 9> velocity_cov{};           //!< row-major covariance of velocity_s_mps [m²/s²]
	bool bottom_lock = false;                       //!< enough valid beams to solve the 3D velocity
	double altitude_m = 0;                          //!< vertical distance to the seabed [m], NaN if unknown
	double beam_inclination_rad = 0;                //!< Janus angle of the beams from the sensor z axis
	std::vector<DvlBeam> beams;                     //!< per-beam range and validity
	DvlFrame frame = DvlFrame::Instrument;          //!< coordinates of velocity_s_mps (version >= 1)
	DvlSign sign = DvlSign::VehicleOverBottom;      //!< sign convention (version >= 1)
	double beam_velocity_sigma_mps = 0;  //!< 1σ of one beam's radial velocity, 0 = unknown (version >= 1)

	void getDescriptionAsText(std::ostream& o) const override;
	bool exportTxtSupported() const override { return true; }
	std::string exportTxtHeader() const override;
	std::string exportTxtDataRow() const override;
};
}  // namespace auvnav::obs
