// A minimal plugin with one plugin-owned state, with a PluginState handle
// (plugin SDK API 2): a pressure depth update h = p_atm + ρ g p_n.z + b with
// an optional offset b [Pa] as a state. The same plugin as
// biased_pressure_legacy.h, without indices or size checks.
#pragma once
#include <auvnav/measurement_model.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/state_block_config.h>

namespace handle_example
{
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
	bool doPredict(const auvnav::NavState& x, const auvnav::Measurement&, const auvnav::FilterContext&,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override
	{
		z_pred[0] = 101325 + 1025 * 9.81 * x.p_n.z() + bias_.valueOr(x, 0.0);
		return true;
	}

 private:
	auvnav::PluginState bias_;
};
}  // namespace handle_example
