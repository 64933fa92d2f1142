// auvnav-eval: chi-square bounds, errors and NEES on a hand-made run, a plot.
#include <auvnav/testing/scratch_dir.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>
#include "eval.h"
#include "plot.h"

using namespace auvnav::eval;
namespace fs = std::filesystem;

TEST(Eval, ChiSquareBoundsMatchTables)
{
	// χ²(3): 2.5 % 0.2158, 97.5 % 9.3484; mean of 20 runs: χ²(60)/20 → 40.482/20, 83.298/20.
	auto [lo, hi] = chi2MeanBounds(3, 1);
	EXPECT_NEAR(lo, 0.2158, 1e-4);
	EXPECT_NEAR(hi, 9.3484, 1e-4);
	std::tie(lo, hi) = chi2MeanBounds(3, 20);
	EXPECT_NEAR(lo, 40.482 / 20, 1e-3);
	EXPECT_NEAR(hi, 83.298 / 20, 1e-3);
}

TEST(Eval, ErrorsAndNeesOnAHandMadeRun)
{
	const auvnav::testing::ScratchDir scratch("eval_test");
	const fs::path& dir = scratch.path();
	// Truth: level, heading 0, at (10, 20, 5); current (0.1, 0.0); 100 m travelled.
	{
		std::ofstream t(dir / "truth.csv");
		t << "unix_time_s,north_m,east_m,down_m,qw,qx,qy,qz,current_n_mps,current_e_mps,distance_m\n";
		for (int k = 0; k <= 100; ++k) t << 1000 + 0.1 * k << ",10,20,5,1,0,0,0,0.1,0,100\n";
	}
	// Estimate: 1 m north and 2 m east off, heading +0.01 rad; P_pos = diag(1, 4, 1), σ_att 0.01 rad.
	{
		std::ofstream s(dir / "states.csv");
		s.precision(17);
		s << "time_s,qw,qx,qy,qz,body_n_m,body_e_m,body_d_m,sigma_pos_n,sigma_pos_e,sigma_pos_d,sigma_att_n,"
		     "sigma_att_e,"
		     "sigma_att_d,cov_pos_ne,cov_pos_nd,cov_pos_ed,cov_att_ne,cov_att_nd,cov_att_ed,current_n,"
		     "current_e,"
		     "sigma_current_n,sigma_current_e,Dl_ln_xx,Dl_ln_yy,Dq_ln_xx,Dq_ln_yy,sigma_Dl_ln_xx,sigma_Dl_ln_"
		     "yy,"
		     "sigma_Dq_ln_xx,sigma_Dq_ln_yy\n";
		const double c = std::cos(0.005), z = std::sin(0.005);
		for (int k = 0; k <= 10; ++k)
			s << 1000 + k << "," << c << ",0,0," << z
			  << ",11,22,5,1,2,1,0.01,0.01,0.01,0,0,0,0,0,0,0.12,0,0.01,0.01," << std::log(40.0) << ","
			  << std::log(1.5) << "," << std::log(8.6) << "," << std::log(5.0) << ",0.1,0.1,0.1,0.1\n";
	}
	const Evaluation ev = evaluate(dir.string(), (dir / "truth.csv").string(), 1.0);
	ASSERT_EQ(ev.samples.size(), 11u);
	const Sample& s = ev.samples.back();
	EXPECT_NEAR(s.pos_err_ned.x(), 1.0, 1e-12);
	EXPECT_NEAR(s.pos_err_ned.y(), 2.0, 1e-12);
	EXPECT_NEAR(s.nees_pos, 1.0 / 1 + 4.0 / 4, 1e-9);  // 2
	EXPECT_NEAR(s.nees_hpos, 2.0, 1e-9);
	EXPECT_NEAR(s.heading_err_rad, 0.01, 1e-9);
	EXPECT_NEAR(s.att_err.z(), 0.01, 1e-9);
	EXPECT_NEAR(s.nees_att, 1.0, 1e-6);
	EXPECT_NEAR(s.current_est.x() - s.current_true.x(), 0.02, 1e-12);
	EXPECT_NEAR(s.damping[0], 40.0, 1e-9);
	EXPECT_NEAR(s.damping_hi[0], 40.0 * std::exp(0.2), 1e-9);
	EXPECT_NEAR(s.distance_m, 100, 1e-12);
	// A missing column is named.
	std::ofstream(dir / "bad" / "states.csv");
	fs::create_directories(dir / "bad");
	std::ofstream(dir / "bad" / "states.csv") << "time_s,qw\n1,1\n";
	try
	{
		evaluate((dir / "bad").string(), (dir / "truth.csv").string());
		FAIL() << "accepted a states.csv without columns";
	}
	catch (const std::runtime_error& e)
	{
		EXPECT_NE(std::string(e.what()).find("no column"), std::string::npos) << e.what();
	}
}

TEST(Eval, TruthIsInterpolatedToTheStateTimes)
{
	// The truth turns at 0.2 rad/s and moves 1 m/s north, sampled at 10 Hz;
	// the states sit between its rows, exactly on the true trajectory.
	const auvnav::testing::ScratchDir scratch("eval_interp_test");
	const fs::path& dir = scratch.path();
	auto yawAt = [](double t) { return 0.2 * (t - 1000); };
	{
		std::ofstream t(dir / "truth.csv");
		t.precision(17);
		t << "unix_time_s,north_m,east_m,down_m,qw,qx,qy,qz,current_n_mps,current_e_mps,distance_m\n";
		for (int k = 0; k <= 50; ++k)
		{
			const double tt = 1000 + 0.1 * k, h = 0.5 * yawAt(tt);
			t << tt << "," << tt - 1000 << ",0,5," << std::cos(h) << ",0,0," << std::sin(h) << ",0,0,"
			  << tt - 1000 << "\n";
		}
	}
	{
		std::ofstream s(dir / "states.csv");
		s.precision(17);
		s << "time_s,qw,qx,qy,qz,body_n_m,body_e_m,body_d_m,sigma_pos_n,sigma_pos_e,sigma_pos_d,sigma_att_n,"
		     "sigma_att_e,"
		     "sigma_att_d,cov_pos_ne,cov_pos_nd,cov_pos_ed,cov_att_ne,cov_att_nd,cov_att_ed,current_n,"
		     "current_e,"
		     "sigma_current_n,sigma_current_e,Dl_ln_xx,Dl_ln_yy,Dq_ln_xx,Dq_ln_yy,sigma_Dl_ln_xx,sigma_Dl_ln_"
		     "yy,"
		     "sigma_Dq_ln_xx,sigma_Dq_ln_yy\n";
		for (double t : {1000.02, 1001.37, 1003.05, 1004.99})
		{
			const double h = 0.5 * yawAt(t);
			s << t << "," << std::cos(h) << ",0,0," << std::sin(h) << "," << t - 1000
			  << ",0,5,1,1,1,0.01,0.01,0.01,0,0,0,0,0,0,0,0,0.01,0.01,0,0,0,0,0.1,0.1,0.1,0.1\n";
		}
	}
	const Evaluation ev = evaluate(dir.string(), (dir / "truth.csv").string(), 0.0);
	ASSERT_EQ(ev.samples.size(), 4u);
	for (const Sample& s : ev.samples)
	{
		// The nearest row would be up to 0.05 s x 0.2 rad/s = 0.01 rad and 5 cm off.
		EXPECT_LT(std::abs(s.heading_err_rad), 1e-9) << s.t;
		EXPECT_LT(s.att_err.norm(), 1e-9) << s.t;
		EXPECT_LT(s.pos_err_ned.norm(), 1e-9) << s.t;
		EXPECT_NEAR(s.distance_m, s.t - 1000, 1e-9);
	}
}

TEST(Eval, PlotDrawsItsSeries)
{
	Plot p("test", "x", "y", 400, 300);
	p.line({0, 1, 2, 3}, {0, 1, 0, 1}, cv::Scalar(0, 0, 255), "red line");
	const auvnav::testing::ScratchDir dir("eval_plot");
	const fs::path png = dir / "plot.png";
	p.save(png.string());
	const cv::Mat img = cv::imread(png.string());
	ASSERT_FALSE(img.empty());
	int red = 0;
	for (int y = 0; y < img.rows; ++y)
		for (int x = 0; x < img.cols; ++x)
		{
			const auto& px = img.at<cv::Vec3b>(y, x);
			red += px[2] > 200 && px[1] < 80 && px[0] < 80;
		}
	EXPECT_GT(red, 300);
}

TEST(Eval, BandBeyondAFixedRangeStaysInsideTheFrame)
{
	// A band ten times the fixed y range (the heading's σ in the first
	// minute): it fills the frame and leaves the margins white.
	Plot p("test", "x", "y", 400, 300);
	p.band({0, 1, 2}, {-10, -10, -10}, {10, 10, 10}, cv::Scalar(255, 0, 0), "band");
	p.yRange(-1, 1);
	const auvnav::testing::ScratchDir dir("eval_band");
	const fs::path png = dir / "band.png";
	p.save(png.string());
	const cv::Mat img = cv::imread(png.string());
	ASSERT_FALSE(img.empty());
	auto tinted = [&](int x, int y)
	{
		const auto& px = img.at<cv::Vec3b>(y, x);
		return px[0] > px[2] + 40;  // blue over white at 35 %: (255, 166, 166)
	};
	EXPECT_TRUE(tinted(200, 150)) << "inside the frame";
	EXPECT_FALSE(tinted(40, 150)) << "left margin (tick labels)";
	EXPECT_FALSE(tinted(200, 10)) << "top margin (title)";
	EXPECT_FALSE(tinted(200, 290)) << "bottom margin (axis label)";
}
