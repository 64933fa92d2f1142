// The one trajectory / ground-truth reader (auvnav/io/trajectory.h): reading
// both formats, the interpolation rule (linear position, slerp attitude),
// gaps, the span's ends and the refusals.
#include <auvnav/io/trajectory.h>
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using namespace auvnav;

namespace
{
/** A file path `name` in a folder of its own (emptied here: the file is
 *  new), removed at exit (scratch_dir.h). */
fs::path scratch(const std::string& name)
{
	return auvnav::testing::scratchFolder("trajectory", name) / name;
}

double yawOf(const Eigen::Quaterniond& q)
{
	const Eigen::Matrix3d R = q.toRotationMatrix();
	return std::atan2(R(1, 0), R(0, 0));
}

/** A ground_truth.csv (columns in another order than the simulator's, and
 *  an extra one) turning at 0.2 rad/s, 1 m/s north, at 10 Hz, with a 2 s
 *  hole after t = 1002. */
fs::path writeTruth()
{
	const fs::path p = scratch("truth.csv");
	std::ofstream f(p);
	f.precision(17);
	f << "time_s,unix_time_s,qw,qx,qy,qz,north_m,east_m,down_m,current_n_mps,current_e_mps,distance_m,"
	     "submerged\n";
	for (int k = 0; k <= 50; ++k)
	{
		if (k > 20 && k < 40) continue;
		const double t = 1000 + 0.1 * k, h = 0.1 * (t - 1000);  // half the yaw
		f << t - 1000 << "," << t << "," << std::cos(h) << ",0,0," << std::sin(h) << "," << t - 1000
		  << ",0,5,0.1," << 0.01 * k << "," << t - 1000 << "," << (k >= 10 ? 1 : 0) << "\n";
	}
	return p;
}
}  // namespace

TEST(Trajectory, GroundTruthIsInterpolatedLinearlyAndAlongTheGeodesic)
{
	const io::Trajectory tr = io::readGroundTruth(writeTruth());
	ASSERT_EQ(tr.size(), 32u);
	for (double t : {1000.02, 1000.55, 1001.37, 1004.99})
	{
		const auto p = io::interpolate(tr, t, 0.5);
		ASSERT_TRUE(p) << t;
		EXPECT_DOUBLE_EQ(p->t_unix, t);
		EXPECT_NEAR(p->p_n.x(), t - 1000, 1e-9) << t;
		EXPECT_NEAR(p->distance_m, t - 1000, 1e-9) << t;
		EXPECT_NEAR(p->current_ne.y(), 0.1 * (t - 1000), 1e-9) << t;
		// The nearest row would be up to 0.05 s x 0.2 rad/s = 0.01 rad off.
		EXPECT_NEAR(yawOf(p->q_nb), 0.2 * (t - 1000), 1e-9) << t;
		EXPECT_NEAR(p->q_nb.norm(), 1.0, 1e-12);
	}
	// submerged from the nearer row.
	EXPECT_FALSE(io::interpolate(tr, 1000.94, 0.5)->submerged);
	EXPECT_TRUE(io::interpolate(tr, 1000.96, 0.5)->submerged);
}

TEST(Trajectory, NoInterpolationAcrossAGapOrOutsideTheSpan)
{
	const io::Trajectory tr = io::readGroundTruth(writeTruth());
	EXPECT_FALSE(io::interpolate(tr, 1003.0, 0.5));  // in the 2 s hole
	EXPECT_TRUE(io::interpolate(tr, 1003.0, 5.0));
	EXPECT_FALSE(io::interpolate(tr, 999.9, 0.5));
	EXPECT_FALSE(io::interpolate(tr, 1005.1, 0.5));
	// A point itself, to the CSV round trip's tolerance, also at the ends.
	ASSERT_TRUE(io::interpolate(tr, 1005.0 + 1e-7, 0.5));
	EXPECT_NEAR(io::interpolate(tr, 1000.0, 0.5)->p_n.x(), 0.0, 1e-12);
	// at(): clamped to the ends, interpolated across gaps.
	EXPECT_NEAR(io::at(tr, 990).p_n.x(), 0.0, 1e-12);
	EXPECT_NEAR(io::at(tr, 1010).p_n.x(), 5.0, 1e-12);
	EXPECT_NEAR(io::at(tr, 1003.0).p_n.x(), 3.0, 1e-9);
}

TEST(Trajectory, TumFileSkipsCommentsAndRepeatedStamps)
{
	const fs::path p = scratch("run.tum");
	{
		std::ofstream f(p);
		f << "# timestamp north east down qx qy qz qw\n\n"
		  << "10.0 0 0 0 0 0 0 1\n"
		  << "10.0 9 9 9 0 0 0 1\n"  // repeated stamp: dropped
		  << "11.0 2 0 0 0 0 0.7071067811865476 0.7071067811865476\n";
	}
	const io::Trajectory tr = io::readTum(p);
	ASSERT_EQ(tr.size(), 2u);
	const auto mid = io::interpolate(tr, 10.5, 2.0);
	ASSERT_TRUE(mid);
	EXPECT_NEAR(mid->p_n.x(), 1.0, 1e-12);
	EXPECT_NEAR(yawOf(mid->q_nb), M_PI / 4, 1e-12);  // half of the 90 deg turn
}

TEST(Trajectory, RefusalsNameTheFileAndLine)
{
	auto message = [](auto&& read)
	{
		try
		{
			read();
		}
		catch (const std::runtime_error& e)
		{
			return std::string(e.what());
		}
		return std::string("(no error)");
	};
	const fs::path tum = scratch("bad.tum");
	std::ofstream(tum) << "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 2\n";
	EXPECT_NE(
	    message([&] { io::readTum(tum); }).find(tum.string() + ":2: non-finite value or non-unit quaternion"),
	    std::string::npos);
	const fs::path csv = scratch("bad.csv");
	std::ofstream(csv) << "unix_time_s,north_m\n1,2\n";
	EXPECT_NE(message([&] { io::readGroundTruth(csv); }).find("no column 'east_m'"), std::string::npos);
	const fs::path back = scratch("backwards.csv");
	std::ofstream(back)
	    << "unix_time_s,north_m,east_m,down_m,qw,qx,qy,qz,current_n_mps,current_e_mps,distance_m\n"
	    << "2,0,0,0,1,0,0,0,0,0,0\n1,0,0,0,1,0,0,0,0,0,0\n";
	EXPECT_NE(message([&] { io::readGroundTruth(back); }).find(back.string() + ":3: time does not increase"),
	          std::string::npos);
	EXPECT_NE(message([&] { io::readTum(scratch("missing.tum")); }).find("cannot read"), std::string::npos);
}
