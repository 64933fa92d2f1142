#include "scene.h"

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
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace auvnav::view
{
namespace
{
/** CSV with a header row: column index by name. */
struct Csv
{
	std::string file;
	std::map<std::string, std::size_t> col;
	std::ifstream in;
	int line_no = 1;
	explicit Csv(const std::string& f) : file(f), in(f)
	{
		if (!in) throw std::runtime_error("cannot read " + f);
		std::string header;
		if (!std::getline(in, header)) throw std::runtime_error(f + ": empty");
		std::stringstream ss(header);
		std::size_t i = 0;
		for (std::string name; std::getline(ss, name, ',');) col[name] = i++;
	}
	std::size_t need(const std::string& name) const
	{
		const auto it = col.find(name);
		if (it == col.end()) throw std::runtime_error(file + ": no column '" + name + "'");
		return it->second;
	}
	bool next(std::vector<std::string>& v)
	{
		std::string line;
		if (!std::getline(in, line)) return false;
		++line_no;
		v.clear();
		std::stringstream ss(line);
		for (std::string f; std::getline(ss, f, ',');) v.push_back(f);
		return true;
	}
	double num(const std::vector<std::string>& v, std::size_t i) const
	{
		if (i >= v.size()) throw std::runtime_error(file + ":" + std::to_string(line_no) + ": too few fields");
		try
		{
			return std::stod(v[i]);
		}
		catch (const std::exception&)
		{
			throw std::runtime_error(file + ":" + std::to_string(line_no) + ": '" + v[i] + "' is not a number");
		}
	}
};

mrpt::math::TPoint3D enu(const Eigen::Vector3d& ned) { return {ned.y(), ned.x(), -ned.z()}; }

mrpt::opengl::CSetOfLines::Ptr strip(const std::vector<TrackPoint>& pts, const unsigned char rgb[3], float width)
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

RunData loadRun(const std::string& dir)
{
	RunData run;
	Csv csv((fs::path(dir) / "states.csv").string());
	const std::size_t t = csv.need("time_s"), qw = csv.need("qw"), qx = csv.need("qx"), qy = csv.need("qy"),
					  qz = csv.need("qz"), n = csv.need("body_n_m"), e = csv.need("body_e_m"), d = csv.need("body_d_m"),
					  sn = csv.need("sigma_pos_n"), se = csv.need("sigma_pos_e"), sd = csv.need("sigma_pos_d");
	std::vector<std::string> v;
	while (csv.next(v))
	{
		TrackPoint p;
		p.t = csv.num(v, t);
		p.q_nb = Eigen::Quaterniond(csv.num(v, qw), csv.num(v, qx), csv.num(v, qy), csv.num(v, qz)).normalized();
		p.p_ned = {csv.num(v, n), csv.num(v, e), csv.num(v, d)};
		p.sigma_ned = {csv.num(v, sn), csv.num(v, se), csv.num(v, sd)};
		if (!p.p_ned.allFinite()) throw std::runtime_error(csv.file + ":" + std::to_string(csv.line_no) + ": non-finite position");
		run.estimate.push_back(p);
	}
	if (run.estimate.empty()) throw std::runtime_error(csv.file + ": no states");
	const fs::path fixes = fs::path(dir) / "position_fixes.csv";
	if (fs::exists(fixes))
	{
		Csv f(fixes.string());
		const std::size_t ft = f.need("time_s"), fn = f.need("north_m"), fe = f.need("east_m"), fs_ = f.need("status");
		while (f.next(v))
		{
			if (fs_ >= v.size()) throw std::runtime_error(f.file + ":" + std::to_string(f.line_no) + ": too few fields");
			run.gps.push_back({f.num(v, ft), {f.num(v, fn), f.num(v, fe)}, v[fs_] == "accepted" || v[fs_] == "recovered"});
		}
	}
	return run;
}

std::vector<TrackPoint> loadTruth(const std::string& file)
{
	Csv csv(file);
	const std::size_t t = csv.need("unix_time_s"), n = csv.need("north_m"), e = csv.need("east_m"), d = csv.need("down_m"),
					  qw = csv.need("qw"), qx = csv.need("qx"), qy = csv.need("qy"), qz = csv.need("qz"),
					  sb = csv.need("seabed_depth_m");
	std::vector<TrackPoint> out;
	std::vector<std::string> v;
	while (csv.next(v))
	{
		TrackPoint p;
		p.t = csv.num(v, t);
		p.p_ned = {csv.num(v, n), csv.num(v, e), csv.num(v, d)};
		p.q_nb = Eigen::Quaterniond(csv.num(v, qw), csv.num(v, qx), csv.num(v, qy), csv.num(v, qz)).normalized();
		p.seabed_depth_m = csv.num(v, sb);
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
	auto grow = [&](const Eigen::Vector3d& ned) {
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

	// 2σ position ellipsoids along the way.
	double next_t = -1e300;
	for (const auto& p : run.estimate)
	{
		if (p.t < next_t || !p.sigma_ned.allFinite()) continue;
		if (2 * p.sigma_ned.maxCoeff() > 0.25 * std::max(20.0, (hi - lo).head<2>().norm())) continue;  // would hide the view
		next_t = p.t + opt.ellipsoid_every_s;
		auto e = CEllipsoid3D::Create();
		const Eigen::Vector3d s = p.sigma_ned.cwiseMax(opt.ellipsoid_min_sigma_m);
		mrpt::math::CMatrixDouble33 cov;
		cov.setZero();
		cov(0, 0) = s.y() * s.y();	// east
		cov(1, 1) = s.x() * s.x();	// north
		cov(2, 2) = s.z() * s.z();	// up
		e->setCovMatrix(cov);
		e->setQuantiles(2.0f);
		e->setColor_u8(230, 40, 40, 90);
		const auto c = enu(p.p_ned);
		e->setLocation(c.x, c.y, c.z);
		e->setName("two_sigma");
		scene->insert(e);
	}

	// GPS fixes: accepted yellow, rejected magenta, on the surface.
	if (!run.gps.empty())
	{
		auto pts = CPointCloudColoured::Create();
		pts->setPointSize(6);
		for (const auto& f : run.gps)
			pts->insertPoint({static_cast<float>(f.ne_m.y()), static_cast<float>(f.ne_m.x()), 0.0f,
							  f.accepted ? uint8_t(240) : uint8_t(230), f.accepted ? uint8_t(220) : uint8_t(0),
							  f.accepted ? uint8_t(0) : uint8_t(230)});
		pts->setName("gps_fixes");
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

void renderToPng(const mrpt::opengl::COpenGLScene& scene, const std::string& png, unsigned width, unsigned height)
{
	mrpt::opengl::CFBORender::Parameters p(width, height);
	mrpt::opengl::CFBORender render(p);
	render.setCamera(scene, scene.getViewport()->getCamera());  // it has its own otherwise
	mrpt::img::CImage img;
	render.render_RGB(scene, img);
	if (!img.saveToFile(png)) throw std::runtime_error("cannot write " + png);
}

}  // namespace auvnav::view
