#pragma once
/** @file measurement_function.h
 *  What the filter needs of a measurement: the function h(x) of the state,
 *  the blocks it reads, the residual and the gate. The UKF (ukf.h) takes
 *  this interface and nothing else, so the filter core builds without MRPT;
 *  the plugin interface (measurement_model.h) adds, above it, turning an
 *  MRPT observation into measurements.
 *
 *  Contract (checked by auvnav/testing/model_checks.h and by the host):
 *  - `uses()` lists every state block h reads. The filter evaluates h only on
 *    sigma points that move those blocks; reading an undeclared block gives
 *    wrong results (the checks perturb undeclared blocks to catch it).
 *  - `predict` is h(x): a pure function of its arguments, no shared mutable
 *    state, no allocation; z, R and h(x) are finite.
 *  - residual(z, z) = 0 and residual is the boxminus of the measurement space
 *    (wrap angles there).
 *  - No exception may leave an implementation (every method is noexcept).
 */
#include <auvnav/angles.h>
#include <auvnav/earth.h>
#include <auvnav/state.h>

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <new>
#include <string>
#include <type_traits>

namespace auvnav
{
/** What the filter knows besides the state when a measurement arrives. */
struct FilterContext
{
	double t_s = 0;  //!< filter time [s, Unix epoch]
	//! When the measurement was taken [s, Unix epoch] (measurementTime()).
	//! The navigator applies it at t_s ≤ t_measurement_s, the last IMU sample
	//! before it, re-filtering if it arrived late (filter_history.h).
	double t_measurement_s = 0;
	Eigen::Vector3d omega_ib_b = Eigen::Vector3d::Zero();      //!< latest raw gyro sample [rad/s], IMU axes
	Eigen::Vector3d omega_ie_n = Eigen::Vector3d::Zero();      //!< Earth rate in the navigation frame
	Eigen::Vector3d imu_position_b = Eigen::Vector3d::Zero();  //!< IMU lever arm in the body frame [m]
	const earth::TangentFrame* frame = nullptr;  //!< navigation frame (origin), never null in updates
	//! Body angular acceleration [rad/s²] from the low-pass filtered derivative
	//! of the gyro (the state has no angular acceleration).
	Eigen::Vector3d alpha_b = Eigen::Vector3d::Zero();
	//! How long alpha_b lags the body's angular acceleration [s]: the
	//! low-pass's time constant plus half the IMU period of the derivative.
	//! A model that sets alpha_b against a history of its own inputs (a
	//! thrust response) compares it with those inputs this much earlier.
	double alpha_delay_s = 0;
	//! The filter's current mean (for decisions in `prepare`, e.g. near the
	//! surface); never use it inside h, which must depend on its argument only.
	const NavState* mean = nullptr;
	//! Distance below the vehicle [m] that NavState::current_far_ne refers to
	//! (the navigator's ProcessModel::current_far_distance_m); 0 = not fixed by
	//! the navigator (a current-profile model then uses its own range).
	double current_far_distance_m = 0;
	//! The filter's covariance (tangent order, state.h), for decisions in
	//! `prepare` such as data association gates; never use it inside h.
	const Covariance* covariance = nullptr;
};

/** Typed, plugin-private data that travels with one Measurement from
 *  `prepare` to `predict` (a lever arm, a beam direction, a landmark).
 *
 *  Contract: fixed storage inside the Measurement (kCapacity bytes, aligned
 *  for double and Eigen's fixed-size types): no heap allocation, copied with
 *  the Measurement. T must be trivially copyable, fit, and be no more aligned
 *  than the storage (static_assert). The plugin writes it in `prepare` with
 *  `m.setPayload(T{...})` (or `m.payload<T>() = ...`) and reads it in
 *  `predict` with `m.payload<T>()`; reading a T that was not written gives
 *  the bytes of a zero-initialised or previously written payload, so a
 *  plugin uses one T per measurement kind (the tag can tell kinds apart). */
class MeasurementPayload
{
 public:
	static constexpr std::size_t kCapacity = 128;  //!< bytes: 16 doubles
	static constexpr std::size_t kAlignment = 16;

	template <class T>
	static constexpr void check()
	{
		static_assert(std::is_trivially_copyable_v<T>, "a measurement payload must be trivially copyable");
		static_assert(sizeof(T) <= kCapacity, "a measurement payload must fit MeasurementPayload::kCapacity");
		static_assert(alignof(T) <= kAlignment,
		              "a measurement payload must not need more than 16-byte alignment");
	}
	template <class T>
	T& as() noexcept
	{
		check<T>();
		return *std::launder(reinterpret_cast<T*>(bytes_));
	}
	template <class T>
	const T& as() const noexcept
	{
		check<T>();
		return *std::launder(reinterpret_cast<const T*>(bytes_));
	}
	template <class T>
	T& set(const T& value) noexcept
	{
		check<T>();
		return *::new (static_cast<void*>(bytes_)) T(value);
	}

 private:
	alignas(kAlignment) unsigned char bytes_[kCapacity] = {};
};

/** One measurement for the filter. Sized by the plugin in `prepare`. */
struct Measurement
{
	Eigen::VectorXd z;  //!< measured value, dimension m
	Eigen::MatrixXd R;  //!< noise covariance (m × m), SPD
	int tag = 0;        //!< plugin-private (e.g. ADCP cell index)
	//! Plugin-private typed data for h (see MeasurementPayload): e.g.
	//! `struct Pole { double north_m, east_m; };` written with
	//! `m.setPayload(Pole{n, e})` in prepare, read with `m.payload<Pole>()` in predict.
	MeasurementPayload payload_storage;
	template <class T>
	T& payload() noexcept
	{
		return payload_storage.as<T>();
	}
	template <class T>
	const T& payload() const noexcept
	{
		return payload_storage.as<T>();
	}
	template <class T>
	T& setPayload(const T& value) noexcept
	{
		return payload_storage.set(value);
	}
	std::string label;  //!< optional sub-name for statistics (e.g. "cell")
	//! A part of the observation that is not applied (e.g. an ADCP cell below
	//! the seabed): counted as skipped; z and R may be empty.
	bool skipped = false;
};

/** What the filter may assume about h and its residual
 *  (MeasurementFunction::structure). The default, {}, is always right: h in
 *  general form, every residual component a plain difference. */
struct MeasurementStructure
{
	/** Blocks of uses() in which h is affine, h = A y + b, while the other
	 *  blocks are held. The attitude never is (it is ignored here). The
	 *  filter then evaluates h only on the sigma points along the Cholesky
	 *  columns of the blocks before the last non-affine one; the other pairs
	 *  are exactly ±γ A L_j about the centre's h, so their share of S and Pxz
	 *  is taken from P and A (A by differences of h at the mean, or
	 *  affineSlopes): the same numbers as evaluating them. Declaring a block
	 *  h is not affine in gives wrong updates (auvnav/testing/model_checks.h
	 *  checks it). 0: no such block. */
	uint32_t affine_in = 0;
	/** Residual components that are angles [rad]: bit i set gives
	 *  r_i = wrapAngle(z_i − h_i) in (−π, π] (angles.h), the others
	 *  r_i = z_i − h_i. Components from 32 on are plain differences. */
	uint32_t angle_components = 0;
	/** True only when the residual is neither (a direction on the sphere, a
	 *  quaternion): the filter then calls residual() once per sigma point,
	 *  which the model overrides. */
	bool custom_residual = false;
};

/** r = z ⊟ z_pred as `angle_components` describes (MeasurementStructure). */
inline void structuredResidual(uint32_t angle_components, const double* z, const double* z_pred, double* r,
                               int m) noexcept
{
	for (int q = 0; q < m; ++q)
	{
		const double d = z[q] - z_pred[q];
		r[q] = q < 32 && ((angle_components >> q) & 1u) ? wrapAngle(d) : d;
	}
}

/** h(x) and what the filter may assume about it. */
class MeasurementFunction
{
 public:
	virtual ~MeasurementFunction() = default;
	/** Bit mask of StateBlock values h reads. */
	virtual uint32_t uses() const noexcept = 0;
	/** h(x) into `z_pred` (pre-sized to m). Returns false if it cannot. */
	virtual bool predict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	                     Eigen::Ref<Eigen::VectorXd> z_pred) const noexcept = 0;
	/** What the filter may assume about h and the residual (the default:
	 *  nothing, plain differences). Constant over the model's life. */
	virtual MeasurementStructure structure() const noexcept { return {}; }
	/** r = z ⊟ z_pred. The default is what structure() says (differences,
	 *  wrapped angles); override it only with structure().custom_residual,
	 *  the one case in which the filter calls it. */
	virtual void residual(const Eigen::Ref<const Eigen::VectorXd>& z,
	                      const Eigen::Ref<const Eigen::VectorXd>& z_pred,
	                      Eigen::Ref<Eigen::VectorXd> r) const noexcept
	{
		structuredResidual(structure().angle_components, z.data(), z_pred.data(), r.data(),
		                   static_cast<int>(z.size()));
	}
	/** Gate probability; the filter gates at the χ² quantile of the
	 *  measurement's own dimension. 1.0 disables the gate. */
	virtual double gateProbability() const noexcept { return 0.999; }
	/** Optionally, h's slopes in closed form along the tangent coordinates
	 *  [from, to) at x, for an h affine in every block of uses() past
	 *  `from` (the filter asks only then): At.row(i − from) = ∂h/∂x_i along
	 *  the retraction of state.h (h(x ⊞ t e_i) = h(x) + t At.row(i − from)ᵀ).
	 *  `At` is (to − from) × m and zero; rows of coordinates h does not read
	 *  stay zero. False (the default): the filter takes the slopes by
	 *  differences of h, one evaluation per coordinate, which is exact for
	 *  an affine h; closed-form slopes save those evaluations and must equal
	 *  them (auvnav/testing/model_checks.h checks it). */
	virtual bool affineSlopes(const NavState& /*x*/, const Measurement& /*m*/, const FilterContext& /*ctx*/,
	                          int /*from*/, int /*to*/, Eigen::Ref<Eigen::MatrixXd> /*At*/) const noexcept
	{
		return false;
	}
};

}  // namespace auvnav
