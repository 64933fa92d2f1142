#pragma once
/** @file state_block_config.h
 *  A plugin-owned state block (state.h StateBlockSpec) from a plugin's YAML:
 *
 *      KEY:
 *        sigma<SUFFIX>: 0.01          # initial σ per coordinate (required, > 0)
 *        mean<SUFFIX>: 0              # initial value (optional, default 0)
 *        process: constant            # constant | random_walk | random_walk_per_m | gauss_markov
 *        process_sigma<SUFFIX>: 0     # random_walk: σ per √s; random_walk_per_m: σ per √m
 *                                     # moved through the water; gauss_markov: stationary σ
 *        tau_s: 600                   # gauss_markov only
 *
 *  SUFFIX names the unit the user writes ("" for SI, "_deg" for angles);
 *  `to_si` converts it (e.g. π/180). The same block shape for every plugin,
 *  so users learn it once.
 */
#include <auvnav/config.h>
#include <auvnav/state.h>

#include <string>
#include <vector>

namespace auvnav
{
inline StateBlockSpec stateBlockFromConfig(const config::Node& n, const std::string& name,
                                           std::vector<std::string> components,
                                           const std::string& suffix = "", double to_si = 1.0)
{
	n.allowOnly({"sigma" + suffix, "mean" + suffix, "process", "process_sigma" + suffix, "tau_s"});
	StateBlockSpec b;
	b.name = name;
	b.components = std::move(components);
	b.sigma = {n.positive("sigma" + suffix) * to_si};
	if (n.has("mean" + suffix))
	{
		if (b.components.size() == 1)
			b.mean = {n.number("mean" + suffix) * to_si};
		else
		{
			const auto m = n.numbers("mean" + suffix);
			if (m.size() != b.components.size())
				n.fail("mean" + suffix, "expected " + std::to_string(b.components.size()) + " values");
			for (double v : m) b.mean.push_back(v * to_si);
		}
	}
	const std::string process = n.string("process", "constant");
	if (process == "constant")
		b.process = StateProcess::RandomConstant;
	else if (process == "random_walk")
		b.process = StateProcess::RandomWalk;
	else if (process == "random_walk_per_m")
		b.process = StateProcess::RandomWalkPerMetre;
	else if (process == "gauss_markov")
		b.process = StateProcess::GaussMarkov;
	else
		n.fail("process",
		       "expected constant, random_walk, random_walk_per_m or gauss_markov, got '" + process + "'");
	if (b.process != StateProcess::RandomConstant)
		b.process_sigma = n.nonNegative("process_sigma" + suffix) * to_si;
	if (b.process == StateProcess::GaussMarkov)
		b.tau_s = n.positive("tau_s");
	else if (n.has("tau_s"))
		n.fail("tau_s", "only a gauss_markov process has a correlation time");
	return b;
}
}  // namespace auvnav
