// Earth model: GeographicLib-backed tangent frame, gravity and Earth rate.
#include <auvnav/earth.h>
#include <gtest/gtest.h>

#include <cmath>

using namespace auvnav::earth;

namespace
{
constexpr double kDeg = M_PI / 180;
}

TEST(Earth, NormalGravityMatchesTheWgs84Formula)
{
	// Somigliana's closed form on the ellipsoid (WGS-84 defining constants) as an
	// independent check of the library call.
	const double ge = 9.7803253359, k = 0.00193185265241, e2 = 0.00669437999013;
	for (double lat_deg : {0.0, -12.975, 45.0, 80.0})
	{
		const double s2 = std::pow(std::sin(lat_deg * kDeg), 2);
		const double somigliana = ge * (1 + k * s2) / std::sqrt(1 - e2 * s2);
		EXPECT_NEAR(normalGravity(lat_deg * kDeg, 0.0), somigliana, 1e-8) << lat_deg;
	}
	// Under water gravity grows by ~3.1e-6 m/s² per metre (free-air gradient).
	EXPECT_NEAR(normalGravity(-13 * kDeg, -100) - normalGravity(-13 * kDeg, 0), 100 * 3.08e-6, 2e-5);
}

TEST(Earth, EarthRateInNedHasNorthAndUpComponents)
{
	const double lat = -12.975 * kDeg;
	const Eigen::Vector3d w = earthRateNed(lat);
	EXPECT_NEAR(w.norm(), 7.292115e-5, 1e-12);
	EXPECT_NEAR(w.x(), 7.292115e-5 * std::cos(lat), 1e-12);
	EXPECT_DOUBLE_EQ(w.y(), 0.0);
	EXPECT_GT(w.z(), 0.0);  // southern hemisphere: −Ω sin(lat) > 0, the vertical part points down
}

TEST(Earth, TangentFrameRoundTripsAndTiltsGravityAwayFromTheOrigin)
{
	const TangentFrame f({-12.975 * kDeg, -38.43 * kDeg, 0.0});
	const Eigen::Vector3d p(1000.0, -500.0, 10.0);
	const Eigen::Vector3d back = f.toNed(f.toGeodetic(p));
	EXPECT_LT((back - p).norm(), 1e-6);
	const Eigen::Vector3d g0 = f.gravityNed({0, 0, 0});
	EXPECT_NEAR(g0.x(), 0.0, 1e-9);
	EXPECT_NEAR(g0.z(), normalGravity(-12.975 * kDeg, 0.0), 1e-9);
	// 1 km north the local vertical is tilted by ~1000/6.38e6 rad toward the origin:
	// gravity gains a southward (−N) component of about g · 1.57e-4.
	const Eigen::Vector3d g1 = f.gravityNed({1000.0, 0, 0});
	EXPECT_NEAR(g1.x() / g1.norm(), -1000.0 / 6.378e6, 0.02 * 1000.0 / 6.378e6);
}
