#include "eval.h"

#include <auvnav/so3.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace auvnav::eval
{
namespace
{
struct Csv
{
	std::string file;
	std::map<std::string, std::size_t> col;
	std::ifstream in;
	int line_no = 1;
	std::vector<std::string> v;
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
	bool next()
	{
		std::string line;
		if (!std::getline(in, line)) return false;
		++line_no;
		v.clear();
		std::stringstream ss(line);
		for (std::string f; std::getline(ss, f, ',');) v.push_back(f);
		return true;
	}
	double num(std::size_t i) const
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
	// Truth first (10 Hz), then the states matched to the nearest truth row.
	std::vector<TruthRow> truth;
	{
		Csv c(truth_csv);
		const auto t = c.need("unix_time_s"), n = c.need("north_m"), e = c.need("east_m"), d = c.need("down_m"),
				   qw = c.need("qw"), qx = c.need("qx"), qy = c.need("qy"), qz = c.need("qz"),
				   cn = c.need("current_n_mps"), ce = c.need("current_e_mps"), dist = c.need("distance_m");
		while (c.next())
			truth.push_back({c.num(t),
							 {c.num(n), c.num(e), c.num(d)},
							 Eigen::Quaterniond(c.num(qw), c.num(qx), c.num(qy), c.num(qz)).normalized().toRotationMatrix(),
							 {c.num(cn), c.num(ce)},
							 c.num(dist)});
		if (truth.empty()) throw std::runtime_error(truth_csv + ": no rows");
	}
	Evaluation ev;
	Csv c(run_dir + "/states.csv");
	const auto t = c.need("time_s"), qw = c.need("qw"), qx = c.need("qx"), qy = c.need("qy"), qz = c.need("qz"),
			   bn = c.need("body_n_m"), be = c.need("body_e_m"), bd = c.need("body_d_m");
	const auto spn = c.need("sigma_pos_n"), spe = c.need("sigma_pos_e"), spd = c.need("sigma_pos_d");
	const auto san = c.need("sigma_att_n"), sae = c.need("sigma_att_e"), sad = c.need("sigma_att_d");
	const auto cpne = c.need("cov_pos_ne"), cpnd = c.need("cov_pos_nd"), cped = c.need("cov_pos_ed");
	const auto cane = c.need("cov_att_ne"), cand = c.need("cov_att_nd"), caed = c.need("cov_att_ed");
	const auto curn = c.need("current_n"), cure = c.need("current_e"), scn = c.need("sigma_current_n"),
			   sce = c.need("sigma_current_e");
	const std::size_t dmp[4] = {c.need("Dl_ln_xx"), c.need("Dl_ln_yy"), c.need("Dq_ln_xx"), c.need("Dq_ln_yy")};
	const std::size_t sdmp[4] = {c.need("sigma_Dl_ln_xx"), c.need("sigma_Dl_ln_yy"), c.need("sigma_Dq_ln_xx"),
								 c.need("sigma_Dq_ln_yy")};
	double next_t = -1e300;
	std::size_t ti = 0;
	while (c.next())
	{
		const double time = c.num(t);
		if (time < next_t) continue;
		while (ti + 1 < truth.size() && std::abs(truth[ti + 1].t - time) <= std::abs(truth[ti].t - time)) ++ti;
		const TruthRow& tr = truth[ti];
		if (std::abs(tr.t - time) > 0.2) continue;	// no truth here
		next_t = time + every_s;
		Sample s;
		s.t = time;
		const Eigen::Matrix3d R =
			Eigen::Quaterniond(c.num(qw), c.num(qx), c.num(qy), c.num(qz)).normalized().toRotationMatrix();
		s.pos_err_ned = Eigen::Vector3d(c.num(bn), c.num(be), c.num(bd)) - tr.p;
		auto sq = [](double v) { return v * v; };
		s.P_pos = symmetric(sq(c.num(spn)), sq(c.num(spe)), sq(c.num(spd)), c.num(cpne), c.num(cpnd), c.num(cped));
		s.P_att = symmetric(sq(c.num(san)), sq(c.num(sae)), sq(c.num(sad)), c.num(cane), c.num(cand), c.num(caed));
		s.att_err = so3::Log(R * tr.R.transpose());
		s.heading_err_rad = std::remainder(std::atan2(R(1, 0), R(0, 0)) - std::atan2(tr.R(1, 0), tr.R(0, 0)), 2 * M_PI);
		s.heading_sigma_rad = c.num(sad);
		s.current_est = {c.num(curn), c.num(cure)};
		s.current_sigma = {c.num(scn), c.num(sce)};
		s.current_true = tr.current;
		for (int k = 0; k < 4; ++k)
		{
			const double mu = c.num(dmp[k]), sg = c.num(sdmp[k]);
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
		Csv n(run_dir + "/nis.csv");
		const auto nt = n.need("time_s"), nl = n.need("label"), nu = n.need("updates"), ns = n.need("nis_sum"),
				   nd = n.need("dim_sum");
		while (n.next())
		{
			if (nl >= n.v.size()) throw std::runtime_error(n.file + ":" + std::to_string(n.line_no) + ": too few fields");
			ev.nis[n.v[nl]].push_back({n.num(nt), static_cast<std::size_t>(n.num(nu)), static_cast<std::size_t>(n.num(nd)),
									   n.num(ns)});
		}
	}
	return ev;
}

}  // namespace auvnav::eval
