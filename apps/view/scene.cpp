#include "scene.h"

#include <auvnav/io/csv_table.h>
#include <mrpt/img/CImage.h>
#include <mrpt/opengl/CEllipsoid3D.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CText.h>
#include <mrpt/opengl/stock_objects.h>

#include <mrpt/poses/CPose3D.h>
#include <algorithm>
#include <iterator>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace fs = std::filesystem;

namespace auvnav::view
{
namespace
{
mrpt::math::TPoint3D enu(const Eigen::Vector3d& ned)
{
	return {ned.y(), ned.x(), -ned.z()};
}

mrpt::opengl::CSetOfLines::Ptr strip(const std::vector<TrackPoint>& pts, const unsigned char rgb[3],
                                     float width)
{
	auto lines = mrpt::opengl::CSetOfLines::Create();
	lines->setLineWidth(width);
	lines->setColor_u8(rgb[0], rgb[1], rgb[2]);
	for (std::size_t i = 1; i < pts.size(); ++i)
	{
		const auto a = enu(pts[i - 1].p_ned), b = enu(pts[i].p_ned);
		lines->appendLine(a.x, a.y, a.z, b.x, b.y, b.z);
	}
	return lines;
}
}  // namespace

namespace
{
/** Positions, attitudes and position σ of a states.csv-format file. */
std::vector<TrackPoint> loadStates(const fs::path& file)
{
	std::vector<TrackPoint> out;
	io::CsvTable csv(file.string());
	const std::size_t t = csv.column("time_s"), qw = csv.column("qw"), qx = csv.column("qx"),
	                  qy = csv.column("qy"), qz = csv.column("qz"), n = csv.column("body_n_m"),
	                  e = csv.column("body_e_m"), d = csv.column("body_d_m"), sn = csv.column("sigma_pos_n"),
	                  se = csv.column("sigma_pos_e"), sd = csv.column("sigma_pos_d");
	while (csv.next())
	{
		TrackPoint p;
		p.t = csv.number(t);
		p.q_nb =
		    Eigen::Quaterniond(csv.number(qw), csv.number(qx), csv.number(qy), csv.number(qz)).normalized();
		p.p_ned = {csv.number(n), csv.number(e), csv.number(d)};
		p.sigma_ned = {csv.number(sn), csv.number(se), csv.number(sd)};
		if (!p.p_ned.allFinite()) throw std::runtime_error(csv.where() + ": non-finite position");
		out.push_back(p);
	}
	if (out.empty()) throw std::runtime_error(csv.file() + ": no states");
	return out;
}
}  // namespace

RunData loadRun(const std::string& dir)
{
	RunData run;
	run.estimate = loadStates(fs::path(dir) / "states.csv");
	if (fs::exists(fs::path(dir) / "smoothed_states.csv"))
		run.smoothed = loadStates(fs::path(dir) / "smoothed_states.csv");
	const fs::path fixes = fs::path(dir) / "position_fixes.csv";
	if (fs::exists(fixes))
	{
		io::CsvTable f(fixes.string());
		const std::size_t ft = f.column("time_s"), fl = f.column("label"), fn = f.column("north_m"),
		                  fe = f.column("east_m"), status = f.column("status");
		while (f.next())
		{
			const std::string& st = f.text(status);
			run.fixes.push_back({f.number(ft),
			                     f.text(fl),
			                     {f.number(fn), f.number(fe)},
			                     st == "accepted" || st == "recovered"});
		}
	}
	return run;
}

std::vector<TrackPoint> loadTruth(const std::string& file)
{
	io::CsvTable csv(file);
	const std::size_t t = csv.column("unix_time_s"), n = csv.column("north_m"), e = csv.column("east_m"),
	                  d = csv.column("down_m"), qw = csv.column("qw"), qx = csv.column("qx"),
	                  qy = csv.column("qy"), qz = csv.column("qz"), sb = csv.column("seabed_depth_m");
	std::vector<TrackPoint> out;
	while (csv.next())
	{
		TrackPoint p;
		p.t = csv.number(t);
		p.p_ned = {csv.number(n), csv.number(e), csv.number(d)};
		p.q_nb =
		    Eigen::Quaterniond(csv.number(qw), csv.number(qx), csv.number(qy), csv.number(qz)).normalized();
		p.seabed_depth_m = csv.number(sb);
		out.push_back(p);
	}
	if (out.empty()) throw std::runtime_error(file + ": no rows");
	return out;
}

mrpt::opengl::COpenGLScene::Ptr buildScene(const RunData& run, const SceneOptions& opt)
{
	using namespace mrpt::opengl;
	auto scene = COpenGLScene::Create();
	// Extent of everything shown (ENU).
	Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
	auto grow = [&](const Eigen::Vector3d& ned)
	{
		const auto p = enu(ned);
		lo = lo.cwiseMin(Eigen::Vector3d(p.x, p.y, p.z));
		hi = hi.cwiseMax(Eigen::Vector3d(p.x, p.y, p.z));
	};
	for (const auto& p : run.estimate) grow(p.p_ned);
	for (const auto& p : run.truth) grow(p.p_ned);
	if (run.estimate.empty() && run.truth.empty()) throw std::runtime_error("nothing to show");

	// Seabed: a grid at the mean true seabed depth (or 2 m below the deepest point).
	double seabed = 0;
	int n_sb = 0;
	for (const auto& p : run.truth)
		if (std::isfinite(p.seabed_depth_m)) seabed += p.seabed_depth_m, ++n_sb;
	const double seabed_z = n_sb ? -seabed / n_sb : lo.z() - 2;
	const double margin = 10;
	auto grid = CGridPlaneXY::Create(static_cast<float>(lo.x() - margin), static_cast<float>(hi.x() + margin),
	                                 static_cast<float>(lo.y() - margin), static_cast<float>(hi.y() + margin),
	                                 static_cast<float>(seabed_z), 5.0f);
	grid->setColor_u8(140, 110, 70);
	grid->setName("seabed");
	scene->insert(grid);

	if (!run.truth.empty())
	{
		auto t = strip(run.truth, kTruthRgb, 2);
		t->setName("ground_truth");
		scene->insert(t);
	}
	auto est = strip(run.estimate, kEstimateRgb, 3);
	est->setName("estimate");
	scene->insert(est);
	if (!run.smoothed.empty())
	{
		auto sm = strip(run.smoothed, kSmoothedRgb, 3);
		sm->setName("smoothed");
		scene->insert(sm);
	}

	// 2σ position ellipsoids along the way.
	double next_t = -1e300;
	for (const auto& p : run.estimate)
	{
		if (p.t < next_t || !p.sigma_ned.allFinite()) continue;
		if (2 * p.sigma_ned.maxCoeff() > 0.25 * std::max(20.0, (hi - lo).head<2>().norm()))
			continue;  // would hide the view
		next_t = p.t + opt.ellipsoid_every_s;
		auto e = CEllipsoid3D::Create();
		const Eigen::Vector3d s = p.sigma_ned.cwiseMax(opt.ellipsoid_min_sigma_m);
		mrpt::math::CMatrixDouble33 cov;
		cov.setZero();
		cov(0, 0) = s.y() * s.y();  // east
		cov(1, 1) = s.x() * s.x();  // north
		cov(2, 2) = s.z() * s.z();  // up
		e->setCovMatrix(cov);
		e->setQuantiles(2.0f);
		e->setColor_u8(230, 40, 40, 90);
		const auto c = enu(p.p_ned);
		e->setLocation(c.x, c.y, c.z);
		e->setName("two_sigma");
		scene->insert(e);
	}

	// Position fixes, one cloud per sensor ("fixes_<label>"), on the surface:
	// accepted in the sensor's colour (the first yellow, then cyan, orange,
	// green …), rejected magenta.
	std::vector<std::string> labels;
	for (const auto& f : run.fixes)
		if (std::find(labels.begin(), labels.end(), f.label) == labels.end()) labels.push_back(f.label);
	static const uint8_t kColours[][3] = {
	    {240, 220, 0}, {0, 210, 230}, {255, 140, 0}, {60, 200, 60}, {200, 200, 200}};
	for (std::size_t i = 0; i < labels.size(); ++i)
	{
		const uint8_t* c = kColours[std::min<std::size_t>(i, std::size(kColours) - 1)];
		auto pts = CPointCloudColoured::Create();
		pts->setPointSize(6);
		for (const auto& f : run.fixes)
			if (f.label == labels[i])
				pts->insertPoint({static_cast<float>(f.ne_m.y()), static_cast<float>(f.ne_m.x()), 0.0f,
				                  f.accepted ? c[0] : uint8_t(230), f.accepted ? c[1] : uint8_t(0),
				                  f.accepted ? c[2] : uint8_t(230)});
		pts->setName("fixes_" + labels[i]);
		scene->insert(pts);
	}

	// The vehicle at its last estimated pose: body axes (x forward, y right, z down).
	const auto& last = run.estimate.empty() ? run.truth.back() : run.estimate.back();
	Eigen::Matrix3d R_enu_ned;
	R_enu_ned << 0, 1, 0, 1, 0, 0, 0, 0, -1;
	const Eigen::Matrix3d R = R_enu_ned * last.q_nb.toRotationMatrix();
	mrpt::math::CMatrixDouble44 T;
	T.setIdentity();
	for (int i = 0; i < 3; ++i)
		for (int j = 0; j < 3; ++j) T(i, j) = R(i, j);
	const auto c = enu(last.p_ned);
	T(0, 3) = c.x;
	T(1, 3) = c.y;
	T(2, 3) = c.z;
	auto vehicle = stock_objects::CornerXYZ(2.0f);
	vehicle->setPose(mrpt::poses::CPose3D(T));
	vehicle->setName("vehicle");
	scene->insert(vehicle);

	// Camera: look at the middle from the south-west, above.
	auto& cam = scene->getViewport()->getCamera();
	const Eigen::Vector3d mid = 0.5 * (lo + hi);
	cam.setPointingAt(static_cast<float>(mid.x()), static_cast<float>(mid.y()), static_cast<float>(mid.z()));
	cam.setZoomDistance(static_cast<float>(std::max(20.0, 2.0 * (hi - lo).head<2>().norm())));
	cam.setAzimuthDegrees(-120);
	cam.setElevationDegrees(55);
	return scene;
}

void renderToPng(const mrpt::opengl::COpenGLScene& scene, const std::string& png, unsigned width,
                 unsigned height)
{
	mrpt::opengl::CFBORender::Parameters p(width, height);
	mrpt::opengl::CFBORender render(p);
	render.setCamera(scene, scene.getViewport()->getCamera());  // it has its own otherwise
	mrpt::img::CImage img;
	render.render_RGB(scene, img);
	if (!img.saveToFile(png)) throw std::runtime_error("cannot write " + png);
}

}  // namespace auvnav::view
