// A minimal plugin with one plugin-owned state, written against the
// deprecated interface (stateBlocks/bindStates/x.extra): a pressure depth
// update h = p_atm + ρ g p_n.z + b with an optional offset b [Pa] as a state.
// Kept to test that the host still honours the shim and to compare with
// biased_pressure.h, the same plugin with a PluginState handle.
#pragma once
#include <auvnav/measurement_model.h>
#include <auvnav/obs/CObservationPressure.h>
#include <auvnav/state_block_config.h>

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
		double bias = 0;
		if (bias_at_ >= 0)
		{
			if (x.extra.size() <= bias_at_) return false;  // declared, but not in this state
			bias = x.extra[bias_at_];
		}
		z_pred[0] = 101325 + 1025 * 9.81 * x.p_n.z() + bias;
		return true;
	}

 private:
	std::vector<auvnav::StateBlockSpec> blocks_;
	int bias_at_ = -1;
};
}  // namespace legacy_example
