#include <auvnav/io/csv_table.h>
#include <auvnav/io/trajectory.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace auvnav::io
{
namespace
{
/** A quaternion read from text, normalised; nullopt unless finite and of unit norm (to 1e-3). */
std::optional<Eigen::Quaterniond> unitQuaternion(double w, double x, double y, double z)
{
	const Eigen::Quaterniond q(w, x, y, z);
	if (!(std::abs(q.norm() - 1) < 1e-3)) return std::nullopt;
	return q.normalized();
}

/** Between a (w = 0) and b (w = 1). */
TrajectoryPoint blend(const TrajectoryPoint& a, const TrajectoryPoint& b, double w, double t)
{
	TrajectoryPoint p = w < 0.5 ? a : b;  // the discrete fields (submerged)
	p.t_unix = t;
	p.p_n = a.p_n + w * (b.p_n - a.p_n);
	p.q_nb = a.q_nb.slerp(w, b.q_nb);  // the geodesic, shortest way round
	p.current_ne = a.current_ne + w * (b.current_ne - a.current_ne);
	p.distance_m = a.distance_m + w * (b.distance_m - a.distance_m);
	return p;
}

/** The first point at or after t - tolerance. */
Trajectory::const_iterator firstNotBefore(const Trajectory& tr, double t)
{
	return std::lower_bound(tr.begin(), tr.end(), t - kTimeTolerance_s,
	                        [](const TrajectoryPoint& p, double v) { return p.t_unix < v; });
}

/** Interpolated or exact point, nullopt outside or across a gap longer than max_gap_s. */
std::optional<TrajectoryPoint> inside(const Trajectory& tr, double t, double max_gap_s)
{
	const auto b = firstNotBefore(tr, t);
	if (b == tr.end()) return std::nullopt;
	if (std::abs(b->t_unix - t) <= kTimeTolerance_s) return *b;
	if (b == tr.begin()) return std::nullopt;
	const auto a = b - 1;
	const double span = b->t_unix - a->t_unix;
	if (span > max_gap_s) return std::nullopt;
	return blend(*a, *b, (t - a->t_unix) / span, t);
}
}  // namespace

Trajectory readGroundTruth(const std::filesystem::path& csv)
{
	CsvTable c(csv.string());
	const std::size_t t = c.column("unix_time_s"), n = c.column("north_m"), e = c.column("east_m"),
	                  d = c.column("down_m"), qw = c.column("qw"), qx = c.column("qx"), qy = c.column("qy"),
	                  qz = c.column("qz"), dist = c.column("distance_m"), cn = c.column("current_n_mps"),
	                  ce = c.column("current_e_mps");
	const bool has_submerged = c.has("submerged");  // hand-made truth files may leave it out
	const std::size_t sub = has_submerged ? c.column("submerged") : 0;
	Trajectory tr;
	while (c.next())
	{
		TrajectoryPoint p;
		p.t_unix = c.number(t);
		p.p_n = {c.number(n), c.number(e), c.number(d)};
		const auto q = unitQuaternion(c.number(qw), c.number(qx), c.number(qy), c.number(qz));
		if (!q) throw std::runtime_error(c.where() + ": non-unit quaternion");
		p.q_nb = *q;
		p.distance_m = c.number(dist);
		p.submerged = has_submerged && c.number(sub) > 0.5;
		p.current_ne = {c.number(cn), c.number(ce)};
		if (!std::isfinite(p.t_unix) || !p.p_n.allFinite())
			throw std::runtime_error(c.where() + ": non-finite time or position");
		if (!tr.empty() && !(p.t_unix > tr.back().t_unix))
			throw std::runtime_error(c.where() + ": time does not increase");
		tr.push_back(p);
	}
	if (tr.empty()) throw std::runtime_error(csv.string() + ": no rows");
	return tr;
}

Trajectory readTum(const std::filesystem::path& file)
{
	std::ifstream f(file);
	if (!f) throw std::runtime_error("cannot read trajectory " + file.string());
	Trajectory tr;
	std::string line;
	int n = 0;
	while (std::getline(f, line))
	{
		++n;
		if (line.empty() || line[0] == '#') continue;
		const std::string where = file.string() + ":" + std::to_string(n);
		std::istringstream ss(line);
		TrajectoryPoint p;
		double qx, qy, qz, qw;
		if (!(ss >> p.t_unix >> p.p_n.x() >> p.p_n.y() >> p.p_n.z() >> qx >> qy >> qz >> qw))
			throw std::runtime_error(where + ": expected 't x y z qx qy qz qw'");
		const auto q = unitQuaternion(qw, qx, qy, qz);
		if (!std::isfinite(p.t_unix) || !p.p_n.allFinite() || !q)
			throw std::runtime_error(where + ": non-finite value or non-unit quaternion");
		p.q_nb = *q;
		if (!tr.empty() && p.t_unix <= tr.back().t_unix) continue;  // keep it strictly increasing
		tr.push_back(p);
	}
	if (tr.empty()) throw std::runtime_error(file.string() + ": no poses");
	return tr;
}

std::optional<TrajectoryPoint> interpolate(const Trajectory& tr, double t, double max_gap_s)
{
	return inside(tr, t, max_gap_s);
}

TrajectoryPoint at(const Trajectory& tr, double t)
{
	if (tr.empty()) throw std::invalid_argument("io::at: empty trajectory");
	if (t <= tr.front().t_unix) return tr.front();
	if (t >= tr.back().t_unix) return tr.back();
	return *inside(tr, t, std::numeric_limits<double>::infinity());
}

}  // namespace auvnav::io
