#pragma once
/** @file model_checks.h
 *  GoogleTest checks for authors of measurement-model plugins (header-only).
 *
 *  The checks turn the contract of measurement_model.h into assertions:
 *
 *      auvnav::testing::TestContext tc;              // tangent frame + FilterContext
 *      MyModel model(cfg, "DVL");
 *      for (uint32_t seed = 1; seed <= 20; ++seed)
 *          EXPECT_TRUE(auvnav::testing::IsWellFormed(model, obs, tc.ctx(),
 *                                                    auvnav::testing::RandomNavState(seed)));
 *
 *  Every function returns ::testing::AssertionResult, so a failure names what
 *  is wrong (measurement index, coordinate, values) inside EXPECT_TRUE.
 *  Random numbers come from std::mt19937 seeded by the caller: a failing seed
 *  reproduces exactly.
 *
 *  Link the test with GTest (auvnav_add_gtest does) and auvnav::nav.
 */
#include <auvnav/earth.h>
#include <auvnav/measurement_model.h>
#include <auvnav/so3.h>
#include <auvnav/state.h>
#include <auvnav/ukf.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace auvnav::testing
{
// ---------------------------------------------------------------- state blocks

/** Names of the blocks set in `mask`, e.g. "attitude|velocity". */
inline std::string blockNames(uint32_t mask)
{
	std::string s;
	for (const auto& b : coreStateBlocks())
		if (mask & b.bit) s += (s.empty() ? "" : "|") + std::string(b.name);
	if (mask & kPluginStates) s += (s.empty() ? "" : "|") + std::string("plugin_states");
	return s.empty() ? "none" : s;
}

// ---------------------------------------------------------------- random states

/** Rotation from yaw, pitch, roll [rad] (Z-Y-X, as MRPT's CPose3D): R_nb. */
inline Eigen::Matrix3d rotationYpr(double yaw, double pitch, double roll)
{
	return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
	        Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
	        Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
	    .toRotationMatrix();
}

/** A random tangent vector of `dim` coordinates with independent
 *  N(0, scale²) entries, except the attitude part, whose rotation angle is
 *  kept below `max_angle_rad` (so that ⊞/⊟ stay inside the injectivity
 *  radius of Log). */
inline TangentVector RandomTangent(uint32_t seed, double scale = 1.0, double max_angle_rad = 3.0,
                                   int dim = idx::core_dim)
{
	std::mt19937 rng(seed);
	std::normal_distribution<double> n01(0.0, 1.0);
	TangentVector d(dim);
	for (int i = 0; i < dim; ++i) d[i] = scale * n01(rng);
	const Eigen::Vector3d att = d.segment<3>(idx::att);
	if (att.norm() > max_angle_rad) d.segment<3>(idx::att) = att * (max_angle_rad / att.norm());
	return d;
}

/** A plausible random AUV state for `seed`: roll and pitch within ±30°, any
 *  heading; gyro bias ~1e-4 rad/s, acceleration ~0.2 m/s², gravity 9.78..9.83,
 *  accelerometer bias ~0.01 m/s², velocity ~1 m/s (vertical ~0.3 m/s),
 *  position ~200 m horizontally at 0..100 m depth, currents ~0.3 m/s, ADCP
 *  bias ~0.02 m/s, model parameters ~100 (all 1σ unless a range is given),
 *  and `plugin_states` plugin-owned states ~0.01. */
inline NavState RandomNavState(uint32_t seed, int plugin_states = 0)
{
	std::mt19937 rng(seed * 2654435761u + 12345u);
	std::normal_distribution<double> n01(0.0, 1.0);
	std::uniform_real_distribution<double> u01(0.0, 1.0);
	auto v3 = [&](double s) { return Eigen::Vector3d(s * n01(rng), s * n01(rng), s * n01(rng)); };
	auto v2 = [&](double s) { return Eigen::Vector2d(s * n01(rng), s * n01(rng)); };
	constexpr double kDeg = M_PI / 180;
	NavState x;
	x.R_nb =
	    rotationYpr((360 * u01(rng) - 180) * kDeg, (60 * u01(rng) - 30) * kDeg, (60 * u01(rng) - 30) * kDeg);
	x.b_w = v3(1e-4);
	x.a_n = v3(0.2);
	x.g = 9.78 + 0.05 * u01(rng);
	x.b_a = v3(0.01);
	x.v_n = Eigen::Vector3d(n01(rng), n01(rng), 0.3 * n01(rng));
	x.p_n = Eigen::Vector3d(200 * n01(rng), 200 * n01(rng), 100 * u01(rng));
	x.current_vehicle_ne = v2(0.3);
	x.current_far_ne = v2(0.3);
	x.b_adcp = v2(0.02);
	for (auto* m : {&x.M_sub, &x.Dl_sub, &x.Dq_sub})
		for (int i = 0; i < 6; ++i) (*m)(i / 3, i % 3) = 100 * n01(rng);
	x.extra.resize(plugin_states);
	for (int i = 0; i < plugin_states; ++i) x.extra[i] = 0.01 * n01(rng);
	return x;
}

/** A diagonal, positive-definite covariance for update tests (1σ): attitude
 *  2°, gyro bias 1e-3 rad/s, acceleration 0.1 m/s², gravity 0.01 m/s², accel
 *  bias 0.01 m/s², velocity 0.5 m/s, position 5 m, currents 0.2 m/s, ADCP
 *  bias 0.05 m/s, model parameters 0.2 (relative for the surge/sway entries,
 *  which the state holds as logarithms; absolute for the couplings), and
 *  0.01 for `plugin_states` plugin-owned states. */
inline Covariance TypicalCovariance(int plugin_states = 0)
{
	TangentVector s = TangentVector::Constant(idx::core_dim + plugin_states, 0.01);
	s.segment<3>(idx::att).setConstant(2 * M_PI / 180);
	s.segment<3>(idx::gyro_bias).setConstant(1e-3);
	s.segment<3>(idx::acc).setConstant(0.1);
	s[idx::gravity] = 0.01;
	s.segment<3>(idx::acc_bias).setConstant(0.01);
	s.segment<3>(idx::vel).setConstant(0.5);
	s.segment<3>(idx::pos).setConstant(5.0);
	s.segment<4>(idx::current_vehicle).setConstant(0.2);
	s.segment<2>(idx::adcp_bias).setConstant(0.05);
	s.segment<18>(idx::inertia).setConstant(0.2);
	return s.cwiseAbs2().asDiagonal();
}

// ---------------------------------------------------------------- context

/** Owns a tangent frame and a FilterContext pointing to it (hence neither
 *  copyable nor movable). Default origin: 53.1° N, 8.8° E, sea level; the
 *  Earth rate is filled in, the gyro sample and IMU lever arm are zero. */
class TestContext
{
 public:
	explicit TestContext(const earth::Geodetic& origin = {53.1 * M_PI / 180, 8.8 * M_PI / 180, 0.0})
	    : frame_(origin)
	{
		ctx_.frame = &frame_;
		ctx_.omega_ie_n = frame_.earthRate();
	}
	TestContext(const TestContext&) = delete;
	TestContext& operator=(const TestContext&) = delete;

	FilterContext& ctx() { return ctx_; }
	const FilterContext& ctx() const { return ctx_; }
	const earth::TangentFrame& frame() const { return frame_; }

 private:
	earth::TangentFrame frame_;
	FilterContext ctx_;
};

// ---------------------------------------------------------------- comparisons

/** tangentNames()[i], or "plugin_state_<k>" past the paper's 43. */
inline std::string coordinateName(int i)
{
	return i < idx::core_dim ? tangentNames()[i] : "plugin_state_" + std::to_string(i - idx::core_dim);
}

/** `a ⊟ b` is within `tol` in every tangent coordinate (both states finite).
 *  On failure, names the offending coordinates (tangentNames()). The attitude
 *  part carries rounding of ~1e-16 even for equal states: use
 *  NavStateIdentical for "unchanged". */
inline ::testing::AssertionResult NavStateNear(const NavState& a, const NavState& b, double tol)
{
	if (!a.allFinite() || !b.allFinite())
		return ::testing::AssertionFailure()
		       << "state not finite (first: " << a.allFinite() << ", second: " << b.allFinite() << ")";
	if (a.dim() != b.dim())
		return ::testing::AssertionFailure()
		       << "states of " << a.dim() << " and " << b.dim() << " coordinates";
	const TangentVector d = a.boxminus(b);
	std::ostringstream bad;
	int count = 0;
	for (int i = 0; i < d.size(); ++i)
		if (!(std::abs(d[i]) <= tol))
		{
			if (count++ < 6) bad << " " << coordinateName(i) << "=" << d[i];
		}
	if (count == 0) return ::testing::AssertionSuccess();
	return ::testing::AssertionFailure()
	       << count << " coordinate(s) of a ⊟ b exceed " << tol << ":" << bad.str();
}

/** Bit-for-bit equal states (e.g. "a refused update leaves the state
 *  untouched"); NavStateNear with tol 0 is not enough, as R_a R_bᵀ is not
 *  exactly I in floating point even for R_a = R_b. */
inline ::testing::AssertionResult NavStateIdentical(const NavState& a, const NavState& b)
{
	if (a.dim() != b.dim())
		return ::testing::AssertionFailure()
		       << "states of " << a.dim() << " and " << b.dim() << " coordinates";
	if (a.R_nb == b.R_nb && a.euclidean() == b.euclidean()) return ::testing::AssertionSuccess();
	const TangentVector d = a.euclidean() - b.euclidean();
	std::ostringstream bad;
	if (a.R_nb != b.R_nb) bad << " attitude (|ΔR| = " << (a.R_nb - b.R_nb).cwiseAbs().maxCoeff() << ")";
	for (int i = idx::att + 3; i < d.size(); ++i)
		if (!(d[i] == 0))
			bad << " " << coordinateName(i) << " " << b.euclidean()[i] << " -> " << a.euclidean()[i];
	return ::testing::AssertionFailure() << "states differ:" << bad.str();
}

/** `(x ⊞ δ) ⊟ x == δ` for a random δ (attitude angle < 3 rad, others ~`scale`). */
inline ::testing::AssertionResult BoxplusRoundTrip(const NavState& x, uint32_t seed, double scale = 1.0,
                                                   double tol = 1e-9)
{
	const TangentVector delta = RandomTangent(seed, scale, 3.0, x.dim());
	const NavState y = x.boxplus(delta);
	const TangentVector back = y.boxminus(x);
	const double err = (back - delta).cwiseAbs().maxCoeff();
	if (!(err <= tol * (1 + scale)))
		return ::testing::AssertionFailure()
		       << "(x ⊞ δ) ⊟ x differs from δ by " << err << " (seed " << seed << ")";
	// The rotation must stay orthonormal.
	const double ortho = (y.R_nb * y.R_nb.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
	if (!(ortho <= 1e-12))
		return ::testing::AssertionFailure() << "x ⊞ δ is not a rotation (|RRᵀ − I| = " << ortho << ")";
	return ::testing::AssertionSuccess();
}

// ---------------------------------------------------------------- the model contract

struct WellFormedOptions
{
	uint32_t seed = 1;               //!< random perturbations
	double undeclared_scale = 10.0;  //!< 1σ of the perturbation of undeclared Euclidean blocks
	double tol = 1e-12;              //!< relative tolerance of "unchanged" / "zero"
	bool accept_skip = true;         //!< a Skip from prepare passes (else fails)
};

namespace detail
{
inline bool nearlyEqual(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double tol)
{
	return a.size() == b.size() && ((a - b).cwiseAbs().array() <= tol * (1.0 + a.cwiseAbs().array())).all();
}
inline std::string vec(const Eigen::VectorXd& v)
{
	std::ostringstream o;
	o.precision(12);
	o << "[" << v.transpose() << "]";
	return o.str();
}
}  // namespace detail

/** The measurement-model contract on one observation and one state:
 *  - uses() is a non-empty subset of kAllBlocks; 0 < gateProbability() ≤ 1;
 *  - prepare returns Ok (or Skip, with no measurements, if `accept_skip`);
 *  - every measurement: non-empty finite z; R of matching size, finite,
 *    symmetric and positive definite;
 *  - h(x) succeeds, is finite, has the right size and is deterministic;
 *  - residual(z, z) = 0 and residual(h(x), h(x)) = 0;
 *  - unless structure().custom_residual: residual(a, h(x)) is what
 *    structure() says (differences, wrapped angle components) bit for bit,
 *    for a = z and for a far from h(x): the filter forms it itself, so an
 *    overridden residual() that differs would be ignored;
 *  - h is unchanged when every block NOT declared in uses() is perturbed by a
 *    large random tangent vector (a wrong uses() mask makes the filter skip
 *    sigma points that matter, silently);
 *  - (x ⊞ δ) ⊟ x = δ for a random δ;
 *  - h is affine in the blocks of structure().affine_in, the others held: along a random
 *    δ in those blocks, h(x ⊞ δ) ⊟ h(x) = −(h(x ⊞ −δ) ⊟ h(x)) = ½ (h(x ⊞ 2δ) ⊟ h(x));
 *  - closed-form affineSlopes(), if the model gives them, equal h's unit
 *    differences along every coordinate the filter asks them for.
 *  `prepare` is called once (models may keep per-sensor state in it). */
inline ::testing::AssertionResult IsWellFormed(MeasurementModel& model, const mrpt::obs::CObservation& obs,
                                               const FilterContext& ctx, const NavState& x,
                                               const WellFormedOptions& opt = {})
{
	using ::testing::AssertionFailure;
	const uint32_t mask = model.uses();
	if (mask == 0 || (mask & ~static_cast<uint32_t>(kAllBlocks)) != 0)
		return AssertionFailure() << "uses() = 0x" << std::hex << mask << " is empty or has unknown bits";
	const double gate = model.gateProbability();
	if (!(gate > 0 && gate <= 1))
		return AssertionFailure() << "gateProbability() = " << gate << " not in (0, 1]";
	if (!x.allFinite()) return AssertionFailure() << "test state is not finite";

	std::vector<Measurement> out;
	std::string why;
	const PrepareStatus st = model.prepare(obs, ctx, out, why);
	if (st == PrepareStatus::Invalid) return AssertionFailure() << "prepare returned Invalid: " << why;
	if (st == PrepareStatus::Skip)
	{
		if (!opt.accept_skip) return AssertionFailure() << "prepare returned Skip: " << why;
		if (!out.empty())
			return AssertionFailure() << "prepare returned Skip with " << out.size() << " measurement(s)";
		return ::testing::AssertionSuccess() << "skipped: " << why;
	}

	// Same state with every undeclared block moved far away.
	TangentVector delta = RandomTangent(opt.seed * 7919u + 1u, opt.undeclared_scale, 3.0, x.dim());
	for (const auto& b : coreStateBlocks())
		if (mask & b.bit) delta.segment(b.begin, b.size).setZero();
	if (mask & kPluginStates) delta.tail(x.dim() - idx::core_dim).setZero();
	const NavState x_far = x.boxplus(delta);
	// A step in the declared affine blocks only (the attitude never is one).
	const MeasurementStructure structure = model.structure();
	const uint32_t affine = structure.affine_in & mask & ~static_cast<uint32_t>(kAttitude);
	if ((structure.affine_in & ~static_cast<uint32_t>(kAllBlocks)) != 0)
		return AssertionFailure() << "structure().affine_in = 0x" << std::hex << structure.affine_in
		                          << " has unknown bits";
	TangentVector step = RandomTangent(opt.seed * 104729u + 3u, 1.0, 3.0, x.dim());
	for (const auto& b : coreStateBlocks())
		if (!(affine & b.bit)) step.segment(b.begin, b.size).setZero();
	if (!(affine & kPluginStates)) step.tail(x.dim() - idx::core_dim).setZero();
	const NavState x_plus = x.boxplus(step), x_minus = x.boxplus(-step), x_twice = x.boxplus(2 * step);

	for (std::size_t k = 0; k < out.size(); ++k)
	{
		if (out[k].skipped) continue;  // a part counted but not applied (e.g. an ADCP cell in the seabed)
		const Measurement& m = out[k];
		const auto fail = [&]()
		{ return AssertionFailure() << "measurement " << k << " '" << m.label << "': "; };
		const Eigen::Index dim = m.z.size();
		if (dim == 0) return fail() << "empty z";
		if (!m.z.allFinite()) return fail() << "z not finite: " << detail::vec(m.z);
		if (m.R.rows() != dim || m.R.cols() != dim)
			return fail() << "R is " << m.R.rows() << "x" << m.R.cols() << " for z of size " << dim;
		if (!m.R.allFinite()) return fail() << "R not finite:\n" << m.R;
		const double asym = (m.R - m.R.transpose()).cwiseAbs().maxCoeff();
		if (!(asym <= 1e-12 * (1 + m.R.cwiseAbs().maxCoeff()))) return fail() << "R not symmetric:\n" << m.R;
		const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(m.R, Eigen::EigenvaluesOnly);
		if (!(es.eigenvalues().minCoeff() > 0))
			return fail() << "R not positive definite, eigenvalues " << detail::vec(es.eigenvalues());

		Eigen::VectorXd h(dim), h2(dim), h_far(dim), r(dim);
		h.setConstant(std::nan(""));
		if (!model.predict(x, m, ctx, h)) return fail() << "predict returned false";
		if (!h.allFinite()) return fail() << "h(x) not finite: " << detail::vec(h);
		h2.setConstant(std::nan(""));
		if (!model.predict(x, m, ctx, h2) || h2 != h)
			return fail() << "h is not deterministic: " << detail::vec(h) << " then " << detail::vec(h2);

		r.setConstant(std::nan(""));
		model.residual(m.z, m.z, r);
		if (!(r.cwiseAbs().array() <= opt.tol * (1 + m.z.cwiseAbs().array())).all())
			return fail() << "residual(z, z) = " << detail::vec(r) << ", expected 0";
		r.setConstant(std::nan(""));
		model.residual(h, h, r);
		if (!(r.cwiseAbs().array() <= opt.tol * (1 + h.cwiseAbs().array())).all())
			return fail() << "residual(h, h) = " << detail::vec(r) << ", expected 0";
		if (!structure.custom_residual)
		{
			// The filter then forms the residual itself from structure():
			// residual() must be that bit for bit, also far apart (where a
			// residual that wraps angles differs from a difference).
			const Eigen::VectorXd far_up = h.array() + 4.0, far_down = h.array() - 7.5;
			for (const Eigen::VectorXd* a : {&m.z, &far_up, &far_down})
			{
				r.setConstant(std::nan(""));
				model.residual(*a, h, r);
				Eigen::VectorXd expected(dim);
				structuredResidual(structure.angle_components, a->data(), h.data(), expected.data(),
				                   static_cast<int>(dim));
				for (Eigen::Index i = 0; i < dim; ++i)
					if (!(r[i] == expected[i]))
						return fail() << "residual(a, h) = " << detail::vec(r)
						              << " is not what structure() declares, " << detail::vec(expected)
						              << " (override residual() only with structure().custom_residual)";
			}
		}

		if (mask != kAllBlocks)
		{
			h_far.setConstant(std::nan(""));
			if (!model.predict(x_far, m, ctx, h_far))
				return fail() << "predict failed after perturbing undeclared blocks ("
				              << blockNames(~mask & kAllBlocks) << ")";
			if (!detail::nearlyEqual(h, h_far, opt.tol))
				return fail() << "h changed when undeclared blocks (" << blockNames(~mask & kAllBlocks)
				              << ") were perturbed: " << detail::vec(h) << " -> " << detail::vec(h_far)
				              << "; uses() = " << blockNames(mask);
		}
		if (affine)
		{
			Eigen::VectorXd hp(dim), hm(dim), h2x(dim), rp(dim), rm(dim), r2(dim);
			if (!model.predict(x_plus, m, ctx, hp) || !model.predict(x_minus, m, ctx, hm) ||
			    !model.predict(x_twice, m, ctx, h2x))
				return fail() << "predict failed along the affine blocks (" << blockNames(affine) << ")";
			model.residual(hp, h, rp);
			model.residual(hm, h, rm);
			model.residual(h2x, h, r2);
			const double size = 1 + rp.cwiseAbs().maxCoeff() + h.cwiseAbs().maxCoeff();
			if (!((rp + rm).cwiseAbs().maxCoeff() <= opt.tol * size) ||
			    !((r2 - 2 * rp).cwiseAbs().maxCoeff() <= opt.tol * size))
				return fail() << "h is not affine in the blocks structure().affine_in declares ("
				              << blockNames(affine) << "): steps +d, -d, +2d move h by " << detail::vec(rp)
				              << ", " << detail::vec(rm) << ", " << detail::vec(r2);
			// The filter asks for slopes past the last non-affine block.
			const int from = tangentPrefix(mask & ~affine, x.dim()), to = tangentPrefix(mask, x.dim());
			Eigen::MatrixXd At = Eigen::MatrixXd::Zero(to - from, dim);
			if (from < to && model.affineSlopes(x, m, ctx, from, to, At))
				for (int i = from; i < to; ++i)
				{
					TangentVector e = TangentVector::Zero(x.dim());
					e[i] = 1.0;
					Eigen::VectorXd he(dim), slope(dim);
					if (!model.predict(x.boxplus(e), m, ctx, he))
						return fail() << "predict failed at a unit step along coordinate " << i;
					model.residual(he, h, slope);
					const double size_i = 1 + slope.cwiseAbs().maxCoeff() + h.cwiseAbs().maxCoeff();
					if (!((At.row(i - from).transpose() - slope).cwiseAbs().maxCoeff() <= opt.tol * size_i))
						return fail() << "affineSlopes() along coordinate " << i << " gives "
						              << detail::vec(At.row(i - from).transpose()) << ", h's difference "
						              << detail::vec(slope);
				}
		}
	}
	const auto rt = BoxplusRoundTrip(x, opt.seed);
	if (!rt) return rt;
	return ::testing::AssertionSuccess();
}

// ---------------------------------------------------------------- filter helpers

/** Result of feeding one observation through a model into a filter. */
struct ApplyResult
{
	PrepareStatus status = PrepareStatus::Invalid;
	std::string why;
	std::vector<UpdateResult> updates;  //!< one per measurement, in order
};

/** prepare, then ManifoldUkf::update for every measurement (as the host does,
 *  without the host's recovery logic). */
inline ApplyResult ApplyObservation(ManifoldUkf& ukf, MeasurementModel& model,
                                    const mrpt::obs::CObservation& obs, const FilterContext& ctx)
{
	ApplyResult res;
	std::vector<Measurement> out;
	res.status = model.prepare(obs, ctx, out, res.why);
	if (res.status != PrepareStatus::Ok) return res;
	for (const auto& m : out)
		if (!m.skipped)
			res.updates.push_back(ukf.update(model, m, ctx));  // as the host: skipped parts are counted only
	return res;
}

/** h(x) for a prepared measurement, for hand-computed comparisons; NaN if
 *  predict fails. */
inline Eigen::VectorXd Predict(const MeasurementModel& model, const Measurement& m, const FilterContext& ctx,
                               const NavState& x)
{
	Eigen::VectorXd h(m.z.size());
	if (!model.predict(x, m, ctx, h)) h.setConstant(std::nan(""));
	return h;
}

}  // namespace auvnav::testing
