#include "eval.h"

#include <auvnav/io/csv_table.h>
#include <auvnav/so3.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <stdexcept>

namespace auvnav::eval
{
namespace
{
struct TruthRow
{
	double t;
	Eigen::Vector3d p;
	Eigen::Matrix3d R;
	Eigen::Vector2d current;
	double distance;
};

Eigen::Matrix3d symmetric(double xx, double yy, double zz, double xy, double xz, double yz)
{
	Eigen::Matrix3d P;
	P << xx, xy, xz, xy, yy, yz, xz, yz, zz;
	return P;
}

/** The truth at time t, a.t <= t <= b.t: linear, the attitude along the
 *  geodesic. */
TruthRow interpolate(const TruthRow& a, const TruthRow& b, double t)
{
	const double span = b.t - a.t;
	const double w = span > 0 ? (t - a.t) / span : 0.0;
	TruthRow r;
	r.t = t;
	r.p = a.p + w * (b.p - a.p);
	r.R = so3::Exp(w * so3::Log(b.R * a.R.transpose())) * a.R;
	r.current = a.current + w * (b.current - a.current);
	r.distance = a.distance + w * (b.distance - a.distance);
	return r;
}

double mahalanobis(const Eigen::Vector3d& e, const Eigen::Matrix3d& P)
{
	const Eigen::LDLT<Eigen::Matrix3d> ldlt(P);
	if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0).all()) return NAN;
	return e.dot(ldlt.solve(e));
}
}  // namespace

std::pair<double, double> chi2MeanBounds(int dof, int runs, double probability)
{
	const boost::math::chi_squared d(static_cast<double>(dof * runs));
	const double a = 0.5 * (1 - probability);
	return {boost::math::quantile(d, a) / runs, boost::math::quantile(d, 1 - a) / runs};
}

Evaluation evaluate(const std::string& run_dir, const std::string& truth_csv, double every_s)
{
	// Truth first (10 Hz), then the states, with the truth interpolated to their times.
	std::vector<TruthRow> truth;
	{
		io::CsvTable c(truth_csv);
		const auto t = c.column("unix_time_s"), n = c.column("north_m"), e = c.column("east_m"), d = c.column("down_m"),
				   qw = c.column("qw"), qx = c.column("qx"), qy = c.column("qy"), qz = c.column("qz"),
				   cn = c.column("current_n_mps"), ce = c.column("current_e_mps"), dist = c.column("distance_m");
		while (c.next())
			truth.push_back({c.number(t),
							 {c.number(n), c.number(e), c.number(d)},
							 Eigen::Quaterniond(c.number(qw), c.number(qx), c.number(qy), c.number(qz)).normalized().toRotationMatrix(),
							 {c.number(cn), c.number(ce)},
							 c.number(dist)});
		if (truth.empty()) throw std::runtime_error(truth_csv + ": no rows");
	}
	Evaluation ev;
	io::CsvTable c(run_dir + "/states.csv");
	const auto t = c.column("time_s"), qw = c.column("qw"), qx = c.column("qx"), qy = c.column("qy"), qz = c.column("qz"),
			   bn = c.column("body_n_m"), be = c.column("body_e_m"), bd = c.column("body_d_m");
	const auto spn = c.column("sigma_pos_n"), spe = c.column("sigma_pos_e"), spd = c.column("sigma_pos_d");
	const auto san = c.column("sigma_att_n"), sae = c.column("sigma_att_e"), sad = c.column("sigma_att_d");
	const auto cpne = c.column("cov_pos_ne"), cpnd = c.column("cov_pos_nd"), cped = c.column("cov_pos_ed");
	const auto cane = c.column("cov_att_ne"), cand = c.column("cov_att_nd"), caed = c.column("cov_att_ed");
	const auto curn = c.column("current_n"), cure = c.column("current_e"), scn = c.column("sigma_current_n"),
			   sce = c.column("sigma_current_e");
	const std::size_t dmp[4] = {c.column("Dl_ln_xx"), c.column("Dl_ln_yy"), c.column("Dq_ln_xx"), c.column("Dq_ln_yy")};
	const std::size_t sdmp[4] = {c.column("sigma_Dl_ln_xx"), c.column("sigma_Dl_ln_yy"), c.column("sigma_Dq_ln_xx"),
								 c.column("sigma_Dq_ln_yy")};
	double next_t = -1e300;
	std::size_t ti = 0;
	while (c.next())
	{
		const double time = c.number(t);
		if (time < next_t) continue;
		while (ti + 1 < truth.size() && truth[ti + 1].t <= time) ++ti;
		// The states are stamped at IMU times, between the truth's rows: at a
		// 19 deg/s turn the nearest row alone is up to 1 deg off in heading.
		TruthRow tr;
		if (truth[ti].t <= time && ti + 1 < truth.size() && truth[ti + 1].t - truth[ti].t <= 0.5)
			tr = interpolate(truth[ti], truth[ti + 1], time);
		else if (std::abs(truth[ti].t - time) < 1e-6)
			tr = truth[ti];
		else
			continue;  // no truth here
		next_t = time + every_s;
		Sample s;
		s.t = time;
		const Eigen::Matrix3d R =
			Eigen::Quaterniond(c.number(qw), c.number(qx), c.number(qy), c.number(qz)).normalized().toRotationMatrix();
		s.pos_err_ned = Eigen::Vector3d(c.number(bn), c.number(be), c.number(bd)) - tr.p;
		auto sq = [](double v) { return v * v; };
		s.P_pos = symmetric(sq(c.number(spn)), sq(c.number(spe)), sq(c.number(spd)), c.number(cpne), c.number(cpnd), c.number(cped));
		s.P_att = symmetric(sq(c.number(san)), sq(c.number(sae)), sq(c.number(sad)), c.number(cane), c.number(cand), c.number(caed));
		s.att_err = so3::Log(R * tr.R.transpose());
		s.heading_err_rad = std::remainder(std::atan2(R(1, 0), R(0, 0)) - std::atan2(tr.R(1, 0), tr.R(0, 0)), 2 * M_PI);
		s.heading_sigma_rad = c.number(sad);
		s.current_est = {c.number(curn), c.number(cure)};
		s.current_sigma = {c.number(scn), c.number(sce)};
		s.current_true = tr.current;
		for (int k = 0; k < 4; ++k)
		{
			const double mu = c.number(dmp[k]), sg = c.number(sdmp[k]);
			s.damping[k] = std::exp(mu);
			s.damping_lo[k] = std::exp(mu - 2 * sg);
			s.damping_hi[k] = std::exp(mu + 2 * sg);
		}
		s.distance_m = tr.distance;
		s.nees_pos = mahalanobis(s.pos_err_ned, s.P_pos);
		s.nees_att = mahalanobis(s.att_err, s.P_att);
		{
			const Eigen::Matrix2d Ph = s.P_pos.topLeftCorner<2, 2>();
			const Eigen::Vector2d eh = s.pos_err_ned.head<2>();
			s.nees_hpos = Ph.determinant() > 0 ? eh.dot(Ph.inverse() * eh) : NAN;
		}
		ev.samples.push_back(s);
	}
	if (ev.samples.empty()) throw std::runtime_error(run_dir + "/states.csv: no state within the truth's time span");
	std::ifstream probe(run_dir + "/nis.csv");
	if (probe)
	{
		io::CsvTable n(run_dir + "/nis.csv");
		const auto nt = n.column("time_s"), nl = n.column("label"), nu = n.column("updates"), ns = n.column("nis_sum"),
				   nd = n.column("dim_sum");
		while (n.next())
		{
			ev.nis[n.text(nl)].push_back({n.number(nt), static_cast<std::size_t>(n.number(nu)), static_cast<std::size_t>(n.number(nd)),
									   n.number(ns)});
		}
	}
	return ev;
}

}  // namespace auvnav::eval
