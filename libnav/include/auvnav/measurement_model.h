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
 *  Plugin-owned states (ABI 4): a model may declare blocks of extra states
 *  (`stateBlocks()`: a DVL scale factor, a USBL bias, a magnetometer's hard
 *  iron). The host appends them after the paper's 43 in the order of the
 *  `sensors:` list, tells the model where its first block starts in
 *  NavState::extra (`bindStates`; its blocks follow each other in declaration
 *  order), and propagates them with their declared process. A model that
 *  reads them declares kPluginStates in uses() and reads
 *  `x.extra[first + i]` in h. Models without states change nothing.
 */
#include <auvnav/measurement_function.h>
#include <mrpt/obs/CObservation.h>

#include <Eigen/Core>
#include <string>
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
	/** The state blocks this model owns (called once, after construction). */
	virtual std::vector<StateBlockSpec> stateBlocks() const { return {}; }
	/** Where the model's first block starts in NavState::extra (called once,
	 *  before any update, if stateBlocks() is not empty). */
	virtual void bindStates(int first_extra_index) noexcept { (void)first_extra_index; }
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
};

/** Base class for plugin authors: implement the do* methods; exceptions they
 *  throw become Invalid / false and never cross into the host. */
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
		try
		{
			return doAffineSlopes(x, m, ctx, from, to, At);
		}
		catch (...)
		{
			return false;
		}
	}

 protected:
	virtual PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                                std::vector<Measurement>& out, std::string& why) = 0;
	virtual bool doPredict(const NavState& x, const Measurement& m, const FilterContext& ctx,
	                       Eigen::Ref<Eigen::VectorXd> z_pred) const = 0;
	/** MeasurementModel::affineSlopes; false (the default): by differences. */
	virtual bool doAffineSlopes(const NavState& /*x*/, const Measurement& /*m*/, const FilterContext& /*ctx*/,
	                            int /*from*/, int /*to*/, Eigen::Ref<Eigen::MatrixXd> /*At*/) const
	{
		return false;
	}
};

}  // namespace auvnav
