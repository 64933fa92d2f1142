#pragma once
/** @file units.h
 *  Units the importer understands, each with its physical kind and its factor
 *  (and offset) to the SI unit auvnav stores. A quantity accepts only units of
 *  its own kind, so `deg` given for an angular rate is an error, not a silent
 *  factor of 57.
 *
 *  Names (case-sensitive, as written in specs):
 *    angle            rad, deg
 *    angular rate     rad/s, deg/s, deg/h
 *    acceleration     m/s^2 (m/s2), g (9.80665 m/s², standard gravity), mg
 *    velocity         m/s, mm/s, cm/s, knot
 *    pressure         Pa, hPa, kPa, MPa, bar, mbar, dbar, psi
 *    length           m, cm, mm, km
 *    magnetic field   T, mT, uT (µT), nT, G (Gauss), mG
 *    temperature      degC, K
 *    force            N, kgf
 *    rotation speed   rpm
 *    dimensionless    1
 *    velocity²        m^2/s^2 (covariances)
 */
#include <string>
#include <vector>

namespace auvnav::import
{
enum class UnitKind
{
	Angle,
	AngularRate,
	Acceleration,
	Velocity,
	Pressure,
	Length,
	MagneticField,
	Temperature,
	Force,
	RotationSpeed,
	Dimensionless,
	VelocitySquared,
	LengthSquared,
	Time
};

struct Unit
{
	std::string name;
	UnitKind kind;
	double factor;  //!< SI value = factor * value + offset
	double offset = 0;
	double toSi(double v) const { return factor * v + offset; }
};

/** "angular rate", for messages. */
const char* kindName(UnitKind k);
/** The units of a kind, for messages ("rad/s, deg/s, deg/h"). */
std::string unitsOfKind(UnitKind k);
/** Looks up `name`; throws ImportError naming the unit and, when the name is
 *  known but of another kind, what it is and what the quantity needs. `what`
 *  names the quantity in the message (e.g. "sensors[0] IMU: angular_velocity"). */
Unit unitFor(const std::string& name, UnitKind expected, const std::string& what);

}  // namespace auvnav::import
