#include "level_fit.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

namespace auvnav::magcal
{
namespace
{
constexpr double kRadToDeg = 180.0 / M_PI;
using Vec5 = Eigen::Matrix<double, 5, 1>;
using Mat5 = Eigen::Matrix<double, 5, 5>;

std::string num(double v, int precision = 3)
{
	char b[64];
	std::snprintf(b, sizeof b, "%.*f", precision, v);
	return b;
}

/** Rotation from sensor axes to a level frame (roll, then pitch; no yaw). */
Eigen::Matrix3d levelling(const Eigen::Vector3d& down_s)
{
	const double roll = std::atan2(down_s.y(), down_s.z());
	const double pitch = std::atan2(-down_s.x(), std::hypot(down_s.y(), down_s.z()));
	return (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
	        Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
	    .toRotationMatrix();
}

Eigen::Matrix2d sqrtSpd2(const Eigen::Matrix2d& A)
{
	const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(A);
	return es.eigenvectors() * es.eigenvalues().cwiseSqrt().asDiagonal() * es.eigenvectors().transpose();
}

/** The unknowns θ. With a given H: (b_x, b_y, W00, W11, W01); without:
 *  (b_x, b_y, H, W00, W01) and W11 from det W = 1. */
struct Model
{
	Eigen::Vector2d b_ut;
	Eigen::Matrix2d W;
	double H_ut;
};

struct Problem
{
	const std::vector<Eigen::Vector3d>& raw_ut;
	std::vector<Eigen::Matrix3d> L;  //!< levelling rotation per reading
	double b_z_ut;
	double H_given_ut;  //!< 0: det W = 1

	Model unpack(const Vec5& p) const
	{
		Model m;
		m.b_ut = p.head<2>();
		if (H_given_ut > 0)
		{
			m.H_ut = H_given_ut;
			m.W << p[2], p[4], p[4], p[3];
		}
		else
		{
			m.H_ut = p[2];
			m.W << p[3], p[4], p[4], (1 + p[4] * p[4]) / p[3];
		}
		return m;
	}
	Vec5 pack(const Model& m) const
	{
		Vec5 p;
		p.head<2>() = m.b_ut;
		if (H_given_ut > 0)
			p.tail<3>() << m.W(0, 0), m.W(1, 1), m.W(0, 1);
		else
			p.tail<3>() << m.H_ut, m.W(0, 0), m.W(0, 1);
		return p;
	}
	/** Calibrated, levelled field of reading i. */
	Eigen::Vector3d levelled(const Model& m, std::size_t i) const
	{
		const Eigen::Vector3d& x = raw_ut[i];
		Eigen::Vector3d c;
		c.head<2>() = m.W * (x.head<2>() - m.b_ut);
		c.z() = x.z() - b_z_ut;
		return L[i] * c;
	}
	double residual(const Model& m, std::size_t i) const { return levelled(m, i).head<2>().norm() - m.H_ut; }

	/** Sum of squared residuals and, when asked, JᵀJ and Jᵀr (central differences). */
	double cost(const Vec5& p, Mat5* JtJ, Vec5* Jtr) const
	{
		const Model m = unpack(p);
		std::array<Model, 10> shifted;
		Vec5 h;
		for (int k = 0; k < 5 && JtJ; ++k)
		{
			h[k] = 1e-6 * (1 + std::abs(p[k]));
			Vec5 plus = p, minus = p;
			plus[k] += h[k];
			minus[k] -= h[k];
			shifted[static_cast<std::size_t>(2 * k)] = unpack(plus);
			shifted[static_cast<std::size_t>(2 * k + 1)] = unpack(minus);
		}
		if (JtJ) JtJ->setZero();
		if (Jtr) Jtr->setZero();
		double sum = 0;
		for (std::size_t i = 0; i < raw_ut.size(); ++i)
		{
			const double r = residual(m, i);
			sum += r * r;
			if (!JtJ) continue;
			Vec5 j;
			for (int k = 0; k < 5; ++k)
				j[k] = (residual(shifted[static_cast<std::size_t>(2 * k)], i) -
				        residual(shifted[static_cast<std::size_t>(2 * k + 1)], i)) /
				       (2 * h[k]);
			JtJ->noalias() += j * j.transpose();
			*Jtr += j * r;
		}
		return sum;
	}
};

/** Algebraic conic through the levelled readings → centre and shape A
 *  with (p − c)ᵀ A (p − c) = 1; throws when it is not an ellipse. */
void algebraicEllipse(const std::vector<Eigen::Vector2d>& pts, Eigen::Vector2d& c, Eigen::Matrix2d& A)
{
	// Centred and scaled, as in the 3-D fit: raw µT squared swamp the constant term.
	Eigen::Vector2d c0;
	double s0 = 0;
	centreAndScale(pts, c0, s0);
	Eigen::Matrix<double, 6, 6> DtD = Eigen::Matrix<double, 6, 6>::Zero();
	for (const auto& p : pts)
	{
		const Eigen::Vector2d y = (p - c0) / s0;
		Eigen::Matrix<double, 6, 1> row;
		row << y.x() * y.x(), 2 * y.x() * y.y(), y.y() * y.y(), 2 * y.x(), 2 * y.y(), 1.0;
		DtD.noalias() += row * row.transpose();
	}
	const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(DtD);
	const Eigen::Matrix<double, 6, 1> q = es.eigenvectors().col(0);
	Eigen::Matrix2d M;
	M << q[0], q[1], q[1], q[2];
	const Eigen::Vector2d n(q[3], q[4]);
	const std::string why =
	    "the levelled readings do not lie on an ellipse: turn through at least the --min-heading-coverage, "
	    "and check for a disturbance during the segment";
	if (!(M.determinant() > 0)) throw MagCalibrationError(why);
	const Eigen::Vector2d y_c = -M.inverse() * n;
	const double r = y_c.dot(M * y_c) - q[5];
	const Eigen::Matrix2d A_y = M / r;
	if (!(r != 0 && A_y.trace() > 0)) throw MagCalibrationError(why);
	c = c0 + s0 * y_c;
	A = A_y / (s0 * s0);
}

/** 360° minus the largest gap between the azimuths of the calibrated readings. */
double headingCoverageDeg(const Problem& pr, const Model& m)
{
	std::vector<double> az;
	az.reserve(pr.raw_ut.size());
	for (std::size_t i = 0; i < pr.raw_ut.size(); ++i)
	{
		const Eigen::Vector3d h = pr.levelled(m, i);
		az.push_back(std::atan2(h.y(), h.x()) * kRadToDeg);
	}
	std::sort(az.begin(), az.end());
	double gap = 360 - (az.back() - az.front());
	for (std::size_t i = 1; i < az.size(); ++i) gap = std::max(gap, az[i] - az[i - 1]);
	return 360 - gap;
}

/** Levenberg–Marquardt on the geometric residuals; returns the iterations used. */
int refine(const Problem& pr, Vec5& p)
{
	double lambda = 1e-3;
	Mat5 JtJ;
	Vec5 Jtr;
	double cost = pr.cost(p, &JtJ, &Jtr);
	int it = 0;
	for (; it < 100; ++it)
	{
		Mat5 H = JtJ;
		H.diagonal() *= 1 + lambda;
		const Vec5 p_new = p - H.ldlt().solve(Jtr);
		Mat5 JtJ_new;
		Vec5 Jtr_new;
		const Eigen::Matrix2d W_new = pr.unpack(p_new).W;
		const bool spd = W_new(0, 0) > 0 && W_new.determinant() > 0;
		const double cost_new = spd ? pr.cost(p_new, &JtJ_new, &Jtr_new) : cost + 1;
		if (!(cost_new <= cost))
		{
			lambda *= 10;
			if (lambda > 1e8) break;
			continue;
		}
		const bool converged = cost - cost_new <= 1e-12 * cost + 1e-18;
		p = p_new;
		cost = cost_new;
		JtJ = JtJ_new;
		Jtr = Jtr_new;
		lambda = std::max(lambda / 10, 1e-9);
		if (converged) break;
	}
	return it;
}

void checkInputs(const std::vector<Eigen::Vector3d>& raw_ut, const std::vector<Eigen::Vector3d>& down_s,
                 const LevelFitOptions& opt)
{
	const std::size_t need = std::max<std::size_t>(opt.min_samples, 10);
	if (raw_ut.size() < need)
		throw MagCalibrationError("too few readings: " + std::to_string(raw_ut.size()) + " (need at least " +
		                          std::to_string(need) + "; widen --from/--to or check --label)");
	if (!down_s.empty() && down_s.size() != raw_ut.size())
		throw MagCalibrationError("one down direction per reading expected");
	for (const auto& p : raw_ut)
		if (!p.allFinite()) throw MagCalibrationError("non-finite reading in the input");
	for (const auto& d : down_s)
		if (!d.allFinite() || std::abs(d.norm() - 1) > 1e-6)
			throw MagCalibrationError("the accelerometer gives no down direction for some readings");
	if (!(opt.horizontal_field_ut >= 0) || !std::isfinite(opt.hard_iron_z_ut))
		throw MagCalibrationError("horizontal field must be >= 0 and the vertical offset finite");
}
}  // namespace

LevelFitResult fitLevel(const std::vector<Eigen::Vector3d>& raw_ut,
                        const std::vector<Eigen::Vector3d>& down_s, const LevelFitOptions& opt)
{
	checkInputs(raw_ut, down_s, opt);
	LevelFitResult res;
	res.samples = raw_ut.size();
	Problem pr{raw_ut, {}, opt.hard_iron_z_ut, opt.horizontal_field_ut};
	pr.L.reserve(raw_ut.size());
	for (std::size_t i = 0; i < raw_ut.size(); ++i)
	{
		const Eigen::Vector3d d = down_s.empty() ? Eigen::Vector3d::UnitZ() : down_s[i];
		res.max_tilt_deg = std::max(res.max_tilt_deg, std::acos(std::clamp(d.z(), -1.0, 1.0)) * kRadToDeg);
		pr.L.push_back(levelling(d));
	}
	if (res.max_tilt_deg > opt.max_tilt_deg)
		throw MagCalibrationError(
		    "the magnetometer's z axis is up to " + num(res.max_tilt_deg, 1) +
		    " deg from the vertical (allowed " + num(opt.max_tilt_deg, 1) +
		    "): a level-turn fit needs a sensor mounted z down (or up) on a level vehicle");

	// Start: an ellipse through the readings levelled before calibration
	// (b_xy and S₂ ≈ identity inside the levelling: a small-tilt approximation).
	std::vector<Eigen::Vector2d> pts;
	for (std::size_t i = 0; i < raw_ut.size(); ++i)
		pts.push_back((pr.L[i] * (raw_ut[i] - opt.hard_iron_z_ut * Eigen::Vector3d::UnitZ())).head<2>());
	Eigen::Vector2d c;
	Eigen::Matrix2d A;
	algebraicEllipse(pts, c, A);
	const Eigen::Matrix2d Q = sqrtSpd2(A);  // |Q (p − c)| = 1
	Model m0{c, Q, 0};
	m0.H_ut = opt.horizontal_field_ut > 0 ? opt.horizontal_field_ut : 1 / std::sqrt(Q.determinant());
	m0.W = m0.H_ut * Q;
	res.heading_coverage_deg = headingCoverageDeg(pr, m0);
	if (res.heading_coverage_deg < opt.min_heading_coverage_deg)
		throw MagCalibrationError("the turn covers only " + num(res.heading_coverage_deg, 0) +
		                          " deg of heading (need " + num(opt.min_heading_coverage_deg, 0) +
		                          "): turn through a full circle, or choose another --from/--to");

	Vec5 p = pr.pack(m0);
	res.iterations = refine(pr, p);
	const Model m = pr.unpack(p);
	Mat5 JtJ;
	Vec5 Jtr;
	const double cost = pr.cost(p, &JtJ, &Jtr);
	const auto n = static_cast<double>(raw_ut.size());
	double sum_v = 0, sum_v2 = 0;
	for (std::size_t i = 0; i < raw_ut.size(); ++i)
	{
		res.max_residual_ut = std::max(res.max_residual_ut, std::abs(pr.residual(m, i)));
		const double v = pr.levelled(m, i).z();
		sum_v += v;
		sum_v2 += v * v;
	}
	res.vertical_field_ut = sum_v / n;
	res.vertical_field_sd_ut =
	    std::sqrt(std::max(sum_v2 / n - res.vertical_field_ut * res.vertical_field_ut, 0.0));
	res.horizontal_field_ut = m.H_ut;
	res.rms_residual_ut = std::sqrt(cost / n);
	res.rms_residual_deg = res.rms_residual_ut / m.H_ut * kRadToDeg;
	const Mat5 cov = JtJ.ldlt().solve(Mat5::Identity()) * (cost / std::max(n - 5, 1.0));
	res.hard_iron_sigma_ut = cov.diagonal().head<2>().cwiseMax(0).cwiseSqrt();
	res.heading_coverage_deg = headingCoverageDeg(pr, m);
	res.hard_iron_ut << m.b_ut, opt.hard_iron_z_ut;
	res.soft_iron.topLeftCorner<2, 2>() = m.W.inverse();

	const Eigen::Vector2d sv =
	    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(res.soft_iron.topLeftCorner<2, 2>()).eigenvalues();
	if (!res.soft_iron.allFinite() || !res.hard_iron_ut.allFinite() ||
	    !(sv.minCoeff() >= 0.2 && sv.maxCoeff() <= 5))
		throw MagCalibrationError(
		    "the fit gave a soft-iron matrix the magnetometer plugin refuses (eigenvalues " +
		    num(sv.minCoeff()) + " .. " + num(sv.maxCoeff()) +
		    ", allowed 0.2 .. 5): are --field-ut/--inclination-deg right, and was the "
		    "field undisturbed?");
	if (!(res.rms_residual_deg <= opt.max_rms_residual_deg))
		throw MagCalibrationError("the readings scatter by " + num(res.rms_residual_deg, 1) +
		                          " deg of heading (rms) about the fitted ellipse (allowed " +
		                          num(opt.max_rms_residual_deg, 1) +
		                          "): the turn is too small to fit or the field was disturbed");
	if (res.heading_coverage_deg < opt.min_heading_coverage_deg)
		throw MagCalibrationError("the turn covers only " + num(res.heading_coverage_deg, 0) +
		                          " deg of heading after calibration (need " +
		                          num(opt.min_heading_coverage_deg, 0) + ")");
	return res;
}

std::vector<Eigen::Vector3d> downFromAccel(const std::vector<double>& t_mag_s,
                                           const std::vector<TimedAccel>& accel,
                                           const Eigen::Matrix3d& R_b_mag, double window_s)
{
	std::vector<Eigen::Vector3d> down;
	if (accel.empty()) return down;
	std::vector<Eigen::Vector3d> prefix(accel.size() + 1, Eigen::Vector3d::Zero());
	for (std::size_t k = 0; k < accel.size(); ++k) prefix[k + 1] = prefix[k] + accel[k].f_b_mps2;
	const auto before = [](const TimedAccel& a, double t) { return a.t_s < t; };
	down.reserve(t_mag_s.size());
	for (const double t : t_mag_s)
	{
		const auto lo = static_cast<std::size_t>(
		    std::lower_bound(accel.begin(), accel.end(), t - window_s / 2, before) - accel.begin());
		auto hi = static_cast<std::size_t>(
		    std::lower_bound(accel.begin(), accel.end(), t + window_s / 2, before) - accel.begin());
		Eigen::Vector3d f_b;
		if (hi > lo)
			f_b = (prefix[hi] - prefix[lo]) / static_cast<double>(hi - lo);
		else  // no reading in the window: the nearest one
		{
			const std::size_t k =
			    (lo == accel.size() || (lo > 0 && t - accel[lo - 1].t_s < accel[lo].t_s - t)) ? lo - 1 : lo;
			f_b = accel[k].f_b_mps2;
		}
		down.push_back(R_b_mag.transpose() * (-f_b).normalized());  // at rest f = −g
	}
	return down;
}

std::string pluginYamlLevel(const LevelFitResult& r, const std::string& source_comment)
{
	std::ostringstream y;
	y << "# Magnetometer calibration written by auvnav-calibrate-mag --level (a level turn).\n";
	std::istringstream src(source_comment);
	for (std::string line; std::getline(src, line);) y << "# " << line << "\n";
	y << "# " << r.samples << " readings, heading coverage " << num(r.heading_coverage_deg, 0)
	  << " deg, tilt up to " << num(r.max_tilt_deg, 1) << " deg; horizontal fit residual rms "
	  << num(r.rms_residual_ut) << " uT (" << num(r.rms_residual_deg, 2) << " deg), max "
	  << num(r.max_residual_ut) << " uT.\n";
	y << "# Horizontal field " << num(r.horizontal_field_ut) << " uT, vertical " << num(r.vertical_field_ut)
	  << " +- " << num(r.vertical_field_sd_ut) << " uT; hard-iron x/y 1-sigma ["
	  << num(r.hard_iron_sigma_ut[0]) << ", " << num(r.hard_iron_sigma_ut[1]) << "] uT.\n";
	y << "# NOT DETERMINED by a level turn: the vertical offset hard_iron_ut[2] (set to "
	  << num(r.hard_iron_ut[2])
	  << ", --hard-iron-z) and\n# the soft iron's z row and column (identity); "
	     "their error enters the heading through the tilt only.\n";
	y << "# Keys of the magnetometer plugin (plugins/magnetometer/magnetometer.yaml):\n";
	y << "# raw = hard_iron_ut + soft_iron * field, sensor axes.\n\n";
	y << "# Hard-iron offset in the sensor axes [uT].\n";
	y << "hard_iron_ut: [" << num(r.hard_iron_ut[0]) << ", " << num(r.hard_iron_ut[1]) << ", "
	  << num(r.hard_iron_ut[2]) << "]\n\n";
	y << "# Soft-iron matrix (3x3, row-major, symmetric positive definite, dimensionless).\n";
	y << "soft_iron: [";
	for (int i = 0; i < 9; ++i) y << (i ? ", " : "") << num(r.soft_iron(i / 3, i % 3), 6);
	y << "]\n";
	return y.str();
}

}  // namespace auvnav::magcal
