#pragma once
/** @file plugin_state.h
 *  A typed handle on one block of plugin-owned states (plugin SDK, API 2).
 *
 *  A model declares each block it owns as a PluginState member, built from
 *  its StateBlockSpec (usually auvnav::stateBlockFromConfig), returns them
 *  from MeasurementModel::states() (SafeMeasurementModel: doStates();
 *  disabled handles, blocks not configured, are skipped by the host), and
 *  reads them in h through the handle:
 *
 *      PluginState scale_{stateBlockFromConfig(cfg.child("scale"), "scale", {""})};
 *      std::vector<PluginState*> doStates() override { return {&scale_}; }
 *      uint32_t doUses() const override { return kVelocity | scale_.uses(); }
 *      … in doPredict: z_pred = (1 + scale_.value(x)) * v;
 *
 *  Contract:
 *  - The host checks every spec once (StateBlockSpec::problem(), block names
 *    unique within the sensor, room in the state) and binds the handle to its
 *    place in NavState::extra before any update; only the host can bind
 *    (detail::PluginStateBinder, state_layout.cpp). A model never sees an
 *    index and never checks a size: SafeMeasurementModel refuses (predict
 *    false) a state that does not hold every block the host bound for it.
 *  - Reads are inline and allocation-free (h runs per sigma point). Reading
 *    an unbound handle is a programming error: an assertion in debug builds,
 *    NaN in release builds (so h fails the host's finiteness check and the
 *    measurement is counted invalid instead of reading out of bounds).
 *  - The writing overloads (a NavState&) are for tests and throw
 *    std::logic_error on an unbound handle or a state without the block;
 *    a non-const NavState picks them for reads too (h's is const).
 *  - A handle is bound to one place for the model's life: the host refuses
 *    to bind it again (a handle shared between models).
 */
#include <auvnav/state.h>

#include <Eigen/Core>
#include <cassert>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace auvnav
{
namespace detail
{
struct PluginStateBinder;  // the host's (state_layout.cpp): the only code that binds
}

class PluginState
{
 public:
	//! A read-only view of a block's values in a NavState.
	using ConstSegment = Eigen::VectorBlock<const ExtraVector>;
	//! A writable view (tests).
	using Segment = Eigen::VectorBlock<ExtraVector>;

	/** A block that is not configured: enabled() is false, the host skips it. */
	PluginState() = default;
	/** The block `spec` declares (checked by the host when it binds it). */
	explicit PluginState(StateBlockSpec spec) : spec_(std::move(spec)) {}

	/** True if built from a spec (a configured block). */
	bool enabled() const noexcept { return !spec_.components.empty(); }
	const StateBlockSpec& spec() const noexcept { return spec_; }
	int dimension() const noexcept { return spec_.dimension(); }
	/** True once the host has placed the block in the filter's state. */
	bool bound() const noexcept { return first_extra_ >= 0; }
	/** True if `x` holds this (bound) block, e.g. FilterContext::mean in
	 *  prepare (h need not ask: SafeMeasurementModel checks its states). */
	bool presentIn(const NavState& x) const noexcept
	{
		return bound() && x.extra.size() >= first_extra_ + dimension();
	}
	/** Tangent index of component i in the filter's state and covariance
	 *  (idx::extra + …), e.g. to read FilterContext::covariance in prepare;
	 *  −1 while unbound. */
	int tangentIndex(int i = 0) const noexcept { return bound() ? idx::extra + first_extra_ + i : -1; }

	/** kPluginStates if the block is enabled, else 0: the handle's share of
	 *  the model's uses(), e.g. `return kAttitude | bias_.uses();`. */
	uint32_t uses() const noexcept { return enabled() ? static_cast<uint32_t>(kPluginStates) : 0u; }
	/** The value of a scalar block, or `fallback` if it is disabled (an
	 *  optional state not configured: the value h assumes without it). */
	double valueOr(const NavState& x, double fallback) const noexcept
	{
		return enabled() ? value(x) : fallback;
	}
	/** The value of a scalar block. */
	double value(const NavState& x) const noexcept
	{
		assert(dimension() == 1 && "PluginState::value() reads a scalar block; use (x, i) or segment(x)");
		return (*this)(x, 0);
	}
	/** Component i of the block. */
	double operator()(const NavState& x, int i) const noexcept
	{
		assert(bound() && "PluginState read before the host bound it (is it in states()?)");
		assert(i >= 0 && i < dimension());
		if (!bound()) return std::numeric_limits<double>::quiet_NaN();
		return x.extra[first_extra_ + i];
	}
	/** The whole block, a view into x.extra. */
	ConstSegment segment(const NavState& x) const noexcept
	{
		assert(bound() && "PluginState read before the host bound it (is it in states()?)");
		return bound() ? x.extra.segment(first_extra_, dimension()) : unboundValues().segment(0, dimension());
	}
	/** The whole block as a fixed-size view (N == dimension()), e.g.
	 *  so3::Exp(misalignment_.segment<3>(x)). */
	template <int N>
	Eigen::VectorBlock<const ExtraVector, N> segment(const NavState& x) const noexcept
	{
		assert(N == dimension() && "PluginState::segment<N>: N is not the block's dimension");
		assert(bound() && "PluginState read before the host bound it (is it in states()?)");
		return bound() ? x.extra.segment<N>(first_extra_) : unboundValues().segment<N>(0);
	}

	/** Writable access for tests (set a block's value in a state). */
	double& value(NavState& x) const
	{
		if (dimension() != 1)
			throw std::logic_error("PluginState '" + spec_.name + "' is not a scalar block");
		return (*this)(x, 0);
	}
	double& operator()(NavState& x, int i) const { return x.extra[checkedIndex(x, i)]; }
	Segment segment(NavState& x) const
	{
		checkedIndex(x, dimension() - 1);
		return x.extra.segment(first_extra_, dimension());
	}

 private:
	friend struct detail::PluginStateBinder;

	/** NaNs an unbound handle reads (never written). */
	static const ExtraVector& unboundValues() noexcept
	{
		static const ExtraVector nan =
		    ExtraVector::Constant(idx::max_extra, std::numeric_limits<double>::quiet_NaN());
		return nan;
	}
	int checkedIndex(const NavState& x, int i) const
	{
		if (!bound()) throw std::logic_error("PluginState '" + spec_.name + "' is not bound");
		if (i < 0 || i >= dimension() || first_extra_ + i >= x.extra.size())
			throw std::logic_error("PluginState '" + spec_.name + "': component " + std::to_string(i) +
			                       " is not in the state");
		return first_extra_ + i;
	}

	StateBlockSpec spec_;
	int first_extra_ = -1;  //!< index of component 0 in NavState::extra; −1: unbound
};

}  // namespace auvnav
