// A minimal plugin with one plugin-owned state, with a PluginState handle
// (plugin SDK API 2): a pressure depth update h = p_atm + ρ g p_n.z + b with
// an optional offset b [Pa] as a state. biased_pressure_legacy.h is the same
// plugin with the deprecated state declaration; it reuses the measurement.
#pragma once
#include <auvnav/measurement_model.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/state_block_config.h>

namespace handle_example
{
/** z = the absolute pressure [Pa] of a CObservationPressure, R = (10 Pa)². */
inline auvnav::PrepareStatus pressureMeasurement(const mrpt::obs::CObservation& obs,
                                                 std::vector<auvnav::Measurement>& out, std::string& why)
{
	const auto* p = dynamic_cast<const auvnav::obs::CObservationPressure*>(&obs);
	if (!p)
	{
		why = "not a pressure";
		return auvnav::PrepareStatus::Invalid;
	}
	auvnav::Measurement m;
	m.z = Eigen::VectorXd::Constant(1, p->pressure_pa);
	m.R = Eigen::MatrixXd::Constant(1, 1, 100.0);
	out.assign(1, m);
	return auvnav::PrepareStatus::Ok;
}

/** h [Pa]: the pressure at depth p_n.z [m] plus the offset `bias_pa`. */
inline double predictedPressure(const auvnav::NavState& x, double bias_pa)
{
	return 101325 + 1025 * 9.81 * x.p_n.z() + bias_pa;
}

class BiasedPressure final : public auvnav::SafeMeasurementModel
{
 public:
	explicit BiasedPressure(const auvnav::config::Node& cfg)
	{
		if (cfg.has("bias"))
			bias_ = auvnav::PluginState(auvnav::stateBlockFromConfig(cfg.child("bias"), "bias", {""}));
	}

 protected:
	uint32_t doUses() const override { return auvnav::kPosition | bias_.uses(); }
	std::vector<auvnav::PluginState*> doStates() override { return {&bias_}; }
	auvnav::PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const auvnav::FilterContext&,
	                                std::vector<auvnav::Measurement>& out, std::string& why) override
	{
		return pressureMeasurement(obs, out, why);
	}
	bool doPredict(const auvnav::NavState& x, const auvnav::Measurement&, const auvnav::FilterContext&,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override
	{
		z_pred[0] = predictedPressure(x, bias_.valueOr(x, 0.0));
		return true;
	}

 private:
	auvnav::PluginState bias_;
};
}  // namespace handle_example
