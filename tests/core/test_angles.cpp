// angles.h: the one wrap, at its boundaries and far out.
#include <auvnav/angles.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace auvnav
{
namespace
{
TEST(Angles, WrapIsHalfOpenAtMinusPi)
{
	EXPECT_DOUBLE_EQ(wrapAngle(M_PI), M_PI);
	EXPECT_DOUBLE_EQ(wrapAngle(-M_PI), M_PI);
	EXPECT_DOUBLE_EQ(wrapAngle(3 * M_PI), M_PI);
	EXPECT_DOUBLE_EQ(wrapAngle(-3 * M_PI), M_PI);
	EXPECT_DOUBLE_EQ(wrapAngle(0.25), 0.25);  // inside: unchanged, bit for bit
	EXPECT_DOUBLE_EQ(wrapAngle(-0.25), -0.25);
	EXPECT_NEAR(wrapAngle(2 * M_PI + 0.5), 0.5, 1e-15);
	EXPECT_NEAR(wrapAngle(-2 * M_PI - 0.5), -0.5, 1e-15);
}

TEST(Angles, WrapStaysInRangeFarOutAndPassesNaN)
{
	for (double a = -1e6; a <= 1e6; a += 977.123)
	{
		const double w = wrapAngle(a);
		EXPECT_GT(w, -M_PI);
		EXPECT_LE(w, M_PI);
		EXPECT_NEAR(std::remainder(w - a, 2 * M_PI), 0.0, 1e-9) << a;
	}
	EXPECT_TRUE(std::isnan(wrapAngle(std::numeric_limits<double>::quiet_NaN())));
	EXPECT_TRUE(std::isnan(wrapAngle(std::numeric_limits<double>::infinity())));
}

TEST(Angles, DegreesWrapLikeRadians)
{
	EXPECT_DOUBLE_EQ(wrapAngleDeg(180), 180);
	EXPECT_DOUBLE_EQ(wrapAngleDeg(-180), 180);
	EXPECT_DOUBLE_EQ(wrapAngleDeg(540), 180);
	EXPECT_DOUBLE_EQ(wrapAngleDeg(-190), 170);
	EXPECT_DOUBLE_EQ(wrapAngleDeg(359), -1);
}

}  // namespace
}  // namespace auvnav
