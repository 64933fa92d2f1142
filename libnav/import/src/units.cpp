#include <auvnav/enum_names.h>
#include <auvnav/import/record.h>
#include <auvnav/import/units.h>

#include <array>

namespace auvnav::import
{
namespace
{
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kStandardGravity = 9.80665;  // m/s², CGPM 1901 (also what the SONIA logs used)

const std::vector<Unit>& table()
{
	static const std::vector<Unit> units = {
	    {"rad", UnitKind::Angle, 1},
	    {"deg", UnitKind::Angle, kDeg},
	    {"rad/s", UnitKind::AngularRate, 1},
	    {"deg/s", UnitKind::AngularRate, kDeg},
	    {"deg/h", UnitKind::AngularRate, kDeg / 3600},
	    {"m/s^2", UnitKind::Acceleration, 1},
	    {"m/s2", UnitKind::Acceleration, 1},
	    {"g", UnitKind::Acceleration, kStandardGravity},
	    {"mg", UnitKind::Acceleration, kStandardGravity * 1e-3},
	    {"m/s", UnitKind::Velocity, 1},
	    {"mm/s", UnitKind::Velocity, 1e-3},
	    {"cm/s", UnitKind::Velocity, 1e-2},
	    {"knot", UnitKind::Velocity, 1852.0 / 3600.0},
	    {"Pa", UnitKind::Pressure, 1},
	    {"hPa", UnitKind::Pressure, 1e2},
	    {"kPa", UnitKind::Pressure, 1e3},
	    {"MPa", UnitKind::Pressure, 1e6},
	    {"bar", UnitKind::Pressure, 1e5},
	    {"mbar", UnitKind::Pressure, 1e2},
	    {"dbar", UnitKind::Pressure, 1e4},
	    {"psi", UnitKind::Pressure, 6894.757293168361},  // 0.45359237 kgf / (0.0254 m)²
	    {"m", UnitKind::Length, 1},
	    {"cm", UnitKind::Length, 1e-2},
	    {"mm", UnitKind::Length, 1e-3},
	    {"km", UnitKind::Length, 1e3},
	    {"T", UnitKind::MagneticField, 1},
	    {"mT", UnitKind::MagneticField, 1e-3},
	    {"uT", UnitKind::MagneticField, 1e-6},
	    {"\xC2\xB5T", UnitKind::MagneticField, 1e-6},  // µT
	    {"nT", UnitKind::MagneticField, 1e-9},
	    {"G", UnitKind::MagneticField, 1e-4},
	    {"Gauss", UnitKind::MagneticField, 1e-4},
	    {"mG", UnitKind::MagneticField, 1e-7},
	    {"degC", UnitKind::Temperature, 1},
	    {"K", UnitKind::Temperature, 1, -273.15},
	    {"N", UnitKind::Force, 1},
	    {"kgf", UnitKind::Force, kStandardGravity},
	    {"rpm", UnitKind::RotationSpeed, 1},
	    {"1", UnitKind::Dimensionless, 1},
	    {"m^2/s^2", UnitKind::VelocitySquared, 1},
	    {"m^2", UnitKind::LengthSquared, 1},
	    {"s", UnitKind::Time, 1},
	    {"ms", UnitKind::Time, 1e-3},
	    {"us", UnitKind::Time, 1e-6},
	};
	return units;
}
}  // namespace

const char* kindName(UnitKind k)
{
	static constexpr const char* kNames[] = {
	    "an angle",      "an angular rate",     "an acceleration",     "a velocity", "a pressure",
	    "a length",      "a magnetic field",    "a temperature",       "a force",    "a rotation speed",
	    "dimensionless", "a velocity variance", "a position variance", "a time"};
	static_assert(namesEveryValue(kNames, UnitKind::Time));
	return nameOf(kNames, k, "?");
}

std::string unitsOfKind(UnitKind k)
{
	std::string out;
	for (const auto& u : table())
		if (u.kind == k) out += (out.empty() ? "" : ", ") + u.name;
	return out;
}

Unit unitFor(const std::string& name, UnitKind expected, const std::string& what)
{
	for (const auto& u : table())
	{
		if (u.name != name) continue;
		if (u.kind == expected) return u;
		throw ImportError(what + ": unit '" + name + "' is " + kindName(u.kind) + "; this quantity is " +
		                  kindName(expected) + " (" + unitsOfKind(expected) + ")");
	}
	throw ImportError(what + ": unknown unit '" + name + "' (" + kindName(expected) + ": " +
	                  unitsOfKind(expected) + ")");
}

}  // namespace auvnav::import
