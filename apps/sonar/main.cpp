// auvnav-sonar: landmark (pole) headings from Gemini imaging-sonar frames.
//   auvnav-sonar --config config/sonar/gemini.yaml [--trajectory RUN/trajectory.tum]
//                [--truth SIMDIR] --out DIR INPUT
// INPUT is a rawlog (frames: CObservationImage with the sonar label) or a
// folder of PNG raw polar frames (beams x bins; geometry from the config; the
// time is the last number in the file name). Writes DIR/landmark_headings.csv,
// annotated fan images DIR/fan_NNNNNN.png and, with --truth, DIR/score.md;
// --export-polar DIR2 also saves the raw frames as PNGs (a PNG-folder input).
#include <auvnav/cli.h>
#include <auvnav/io/rawlog.h>
#include <auvnav/io/trajectory.h>
#include <auvnav/obs/register.h>
#include <auvnav/sonar/frame.h>
#include <auvnav/sonar/pipeline.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "scoring.h"

namespace fs = std::filesystem;
using namespace auvnav;

namespace
{
constexpr double kDeg = M_PI / 180;
constexpr double kMaxTrajectoryGap_s = 2.0;  // no pose interpolated across a longer gap

struct Frame
{
	double t = NAN;  //!< Unix time [s] (or the file's number)
	std::string name;
	cv::Mat polar;
	sonar::PolarGeometry geometry;
};

/** Calls `fn` for each frame of a rawlog; counts what it skips. */
void rawlogFrames(const std::string& path, const sonar::SonarConfig& cfg,
                  const std::function<void(Frame&)>& fn, std::size_t& skipped)
{
	io::RawlogReader reader(path);
	std::size_t index = 0;
	while (auto obs = reader.next())
	{
		const auto* img = dynamic_cast<const mrpt::obs::CObservationImage*>(obs.get());
		if (!img || img->sensorLabel != cfg.label) continue;
		std::string why;
		auto g = sonar::geometryOf(*img, why);
		if (!g && cfg.geometry) g = cfg.geometry;
		if (!g)
		{
			std::cerr << "auvnav-sonar: frame " << index << " skipped: " << why << "\n";
			++skipped;
			continue;
		}
		Frame f;
		f.t = mrpt::Clock::toDouble(img->timestamp);
		f.name = "frame " + std::to_string(index++);
		f.polar = sonar::polarImage(*img);
		f.geometry = *g;
		if (f.polar.cols != g->beam_count || f.polar.rows != g->range_bins)
		{
			std::cerr << "auvnav-sonar: " << f.name << " skipped: image size disagrees with the geometry\n";
			++skipped;
			continue;
		}
		fn(f);
	}
}

/** Calls `fn` for each PNG in a folder, in name order. */
void folderFrames(const std::string& dir, const sonar::SonarConfig& cfg,
                  const std::function<void(Frame&)>& fn, std::size_t& skipped)
{
	if (!cfg.geometry)
		throw std::runtime_error("PNG frames need 'geometry:' in the config (beams, bins, aperture, ranges)");
	std::vector<fs::path> files;
	for (const auto& e : fs::directory_iterator(dir))
	{
		auto ext = e.path().extension().string();
		std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
		if (e.is_regular_file() && ext == ".png") files.push_back(e.path());
	}
	std::sort(files.begin(), files.end());
	if (files.empty()) throw std::runtime_error(dir + ": no .png frames");
	const std::regex number(R"(([0-9]+(\.[0-9]+)?)(?!.*[0-9]))");
	for (std::size_t i = 0; i < files.size(); ++i)
	{
		Frame f;
		f.name = files[i].filename().string();
		f.polar = cv::imread(files[i].string(), cv::IMREAD_GRAYSCALE);
		f.geometry = *cfg.geometry;
		if (f.polar.empty() || f.polar.cols != f.geometry.beam_count || f.polar.rows != f.geometry.range_bins)
		{
			std::cerr << "auvnav-sonar: " << f.name << " skipped: "
			          << (f.polar.empty()
			                  ? "not a readable image"
			                  : "size " + std::to_string(f.polar.cols) + "x" + std::to_string(f.polar.rows) +
			                        " is not beams x bins " + std::to_string(f.geometry.beam_count) + "x" +
			                        std::to_string(f.geometry.range_bins))
			          << "\n";
			++skipped;
			continue;
		}
		std::smatch m;
		const std::string stem = files[i].stem().string();
		f.t = std::regex_search(stem, m, number) ? std::stod(m[1]) : static_cast<double>(i);
		fn(f);
	}
}

/** Annotated fan image: detections (green associated with the pole id,
 *  orange not), predicted map poles (blue), the implied heading. */
cv::Mat annotate(const Frame& f, const sonar::SonarConfig& cfg, const sonar::FrameResult& r,
                 const std::optional<sonar::SonarPose>& pose, double nav_heading_rad)
{
	const double ppm = std::max(4.0, 600.0 / f.geometry.max_range_m);
	cv::Mat fan = sonar::fanImage(f.polar, f.geometry, ppm), bgr;
	cv::cvtColor(fan, bgr, cv::COLOR_GRAY2BGR);
	if (pose)
		for (const auto& p : cfg.map.poles)
		{
			double b = 0, rg = 0;
			sonar::predictPole(*pose, p.ne_m, b, rg);
			if (!f.geometry.inView(b, rg)) continue;
			const cv::Point2d px = sonar::fanPixel(f.geometry, ppm, b, rg);
			cv::drawMarker(bgr, px, cv::Scalar(255, 128, 0), cv::MARKER_TILTED_CROSS, 10, 1);
		}
	std::vector<int> pole_of(r.detections.size(), -1);
	for (const auto& a : r.associations) pole_of[static_cast<std::size_t>(a.detection)] = a.pole;
	for (std::size_t i = 0; i < r.detections.size(); ++i)
	{
		const auto& d = r.detections[i];
		const cv::Point2d px = sonar::fanPixel(f.geometry, ppm, d.bearing_rad, d.range_m);
		const cv::Scalar colour = pole_of[i] >= 0 ? cv::Scalar(0, 220, 0) : cv::Scalar(0, 140, 255);
		cv::circle(bgr, px, 8, colour, 2);
		if (pole_of[i] >= 0)
			cv::putText(bgr, cfg.map.poles[static_cast<std::size_t>(pole_of[i])].id, px + cv::Point2d(10, -6),
			            cv::FONT_HERSHEY_SIMPLEX, 0.5, colour, 1);
	}
	char text[256];
	if (r.heading)
		std::snprintf(text, sizeof text, "%s  landmark heading %.2f +- %.2f deg (%d poles)  nav %.2f deg",
		              f.name.c_str(), r.heading->heading_rad / kDeg, r.heading->sigma_rad / kDeg,
		              r.heading->poles, nav_heading_rad / kDeg);
	else
		std::snprintf(text, sizeof text, "%s  %zu detections, no landmark heading", f.name.c_str(),
		              r.detections.size());
	cv::putText(bgr, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 1);
	return bgr;
}
}  // namespace

int main(int argc, char** argv)
{
	TCLAP::CmdLine cmd(
	    "Landmark (pole) headings from imaging-sonar frames: detection with OpenCV, association with the "
	    "surveyed pole map from a trajectory, the heading each frame implies; annotated fan images and a "
	    "CSV.",
	    ' ', "0.1.0");
	TCLAP::UnlabeledValueArg<std::string> input("input", "Rawlog or folder of PNG polar frames", true, "",
	                                            "INPUT", cmd);
	TCLAP::ValueArg<std::string> config("c", "config", "Sonar YAML (config/sonar/gemini.yaml)", true, "",
	                                    "FILE", cmd);
	TCLAP::ValueArg<std::string> out("o", "out", "Output directory", true, "", "DIR", cmd);
	TCLAP::ValueArg<std::string> traj("t", "trajectory",
	                                  "TUM trajectory (auvnav-run's trajectory.tum or a ground_truth.tum)",
	                                  false, "", "FILE", cmd);
	TCLAP::ValueArg<std::string> truth("", "truth", "auvnav-sim output folder: score against sonar_truth.csv",
	                                   false, "", "DIR", cmd);
	TCLAP::ValueArg<std::string> export_polar(
	    "", "export-polar",
	    "Also write each raw polar frame as DIR/frame_<unix time>.png (input for a later PNG-folder run)",
	    false, "", "DIR", cmd);
	TCLAP::ValueArg<int> every("", "images-every", "Write every Nth annotated fan image (0: none)", false, 1,
	                           "N", cmd);
	const cli::ObsLibOption obs_libs(cmd);
	if (const auto code = auvnav::cli::parse(cmd, argc, argv, "auvnav-sonar")) return *code;
	if (const auto code = obs_libs.load("auvnav-sonar")) return *code;
	try
	{
		obs::registerAllClasses();
		const auto cfg_file = config::Node::load(config.getValue());
		const auto cfg = sonar::SonarConfig::fromConfig(cfg_file);
		cfg_file.checkAllKeysUsed();
		std::optional<auvnav::io::Trajectory> trajectory;
		if (!traj.getValue().empty()) trajectory = auvnav::io::readTum(traj.getValue());
		std::optional<sonarapp::SonarTruth> sim_truth;
		if (!truth.getValue().empty()) sim_truth = sonarapp::SonarTruth::load(truth.getValue());
		fs::create_directories(out.getValue());
		if (!export_polar.getValue().empty()) fs::create_directories(export_polar.getValue());
		std::ofstream csv(fs::path(out.getValue()) / "landmark_headings.csv");
		csv << "time_s,frame,detections,associated,pole_ids,landmark_heading_deg,landmark_sigma_deg,nav_"
		       "heading_deg,"
		       "difference_deg\n";
		sonarapp::Score score;
		std::size_t frames = 0, skipped = 0, with_heading = 0, image_index = 0;
		const Eigen::Matrix2d P = Eigen::Matrix2d::Identity() * cfg.position_sigma_m * cfg.position_sigma_m;
		auto process = [&](Frame& f)
		{
			std::optional<sonar::SonarPose> pose;
			double nav_heading = NAN;
			if (trajectory)
				if (const auto p = auvnav::io::interpolate(*trajectory, f.t, kMaxTrajectoryGap_s))
				{
					const Eigen::Matrix3d R = p->q_nb.toRotationMatrix();
					pose = sonar::sonarPose(cfg, p->p_n, R, P, cfg.heading_sigma_rad);
					nav_heading = std::atan2(R(1, 0), R(0, 0));
				}
			if (!export_polar.getValue().empty())
			{
				char name[64];
				std::snprintf(name, sizeof name, "frame_%.3f.png", f.t);
				cv::imwrite((fs::path(export_polar.getValue()) / name).string(), f.polar);
			}
			const auto r = sonar::analyseFrame(f.polar, f.geometry, cfg, pose);
			std::string ids;
			for (const auto& a : r.associations)
				ids += (ids.empty() ? "" : ";") + cfg.map.poles[static_cast<std::size_t>(a.pole)].id;
			char line[512];
			if (r.heading)
			{
				++with_heading;
				std::snprintf(line, sizeof line, "%.3f,%s,%zu,%zu,%s,%.4f,%.4f,%.4f,%.4f\n", f.t,
				              f.name.c_str(), r.detections.size(), r.associations.size(), ids.c_str(),
				              r.heading->heading_rad / kDeg, r.heading->sigma_rad / kDeg, nav_heading / kDeg,
				              auvnav::wrapAngle(r.heading->heading_rad - nav_heading) / kDeg);
			}
			else
				std::snprintf(line, sizeof line, "%.3f,%s,%zu,%zu,%s,,,%.4f,\n", f.t, f.name.c_str(),
				              r.detections.size(), r.associations.size(), ids.c_str(), nav_heading / kDeg);
			csv << line;
			csv.flush();
			if (sim_truth)
			{
				if (const auto* tf = sim_truth->at(f.t))
					sonarapp::scoreFrame(
					    *tf, r.detections,
					    r.heading ? std::optional<double>(r.heading->heading_rad) : std::nullopt,
					    r.heading ? r.heading->sigma_rad : 1.0, score);
			}
			if (every.getValue() > 0 && frames % static_cast<std::size_t>(every.getValue()) == 0)
			{
				char name[64];
				std::snprintf(name, sizeof name, "fan_%06zu.png", image_index++);
				cv::imwrite((fs::path(out.getValue()) / name).string(),
				            annotate(f, cfg, r, pose, nav_heading));
			}
			++frames;
		};
		if (fs::is_directory(input.getValue()))
			folderFrames(input.getValue(), cfg, process, skipped);
		else
			rawlogFrames(input.getValue(), cfg, process, skipped);
		std::printf("%zu frames (%zu skipped), %zu with a landmark heading; outputs in %s\n", frames, skipped,
		            with_heading, out.getValue().c_str());
		if (sim_truth)
		{
			const std::string md = score.markdown();
			std::ofstream(fs::path(out.getValue()) / "score.md") << md;
			std::cout << md;
		}
		if (frames == 0)
		{
			std::cerr << "auvnav-sonar: no frames with label '" << cfg.label << "' in " << input.getValue()
			          << "\n";
			return cli::kExitBadInput;
		}
	}
	catch (const std::exception& e)
	{
		return auvnav::cli::fail("auvnav-sonar", e.what());
	}
	return 0;
}
