// Sonar frames: polar geometry, the CObservationImage round trip, the pole
// detector on synthetic frames, association with the pole map (including a
// wrong position estimate) and the landmark heading.
#include <auvnav/sonar/frame.h>
#include <auvnav/sonar/landmarks.h>
#include <auvnav/sonar/pipeline.h>
#include <auvnav/testing/sonar_frames.h>
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <cmath>

using namespace auvnav;
using namespace auvnav::sonar;
using auvnav::testing::geminiGeometry;
using auvnav::testing::renderPolarFrame;
using auvnav::testing::SyntheticPole;

namespace
{
constexpr double kDeg = M_PI / 180;

PoleMap mapOf(std::initializer_list<std::pair<double, double>> ne)
{
	PoleMap m;
	int i = 1;
	for (const auto& [n, e] : ne) m.poles.push_back({"P" + std::to_string(i++), Eigen::Vector2d(n, e), 0.15});
	return m;
}
}  // namespace

TEST(SonarGeometry, KnownPointsMapToTheirBearingAndRange)
{
	const PolarGeometry g = geminiGeometry();
	// Column centres span the aperture symmetrically; the middle of the image is bearing 0.
	EXPECT_NEAR(g.bearingOfColumn(0), -65 * kDeg + 0.5 * 130.0 / 256 * kDeg, 1e-12);
	EXPECT_NEAR(g.bearingOfColumn(255), 65 * kDeg - 0.5 * 130.0 / 256 * kDeg, 1e-12);
	EXPECT_NEAR(g.bearingOfColumn(127.5), 0.0, 1e-12);
	EXPECT_NEAR(g.rangeOfRow(0), 0.5, 1e-12);
	EXPECT_NEAR(g.rangeOfRow(399), 30.0, 1e-12);
	for (double b : {-60.0, -10.0, 0.0, 33.3})
		EXPECT_NEAR(g.bearingOfColumn(g.columnOfBearing(b * kDeg)), b * kDeg, 1e-12);
	// Cartesian: 10 m ahead and 10 m to starboard is 45° at 14.142 m, and back.
	double b = 0, r = 0;
	PolarGeometry::toPolar(Eigen::Vector2d(10, 10), b, r);
	EXPECT_NEAR(b, 45 * kDeg, 1e-12);
	EXPECT_NEAR(r, std::sqrt(200.0), 1e-12);
	EXPECT_LT((PolarGeometry::toCartesian(b, r) - Eigen::Vector2d(10, 10)).norm(), 1e-12);
	// The fan image puts the sonar at the bottom centre, forward up, starboard right.
	const double ppm = 10;
	const cv::Point2d apex = fanPixel(g, ppm, 0, 0), ahead = fanPixel(g, ppm, 0, 10),
	                  right = fanPixel(g, ppm, 90 * kDeg, 5);
	EXPECT_NEAR(ahead.x, apex.x, 1e-9);
	EXPECT_NEAR(apex.y - ahead.y, 100, 1e-9);
	EXPECT_NEAR(right.x - apex.x, 50, 1e-9);
	EXPECT_FALSE(g.inView(70 * kDeg, 10));
	EXPECT_TRUE(g.inView(-64 * kDeg, 29.9));
	PolarGeometry bad = g;
	bad.max_range_m = 0.2;
	EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(SonarGeometry, FanImageShowsABrightPolarPointWhereTheGeometrySays)
{
	const PolarGeometry g = geminiGeometry();
	cv::Mat polar = cv::Mat::zeros(g.range_bins, g.beam_count, CV_8UC1);
	const double bearing = 30 * kDeg, range = 12;
	const int c = static_cast<int>(std::lround(g.columnOfBearing(bearing))),
	          r = static_cast<int>(std::lround(g.rowOfRange(range)));
	cv::rectangle(polar, cv::Rect(c - 1, r - 1, 3, 3), cv::Scalar(255), cv::FILLED);
	const double ppm = 10;
	const cv::Mat fan = fanImage(polar, g, ppm);
	cv::Point max_at;
	cv::minMaxLoc(fan, nullptr, nullptr, nullptr, &max_at);
	const cv::Point2d expected = fanPixel(g, ppm, g.bearingOfColumn(c), g.rangeOfRow(r));
	EXPECT_LT(std::hypot(max_at.x - expected.x, max_at.y - expected.y), 2.5);
}

TEST(SonarFrame, GeometryRoundTripsThroughCObservationImage)
{
	const PolarGeometry g = geminiGeometry();
	const cv::Mat img = renderPolarFrame(g, {}, 1);
	const auto obs = makeFrame(img, g, "SONAR", 1492693200.5);
	std::string why;
	const auto back = geometryOf(*obs, why);
	ASSERT_TRUE(back) << why;
	EXPECT_EQ(back->beam_count, 256);
	EXPECT_EQ(back->range_bins, 400);
	EXPECT_NEAR(back->aperture_rad, g.aperture_rad, 1e-12);
	EXPECT_NEAR(back->min_range_m, 0.5, 1e-12);
	EXPECT_NEAR(back->max_range_m, 30, 1e-12);
	EXPECT_EQ(cv::norm(polarImage(*obs), img, cv::NORM_INF), 0.0);
	// A camera image is not a sonar frame; nor is one whose size disagrees.
	mrpt::obs::CObservationImage camera;
	EXPECT_FALSE(geometryOf(camera, why));
	EXPECT_NE(why.find("camera model"), std::string::npos);
	auto wrong = makeFrame(img, g, "SONAR", 0);
	wrong->cameraParams.ncols = 300;
	EXPECT_FALSE(geometryOf(*wrong, why));
	EXPECT_NE(why.find("disagrees"), std::string::npos) << why;
}

TEST(SonarDetector, FindsKnownPolesWithBearingAndRange)
{
	const PolarGeometry g = geminiGeometry();
	const std::vector<SyntheticPole> poles = {
	    {-40 * kDeg, 22.0}, {5 * kDeg, 15.0}, {47 * kDeg, 27.5}, {20 * kDeg, 4.0}};
	int found = 0, spurious = 0;
	double worst_bearing = 0, worst_range = 0;
	for (unsigned seed = 1; seed <= 20; ++seed)
	{
		const auto dets = detectPoles(renderPolarFrame(g, poles, seed), g);
		std::vector<bool> used(poles.size(), false);
		for (const auto& d : dets)
		{
			bool matched = false;
			for (std::size_t j = 0; j < poles.size(); ++j)
			{
				const double db = std::abs(d.bearing_rad - poles[j].bearing_rad),
				             dr = std::abs(d.range_m - poles[j].range_m);
				if (!used[j] && db < 1.5 * kDeg && dr < 0.5)
				{
					used[j] = matched = true;
					worst_bearing = std::max(worst_bearing, db);
					worst_range = std::max(worst_range, dr);
					EXPECT_GT(d.sigma_bearing_rad, 0);
					EXPECT_LT(d.sigma_bearing_rad, 1 * kDeg);
					// Behind the seabed onset a shadow confirmed it; before it, brightness.
					if (poles[j].range_m > 8)
					{
						EXPECT_LT(d.shadow_ratio, 0.6);
					}
					break;
				}
			}
			found += matched;
			spurious += !matched;
		}
	}
	EXPECT_GE(found, 76) << "of 80";  // ≥ 95 % recall on clean synthetic frames
	EXPECT_LE(spurious, 1);
	EXPECT_LT(worst_bearing, 0.6 * kDeg);
	EXPECT_LT(worst_range, 0.3);
}

TEST(SonarDetector, SeabedAndNoiseOnlyFramesGiveNoPoles)
{
	const PolarGeometry g = geminiGeometry();
	int false_poles = 0;
	for (unsigned seed = 100; seed < 300; ++seed)
		false_poles += static_cast<int>(detectPoles(renderPolarFrame(g, {}, seed), g).size());
	EXPECT_LE(false_poles, 1) << "in 200 empty frames";  // < 1 per 100 frames
}

TEST(SonarDetector, BrightReturnWithoutShadowOverSeabedIsRejected)
{
	// A bright compact echo over the seabed with the seabed continuing behind
	// it (a fish, a rock top) is not a pole.
	const PolarGeometry g = geminiGeometry();
	auvnav::testing::SyntheticScene no_shadow;
	no_shadow.shadow_factor = 1.0;
	int found = 0;
	for (unsigned seed = 1; seed <= 10; ++seed)
		found += static_cast<int>(
		    detectPoles(renderPolarFrame(g, {{10 * kDeg, 18.0}}, seed, no_shadow), g).size());
	EXPECT_EQ(found, 0);
}

TEST(SonarDetector, RejectsAnImageOfTheWrongShape)
{
	const PolarGeometry g = geminiGeometry();
	EXPECT_THROW(detectPoles(cv::Mat::zeros(10, 10, CV_8UC1), g), std::invalid_argument);
}

TEST(SonarAssociation, AssociatesEachDetectionWithItsPole)
{
	const PoleMap map = mapOf({{20, 0}, {20, 8}, {30, -10}});
	SonarPose pose;
	pose.ne_m = {0, 0};
	pose.heading_rad = 10 * kDeg;
	pose.P_ne = Eigen::Matrix2d::Identity() * 0.25;
	pose.sigma_heading_rad = 1 * kDeg;
	std::vector<Detection> dets;
	for (const auto& p : map.poles)
	{
		Detection d;
		predictPole(pose, p.ne_m, d.bearing_rad, d.range_m);
		d.range_m -= p.radius_m;
		d.bearing_rad += 0.2 * kDeg;
		d.sigma_bearing_rad = 0.2 * kDeg;
		d.sigma_range_m = 0.05;
		dets.push_back(d);
	}
	const auto as = associate(dets, map, pose);
	ASSERT_EQ(as.size(), 3u);
	for (const auto& a : as) EXPECT_EQ(a.detection, a.pole);
	// The implied vehicle heading: the pose's heading minus the common 0.2° offset.
	const auto h = headingFromPoles(dets, as, map, pose, 0.0);
	ASSERT_TRUE(h);
	EXPECT_NEAR(h->heading_rad, 9.8 * kDeg, 1e-9);
	EXPECT_EQ(h->poles, 3);
	EXPECT_GT(h->sigma_rad, 0);
	EXPECT_LT(h->sigma_rad, 2 * kDeg);
	// With a mounting yaw of 5°, the vehicle heading is 5° less.
	EXPECT_NEAR(headingFromPoles(dets, as, map, pose, 5 * kDeg)->heading_rad, 4.8 * kDeg, 1e-9);
}

TEST(SonarAssociation, WrongPositionEstimateAssociatesNothingBeyondTheGate)
{
	const PoleMap map = mapOf({{20, 0}, {20, 8}, {30, -10}});
	SonarPose truth;
	truth.heading_rad = 0;
	std::vector<Detection> dets;
	for (const auto& p : map.poles)
	{
		Detection d;
		predictPole(truth, p.ne_m, d.bearing_rad, d.range_m);
		d.range_m -= p.radius_m;
		d.sigma_bearing_rad = 0.2 * kDeg;
		d.sigma_range_m = 0.05;
		dets.push_back(d);
	}
	// The estimate is 6 m off but claims 0.5 m: every pair is outside the gate.
	SonarPose wrong = truth;
	wrong.ne_m = {3, -5.2};
	wrong.P_ne = Eigen::Matrix2d::Identity() * 0.25;
	wrong.sigma_heading_rad = 1 * kDeg;
	const auto as = associate(dets, map, wrong);
	EXPECT_TRUE(as.empty()) << as.size() << " associations";
	for (const auto& a : as) EXPECT_LE(a.nis, 9.21);
	// Claiming the right uncertainty (6 m), associations come back, and every
	// one that is made is correct.
	wrong.P_ne = Eigen::Matrix2d::Identity() * 36;
	for (const auto& a : associate(dets, map, wrong)) EXPECT_EQ(a.detection, a.pole);
	// Two poles 0.6 m apart seen from a vague position: ambiguous, left out.
	const PoleMap twins = mapOf({{20, 0}, {20, 0.6}});
	Detection d;
	predictPole(truth, twins.poles[0].ne_m, d.bearing_rad, d.range_m);
	d.sigma_bearing_rad = 0.2 * kDeg;
	d.sigma_range_m = 0.05;
	SonarPose vague = truth;
	vague.P_ne = Eigen::Matrix2d::Identity() * 4;
	EXPECT_TRUE(associate({d}, twins, vague).empty());
}

TEST(SonarPoleMap, RejectsDuplicatesAndEmptyMapsNamingTheKey)
{
	EXPECT_THROW(PoleMap::fromConfig(config::Node::fromText("poles: []")), std::exception);
	try
	{
		PoleMap::fromConfig(config::Node::fromText(
		    "poles:\n  - {id: A, north_m: 1, east_m: 2}\n  - {id: A, north_m: 3, east_m: 4}\n", "map.yaml"));
		FAIL() << "duplicate accepted";
	}
	catch (const std::exception& e)
	{
		EXPECT_NE(std::string(e.what()).find("duplicate"), std::string::npos) << e.what();
	}
	const auto m = PoleMap::fromConfig(
	    config::Node::fromText("poles:\n  - {id: A, north_m: 1, east_m: 2, radius_m: 0.2}\n"));
	ASSERT_EQ(m.poles.size(), 1u);
	EXPECT_EQ(m.poles[0].ne_m, Eigen::Vector2d(1, 2));
}
