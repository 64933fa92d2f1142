#pragma once
/** @file measurement_model.h
 *  The stable measurement-model interface that sensor plugins implement.
 *
 *  A plugin DESCRIBES a measurement; the filter owns sigma points, covariance
 *  and gating. Per observation the filter calls `prepare` once (turn the MRPT
 *  observation into zero or more measurements: value z, noise R), then, per
 *  measurement, `predict` once per sigma point (h(x), a pure function: no
 *  shared mutable state, no allocation), and `residual` to compare.
 *
 *  Contract: that of measurement_function.h (what h reads, h pure and
 *  finite, the residual a boxminus), and: R is symmetric positive definite;
 *  a NaN/Inf anywhere is rejected by the host and counted as invalid; no
 *  exception may leave a plugin (derive from SafeMeasurementModel, which
 *  turns exceptions into `Invalid`).
 *
 *  Plugin-owned states: a model may own blocks of extra states (a DVL
 *  scale factor, a USBL bias, a magnetometer's hard iron), each a
 *  PluginState member (plugin_state.h) it returns from states(). The host
 *  checks them, appends them after the paper's 43 in the order of the
 *  `sensors:` list, binds each handle to its place, and propagates them with
 *  their declared process. A model that reads them declares kPluginStates in
 *  uses() and reads them through the handles in h. Models without states
 *  change nothing.
 */
#include <auvnav/measurement_function.h>
#include <auvnav/plugin_state.h>
#include <mrpt/obs/CObservation.h>

#include <Eigen/Core>
#include <climits>
#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace auvnav
{
/** A position fix to start the filter from (position: gps in the config):
 *  where the sensor point (antenna, transponder) is, and where it sits on the
 *  body; the navigator moves it to the IMU with the initial attitude. */
struct InitialFix
{
	Eigen::Vector3d p_n =
	    Eigen::Vector3d::Zero();  //!< sensor point, navigation frame [m] (its down is ignored)
	Eigen::Vector3d r_b = Eigen::Vector3d::Zero();  //!< sensor point in the body frame [m]
};

enum class PrepareStatus
{
	Ok,      //!< `out` holds the measurements to apply (possibly none)
	Skip,    //!< nothing to apply, not an error (e.g. DVL without bottom lock)
	Invalid  //!< bad observation (NaN, wrong class, …): rejected and counted
};

class MeasurementModel : public MeasurementFunction
{
 public:
	/** Observation → measurements. `why` explains Invalid/Skip (short). */
	virtual PrepareStatus prepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                              std::vector<Measurement>& out, std::string& why) noexcept = 0;
	/** The fix in `obs` as measured, with no rate limit and no state (false:
	 *  this observation gives none). Called before initialisation for the
	 *  sensor named by filter.initial.gps_label (the start waits for a
	 *  consensus of these, fix_consensus.h), and afterwards for every
	 *  observation of a sensor whose reportsPositionFix() is true (the
	 *  re-initialisation rule checks its rejected fixes against all of them,
	 *  aiding_policy.h). */
	virtual bool initialFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        InitialFix& out) noexcept
	{
		(void)obs, (void)ctx, (void)out;
		return false;
	}
	/** The model's plugin-owned state blocks (plugin_state.h), in the order
	 *  they take in the state; disabled handles (not configured) are
	 *  skipped. Called once, after construction, by the host, which checks
	 *  and binds them before any update. The handles are the model's own
	 *  members and live as long as it does. */
	virtual std::vector<PluginState*> states() noexcept { return {}; }
	/** Deprecated (API 2): return PluginState handles from states() instead.
	 *  Still honoured by the host for a model whose states() is empty. */
	[[deprecated("use states(): PluginState handles (plugin_state.h)")]] virtual std::vector<StateBlockSpec>
	stateBlocks() const
	{
		return {};
	}
	/** Deprecated (API 2) with stateBlocks(): where the first block starts in
	 *  NavState::extra; the handles of states() are bound by the host. */
	[[deprecated("use states(): the host binds PluginState handles")]] virtual void bindStates(
	    int first_extra_index) noexcept
	{
		(void)first_extra_index;
	}
	/** When the measurement in `obs` was taken [s, Unix epoch]. `stamp_s` is
	 *  the navigator's own estimate: the observation's timestamp minus the
	 *  sensor entry's `latency_s`. Override it when the observation carries
	 *  its measurement time (a USBL fix's acoustic time). NaN: the observation
	 *  is invalid. Called once per observation, before prepare. */
	virtual double measurementTime(const mrpt::obs::CObservation& obs, double stamp_s) const noexcept
	{
		(void)obs;
		return stamp_s;
	}
	/** True if z[0], z[1] of this model's measurements are the north and
	 *  east [m] of a point in the navigation frame (a GNSS or acoustic fix):
	 *  the host records them (position_fixes.csv) and the viewers draw them. */
	virtual bool reportsPositionFix() const noexcept { return false; }

 protected:
	/** True if x holds every plugin state the host bound for this model
	 *  (SafeMeasurementModel asks before h: one comparison). */
	bool holdsBoundStates(const NavState& x) const noexcept { return x.extra.size() >= bound_extra_end_; }

 private:
	friend struct detail::PluginStateBinder;
	friend class SafeMeasurementModel;
	//! states() threw: the host refuses the model (and h is never evaluated).
	static constexpr int kStatesFailed = INT_MAX;
	//! NavState::extra.size() h needs: the end of the model's bound blocks.
	int bound_extra_end_ = 0;
};

/** Base class for plugin authors: implement the do* methods; an exception
 *  they throw never crosses into the host but becomes the safe answer of
 *  that method: prepare Invalid, predict / affineSlopes / initialFix /
 *  reportsPositionFix false, measurementTime NaN (the observation is
 *  invalid), residual NaN (rejected), states() empty with the model refused
 *  by the host, uses() every block, structure() none, gateProbability() the
 *  default.
 *
 *  Every method the host calls is `final` here: override the do* methods.
 *
 *  predict() (per sigma point) adds one comparison to doPredict: a state
 *  without the model's bound plugin states is refused, so h never checks
 *  sizes. */
class SafeMeasurementModel : public MeasurementModel
{
 public:
	PrepareStatus prepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                      std::vector<Measurement>& out, std::string& why) noexcept final
	{
		try
		{
			return doPrepare(obs, ctx, out, why);
		}
		catch (const std::exception& e)
		{
			why = std::string("exception in prepare: ") + e.what();
		}
		catch (...)
		{
			why = "unknown exception in prepare";
		}
		out.clear();
		return PrepareStatus::Invalid;
	}
	bool predict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	             Eigen::Ref<Eigen::VectorXd> z_pred) const noexcept final
	{
		if (!holdsBoundStates(x)) return false;
		try
		{
			return doPredict(x, m, ctx, z_pred);
		}
		catch (...)
		{
			return false;
		}
	}
	bool affineSlopes(const NavState& x, const Measurement& m, const FilterContext& ctx, int from, int to,
	                  Eigen::Ref<Eigen::MatrixXd> At) const noexcept final
	{
		if (!holdsBoundStates(x)) return false;
		try
		{
			return doAffineSlopes(x, m, ctx, from, to, At);
		}
		catch (...)
		{
			return false;
		}
	}
	void residual(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::Ref<const Eigen::VectorXd>& z_pred,
	              Eigen::Ref<Eigen::VectorXd> r) const noexcept final
	{
		try
		{
			doResidual(z, z_pred, r);
			return;
		}
		catch (...)
		{
		}
		r.setConstant(std::numeric_limits<double>::quiet_NaN());
	}
	bool initialFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                InitialFix& out) noexcept final
	{
		try
		{
			return doInitialFix(obs, ctx, out);
		}
		catch (...)
		{
			return false;
		}
	}
	std::vector<PluginState*> states() noexcept final
	{
		try
		{
			return doStates();
		}
		catch (...)
		{
			bound_extra_end_ = kStatesFailed;
			return {};
		}
	}
	double measurementTime(const mrpt::obs::CObservation& obs, double stamp_s) const noexcept final
	{
		try
		{
			return doMeasurementTime(obs, stamp_s);
		}
		catch (...)
		{
			return std::numeric_limits<double>::quiet_NaN();
		}
	}
	bool reportsPositionFix() const noexcept final
	{
		try
		{
			return doReportsPositionFix();
		}
		catch (...)
		{
			return false;
		}
	}
	uint32_t uses() const noexcept final
	{
		try
		{
			return doUses();
		}
		catch (...)
		{
			return kAllBlocks;
		}
	}
	MeasurementStructure structure() const noexcept final
	{
		try
		{
			return doStructure();
		}
		catch (...)
		{
			return {};
		}
	}
	double gateProbability() const noexcept final
	{
		try
		{
			return doGateProbability();
		}
		catch (...)
		{
			return MeasurementFunction::gateProbability();
		}
	}

 protected:
	virtual PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                                std::vector<Measurement>& out, std::string& why) = 0;
	virtual bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	                       Eigen::Ref<Eigen::VectorXd> z_pred) const = 0;
	/** MeasurementFunction::affineSlopes; false (the default): by differences. */
	virtual bool doAffineSlopes(const NavState& /*x*/, const Measurement& /*m*/, const FilterContext& /*ctx*/,
	                            int /*from*/, int /*to*/, Eigen::Ref<Eigen::MatrixXd> /*At*/) const
	{
		return false;
	}
	/** MeasurementFunction::residual (only with structure().custom_residual). */
	virtual void doResidual(const Eigen::Ref<const Eigen::VectorXd>& z,
	                        const Eigen::Ref<const Eigen::VectorXd>& z_pred,
	                        Eigen::Ref<Eigen::VectorXd> r) const
	{
		MeasurementFunction::residual(z, z_pred, r);
	}
	/** MeasurementModel::initialFix; false (the default): no fixes. */
	virtual bool doInitialFix(const mrpt::obs::CObservation& /*obs*/, const FilterContext& /*ctx*/,
	                          InitialFix& /*out*/)
	{
		return false;
	}
	/** MeasurementModel::states: the enabled handles (the default: none). */
	virtual std::vector<PluginState*> doStates() { return {}; }
	/** MeasurementModel::measurementTime; the default: `stamp_s`. */
	virtual double doMeasurementTime(const mrpt::obs::CObservation& /*obs*/, double stamp_s) const
	{
		return stamp_s;
	}
	/** MeasurementModel::reportsPositionFix; the default: false. */
	virtual bool doReportsPositionFix() const { return false; }
	/** MeasurementFunction::uses. The default, every block, is always right
	 *  but makes every update span the whole state: override it. */
	virtual uint32_t doUses() const { return kAllBlocks; }
	/** MeasurementFunction::structure; the default: {} (always right). */
	virtual MeasurementStructure doStructure() const { return {}; }
	/** MeasurementFunction::gateProbability; the default: 0.999. */
	virtual double doGateProbability() const { return MeasurementFunction::gateProbability(); }
};

namespace detail
{
// A plugin whose model still declares stateBlocks() or bindStates() (before
// API 2's handles) builds, with a deprecation warning from AUVNAV_PLUGIN
// (overriding a deprecated virtual alone warns in no compiler).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
template <class Model>
constexpr bool declaresLegacyStates()
{
	return !std::is_same_v<decltype(&Model::stateBlocks), decltype(&MeasurementModel::stateBlocks)> ||
	       !std::is_same_v<decltype(&Model::bindStates), decltype(&MeasurementModel::bindStates)>;
}
#pragma GCC diagnostic pop
template <bool kLegacy>
struct LegacyStatesNotice
{
	static constexpr bool value = true;
};
template <>
struct LegacyStatesNotice<true>
{
	[[deprecated(
	    "stateBlocks()/bindStates() are deprecated: declare PluginState members and return them from "
	    "doStates() (docs/plugin_sdk_changelog.md, API 2)")]] static constexpr bool value = true;
};
}  // namespace detail

}  // namespace auvnav
