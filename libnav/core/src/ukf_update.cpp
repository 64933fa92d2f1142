// ManifoldUkf::update: the unscented update over the blocks a model reads,
// the affine part in closed form, gating and recovery.
#include <auvnav/so3.h>
#include <auvnav/ukf.h>

#include "covariance_kernels.h"
#include "ukf_detail.h"

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <limits>

namespace auvnav
{
using namespace ukf_detail;

namespace
{
/** r = a ⊟ b for an update's m-vectors: formed here as the model's
 *  structure() describes (differences, wrapped angles: no virtual call and
 *  three Refs per sigma point, which cost more than the arithmetic at
 *  m ≤ 3), or the model's own residual with structure().custom_residual. */
class Residuals
{
 public:
	Residuals(const MeasurementFunction& model, const MeasurementStructure& s, int m)
	    : model_(model), custom_(s.custom_residual), angles_(s.angle_components), m_(m)
	{
	}
	__attribute__((always_inline)) void into(const double* a, const double* b, double* out) const
	{
		if (custom_)
			modelResidual(a, b, out);
		else if (angles_ == 0)
			for (int q = 0; q < m_; ++q) out[q] = a[q] - b[q];
		else
			structuredResidual(angles_, a, b, out, m_);
	}

 private:
	void modelResidual(const double* a, const double* b, double* out) const
	{
		using ConstMapV = Eigen::Map<const Eigen::VectorXd>;
		model_.residual(ConstMapV(a, m_), ConstMapV(b, m_), Eigen::Map<Eigen::VectorXd>(out, m_));
	}

	const MeasurementFunction& model_;
	const bool custom_;
	const uint32_t angles_;
	const int m_;
};

/** Aᵀ ((k − kn) × m): h's slope along tangent coordinates kn..k−1 of x, the
 *  model's own (MeasurementFunction::affineSlopes) or else by a difference at
 *  the sigma points' step γσᵢ (exact for h affine there), zero for
 *  coordinates of blocks h does not read. z0 = h(x); z_scratch and dz are
 *  overwritten. False, with `why`, if h fails or is not finite. */
bool affineSlopes(const MeasurementFunction& model, const Residuals& residuals, const Measurement& meas,
                  const FilterContext& ctx, const NavState& x, const Covariance& P, double gamma, int kn,
                  int k, const Eigen::Ref<const Eigen::VectorXd>& z0, Eigen::Ref<Eigen::VectorXd> z_scratch,
                  Eigen::Ref<Eigen::VectorXd> dz, Eigen::Ref<Eigen::MatrixXd> At, const char*& why)
{
	const int n = static_cast<int>(P.rows());
	At.setZero();
	if (model.affineSlopes(x, meas, ctx, kn, k, At))
	{
		bool finite = true;
		for (Eigen::Index c = 0; c < At.cols(); ++c)
			finite = finite && allFiniteEntries(At.col(c).data(), At.rows());
		if (finite) return true;
		why = "model returned non-finite affine slopes";
		return false;
	}
	At.setZero();  // a model that declined may have written some
	for (int i = kn; i < k; ++i)
	{
		if (!(blockOfCoordinate(i, n) & model.uses())) continue;
		const double root = gamma * std::sqrt(std::max(P(i, i), 0.0));
		const double h = root > 0 ? root : 1.0;
		const bool ok = model.predict(x.boxplusCoordinate(i, h), meas, ctx, z_scratch);
		if (!ok || !allFiniteEntries(z_scratch.data(), z_scratch.size()))
		{
			why = ok ? "model returned a non-finite h" : "model could not evaluate h";
			return false;
		}
		residuals.into(z_scratch.data(), z0.data(), dz.data());
		At.row(i - kn) = dz.transpose() / h;
	}
	return true;
}

/** Variance β ≥ 0 to add along the normal correction dx = K ν so that the
 *  innovation lands on the gate, or a negative value if no β can (the state
 *  cannot explain ν: blame the aid). With u = H dx = S_x S⁻¹ ν, the innovation
 *  covariance becomes S + β u uᵀ, and by Sherman–Morrison its NIS is
 *  q − β a²/(1 + β b) with q = νᵀS⁻¹ν, a = νᵀS⁻¹u, b = uᵀS⁻¹u. Only S⁻¹ is
 *  needed (never S_x⁻¹, which is near singular when the state hardly moves
 *  the measurement), and the added covariance is bounded by the innovation. */
double inflationAlongCorrection(const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>>& llt_S,
                                const Eigen::Ref<const Eigen::VectorXd>& nu,
                                const Eigen::Ref<const Eigen::VectorXd>& Si_nu,
                                const Eigen::Ref<const Eigen::VectorXd>& u, double gate)
{
	const Eigen::VectorXd Si_u = llt_S.solve(u);
	const double q = nu.dot(Si_nu), a = nu.dot(Si_u), b = u.dot(Si_u);
	const double excess = q - gate;  // > 0: the update failed the gate
	const double denom = a * a - excess * b;
	if (!(b > 0) || !(denom > 1e-12 * a * a)) return -1;  // q − a²/b ≥ gate: out of reach
	return excess / denom;
}
}  // namespace

UpdateResult ManifoldUkf::update(const MeasurementFunction& model, const Measurement& meas,
                                 const FilterContext& ctx, Recovery recovery)
{
	UpdateResult res;
	const int m = static_cast<int>(meas.z.size());
	res.dim = m;
	if (m == 0 || meas.R.rows() != m || meas.R.cols() != m)
	{
		res.why = "measurement and noise sizes disagree";
		return res;
	}
	if (!allFiniteEntries(meas.z) || !allFiniteEntries(meas.R))
	{
		res.why = "non-finite measurement or noise";
		return res;
	}
	const int n = n_;
	const int k = tangentPrefix(model.uses(), n);
	if (k == 0)
	{
		res.why = "model declares no state dependence";
		return res;
	}
	// Blocks h is affine in (measurement_function.h): sigma points only along
	// the first kn Cholesky columns (those that move a non-affine block);
	// the pairs along columns kn..k−1 are ±γ A L_j about z₀, taken from P.
	const MeasurementStructure structure = model.structure();
	const uint32_t affine = structure.affine_in & model.uses() & ~static_cast<uint32_t>(kAttitude);
	const int kn = affine ? tangentPrefix(model.uses() & ~affine, n) : k;
	leadingCholeskyColumns(kn);
	const double g = w_.gamma;
	const int count = 2 * kn + 1;
	// Temporaries as Maps into one grow-only buffer (sizes below).
	using MapM = Eigen::Map<Eigen::MatrixXd>;
	using MapV = Eigen::Map<Eigen::VectorXd>;
	const std::size_t scratch_size =
	    static_cast<std::size_t>(m) * (16 + 3 * count + 2 * m + k + 2 * kn + 2 * n + 2 * (k - kn) + kn);
	if (update_scratch_.size() < scratch_size) update_scratch_.resize(scratch_size);
	double* cursor = update_scratch_.data();
	auto takeM = [&](int rows, int cols)
	{
		MapM out(cursor, rows, cols);
		cursor += static_cast<std::ptrdiff_t>(rows) * cols;
		return out;
	};
	auto takeV = [&](int rows)
	{
		MapV out(cursor, rows);
		cursor += rows;
		return out;
	};
	MapM z_sigma = takeM(m, count + 1);  // h at the sigma points; the last column h's scratch
	// Sigma points that move the first k coordinates; the rest evaluate like the centre.
	if (!model.predict(x_, meas, ctx, z_sigma.col(0)))
	{
		res.why = "model could not evaluate h";
		return res;
	}
	// Attitude-heavy columns are evaluated at a shorter step (ukf.h).
	std::array<double, 3> scale{1.0, 1.0, 1.0};
	// Only the blocks h reads are perturbed (its contract, measurement_function.h);
	// the rest of both points holds x's values.
	const uint32_t read_blocks = model.uses();
	if (kn > 0)
	{
		pair_scratch_[0] = x_;
		pair_scratch_[1] = x_;
	}
	for (int j = 0; j < kn; ++j)
	{
		if (j < 3) scale[j] = attitudeTurnScale(g * L_.col(j).head<3>(), ut_.max_attitude_spread_rad);
		const double step = j < 3 ? g * scale[j] : g;
		// (−step)·L_j is −(step·L_j) exactly: the pair is x ⊞ ±step·L_j.
		x_.boxplusPairBlocks(L_.col(j), step, read_blocks, pair_scratch_[0], pair_scratch_[1]);
		for (int s = 0; s < 2; ++s)
			if (!model.predict(pair_scratch_[s], meas, ctx, z_sigma.col(1 + 2 * j + s)))
			{
				res.why = "model could not evaluate h";
				return res;
			}
	}
	if (!allFiniteEntries(z_sigma.data(), static_cast<Eigen::Index>(m) * count))  // columns 0..count−1
	{
		res.why = "model returned a non-finite h";
		return res;
	}
	// Mean in the measurement space, via residuals about the centre (wraps
	// angles): z̄ = z₀ + Σ W_i (z_i ⊟ z₀), the weights summing to one. A
	// scaled pair enters as deviations ±a/s + m from z₀ (no point of its own).
	const double w_center_c = w_.wc0 + 2 * (n - kn) * w_.wi;
	const Residuals residuals(model, structure, m);
	const double* z0 = z_sigma.col(0).data();
	MapV r = takeV(m), z_mean = takeV(m), acc = takeV(m);
	z_mean = z_sigma.col(0);
	acc.setZero();
	// ŷ± of the scaled pairs, about z₀: every update while the heading is
	// unknown (a vehicle without a heading source), so from the arena too.
	MapM D_scaled = takeM(m, 6);
	MapV rm = takeV(m);
	for (int j = 0; j < std::min(kn, 3); ++j)
		if (scale[j] < 1.0)
		{
			residuals.into(z_sigma.col(1 + 2 * j).data(), z0, r.data());
			residuals.into(z_sigma.col(2 + 2 * j).data(), z0, rm.data());
			const double s = scale[j];
			D_scaled.col(2 * j) = 0.5 * (r + rm) + 0.5 * (r - rm) / s;
			D_scaled.col(2 * j + 1) = 0.5 * (r + rm) - 0.5 * (r - rm) / s;
		}
	auto isScaled = [&](int i) { return i >= 1 && i <= 6 && i <= 2 * kn && scale[(i - 1) / 2] < 1.0; };
	for (int i = 1; i < count; ++i)
	{
		if (isScaled(i))
			acc += w_.wi * D_scaled.col(i - 1);
		else
		{
			residuals.into(z_sigma.col(i).data(), z0, r.data());
			for (int q = 0; q < m; ++q) acc[q] += w_.wi * r[q];  // acc += W r, entry by entry
		}
	}
	z_mean += acc;  // centre residual is zero; its weight does not matter
	MapM E = takeM(m, count);
	for (int i = 0; i < count; ++i)
	{
		if (isScaled(i))
			E.col(i) = D_scaled.col(i - 1) - acc;
		else
			residuals.into(z_sigma.col(i).data(), z_mean.data(), E.col(i).data());  // straight into E
	}
	// S = Σ W_i e_i e_iᵀ + R and Pxz = Σ_j W γ L_j (e₊ⱼ − e₋ⱼ)ᵀ, each as one
	// product (not 2k+1 small outer products).
	MapM EW = takeM(m, count);
	EW.col(0) = w_center_c * E.col(0);
	EW.rightCols(count - 1) = w_.wi * E.rightCols(count - 1);
	MapM S = takeM(m, m);
	S = meas.R;
	S.noalias() += EW.lazyProduct(E.transpose());
	MapM D = takeM(m, kn);
	const double wg = w_.wi * g;
	for (int j = 0; j < kn; ++j)  // D_j = W γ (e₊ⱼ − e₋ⱼ), entry by entry (m is small)
		for (int q = 0; q < m; ++q) D(q, j) = wg * (E(q, 1 + 2 * j) - E(q, 2 + 2 * j));
	// Pxz = L_{:,0:kn} Mᵀ (+ the affine pairs' P_{:,kn:k} part below), with M
	// the sigma points' D less, for affine pairs, their share through L_{:,0:kn}.
	MapM M = takeM(m, kn);
	M = D;
	MapM Pxz = takeM(n, m);
	const double c_lin = 2 * w_.wi * g * g;  // 1 up to rounding
	const double* At_data = nullptr;         // Aᵀ below (k − kn × m), for a smoother's B
	if (kn < k)
	{
		// The affine pairs (j ≥ kn): e± = e₀ ± γ A L_{kn:k,j}, so they add
		// 2W γ² A G Aᵀ to S and 2W γ² C Aᵀ to Pxz, with C = Σ_{j≥kn} L_j L_{kn:k,j}ᵀ
		// = P_{:,kn:k} − L_{:,0:kn} L_{kn:k,0:kn}ᵀ and G its rows kn..k−1
		// (C is never formed). A is h's slope along each read coordinate (a
		// difference: exact for an affine h), at the sigma points' own step.
		const int nk = k - kn;
		MapM At = takeM(nk, m);  // Aᵀ: columns contiguous for the dot products
		At_data = At.data();
		if (!affineSlopes(model, residuals, meas, ctx, x_, P_, g, kn, k, z_sigma.col(0), z_sigma.col(count),
		                  takeV(m), At, res.why))
			return res;
		// P_{:,kn:k} Aᵀ as axpys of P's contiguous columns (short dot
		// products per entry cost more in set-up than in arithmetic).
		// Runs of coordinates h reads, up to four of P's columns per pass.
		Pxz.setZero();
		for (int i = 0; i < m; ++i)
		{
			const double* a = At.col(i).data();
			for (int l = 0; l < nk;)
			{
				if (a[l] == 0)
				{
					++l;
					continue;
				}
				int end = l;
				while (end < nk && a[end] != 0) ++end;
				kernels::subtractCombination(Pxz.col(i), P_.middleCols(kn + l, end - l),
				                             (-c_lin) * Eigen::Map<const Eigen::VectorXd>(a + l, end - l));
				l = end;
			}
		}
		// G Aᵀ = P_{kn:k,kn:k} Aᵀ − L_{kn:k,0:kn} (A L_{kn:k,0:kn})ᵀ, for S.
		MapM GAt = takeM(nk, m);
		GAt = Pxz.middleRows(kn, nk);
		if (kn > 0)
		{
			MapM AL = takeM(m, kn);
			AL.noalias() = At.transpose().lazyProduct(L_.block(kn, 0, nk, kn));  // m × kn
			M.noalias() -= c_lin * AL;
			GAt.noalias() -= c_lin * L_.block(kn, 0, nk, kn).lazyProduct(AL.transpose());
		}
		S.noalias() += At.transpose().lazyProduct(GAt);
	}
	else
		Pxz.setZero();
	// n × kn × m, small: a matrix-vector product per measurement coordinate.
	// (kn = 0: h affine in all it reads, no sigma point; M has no storage.)
	if (kn > 0)
		for (int i = 0; i < m; ++i)  // axpys of L's columns (a gemv's set-up costs more at these sizes)
			kernels::subtractCombination(Pxz.col(i), L_.leftCols(kn), -M.row(i).transpose());

	MapV nu = takeV(m);
	residuals.into(meas.z.data(), z_mean.data(), nu.data());
	MapM S_factor = takeM(m, m);  // the LLT's storage (S itself is read again on a recovery)
	S_factor = S;
	Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(S_factor);
	if (llt.info() != Eigen::Success || !allFiniteEntries(nu))
	{
		res.why = "innovation covariance not positive definite";
		return res;
	}
	{
		MapV Si_nu = takeV(m);
		Si_nu = nu;
		llt.solveInPlace(Si_nu);
		res.nis = nu.dot(Si_nu);
	}
	res.innovation = nu;
	const double gate = chiSquareQuantile(m, model.gateProbability());
	if (res.nis > gate)
	{
		if (recovery == Recovery::None)
		{
			res.status = UpdateStatus::Rejected;
			res.why = "chi-square gate";
			return res;
		}
		res.status = UpdateStatus::Recovered;
		bool widened = false;
		if (recovery == Recovery::State)
		{
			// The normal correction dx = Pxz S⁻¹ ν and what it does to z,
			// u = H dx = S_x S⁻¹ ν (S_x = S − R, the state's share of S).
			const Eigen::VectorXd Si_nu = llt.solve(nu);
			const TangentVector dx0 = Pxz * Si_nu;
			const Eigen::VectorXd u = (S - meas.R) * Si_nu;
			const double beta = inflationAlongCorrection(llt, nu, Si_nu, u, gate);
			if (beta > 0 && std::isfinite(beta) && dx0.allFinite())
			{
				// P' = P + β dx dxᵀ; then Pxz' = Pxz + β dx uᵀ, S' = S + β u uᵀ.
				const TangentVector v = std::sqrt(beta) * dx0;  // v vᵀ: exactly symmetric
				P_.noalias() += v * v.transpose();
				Pxz.noalias() += beta * dx0 * u.transpose();
				S.noalias() += beta * u * u.transpose();
				widened = true;
			}
		}
		if (!widened) S *= res.nis / gate;  // the aid blamed: the innovation on the gate boundary
		llt.compute(S);
		if (llt.info() != Eigen::Success)
		{
			res.status = UpdateStatus::Invalid;
			res.why = "innovation covariance not positive definite";
			return res;
		}
	}
	else
		res.status = UpdateStatus::Accepted;
	// With S = L Lᵀ and W = Pxz L⁻ᵀ: dx = K ν = W (L⁻¹ ν) and
	// P −= K S Kᵀ = W Wᵀ, a rank-m downdate (P
	// stays exactly symmetric: no symmetrize pass).
	MapM W = takeM(n, m);
	W = Pxz;
	// W Lᵀ = Pxz column by column (forward substitution as axpys: the
	// blocked triangular solver packs its operands, costly for m ≤ 6).
	const auto& L_S = llt.matrixLLT();  // L in its lower triangle
	kernels::solveRightLowerTransposed(kernels::columns(W.data(), n, m, n), L_S);
	MapV u = takeV(m);
	u = nu;
	llt.matrixL().solveInPlace(u);
	TangentVector dx = TangentVector::Zero(n);
	kernels::subtractCombination(dx, W, -u);
	x_ = x_.boxplus(dx);
	x_.R_nb = so3::normalized(x_.R_nb);
	kernels::downdateSymmetric(P_, W);
	if (observer_)
	{
		// P⁻¹ W = P⁻¹ Pxz L_S⁻ᵀ with Pxz = L_{:,0:kn} Mᵀ + c P_{:,kn:k} Aᵀ
		// (above) and P_{:,0:kn} = L_{:,0:kn} L11ᵀ (L11: L's leading kn × kn
		// block), so P⁻¹ Pxz = [L11⁻ᵀ Mᵀ; c Aᵀ; 0]. That needs only the
		// columns the filter factored anyway: none past kn, and P B = W holds
		// even where P is not positive definite past them.
		// A recovery's widening P += β dx dxᵀ is reported as nothing: to a
		// smoother it is process noise added at this tick (it leaves the
		// cross covariance with past states as it is). With P, Pxz and S
		// widened together, B is the same expression: exactly so for an h
		// linear over the spread (u = H dx then), else to first order.
		// In the update's arena, by the same solve as W (B L_Sᵀ = that), then
		// L11ᵀ B_top = that by back substitution.
		MapM B = takeM(k, m);
		B.topRows(kn) = M.transpose();
		if (kn < k) B.bottomRows(k - kn) = c_lin * Eigen::Map<const Eigen::MatrixXd>(At_data, k - kn, m);
		kernels::solveRightLowerTransposed(kernels::columns(B.data(), k, m, k), L_S);
		kernels::solveLeftLowerTransposed(kernels::columns(B.data(), kn, m, k),
		                                  kernels::columns(L_.data(), kn, kn, L_.outerStride()));
		observer_->onUpdate(B, u, W);
	}
	applySigmaLimits();
	return res;
}

}  // namespace auvnav
