// auvnav-view's scene: contents, the saved scene read back with MRPT's reader
// (what SceneViewer3D does), and an off-screen render that shows the trajectory.
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>
#include <mrpt/opengl/CEllipsoid3D.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>
#include "scene.h"

using namespace auvnav::view;
namespace fs = std::filesystem;

namespace
{
/** A 100 m square at 5 m depth, σ growing along it, and its truth 1 m off. */
RunData squareRun()
{
	RunData r;
	const Eigen::Vector2d corners[] = {{0, 0}, {100, 0}, {100, 100}, {0, 100}, {0, 0}};
	double t = 0;
	for (int leg = 0; leg < 4; ++leg)
		for (int k = 0; k < 100; ++k, t += 1)
		{
			const Eigen::Vector2d ne = corners[leg] + (corners[leg + 1] - corners[leg]) * (k / 100.0);
			TrackPoint p;
			p.t = t;
			p.p_ned = {ne.x(), ne.y(), 5};
			p.sigma_ned = Eigen::Vector3d(0.5 + 0.01 * t, 0.5 + 0.01 * t, 0.1);
			r.estimate.push_back(p);
			TrackPoint q = p;
			q.p_ned.x() += 1;
			q.seabed_depth_m = 12;
			r.truth.push_back(q);
		}
	r.fixes = {{0, "GPS", {0, 0}, true},
	           {10, "GPS", {3, 0}, false},
	           {200, "USBL", {40, 20}, true},
	           {202, "USBL", {55, 20}, false}};
	return r;
}

std::size_t countNamed(const mrpt::opengl::COpenGLScene& s, const std::string& name)
{
	std::size_t n = 0;
	for (const auto& o : *s.getViewport())
		if (o && o->getName() == name) ++n;
	return n;
}
}  // namespace

TEST(View, SceneHoldsTrajectoryTruthEllipsoidsVehicleGpsAndSeabed)
{
	const auto scene = buildScene(squareRun(), SceneOptions{60, 0.05});
	EXPECT_EQ(countNamed(*scene, "estimate"), 1u);
	EXPECT_EQ(countNamed(*scene, "ground_truth"), 1u);
	EXPECT_EQ(countNamed(*scene, "seabed"), 1u);
	EXPECT_EQ(countNamed(*scene, "vehicle"), 1u);
	EXPECT_EQ(countNamed(*scene, "fixes_GPS"), 1u);
	EXPECT_EQ(countNamed(*scene, "fixes_USBL"), 1u);
	const auto usbl =
	    std::dynamic_pointer_cast<mrpt::opengl::CPointCloudColoured>(scene->getByName("fixes_USBL"));
	ASSERT_TRUE(usbl);
	ASSERT_EQ(usbl->size(), 2u);
	EXPECT_FLOAT_EQ(usbl->getPoint3Df(0).x, 20.0f);  // ENU: x = east
	EXPECT_FLOAT_EQ(usbl->getPoint3Df(0).y, 40.0f);
	EXPECT_EQ(countNamed(*scene, "two_sigma"), 7u);  // t = 0, 60, ..., 360 of 0..399 s
	ASSERT_TRUE(scene->getByName("seabed"));
}

TEST(View, SavedSceneReadsBackWithMrptsReader)
{
	const auto scene = buildScene(squareRun());
	const auvnav::testing::ScratchDir dir("view_scene");
	const fs::path file = dir / "scene.3Dscene";
	ASSERT_TRUE(scene->saveToFile(file.string()));
	mrpt::opengl::COpenGLScene back;
	ASSERT_TRUE(back.loadFromFile(file.string()));
	for (const char* name : {"estimate", "ground_truth", "seabed", "vehicle", "fixes_GPS", "fixes_USBL"})
		EXPECT_EQ(countNamed(back, name), 1u) << name;
	EXPECT_EQ(countNamed(back, "two_sigma"), countNamed(*scene, "two_sigma"));
}

TEST(View, OffscreenScreenshotShowsTheTrajectory)
{
	const auvnav::testing::ScratchDir dir("view_png");
	const fs::path png = dir / "screenshot.png";
	renderToPng(*buildScene(squareRun()), png.string(), 640, 400);
	mrpt::img::CImage img;
	ASSERT_TRUE(img.loadFromFile(png.string()));
	ASSERT_EQ(img.getWidth(), 640u);
	// Pixels of the trajectory's colour (blue), and pixels other than the background.
	const uint8_t* bg = img(0, 0);
	const int bg_b = bg[0], bg_g = bg[1], bg_r = bg[2];
	std::size_t blue = 0, drawn = 0;
	for (unsigned y = 0; y < img.getHeight(); ++y)
		for (unsigned x = 0; x < img.getWidth(); ++x)
		{
			const uint8_t* px = img(x, y);  // BGR
			const int b = px[0], g = px[1], r = px[2];
			if (b > 180 && r < 90 && g < 140) ++blue;
			if (std::abs(b - bg_b) + std::abs(g - bg_g) + std::abs(r - bg_r) > 30) ++drawn;
		}
	EXPECT_GT(blue, 150u) << "trajectory pixels";
	EXPECT_GT(drawn, 640u * 400u / 100) << "less than 1 % of the image differs from the background";
}

TEST(View, BadRunFolderIsRefusedNamingTheFile)
{
	const auvnav::testing::ScratchDir scratch("view_bad");
	const fs::path& dir = scratch.path();
	EXPECT_THROW(loadRun((dir / "missing").string()), std::runtime_error);
	std::ofstream(dir / "states.csv")
	    << "time_s,qw,qx,qy,qz,body_n_m,body_e_m,body_d_m,sigma_pos_n,sigma_pos_e,sigma_pos_d\n"
	    << "1,1,0,0,0,abc,0,0,1,1,1\n";
	try
	{
		loadRun(dir.string());
		FAIL() << "accepted a non-number";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("states.csv:2"), std::string::npos) << e.what();
	}
}

// A smoothed run (auvnav-run --smooth) is drawn beside the filtered one.
TEST(View, ASmoothedTrajectoryIsDrawnBesideTheFilteredOne)
{
	RunData r = squareRun();
	EXPECT_EQ(countNamed(*buildScene(r), "smoothed"), 0u);
	for (std::size_t i = 0; i < r.estimate.size(); i += 10) r.smoothed.push_back(r.truth[i]);
	const auto scene = buildScene(r);
	EXPECT_EQ(countNamed(*scene, "smoothed"), 1u);
	EXPECT_EQ(countNamed(*scene, "estimate"), 1u);
	const auto lines = std::dynamic_pointer_cast<mrpt::opengl::CSetOfLines>(scene->getByName("smoothed"));
	ASSERT_TRUE(lines);
	EXPECT_EQ(lines->getLineCount(), r.smoothed.size() - 1);
}
