#include "mag_fit.h"

#include <auvnav/io/rawlog.h>
#include <auvnav/obs/register.h>
#include <mrpt/obs/CObservationIMU.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

namespace auvnav::magcal
{
namespace
{
using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;

std::string num(double v, int precision = 3)
{
	char b[64];
	std::snprintf(b, sizeof b, "%.*f", precision, v);
	return b;
}

/** Symmetric square root of a symmetric positive-definite matrix. */
Eigen::Matrix3d sqrtSpd(const Eigen::Matrix3d& A)
{
	const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(A);
	return es.eigenvectors() * es.eigenvalues().cwiseSqrt().asDiagonal() * es.eigenvectors().transpose();
}

Eigen::Matrix3d symmetricFrom(const Eigen::Ref<const Eigen::Matrix<double, 6, 1>>& w)
{
	Eigen::Matrix3d W;
	W << w[0], w[3], w[4], w[3], w[1], w[5], w[4], w[5], w[2];
	return W;
}

/** Step 1: algebraic quadric fit → centre b and shape A with (x−b)ᵀA(x−b) = 1. */
void algebraicEllipsoid(const std::vector<Eigen::Vector3d>& x, Eigen::Vector3d& b, Eigen::Matrix3d& A)
{
	// Centre and scale the data: the 10 × 10 scatter matrix of raw µT values
	// mixes entries of order 1e8 and 1, which loses the small eigenvalue.
	Eigen::Vector3d c0;
	double s0 = 0;
	centreAndScale(x, c0, s0);
	// Quadric yᵀ M y + 2 nᵀ y + k = 0 with q = (M00, M11, M22, M01, M02, M12, n0, n1, n2, k).
	Eigen::Matrix<double, 10, 10> DtD = Eigen::Matrix<double, 10, 10>::Zero();
	for (const auto& p : x)
	{
		const Eigen::Vector3d y = (p - c0) / s0;
		Eigen::Matrix<double, 10, 1> row;
		row << y[0] * y[0], y[1] * y[1], y[2] * y[2], 2 * y[0] * y[1], 2 * y[0] * y[2], 2 * y[1] * y[2],
		    2 * y[0], 2 * y[1], 2 * y[2], 1.0;
		DtD.noalias() += row * row.transpose();
	}
	const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 10, 10>> es(DtD);
	const Eigen::Matrix<double, 10, 1> q = es.eigenvectors().col(0);  // smallest eigenvalue first
	Eigen::Matrix3d M;
	M << q[0], q[3], q[4], q[3], q[1], q[5], q[4], q[5], q[2];
	const Eigen::Vector3d n(q[6], q[7], q[8]);
	const Eigen::FullPivLU<Eigen::Matrix3d> lu(M);
	if (!lu.isInvertible())
		throw MagCalibrationError("the readings do not lie on an ellipsoid (degenerate quadric)");
	const Eigen::Vector3d y_c = -lu.solve(n);
	const double r = y_c.dot(M * y_c) - q[9];
	const Eigen::Matrix3d A_y = M / r;
	const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> ea(0.5 * (A_y + A_y.transpose()));
	if (!(r != 0 && ea.eigenvalues().minCoeff() > 0))
		throw MagCalibrationError(
		    "the readings do not lie on an ellipsoid (the fitted quadric is not positive definite): rotate "
		    "through "
		    "more orientations, or check for a disturbance during the segment");
	b = c0 + s0 * y_c;
	A = ea.eigenvectors() * ea.eigenvalues().asDiagonal() * ea.eigenvectors().transpose() / (s0 * s0);
}

/** Residuals |W(x−b)| − F and their Jacobian w.r.t. (b, w). */
double residuals(const std::vector<Eigen::Vector3d>& x, const Eigen::Vector3d& b, const Eigen::Matrix3d& W,
                 double F, Mat9* JtJ, Vec9* Jtr, double* max_abs)
{
	double sum = 0, mx = 0;
	if (JtJ) JtJ->setZero();
	if (Jtr) Jtr->setZero();
	for (const auto& p : x)
	{
		const Eigen::Vector3d d = p - b;
		const Eigen::Vector3d c = W * d;
		const double len = c.norm();
		const double r = len - F;
		sum += r * r;
		mx = std::max(mx, std::abs(r));
		if (!JtJ) continue;
		const Eigen::Vector3d u = c / std::max(len, 1e-12);
		Vec9 j;
		j.head<3>() = -(W.transpose() * u);  // ∂r/∂b = −uᵀW (W symmetric)
		j[3] = u[0] * d[0];
		j[4] = u[1] * d[1];
		j[5] = u[2] * d[2];
		j[6] = u[0] * d[1] + u[1] * d[0];
		j[7] = u[0] * d[2] + u[2] * d[0];
		j[8] = u[1] * d[2] + u[2] * d[1];
		JtJ->noalias() += j * j.transpose();
		*Jtr += j * r;
	}
	if (max_abs) *max_abs = mx;
	return sum;
}

/** Of 12 directions spread evenly over the sphere (icosahedron vertices),
 *  those nearest to at least 3 of the calibrated reading directions. */
int directionsCovered(const std::vector<Eigen::Vector3d>& x, const Eigen::Vector3d& b,
                      const Eigen::Matrix3d& W)
{
	const double g = (1 + std::sqrt(5.0)) / 2;
	std::array<Eigen::Vector3d, 12> v;
	int k = 0;
	for (double s1 : {-1.0, 1.0})
		for (double s2 : {-1.0, 1.0})
		{
			v[static_cast<std::size_t>(k++)] = Eigen::Vector3d(0, s1, s2 * g).normalized();
			v[static_cast<std::size_t>(k++)] = Eigen::Vector3d(s1, s2 * g, 0).normalized();
			v[static_cast<std::size_t>(k++)] = Eigen::Vector3d(s2 * g, 0, s1).normalized();
		}
	std::array<int, 12> count{};
	for (const auto& p : x)
	{
		const Eigen::Vector3d u = (W * (p - b)).normalized();
		std::size_t best = 0;
		for (std::size_t i = 1; i < v.size(); ++i)
			if (u.dot(v[i]) > u.dot(v[best])) best = i;
		++count[best];
	}
	return static_cast<int>(std::count_if(count.begin(), count.end(), [](int c) { return c >= 3; }));
}
}  // namespace

FitResult fit(const std::vector<Eigen::Vector3d>& raw_ut, const FitOptions& opt)
{
	FitResult res;
	res.samples = raw_ut.size();
	if (raw_ut.size() < std::max<std::size_t>(opt.min_samples, 10))
		throw MagCalibrationError("too few readings: " + std::to_string(raw_ut.size()) + " (need at least " +
		                          std::to_string(std::max<std::size_t>(opt.min_samples, 10)) +
		                          "; widen --from/--to or check --label)");
	for (const auto& p : raw_ut)
		if (!p.allFinite()) throw MagCalibrationError("non-finite reading in the input");
	if (opt.field_ut < 0 || !std::isfinite(opt.field_ut))
		throw MagCalibrationError("field strength must be > 0");

	// Coverage before fitting: readings from a turn about one axis lie on a
	// circle, whose covariance has one (nearly) zero eigenvalue.
	Eigen::Vector3d mean = Eigen::Vector3d::Zero();
	for (const auto& p : raw_ut) mean += p;
	mean /= static_cast<double>(raw_ut.size());
	Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
	for (const auto& p : raw_ut) C.noalias() += (p - mean) * (p - mean).transpose();
	C /= static_cast<double>(raw_ut.size());
	const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C).eigenvalues();
	res.spread = ev.maxCoeff() > 0 ? std::sqrt(std::max(ev.minCoeff(), 0.0) / ev.maxCoeff()) : 0.0;
	if (!(res.spread >= opt.min_spread))
		throw MagCalibrationError(
		    "the segment does not rotate enough: spread " + num(res.spread) + " < " + num(opt.min_spread) +
		    " (1 = every orientation, 0 = a turn about one axis); rotate the sensor through "
		    "roll and pitch as well as yaw, or choose another --from/--to");

	Eigen::Vector3d b;
	Eigen::Matrix3d A;
	algebraicEllipsoid(raw_ut, b, A);
	// W = S⁻¹ with |W(x−b)| = F: W = F·A^½. Without F, det W = 1 for now.
	const Eigen::Matrix3d A_half = sqrtSpd(A);
	const double F = opt.field_ut > 0 ? opt.field_ut : std::pow(A_half.determinant(), -1.0 / 3.0);
	Eigen::Matrix3d W = F * A_half;

	// Gauss–Newton (Levenberg–Marquardt damping) on the geometric residuals.
	double lambda = 1e-3;
	Mat9 JtJ;
	Vec9 Jtr;
	double cost = residuals(raw_ut, b, W, F, &JtJ, &Jtr, nullptr);
	for (res.iterations = 0; res.iterations < 100; ++res.iterations)
	{
		Mat9 H = JtJ;
		H.diagonal() *= 1 + lambda;
		const Vec9 step = -H.ldlt().solve(Jtr);
		const Eigen::Vector3d b_new = b + step.head<3>();
		Eigen::Matrix<double, 6, 1> w;
		w << W(0, 0), W(1, 1), W(2, 2), W(0, 1), W(0, 2), W(1, 2);
		const Eigen::Matrix3d W_new = symmetricFrom(w + step.tail<6>());
		Mat9 JtJ_new;
		Vec9 Jtr_new;
		const double cost_new = residuals(raw_ut, b_new, W_new, F, &JtJ_new, &Jtr_new, nullptr);
		if (cost_new <= cost)
		{
			const bool converged =
			    cost - cost_new <= 1e-12 * cost + 1e-18 || step.norm() < 1e-10 * (1 + b.norm());
			b = b_new;
			W = W_new;
			cost = cost_new;
			JtJ = JtJ_new;
			Jtr = Jtr_new;
			lambda = std::max(lambda / 10, 1e-9);
			if (converged) break;
		}
		else
		{
			lambda *= 10;
			if (lambda > 1e8) break;
		}
	}
	double max_abs = 0;
	cost = residuals(raw_ut, b, W, F, &JtJ, &Jtr, &max_abs);
	double F_out = F;
	if (opt.field_ut <= 0)
	{
		// No field given: S with determinant 1; the calibrated norm follows.
		const double c = std::pow(W.determinant(), -1.0 / 3.0);
		W *= c;
		F_out = c * F;
		max_abs *= c;
		cost *= c * c;
	}
	const auto n = static_cast<double>(raw_ut.size());
	res.hard_iron_ut = b;
	res.soft_iron = W.inverse();
	res.soft_iron = 0.5 * (res.soft_iron + res.soft_iron.transpose());
	res.field_ut = F_out;
	res.rms_residual_ut = std::sqrt(cost / n);
	res.max_residual_ut = max_abs;
	const double sigma2 = cost / std::max(n - 9, 1.0);
	const Mat9 cov = JtJ.ldlt().solve(Mat9::Identity()) * sigma2;
	res.hard_iron_sigma_ut = cov.diagonal().head<3>().cwiseMax(0).cwiseSqrt();
	res.directions_covered = directionsCovered(raw_ut, b, W);

	const Eigen::Vector3d sv = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(res.soft_iron).eigenvalues();
	if (!res.soft_iron.allFinite() || !b.allFinite() || !(sv.minCoeff() >= 0.2 && sv.maxCoeff() <= 5))
		throw MagCalibrationError(
		    "the fit gave a soft-iron matrix the magnetometer plugin refuses (eigenvalues " +
		    num(sv.minCoeff()) + " .. " + num(sv.maxCoeff()) +
		    ", allowed 0.2 .. 5): is --field-ut in uT, and was the field undisturbed?");
	return res;
}

namespace
{
bool hasAccel(const mrpt::obs::CObservationIMU& imu)
{
	using namespace mrpt::obs;
	return imu.has(IMU_X_ACC) && imu.has(IMU_Y_ACC) && imu.has(IMU_Z_ACC);
}

/** Specific force in the body frame, or NaN when the fields are missing. */
Eigen::Vector3d accelBody(const mrpt::obs::CObservationIMU& imu)
{
	using namespace mrpt::obs;
	if (!hasAccel(imu)) return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
	const Eigen::Vector3d f_s(imu.get(IMU_X_ACC), imu.get(IMU_Y_ACC), imu.get(IMU_Z_ACC));
	return imu.sensorPose.getRotationMatrix().asEigen() * f_s;
}
}  // namespace

Samples readSamples(const std::string& rawlog, const std::string& label, double from_s, double to_s,
                    const std::string& accel_label)
{
	using namespace mrpt::obs;
	// Imported logs hold auvnav's own classes (DVL, pressure...) besides the
	// IMU records; MRPT cannot deserialize a log with an unregistered class.
	obs::registerAllClasses();
	Samples s;
	io::RawlogReader reader(rawlog);
	std::map<std::string, int> labels;
	std::vector<std::pair<double, Eigen::Vector3d>> accel_abs;  // absolute time: t_first_s may come later
	bool first = true;
	while (auto o = reader.next())
	{
		++labels[o->sensorLabel];
		if (!accel_label.empty() && o->sensorLabel == accel_label)
			if (const auto* a = dynamic_cast<const CObservationIMU*>(o.get()))
			{
				const Eigen::Vector3d f_b = accelBody(*a);
				const double t = mrpt::Clock::toDouble(o->timestamp);
				if (f_b.allFinite() && std::isfinite(t)) accel_abs.emplace_back(t, f_b);
			}
		if (o->sensorLabel != label) continue;
		const auto* imu = dynamic_cast<const CObservationIMU*>(o.get());
		if (!imu || !imu->has(IMU_MAG_X) || !imu->has(IMU_MAG_Y) || !imu->has(IMU_MAG_Z))
		{
			++s.unusable;
			continue;
		}
		const Eigen::Vector3d m(imu->get(IMU_MAG_X), imu->get(IMU_MAG_Y), imu->get(IMU_MAG_Z));
		const double t = mrpt::Clock::toDouble(o->timestamp);
		if (!m.allFinite() || !std::isfinite(t))
		{
			++s.unusable;
			continue;
		}
		if (first)
		{
			s.t_first_s = t;
			first = false;
		}
		const double rel = t - s.t_first_s;
		if (rel < from_s || rel > to_s) continue;
		if (s.raw_ut.empty())
		{
			s.t_from_s = rel;
			s.R_b_mag = imu->sensorPose.getRotationMatrix().asEigen();
		}
		s.t_to_s = rel;
		s.raw_ut.push_back(100.0 * m);  // gauss → µT
		s.t_s.push_back(rel);
	}
	for (const auto& [l, count] : labels) s.labels.push_back(l);
	std::stable_sort(accel_abs.begin(), accel_abs.end(),
	                 [](const auto& a, const auto& b) { return a.first < b.first; });
	for (const auto& [t, f_b] : accel_abs) s.accel.push_back({t - s.t_first_s, f_b});
	return s;
}

std::string pluginYaml(const FitResult& r, const std::string& source_comment)
{
	std::ostringstream y;
	y << "# Magnetometer calibration written by auvnav-calibrate-mag.\n";
	std::istringstream src(source_comment);
	for (std::string line; std::getline(src, line);) y << "# " << line << "\n";
	y << "# " << r.samples << " readings; fit residual rms " << num(r.rms_residual_ut) << " uT, max "
	  << num(r.max_residual_ut) << " uT; coverage " << r.directions_covered << "/" << FitResult::kDirections
	  << " directions, spread " << num(r.spread) << ".\n";
	y << "# Calibrated field norm " << num(r.field_ut) << " uT; hard-iron 1-sigma ["
	  << num(r.hard_iron_sigma_ut[0]) << ", " << num(r.hard_iron_sigma_ut[1]) << ", "
	  << num(r.hard_iron_sigma_ut[2]) << "] uT.\n";
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
