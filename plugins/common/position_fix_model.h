#pragma once
/** @file position_fix_model.h
 *  What the position-fix plugins (gps, usbl) have in common (internal to
 *  plugins/; header-only, so that each plugin stays one self-contained
 *  MODULE). A fix is the navigation-frame position of one point on the
 *  vehicle (the GPS antenna, the USBL transponder) at lever arm r_f
 *  (`position_m`, body FRD), offset by an optional plugin-owned bias
 *  b = (b_n, b_e) (`states: {bias: …}`, state_block_config.h). With r_imu the
 *  IMU lever arm:
 *
 *      h = (p_n + R_nb (r_f − r_imu) + [b_n, b_e, 0]).head(measuredAxes())
 *
 *  The plugin decodes its observation into a `Fix` (decodeFix) and turns that
 *  into measurements (measureFix); this base gives prepare (decode, then
 *  measure), h, the initial fix, the bias state, uses() and the
 *  `gate_probability` key.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>
#include <auvnav/state_block_config.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "plugin_common.h"

namespace auvnav::plugins
{
/** `Fix`: what the plugin decodes from one observation; its member
 *  `Eigen::Vector3d p_n` is the point's position [m, navigation frame]. */
template <class Fix>
class PositionFixModel : public GatedModel
{
 public:
	/** The point's lever arm r_f [m, body FRD]. */
	const Eigen::Vector3d& position_b() const { return position_b_; }

 protected:
	/** Reads `position_m` (default `default_position_b`; a lever arm longer
	 *  than 100 m is refused), `gate_probability` and `states: {bias: …}`
	 *  (any other state is refused). `measured_axes`: how many of north,
	 *  east, down a measurement holds, 2 or 3. */
	PositionFixModel(const config::Node& cfg, const Eigen::Vector3d& default_position_b, int measured_axes)
	    : GatedModel(cfg),
	      position_b_(cfg.vector3("position_m", default_position_b)),
	      measured_axes_(measured_axes)
	{
		if (position_b_.cwiseAbs().maxCoeff() > 100) cfg.fail("position_m", "lever arm longer than 100 m");
		if (!cfg.has("states")) return;
		const auto states = cfg.child("states");
		states.allowOnly({"bias"});
		if (states.has("bias"))
			bias_ = PluginState(stateBlockFromConfig(states.child("bias"), "bias", {"n", "e"}));
	}

	/** The fix `obs` carries (Ok), or why there is none (Skip, Invalid). */
	virtual PrepareStatus decodeFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, Fix& fix,
	                                std::string& why) const = 0;
	/** Appends the measurement(s) of a decoded `fix` of `obs` to `out` (Ok),
	 *  or says why there are none (Skip). */
	virtual PrepareStatus measureFix(const Fix& fix, const mrpt::obs::CObservation& obs,
	                                 const FilterContext& ctx, std::vector<Measurement>& out,
	                                 std::string& why) = 0;

	/** How many of north, east, down a measurement holds: 2 or 3. */
	int measuredAxes() const { return measured_axes_; }

	/** (b_n, b_e) [m]; disabled if not configured. */
	const PluginState& bias() const { return bias_; }
	/** Where the point is in state x [m, navigation frame], bias not added. */
	Eigen::Vector3d pointPosition_n(const NavState& x, const FilterContext& ctx) const
	{
		return x.p_n + x.R_nb * (position_b_ - ctx.imu_position_b);
	}

	uint32_t doUses() const override { return kAttitude | kPosition | bias_.uses(); }
	std::vector<PluginState*> doStates() override { return {&bias_}; }
	bool doReportsPositionFix() const override { return true; }
	PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const FilterContext& ctx,
	                        std::vector<Measurement>& out, std::string& why) override
	{
		out.clear();
		Fix fix;
		const PrepareStatus decoded = decodeFix(obs, ctx, fix, why);
		if (decoded != PrepareStatus::Ok) return decoded;
		return measureFix(fix, obs, ctx, out, why);
	}
	/** The point's position from a valid fix (no rate limit, no state). */
	bool doInitialFix(const mrpt::obs::CObservation& obs, const FilterContext& ctx, InitialFix& out) override
	{
		Fix fix;
		std::string why;
		if (decodeFix(obs, ctx, fix, why) != PrepareStatus::Ok) return false;
		out.p_n = fix.p_n;
		out.r_b = position_b_;
		return true;
	}
	bool doPredict(const NavState& x, const Measurement& /*m*/, const FilterContext& ctx,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override
	{
		if (z_pred.size() != measured_axes_) return false;
		Eigen::Vector3d p_n = pointPosition_n(x, ctx);
		if (bias_.enabled()) p_n.head<2>() += bias_.segment<2>(x);
		z_pred = p_n.head(measured_axes_);
		return true;
	}

 private:
	Eigen::Vector3d position_b_;
	int measured_axes_;
	PluginState bias_;
};
}  // namespace auvnav::plugins
