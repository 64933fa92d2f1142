#include <auvnav/sonar/geometry.h>

#include <cmath>
#include <stdexcept>

namespace auvnav::sonar
{
void PolarGeometry::validate() const
{
	auto bad = [](const std::string& what) { throw std::invalid_argument("sonar geometry: " + what); };
	if (beam_count < 2) bad("beam_count must be at least 2");
	if (range_bins < 2) bad("range_bins must be at least 2");
	if (!(aperture_rad > 0 && aperture_rad < 2 * M_PI)) bad("aperture must be in (0, 360) degrees");
	if (!(min_range_m >= 0)) bad("min_range_m must be a non-negative number");
	if (!(max_range_m > min_range_m) || !std::isfinite(max_range_m))
		bad("max_range_m must exceed min_range_m");
}

PolarGeometry PolarGeometry::fromConfig(const config::Node& n)
{
	PolarGeometry g;
	g.beam_count = n.integer("beam_count");
	g.range_bins = n.integer("range_bins");
	g.aperture_rad = n.inRange("aperture_deg", 1, 359) * M_PI / 180;
	g.min_range_m = n.nonNegative("min_range_m");
	g.max_range_m = n.positive("max_range_m");
	try
	{
		g.validate();
	}
	catch (const std::exception& e)
	{
		n.fail("beam_count", e.what());
	}
	return g;
}

Eigen::Vector2d PolarGeometry::toCartesian(double bearing_rad, double range_m)
{
	return {range_m * std::cos(bearing_rad), range_m * std::sin(bearing_rad)};
}

void PolarGeometry::toPolar(const Eigen::Vector2d& xy_m, double& bearing_rad, double& range_m)
{
	bearing_rad = std::atan2(xy_m.y(), xy_m.x());
	range_m = xy_m.norm();
}

}  // namespace auvnav::sonar
