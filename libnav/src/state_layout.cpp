#include <auvnav/plugin_host.h>
#include <auvnav/state_layout.h>

#include <cmath>
#include <map>

namespace auvnav
{
namespace
{
/** The model's blocks; its exceptions become errors naming the sensor. */
std::vector<StateBlockSpec> blocksOf(const LabelledModel& m)
{
	try
	{
		return m.model.stateBlocks();
	}
	catch (const std::exception& e)
	{
		throw PluginError("sensor '" + m.label + "' (plugin " + m.plugin +
		                  "): stateBlocks() failed: " + e.what());
	}
}
}  // namespace

StateLayout appendPluginStates(const std::vector<LabelledModel>& models, ProcessModel& pm, Covariance& P0)
{
	StateLayout layout;
	layout.tangent_names = tangentNames();
	layout.stored_names = storedNames();
	for (const LabelledModel& m : models)
	{
		const std::vector<StateBlockSpec> blocks = blocksOf(m);
		if (blocks.empty()) continue;
		const int first_extra = pm.dim() - idx::core_dim;
		for (const StateBlockSpec& b : blocks)
		{
			const int at = pm.dim();
			try
			{
				pm.appendBlock(b);
			}
			catch (const std::exception& e)
			{
				throw PluginError("sensor '" + m.label + "' (plugin " + m.plugin + "): " + e.what());
			}
			P0.conservativeResize(pm.dim(), pm.dim());
			P0.rightCols(b.dimension()).setZero();
			P0.bottomRows(b.dimension()).setZero();
			for (int i = 0; i < b.dimension(); ++i)
			{
				const double sigma = b.sigma.size() == 1 ? b.sigma[0] : b.sigma[i];
				P0(at + i, at + i) = sigma * sigma;
				const std::string name =
				    m.label + "." + b.name + (b.components[i].empty() ? "" : "_" + b.components[i]);
				layout.tangent_names.push_back(name);
				layout.stored_names.push_back(name);
			}
			layout.plugin_blocks.push_back({m.label, b.name, at, b.dimension()});
		}
		m.model.bindStates(first_extra);
	}
	return layout;
}

std::pair<TangentVector, TangentVector> sigmaLimitsFromConfig(const config::Node& limits,
                                                              const StateLayout& layout, const Covariance& P0)
{
	const auto& names = layout.tangent_names;
	// What a key may name, each [first, count).
	std::map<std::string, std::pair<int, int>> targets = {{"att", {idx::att, 3}},
	                                                      {"gyro_bias", {idx::gyro_bias, 3}},
	                                                      {"acc", {idx::acc, 3}},
	                                                      {"gravity", {idx::gravity, 1}},
	                                                      {"acc_bias", {idx::acc_bias, 3}},
	                                                      {"vel", {idx::vel, 3}},
	                                                      {"pos", {idx::pos, 3}},
	                                                      {"current", {idx::current_vehicle, 2}},
	                                                      {"current_far", {idx::current_far, 2}},
	                                                      {"adcp_bias", {idx::adcp_bias, 2}},
	                                                      {"M", {idx::inertia, 6}},
	                                                      {"Dl", {idx::damping_lin, 6}},
	                                                      {"Dq", {idx::damping_quad, 6}}};
	for (const auto& b : layout.plugin_blocks) targets[b.sensor + "." + b.name] = {b.offset, b.dim};
	for (int i = 0; i < static_cast<int>(names.size()); ++i) targets.emplace(names[i], std::make_pair(i, 1));
	std::vector<std::string> keys;
	for (const auto& [name, range] : targets) keys.push_back(name);
	limits.allowOnly(keys);
	const int n = static_cast<int>(names.size());
	TangentVector lo = TangentVector::Zero(n), hi = TangentVector::Constant(n, INFINITY);
	// Blocks first, then single states, so that a state's own entry wins.
	for (const bool single : {false, true})
		for (const auto& key : limits.keys())
		{
			const auto [first, count] = targets.at(key);
			if ((count == 1 && first < n && names[first] == key) != single) continue;
			const auto l = limits.child(key);
			l.allowOnly({"min", "max"});
			const double min_sigma = l.nonNegative("min", 0.0);
			const double max_sigma = l.has("max") ? l.positive("max") : INFINITY;
			if (max_sigma < min_sigma) l.fail("max", "is below min");
			lo.segment(first, count).setConstant(min_sigma);
			hi.segment(first, count).setConstant(max_sigma);
		}
	for (int i = 0; i < n; ++i)
		if (std::sqrt(P0(i, i)) < lo[i] || std::sqrt(P0(i, i)) > hi[i])
			limits.fail(names[i], "its initial sigma " + std::to_string(std::sqrt(P0(i, i))) +
			                          " (filter.initial) is outside its limits [" + std::to_string(lo[i]) +
			                          ", " + std::to_string(hi[i]) + "]");
	return {lo, hi};
}

}  // namespace auvnav
