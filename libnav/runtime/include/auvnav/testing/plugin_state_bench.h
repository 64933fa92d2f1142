#pragma once
/** @file plugin_state_bench.h
 *  A model's plugin-owned states laid out and bound exactly as the navigator
 *  does it (appendPluginStates: the host's checks, the handles bound), for
 *  the model's unit tests (header-only):
 *
 *      MyModel model(cfg, "DVL");
 *      const auvnav::testing::PluginStateBench bench(model);  // binds model.states()
 *      NavState x = bench.randomState(seed);       // RandomNavState with the extras sized
 *      bench["scale_factor"](x, 0) = 0.005;        // set a block's value, by block name
 *      ManifoldUkf ukf(bench.process, UtParams{}); // the blocks appended, with their process
 *      ukf.initialize(x, bench.P0);                // TypicalCovariance() + the blocks' σ²
 *
 *  `extra_before` puts another sensor's block of that many coordinates
 *  first, so that a test shows the model reads its own place, not index 0.
 *  A model's unusable blocks throw PluginError, as in the navigator.
 *  Link auvnav::nav (and GTest, for model_checks.h).
 */
#include <auvnav/measurement_model.h>
#include <auvnav/plugin_host.h>
#include <auvnav/plugin_state.h>
#include <auvnav/process_model.h>
#include <auvnav/state_layout.h>
#include <auvnav/testing/model_checks.h>

#include <cstdint>
#include <string>
#include <vector>

namespace auvnav::testing
{
class PluginStateBench
{
 public:
	explicit PluginStateBench(MeasurementModel& model, int extra_before = 0,
	                          const std::string& label = "SENSOR", const std::string& plugin = "under_test")
	    : P0(TypicalCovariance())
	{
		OtherSensor other(extra_before);
		const std::string other_label = "OTHER", other_plugin = "other";
		std::vector<LabelledModel> models;
		if (extra_before > 0) models.push_back({other_label, other_plugin, other});
		models.push_back({label, plugin, model});
		layout = appendPluginStates(models, process, P0);
		for (PluginState* h : model.states())
			if (h && h->bound()) handles_.push_back(h);
	}

	ProcessModel process;  //!< ProcessModel{} with the blocks appended (their process and mean)
	Covariance P0;         //!< TypicalCovariance() of the 43, then the blocks' initial σ²
	StateLayout layout;    //!< names and offsets, as the navigator's

	/** NavState::extra.size() of the filter's state. */
	int extraSize() const { return process.dim() - idx::core_dim; }
	/** NavState{} with the blocks at their initial means (the other sensor's at 0). */
	NavState initialState() const
	{
		NavState x;
		x.extra = process.prior_mean.tail(extraSize());
		return x;
	}
	/** RandomNavState(seed) with every plugin state ~0.01. */
	NavState randomState(uint32_t seed) const { return RandomNavState(seed, extraSize()); }
	/** The model's bound handle of block `name` (std::out_of_range if none). */
	const PluginState& operator[](const std::string& name) const
	{
		for (const PluginState* h : handles_)
			if (h->spec().name == name) return *h;
		throw std::out_of_range("the model has no bound state block '" + name + "'");
	}

 private:
	/** Another sensor that owns one block of `n` coordinates (none for 0). */
	class OtherSensor final : public MeasurementModel
	{
	 public:
		explicit OtherSensor(int n)
		{
			if (n <= 0) return;
			StateBlockSpec s;
			s.name = "other";
			for (int i = 0; i < n; ++i) s.components.push_back(std::to_string(i));
			s.sigma = {0.01};
			block_ = PluginState(s);
		}
		uint32_t uses() const noexcept override { return 0; }
		bool predict(const NavState&, const Measurement&, const FilterContext&,
		             Eigen::Ref<Eigen::VectorXd>) const noexcept override
		{
			return false;
		}
		PrepareStatus prepare(const mrpt::obs::CObservation&, const FilterContext&, std::vector<Measurement>&,
		                      std::string&) noexcept override
		{
			return PrepareStatus::Skip;
		}
		std::vector<PluginState*> states() noexcept override { return {&block_}; }

	 private:
		PluginState block_;
	};

	std::vector<const PluginState*> handles_;
};

}  // namespace auvnav::testing
