#include "eval.h"

#include <auvnav/angles.h>
#include <auvnav/io/csv_table.h>
#include <auvnav/io/trajectory.h>
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
/** Truth rows further apart than this are a gap: no sample there. */
constexpr double kMaxTruthGap_s = 0.5;

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

namespace
{
/** The columns of states.csv a Sample needs. */
struct StateColumns
{
	std::size_t t, qw, qx, qy, qz, bn, be, bd, spn, spe, spd, san, sae, sad, cpne, cpnd, cped, cane, cand,
	    caed, curn, cure, scn, sce, dmp[4], sdmp[4];
	explicit StateColumns(const io::CsvTable& c)
	    : t(c.column("time_s")),
	      qw(c.column("qw")),
	      qx(c.column("qx")),
	      qy(c.column("qy")),
	      qz(c.column("qz")),
	      bn(c.column("body_n_m")),
	      be(c.column("body_e_m")),
	      bd(c.column("body_d_m")),
	      spn(c.column("sigma_pos_n")),
	      spe(c.column("sigma_pos_e")),
	      spd(c.column("sigma_pos_d")),
	      san(c.column("sigma_att_n")),
	      sae(c.column("sigma_att_e")),
	      sad(c.column("sigma_att_d")),
	      cpne(c.column("cov_pos_ne")),
	      cpnd(c.column("cov_pos_nd")),
	      cped(c.column("cov_pos_ed")),
	      cane(c.column("cov_att_ne")),
	      cand(c.column("cov_att_nd")),
	      caed(c.column("cov_att_ed")),
	      curn(c.column("current_n")),
	      cure(c.column("current_e")),
	      scn(c.column("sigma_current_n")),
	      sce(c.column("sigma_current_e")),
	      dmp{c.column("Dl_ln_xx"), c.column("Dl_ln_yy"), c.column("Dq_ln_xx"), c.column("Dq_ln_yy")},
	      sdmp{c.column("sigma_Dl_ln_xx"), c.column("sigma_Dl_ln_yy"), c.column("sigma_Dq_ln_xx"),
	           c.column("sigma_Dq_ln_yy")}
	{
	}
};

/** The current states.csv row against the truth at its time. */
Sample sampleOf(const io::CsvTable& c, const StateColumns& k, const io::TrajectoryPoint& tr)
{
	Sample s;
	s.t = c.number(k.t);
	const Eigen::Matrix3d R =
	    Eigen::Quaterniond(c.number(k.qw), c.number(k.qx), c.number(k.qy), c.number(k.qz))
	        .normalized()
	        .toRotationMatrix();
	const Eigen::Matrix3d R_true = tr.q_nb.toRotationMatrix();
	s.pos_err_ned = Eigen::Vector3d(c.number(k.bn), c.number(k.be), c.number(k.bd)) - tr.p_n;
	auto sq = [](double v) { return v * v; };
	s.P_pos = symmetric(sq(c.number(k.spn)), sq(c.number(k.spe)), sq(c.number(k.spd)), c.number(k.cpne),
	                    c.number(k.cpnd), c.number(k.cped));
	s.P_att = symmetric(sq(c.number(k.san)), sq(c.number(k.sae)), sq(c.number(k.sad)), c.number(k.cane),
	                    c.number(k.cand), c.number(k.caed));
	s.att_err = so3::Log(R * R_true.transpose());
	s.heading_err_rad = wrapAngle(std::atan2(R(1, 0), R(0, 0)) - std::atan2(R_true(1, 0), R_true(0, 0)));
	s.heading_sigma_rad = c.number(k.sad);
	s.current_est = {c.number(k.curn), c.number(k.cure)};
	s.current_sigma = {c.number(k.scn), c.number(k.sce)};
	s.current_true = tr.current_ne;
	for (int i = 0; i < 4; ++i)
	{
		const double mu = c.number(k.dmp[i]), sg = c.number(k.sdmp[i]);
		s.damping[i] = std::exp(mu);
		s.damping_lo[i] = std::exp(mu - 2 * sg);
		s.damping_hi[i] = std::exp(mu + 2 * sg);
	}
	s.distance_m = tr.distance_m;
	s.depth_true_m = tr.p_n.z();
	s.nees_pos = mahalanobis(s.pos_err_ned, s.P_pos);
	s.nees_att = mahalanobis(s.att_err, s.P_att);
	const Eigen::Matrix2d Ph = s.P_pos.topLeftCorner<2, 2>();
	const Eigen::Vector2d eh = s.pos_err_ned.head<2>();
	s.nees_hpos = Ph.determinant() > 0 ? eh.dot(Ph.inverse() * eh) : NAN;
	return s;
}
}  // namespace

Evaluation evaluate(const std::string& run_dir, const std::string& truth_csv, double every_s,
                    const std::string& states_file)
{
	// The states are stamped at IMU times, between the truth's (10 Hz) rows:
	// at a 19 deg/s turn the nearest row alone is up to 1 deg off in heading,
	// so the truth is interpolated to them (io::interpolate, as everywhere).
	const io::Trajectory truth = io::readGroundTruth(truth_csv);
	Evaluation ev;
	io::CsvTable c(run_dir + "/" + states_file);
	const StateColumns k(c);
	double next_t = -1e300;
	while (c.next())
	{
		const double time = c.number(k.t);
		if (time < next_t) continue;
		const auto tr = io::interpolate(truth, time, kMaxTruthGap_s);
		if (!tr) continue;  // no truth here
		next_t = time + every_s;
		ev.samples.push_back(sampleOf(c, k, *tr));
	}
	if (ev.samples.empty())
		throw std::runtime_error(run_dir + "/" + states_file + ": no state within the truth's time span");
	std::ifstream probe(run_dir + "/nis.csv");
	if (probe)
	{
		io::CsvTable n(run_dir + "/nis.csv");
		const auto nt = n.column("time_s"), nl = n.column("label"), nu = n.column("updates"),
		           ns = n.column("nis_sum"), nd = n.column("dim_sum");
		while (n.next())
		{
			ev.nis[n.text(nl)].push_back({n.number(nt), static_cast<std::size_t>(n.number(nu)),
			                              static_cast<std::size_t>(n.number(nd)), n.number(ns)});
		}
	}
	return ev;
}

std::optional<Sample> sampleAt(const std::string& run_dir, const std::string& truth_csv,
                               double after_truth_start_s, const std::string& states_file)
{
	const io::Trajectory truth = io::readGroundTruth(truth_csv);
	const double t_unix = truth.front().t_unix + after_truth_start_s;
	io::CsvTable c(run_dir + "/" + states_file);
	const StateColumns k(c);
	while (c.next())
	{
		const double time = c.number(k.t);
		if (time < t_unix) continue;
		const auto tr = io::interpolate(truth, time, kMaxTruthGap_s);
		if (!tr) return std::nullopt;
		return sampleOf(c, k, *tr);
	}
	return std::nullopt;
}
}  // namespace auvnav::eval
