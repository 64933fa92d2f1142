#pragma once
/** @file so3.h
 *  SO(3) exponential and logarithm maps for the filter's attitude.
 *
 *  Convention (used everywhere in auvnav): the attitude R_nb is perturbed on
 *  the LEFT, in the navigation frame:  R ⊞ δ = Exp(δ) · R,  R ⊟ R̂ = Log(R · R̂ᵀ).
 *  So an attitude error vector is a small rotation about navigation-frame
 *  (NED) axes: its third component is the heading error.
 *
 *  Log returns the rotation vector with angle in [0, π]; near π the axis is
 *  recovered from the symmetric part so the map stays accurate there.
 */
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace auvnav::so3
{
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v)
{
	Eigen::Matrix3d S;
	S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
	return S;
}

namespace detail
{
/** Taylor series in x = θ² for |θ| < 0.1 (x < 0.01), where the next term is
 *  below 1e-20 of the sum: sin θ / θ, (1 − cos θ) / θ², and asin(s) / s in
 *  x = s². Cheaper than the library's sin, cos and atan2 (every sigma point
 *  takes an Exp or a Log) and as accurate there. */
constexpr double kSeriesMaxX = 0.01;
inline double sinc(double x)
{
	return 1 + x * (-1.0 / 6 + x * (1.0 / 120 +
	                                x * (-1.0 / 5040 + x * (1.0 / 362880 + x * (-1.0 / 39916800 +
	                                                                            x * (1.0 / 6227020800.0))))));
}
inline double versinOver2(double x)  // (1 − cos θ) / θ²
{
	return 0.5 +
	       x * (-1.0 / 24 +
	            x * (1.0 / 720 + x * (-1.0 / 40320 + x * (1.0 / 3628800 + x * (-1.0 / 479001600 +
	                                                                           x * (1.0 / 87178291200.0))))));
}
inline double asinOverS(double x)  // asin(s) / s, x = s²: Σ C(2n,n) xⁿ / (4ⁿ (2n + 1))
{
	return 1 + x * (1.0 / 6 +
	                x * (3.0 / 40 +
	                     x * (5.0 / 112 +
	                          x * (35.0 / 1152 +
	                               x * (63.0 / 2816 + x * (231.0 / 13312 +
	                                                       x * (143.0 / 10240 + x * (6435.0 / 557056))))))));
}
}  // namespace detail

/** Rotation matrix of the rotation vector `phi` (Rodrigues):
 *  I + a K + b K² with K = skew(φ), a = sin θ / θ, b = (1 − cos θ) / θ², and
 *  K² = φφᵀ − θ² I written out entry by entry (no 3 × 3 product). Each
 *  entry pairs the same symmetric part b φᵢφⱼ with ± a φₖ, so Exp(−φ) is
 *  Exp(φ)ᵀ bit for bit (a sigma-point pair shares one Exp: state.cpp). */
inline Eigen::Matrix3d Exp(const Eigen::Vector3d& phi)
{
	const double x = phi.x(), y = phi.y(), z = phi.z();
	const double theta2 = phi.squaredNorm();
	double a, b;
	if (theta2 < detail::kSeriesMaxX)
	{
		a = detail::sinc(theta2);
		b = detail::versinOver2(theta2);
	}
	else
	{
		const double theta = std::sqrt(theta2);
		a = std::sin(theta) / theta;
		b = (1 - std::cos(theta)) / theta2;
	}
	const double bxy = b * (x * y), bxz = b * (x * z), byz = b * (y * z);
	const double ax = a * x, ay = a * y, az = a * z;
	Eigen::Matrix3d R;
	R << 1 - b * (y * y + z * z), bxy - az, bxz + ay,  //
	    bxy + az, 1 - b * (x * x + z * z), byz - ax,   //
	    bxz - ay, byz + ax, 1 - b * (x * x + y * y);
	return R;
}

/** Rotation vector of `R` (angle in [0, π]). */
inline Eigen::Vector3d Log(const Eigen::Matrix3d& R)
{
	const Eigen::Vector3d w(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));  // 2 sin θ · axis
	const double c = std::clamp(0.5 * (R.trace() - 1.0), -1.0, 1.0);
	// θ < π/2 (c > 0) and sin θ < 0.1: θ / (2 sin θ) from the series in sin²θ.
	const double s2 = 0.25 * w.squaredNorm();
	if (c > 0 && s2 < detail::kSeriesMaxX) return (0.5 * detail::asinOverS(s2)) * w;
	const double s = 0.5 * w.norm();
	const double theta = std::atan2(s, c);
	if (theta < 1e-6) return 0.5 * (1 + theta * theta / 6) * w;  // θ/sinθ ≈ 1 + θ²/6
	if (M_PI - theta > 1e-3) return (theta / (2 * std::sin(theta))) * w;
	// Near π: the symmetric part (R + Rᵀ)/2 = cos θ·I + (1 − cos θ)·a aᵀ gives
	// a aᵀ exactly (not (R + I)/2, which keeps the O(π − θ) antisymmetric part);
	// axis from its largest diagonal, sign from the antisymmetric part.
	const Eigen::Matrix3d B = (0.5 * (R + R.transpose()) - c * Eigen::Matrix3d::Identity()) / (1 - c);
	int k = 0;
	B.diagonal().maxCoeff(&k);
	Eigen::Vector3d axis = B.col(k) / std::sqrt(std::max(B(k, k), 1e-300));
	axis.normalize();
	if (axis.dot(w) < 0) axis = -axis;
	return theta * axis;
}

/** Nearest rotation to a nearly orthonormal matrix (after many products). */
inline Eigen::Matrix3d normalized(const Eigen::Matrix3d& R)
{
	return Eigen::Quaterniond(R).normalized().toRotationMatrix();
}

}  // namespace auvnav::so3
