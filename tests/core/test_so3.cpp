// Manifold property tests of so3.h and the NavState ⊞/⊟ (in the style of
// manif's common tester): Exp/Log round trips everywhere including at and near
// π, group properties, and the boxplus/boxminus axioms.
#include <auvnav/so3.h>
#include <auvnav/state.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <set>
#include <string>

#include "filter_test_util.h"

using namespace auvnav;

namespace
{
Eigen::Vector3d randomAxis(std::mt19937& rng)
{
	std::normal_distribution<double> nd;
	Eigen::Vector3d a(nd(rng), nd(rng), nd(rng));
	return a.normalized();
}

double orthonormalityError(const Eigen::Matrix3d& R)
{
	return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

/** Log(Exp(v)) == v, Exp(Log(R)) == R, R orthonormal with det 1. */
void expectRoundTrip(const Eigen::Vector3d& v, double tol, const std::string& what)
{
	const Eigen::Matrix3d R = so3::Exp(v);
	EXPECT_LT(orthonormalityError(R), 1e-15 * 8) << what;
	EXPECT_NEAR(R.determinant(), 1.0, 1e-14) << what;
	const Eigen::Vector3d l = so3::Log(R);
	EXPECT_LT((l - v).norm(), tol) << what << ": v = " << v.transpose()
	                               << ", Log(Exp(v)) = " << l.transpose();
	EXPECT_LT((so3::Exp(l) - R).cwiseAbs().maxCoeff(), tol) << what;
}

NavState randomState(std::mt19937& rng, const Eigen::Vector3d& att)
{
	std::normal_distribution<double> nd;
	NavState x = test::makeState(0.3);
	TangentVector e = x.euclidean();
	for (int i = 3; i < idx::core_dim; ++i) e[i] += nd(rng);
	x.setEuclidean(e);
	x.R_nb = so3::Exp(att);
	return x;
}

TangentVector randomDelta(std::mt19937& rng, const Eigen::Vector3d& att)
{
	std::normal_distribution<double> nd;
	TangentVector d(idx::core_dim);
	for (int i = 0; i < idx::core_dim; ++i) d[i] = 3 * nd(rng);
	d.head<3>() = att;
	return d;
}

}  // namespace

TEST(So3, ExpAndLogAtIdentity)
{
	EXPECT_EQ(so3::Exp(Eigen::Vector3d::Zero()), Eigen::Matrix3d::Identity());
	EXPECT_EQ(so3::Log(Eigen::Matrix3d::Identity()), Eigen::Vector3d::Zero());
}

TEST(So3, RoundTripNearIdentityIsRelativelyAccurate)
{
	std::mt19937 rng(1);
	// Both sides of the series switches (Exp: |v| < 1e-8, Log: θ < 1e-6).
	for (double angle :
	     {1e-12, 1e-9, 1e-8 * 0.999, 1e-8 * 1.001, 1e-7, 1e-6 * 0.999, 1e-6, 1e-6 * 1.001, 1e-5})
		for (int k = 0; k < 20; ++k)
		{
			const Eigen::Vector3d v = angle * randomAxis(rng);
			const Eigen::Vector3d l = so3::Log(so3::Exp(v));
			EXPECT_LT((l - v).norm(), 1e-14 * angle) << "angle " << angle;
			// First order: Exp(v) a ≈ a + v × a.
			const Eigen::Vector3d a(0.3, -1.2, 0.7);
			EXPECT_LT((so3::Exp(v) * a - a - v.cross(a)).norm(), angle * angle * a.squaredNorm() + 1e-15)
			    << angle;
		}
}

// Exp and Log switch to Taylor series below θ = 0.1 (so3.h); on both sides
// of the switch they equal the closed forms evaluated in long double.
TEST(So3, SeriesBranchesEqualTheClosedFormsInLongDouble)
{
	std::mt19937 rng(5);
	double worst_exp = 0, worst_log = 0;
	for (double angle : {1e-9, 1e-4, 0.01, 0.05, 0.0999, 0.1001, 0.2, 1.0, 1.6})
		for (int k = 0; k < 50; ++k)
		{
			const Eigen::Vector3d v = angle * randomAxis(rng);
			// Rodrigues in long double.
			const long double th = std::sqrt(static_cast<long double>(v.squaredNorm()));
			const long double a = std::sin(th) / th, b = (1 - std::cos(th)) / (th * th);
			Eigen::Matrix<long double, 3, 3> K;
			K << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
			const Eigen::Matrix<long double, 3, 3> R_ld =
			    Eigen::Matrix<long double, 3, 3>::Identity() + a * K + b * K * K;
			const Eigen::Matrix3d R = so3::Exp(v);
			worst_exp = std::max(worst_exp,
			                     static_cast<double>((R.cast<long double>() - R_ld).cwiseAbs().maxCoeff()));
			// Log of that rotation (rounded to double) against θ / (2 sin θ) w in long double.
			const Eigen::Matrix<long double, 3, 3> Rd = R.cast<long double>();
			const Eigen::Matrix<long double, 3, 1> w(Rd(2, 1) - Rd(1, 2), Rd(0, 2) - Rd(2, 0),
			                                         Rd(1, 0) - Rd(0, 1));
			const long double s = 0.5L * w.norm(), c = 0.5L * (Rd.trace() - 1);
			const long double t = std::atan2(s, c);
			const Eigen::Matrix<long double, 3, 1> l_ld = (t / (2 * s)) * w;
			worst_log = std::max(
			    worst_log,
			    static_cast<double>(((so3::Log(R).cast<long double>() - l_ld).norm() / l_ld.norm())));
		}
	std::printf("Exp: worst entry difference %.2e; Log: worst relative difference %.2e\n", worst_exp,
	            worst_log);
	EXPECT_LT(worst_exp, 4e-16);
	EXPECT_LT(worst_log, 4e-16);
}

TEST(So3, RoundTripRandom)
{
	std::mt19937 rng(2);
	std::uniform_real_distribution<double> ang(0, M_PI - 1e-3);
	for (int k = 0; k < 2000; ++k) expectRoundTrip(ang(rng) * randomAxis(rng), 1e-12, "random");
}

TEST(So3, RoundTripNearPi)
{
	std::mt19937 rng(3);
	// Includes both sides of Log's switch to the near-π branch at π − 1e-3.
	for (double eps : {1e-1, 1e-2, 1.001e-3, 1e-3, 0.999e-3, 5e-4, 1e-4, 1e-6, 1e-9, 1e-12})
		for (int k = 0; k < 50; ++k)
			expectRoundTrip((M_PI - eps) * randomAxis(rng), 1e-12, "pi - " + std::to_string(eps));
}

TEST(So3, ExactlyPiGivesPlusOrMinusTheVector)
{
	std::mt19937 rng(4);
	std::vector<Eigen::Vector3d> axes = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
	                                     Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 1, 0).normalized(),
	                                     Eigen::Vector3d(-1, 1, 1).normalized()};
	for (int k = 0; k < 100; ++k) axes.push_back(randomAxis(rng));
	for (const auto& a : axes)
	{
		const Eigen::Vector3d v = M_PI * a;
		const Eigen::Matrix3d R = so3::Exp(v);
		const Eigen::Vector3d l = so3::Log(R);
		EXPECT_NEAR(l.norm(), M_PI, 1e-12);
		EXPECT_LT(std::min((l - v).norm(), (l + v).norm()), 1e-12) << a.transpose();
		EXPECT_LT((so3::Exp(l) - R).cwiseAbs().maxCoeff(), 1e-12) << a.transpose();
	}
}

TEST(So3, BeyondPiWrapsToTheShorterRotation)
{
	std::mt19937 rng(5);
	for (double angle : {M_PI + 1e-6, M_PI + 1e-3, 4.0, 2 * M_PI - 0.1})
		for (int k = 0; k < 20; ++k)
		{
			const Eigen::Vector3d a = randomAxis(rng);
			const Eigen::Vector3d l = so3::Log(so3::Exp(angle * a));
			EXPECT_LT((l - (angle - 2 * M_PI) * a).norm(), 1e-12) << angle;
		}
}

TEST(So3, GroupProperties)
{
	std::mt19937 rng(6);
	std::uniform_real_distribution<double> ang(0, 3.0);
	for (int k = 0; k < 200; ++k)
	{
		const Eigen::Vector3d v = ang(rng) * randomAxis(rng);
		const Eigen::Matrix3d R = so3::Exp(v);
		// Inverse, one-parameter subgroup, adjoint.
		EXPECT_LT((so3::Exp(-v) - R.transpose()).cwiseAbs().maxCoeff(), 1e-14);
		EXPECT_LT((so3::Exp(0.3 * v) * so3::Exp(0.7 * v) - R).cwiseAbs().maxCoeff(), 1e-14);
		EXPECT_LT((so3::Log(R.transpose()) + v).norm(), 1e-12);
		const Eigen::Matrix3d Q = so3::Exp(ang(rng) * randomAxis(rng));
		EXPECT_LT((so3::Exp(Q * v) - Q * R * Q.transpose()).cwiseAbs().maxCoeff(), 1e-14);
		// (To rounding: a fused multiply-add may round the two differently.)
		EXPECT_LT((so3::skew(v) * Eigen::Vector3d(1, 2, 3) - v.cross(Eigen::Vector3d(1, 2, 3))).norm(),
		          1e-15 * (1 + 4 * v.norm()));
	}
	// Convention: a positive third component is a heading (yaw) turn N → E.
	const Eigen::Matrix3d Rz = so3::Exp(Eigen::Vector3d(0, 0, 0.5));
	EXPECT_NEAR(Rz(1, 0), std::sin(0.5), 1e-15);
	EXPECT_NEAR(Rz(0, 0), std::cos(0.5), 1e-15);
}

TEST(So3, NormalizedRepairsDrift)
{
	const Eigen::Matrix3d R = so3::Exp(Eigen::Vector3d(0.2, -1.0, 2.5));
	Eigen::Matrix3d D = R;
	D(0, 1) += 1e-7;
	D(2, 2) -= 1e-7;
	const Eigen::Matrix3d N = so3::normalized(D);
	EXPECT_LT(orthonormalityError(N), 1e-15 * 4);
	EXPECT_LT((N - R).cwiseAbs().maxCoeff(), 1e-6);
}

// ---------------------------------------------------------------- NavState

namespace
{
/** Equal to within four units in the last place of the larger magnitude
 *  (1 for values below 1): what two evaluations of the same sum may differ
 *  by when one fuses a multiply and an add and the other does not. */
bool sameToRounding(double a, double b)
{
	return std::abs(a - b) <=
	       4 * std::numeric_limits<double>::epsilon() * std::max({1.0, std::abs(a), std::abs(b)});
}
bool sameToRounding(const TangentVector& a, const TangentVector& b)
{
	if (a.size() != b.size()) return false;
	for (Eigen::Index i = 0; i < a.size(); ++i)
		if (!sameToRounding(a[i], b[i])) return false;
	return true;
}
}  // namespace

TEST(NavStateManifold, BoxplusZeroIsIdentity)
{
	std::mt19937 rng(7);
	for (int k = 0; k < 50; ++k)
	{
		const NavState x = randomState(rng, 3.0 * randomAxis(rng));
		const NavState y = x.boxplus(TangentVector::Zero(idx::core_dim));
		EXPECT_EQ(y.R_nb, x.R_nb);
		EXPECT_EQ(y.euclidean(), x.euclidean());
		// R Rᵀ is I up to rounding, which the turned members (velocity,
		// acceleration, currents) carry in proportion to their size.
		const double scale = 1.0 + x.euclidean().cwiseAbs().maxCoeff();
		EXPECT_LT(x.boxminus(x).cwiseAbs().maxCoeff(), 1e-15 * scale);
	}
}

TEST(NavStateManifold, BoxplusCoordinateIsBoxplusOfThatVector)
{
	std::mt19937 rng(9);
	for (int k = 0; k < 20; ++k)
	{
		const NavState x = randomState(rng, 3.0 * randomAxis(rng));
		for (int i = 0; i < idx::core_dim; ++i)
		{
			const double h = 0.1 + 0.01 * i;
			TangentVector d = TangentVector::Zero(idx::core_dim);
			d[i] = h;
			const NavState a = x.boxplusCoordinate(i, h), b = x.boxplus(d);
			// The same members to rounding: the general form adds zeros, and
			// the compiler may fuse a product and a sum in one form and not
			// the other (as GCC does on aarch64).
			EXPECT_LT((a.R_nb - b.R_nb).cwiseAbs().maxCoeff(), 4e-16) << i;
			EXPECT_TRUE(sameToRounding(a.euclidean(), b.euclidean())) << i;
		}
	}
}

TEST(So3, ExpOfTheOppositeVectorIsTheTransposeBitForBit)
{
	// What boxplusPair relies on: one Exp serves both points of a sigma pair.
	// Angles across the series branch (θ < 0.1) and the closed form.
	std::mt19937 rng(13);
	std::uniform_real_distribution<double> log_angle(-9.0, std::log(3.1));
	for (int k = 0; k < 20000; ++k)
	{
		const Eigen::Vector3d phi = std::exp(log_angle(rng)) * randomAxis(rng);
		const Eigen::Matrix3d plus = so3::Exp(phi), minus = so3::Exp(-phi);
		ASSERT_TRUE((minus.array() == plus.transpose().array()).all()) << "phi = " << phi.transpose();
		EXPECT_LT(orthonormalityError(plus),
		          4e-15);  // the product form reached 1.7e-15 here, this one 1.2e-15
	}
}

TEST(NavStateManifold, BoxplusPairIsTwoBoxplusCallsBitForBit)
{
	std::mt19937 rng(17);
	std::normal_distribution<double> nd;
	NavState plus, minus;
	for (int k = 0; k < 200; ++k)
	{
		NavState x = randomState(rng, 3.0 * randomAxis(rng));
		x.extra.resize(k % 3);  // plugin states too
		for (int i = 0; i < x.extra.size(); ++i) x.extra[i] = nd(rng);
		TangentVector d(x.dim());
		for (int i = 0; i < d.size(); ++i) d[i] = (k % 2 ? 0.01 : 0.4) * nd(rng);
		if (k % 4 == 0) d.head<3>().setZero();  // the branch without a turn
		x.boxplusPair(d, plus, minus);
		const NavState a = x.boxplus(d), b = x.boxplus(-d);
		EXPECT_EQ(plus.R_nb, a.R_nb) << k;
		EXPECT_EQ(plus.euclidean(), a.euclidean()) << k;
		EXPECT_EQ(minus.R_nb, b.R_nb) << k;
		EXPECT_EQ(minus.euclidean(), b.euclidean()) << k;
	}
	EXPECT_THROW(NavState().boxplusPair(TangentVector::Zero(idx::core_dim + 1), plus, minus),
	             std::invalid_argument);
	EXPECT_THROW(plus.boxplusPair(TangentVector::Zero(idx::core_dim), plus, minus), std::invalid_argument);
	EXPECT_THROW(plus.boxplusPair(TangentVector::Zero(idx::core_dim), minus, minus), std::invalid_argument);
}

TEST(NavStateManifold, BoxplusPairBlocksOfAStepWritesTheAskedBlocksAndNothingElse)
{
	std::mt19937 rng(23);
	std::normal_distribution<double> nd;
	std::uniform_int_distribution<uint32_t> masks(0, kAllBlocks);
	NavState full_plus, full_minus;
	for (int k = 0; k < 300; ++k)
	{
		NavState x = randomState(rng, 3.0 * randomAxis(rng));
		x.extra.resize(k % 3);
		for (int i = 0; i < x.extra.size(); ++i) x.extra[i] = nd(rng);
		TangentVector d(x.dim());
		for (int i = 0; i < d.size(); ++i) d[i] = (k % 2 ? 0.01 : 0.4) * nd(rng);
		if (k % 4 == 0) d.head<3>().setZero();  // the branch without a turn
		const uint32_t blocks = k < 2 ? (k ? kAllBlocks : 0u) : masks(rng);
		// Both points start as another state: what is not asked for must stay.
		NavState before = randomState(rng, randomAxis(rng));
		before.extra.resize(x.extra.size());
		for (int i = 0; i < before.extra.size(); ++i) before.extra[i] = nd(rng);
		NavState plus = before, minus = before;
		// δ = step·d as the filter steps along a Cholesky column: the same
		// bits as the pair of the product formed first.
		const double step = k % 3 == 0 ? 1.0 : 1.7320508075688772 * (1 + 0.1 * nd(rng));
		x.boxplusPairBlocks(d, step, blocks, plus, minus);
		const TangentVector delta = step * d;
		x.boxplusPair(delta, full_plus, full_minus);
		// The asked blocks as the full pair gives them, to rounding (a
		// product and a sum may be fused in one and not the other); the rest
		// untouched, bit for bit.
		EXPECT_LT((plus.R_nb - full_plus.R_nb).cwiseAbs().maxCoeff(), 4e-16) << k;  // the attitude always
		EXPECT_LT((minus.R_nb - full_minus.R_nb).cwiseAbs().maxCoeff(), 4e-16) << k;
		const TangentVector e_plus = plus.euclidean(), e_minus = minus.euclidean(),
		                    e_before = before.euclidean(), e_full_plus = full_plus.euclidean(),
		                    e_full_minus = full_minus.euclidean();
		int asked = 0, kept = 0;
		for (int i = idx::gyro_bias; i < x.dim(); ++i)
			if (blocks & blockOfCoordinate(i, x.dim()))
			{
				EXPECT_TRUE(sameToRounding(e_plus[i], e_full_plus[i])) << k << " coordinate " << i;
				EXPECT_TRUE(sameToRounding(e_minus[i], e_full_minus[i])) << k << " coordinate " << i;
				++asked;
			}
			else
			{
				EXPECT_EQ(e_plus[i], e_before[i]) << k << " coordinate " << i;
				EXPECT_EQ(e_minus[i], e_before[i]) << k << " coordinate " << i;
				++kept;
			}
		EXPECT_EQ(asked + kept, x.dim() - 3);
		if (k == 0)
		{
			EXPECT_EQ(asked, 0);
		}
		if (k == 1)
		{
			EXPECT_EQ(kept, 0);
		}
	}
}

TEST(NavStateManifold, BoxminusHeadIsTheHeadOfBoxminus)
{
	std::mt19937 rng(10);
	for (int k = 0; k < 20; ++k)
	{
		const NavState x = randomState(rng, 3.0 * randomAxis(rng)),
		               y = randomState(rng, 2.0 * randomAxis(rng));
		const TangentVector d = x.boxminus(y);
		// Bit for bit: the prediction's mean iteration uses the head alone.
		EXPECT_EQ(x.boxminusHead(y), d.head<idx::adcp_bias>()) << k;
		EXPECT_GT(d.head<idx::adcp_bias>().cwiseAbs().minCoeff(), 0.0) << k;  // every head entry moved
	}
}

TEST(NavStateManifold, BoxplusThenBoxminusRecoversDelta)
{
	std::mt19937 rng(8);
	std::uniform_real_distribution<double> ang(0, M_PI - 1e-3);
	for (double att_norm : {0.0, 1e-9, 1e-6, 0.5, 3.0, M_PI - 1e-3, M_PI - 1e-6, -1.0})
		for (int k = 0; k < 50; ++k)
		{
			const double a = att_norm < 0 ? ang(rng) : att_norm;
			const NavState x = randomState(rng, (M_PI - 1e-4) * randomAxis(rng));  // base attitude near π too
			const TangentVector d = randomDelta(rng, a * randomAxis(rng));
			const TangentVector back = x.boxplus(d).boxminus(x);
			EXPECT_LT((back - d).head<3>().norm(), 1e-12) << "|δ_att| = " << a;
			// Velocity and acceleration are rotated and back (|v| up to ~10): 1e-11.
			EXPECT_LT((back - d).tail<40>().cwiseAbs().maxCoeff(), 1e-11);
		}
}

TEST(NavStateManifold, BoxplusOfBoxminusReachesTheOtherState)
{
	std::mt19937 rng(9);
	for (double rel : {0.1, 2.0, M_PI - 1e-3, M_PI - 1e-6})
		for (int k = 0; k < 50; ++k)
		{
			const NavState x = randomState(rng, 2.5 * randomAxis(rng));
			NavState y = randomState(rng, Eigen::Vector3d::Zero());
			y.R_nb = so3::Exp(rel * randomAxis(rng)) * x.R_nb;  // y at angle `rel` from x
			const NavState z = x.boxplus(y.boxminus(x));
			EXPECT_LT((z.R_nb - y.R_nb).cwiseAbs().maxCoeff(), 1e-12) << rel;
			// 1e-11: velocity, acceleration and the accelerometer bias are turned and back.
			EXPECT_LT((z.euclidean() - y.euclidean()).cwiseAbs().maxCoeff(), 1e-11);
			EXPECT_NEAR(y.boxminus(x).head<3>().norm(), rel, 1e-12);
		}
}

TEST(NavStateManifold, AttitudeErrorIsALeftPerturbationInTheNavigationFrame)
{
	NavState x = test::makeState(0.7);
	TangentVector d = TangentVector::Zero(idx::core_dim);
	d[idx::att + 2] = 0.1;  // heading error
	const NavState y = x.boxplus(d);
	EXPECT_LT((y.R_nb - so3::Exp(Eigen::Vector3d(0, 0, 0.1)) * x.R_nb).cwiseAbs().maxCoeff(), 1e-15);
	const double yaw_x = std::atan2(x.R_nb(1, 0), x.R_nb(0, 0)),
	             yaw_y = std::atan2(y.R_nb(1, 0), y.R_nb(0, 0));
	EXPECT_NEAR(yaw_y - yaw_x, 0.1, 1e-12);
}

TEST(NavStateManifold, EuclideanRoundTripAndLayout)
{
	const NavState x = test::makeState(0.2);
	const TangentVector e = x.euclidean();
	EXPECT_EQ(e.head<3>(), Eigen::Vector3d::Zero());
	NavState y;
	y.setEuclidean(e);
	EXPECT_EQ(y.euclidean(), e);
	EXPECT_EQ(e[idx::damping_quad + 5], x.Dq_sub(1, 2));  // row-major 2x3 blocks
	EXPECT_EQ(e[idx::inertia + 1], x.M_sub(0, 1));
	EXPECT_EQ(e[idx::damping_lin + 3], x.Dl_sub(1, 0));

	EXPECT_EQ(tangentPrefix(0), 0);
	EXPECT_EQ(tangentPrefix(kAttitude), 3);
	EXPECT_EQ(tangentPrefix(kAttitude | kGyroBias), 6);
	EXPECT_EQ(tangentPrefix(kGravity), 10);
	EXPECT_EQ(tangentPrefix(kAttitude | kVelocity), 16);
	EXPECT_EQ(tangentPrefix(kPosition), 19);
	EXPECT_EQ(tangentPrefix(kAdcpBias), 25);
	EXPECT_EQ(tangentPrefix(kDampingQuadratic), 43);
	EXPECT_EQ(tangentPrefix(kAllBlocks), 43);

	const auto& names = tangentNames();
	ASSERT_EQ(names.size(), std::size_t(idx::core_dim));
	EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
	EXPECT_EQ(names[idx::att + 2], "att_d");
	EXPECT_EQ(names[idx::gravity], "gravity");
	EXPECT_EQ(names[idx::core_dim - 1], "Dq_ypsi");

	// The stored values differ from the tangent coordinates only in the
	// accelerometer bias's axes.
	const auto& stored = storedNames();
	ASSERT_EQ(stored.size(), names.size());
	for (int i = 0; i < idx::core_dim; ++i)
	{
		if (i < idx::acc_bias || i >= idx::acc_bias + 3)
		{
			EXPECT_EQ(stored[i], names[i]) << i;
		}
	}
	EXPECT_EQ(names[idx::acc_bias], "acc_bias_n");
	EXPECT_EQ(stored[idx::acc_bias], "acc_bias_x");
	EXPECT_EQ(stored[idx::acc_bias + 2], "acc_bias_z");
}

TEST(NavStateManifold, AccelerometerBiasIsPerturbedInNedAxes)
{
	// Body yawed 90°: x forward points east, y right points south, z down.
	NavState x = test::makeState(0.3);
	x.R_nb = so3::Exp(Eigen::Vector3d(0, 0, M_PI / 2));
	TangentVector d = TangentVector::Zero(idx::core_dim);
	d[idx::acc_bias + 1] = 1e-3;  // east
	const NavState y = x.boxplus(d);
	EXPECT_NEAR(y.b_a.x() - x.b_a.x(), 1e-3, 1e-15);  // along body x
	EXPECT_NEAR(y.b_a.y() - x.b_a.y(), 0, 1e-15);
	EXPECT_NEAR(y.b_a.z() - x.b_a.z(), 0, 1e-15);
	EXPECT_NEAR(y.boxminus(x)[idx::acc_bias + 1], 1e-3, 1e-15);
	// A heading change alone leaves the bias (a body-fixed vector) as it is.
	TangentVector h = TangentVector::Zero(idx::core_dim);
	h[idx::att + 2] = 0.5;
	EXPECT_EQ(x.boxplus(h).b_a, x.b_a);
}
