// The plugin of biased_pressure.h written against the deprecated interface
// (stateBlocks/bindStates/x.extra): the same measurement, with its offset
// b [Pa] declared as a StateBlockSpec and read at the index the host binds.
// Kept to test that the host still honours the shim; only the state differs.
#pragma once
#include <auvnav/measurement_model.h>
#include <auvnav/state_block_config.h>

#include "biased_pressure.h"

namespace legacy_example
{
class BiasedPressure final : public auvnav::SafeMeasurementModel
{
 public:
	explicit BiasedPressure(const auvnav::config::Node& cfg)
	{
		if (cfg.has("bias")) blocks_.push_back(auvnav::stateBlockFromConfig(cfg.child("bias"), "bias", {""}));
	}
	uint32_t doUses() const override
	{
		return auvnav::kPosition | (blocks_.empty() ? 0u : static_cast<uint32_t>(auvnav::kPluginStates));
	}
	std::vector<auvnav::StateBlockSpec> stateBlocks() const override { return blocks_; }
	void bindStates(int first_extra_index) noexcept override { bias_at_ = first_extra_index; }

 protected:
	auvnav::PrepareStatus doPrepare(const mrpt::obs::CObservation& obs, const auvnav::FilterContext&,
	                                std::vector<auvnav::Measurement>& out, std::string& why) override
	{
		return handle_example::pressureMeasurement(obs, out, why);
	}
	bool doPredict(const auvnav::NavState& x, const auvnav::Measurement&, const auvnav::FilterContext&,
	               Eigen::Ref<Eigen::VectorXd> z_pred) const override
	{
		double bias = 0;
		if (bias_at_ >= 0)
		{
			if (x.extra.size() <= bias_at_) return false;  // declared, but not in this state
			bias = x.extra[bias_at_];
		}
		z_pred[0] = handle_example::predictedPressure(x, bias);
		return true;
	}

 private:
	std::vector<auvnav::StateBlockSpec> blocks_;
	int bias_at_ = -1;
};
}  // namespace legacy_example
