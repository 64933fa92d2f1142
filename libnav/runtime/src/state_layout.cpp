#include <auvnav/plugin_host.h>
#include <auvnav/state_layout.h>

#include <cmath>
#include <map>

namespace auvnav
{
namespace detail
{
/** The host's access to what only it may set: a handle's place and the
 *  extent of a model's bound states (plugin_state.h, measurement_model.h). */
struct PluginStateBinder
{
	static void bind(PluginState& s, int first_extra) { s.first_extra_ = first_extra; }
	static bool statesFailed(const MeasurementModel& m) { return m.bound_extra_end_ == m.kStatesFailed; }
	static void setBoundExtraEnd(MeasurementModel& m, int end) { m.bound_extra_end_ = end; }
};
}  // namespace detail

namespace
{
using detail::PluginStateBinder;

/** "sensor 'DVL' (plugin dvl): " for the errors about one model. */
std::string sensorPrefix(const LabelledModel& m)
{
	return "sensor '" + m.label + "' (plugin " + m.plugin + "): ";
}

/** The model's enabled handles; a failed states() is refused. */
std::vector<PluginState*> handlesOf(const LabelledModel& m)
{
	std::vector<PluginState*> handles;
	for (PluginState* h : m.model.states())
	{
		if (!h) throw PluginError(sensorPrefix(m) + "states() returned a null handle");
		if (h->enabled()) handles.push_back(h);
	}
	if (PluginStateBinder::statesFailed(m.model)) throw PluginError(sensorPrefix(m) + "states() failed");
	return handles;
}

/** The blocks of a model that declares them the deprecated way (no
 *  handles); its exceptions become errors naming the sensor. */
std::vector<StateBlockSpec> legacyBlocksOf(const LabelledModel& m)
{
	try
	{
// The host honours the deprecated interface for plugins not yet ported
// (measurement_model.h); this is its one call, so the warning is noise here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
		return m.model.stateBlocks();
#pragma GCC diagnostic pop
	}
	catch (const std::exception& e)
	{
		throw PluginError(sensorPrefix(m) + "stateBlocks() failed: " + e.what());
	}
}

void legacyBind(MeasurementModel& model, int first_extra)
{
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"  // as in legacyBlocksOf
	model.bindStates(first_extra);
#pragma GCC diagnostic pop
}

/** Refuses two blocks of one sensor with the same name (their outputs and
 *  σ-limit keys would collide). */
void checkUniqueNames(const LabelledModel& m, const std::vector<StateBlockSpec>& specs)
{
	for (std::size_t i = 0; i < specs.size(); ++i)
		for (std::size_t j = 0; j < i; ++j)
			if (specs[i].name == specs[j].name)
				throw PluginError(sensorPrefix(m) + "two state blocks named '" + specs[i].name + "'");
}

/** Appends one checked block to pm, P0 and the layout's names; returns its
 *  first index in NavState::extra. */
int appendBlock(const LabelledModel& m, const StateBlockSpec& b, ProcessModel& pm, Covariance& P0,
                StateLayout& layout)
{
	const int at = pm.dim();
	try
	{
		pm.appendBlock(b);  // checks StateBlockSpec::problem() and the room left
	}
	catch (const std::exception& e)
	{
		throw PluginError(sensorPrefix(m) + e.what());
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
	return at - idx::core_dim;
}
}  // namespace

StateLayout appendPluginStates(const std::vector<LabelledModel>& models, ProcessModel& pm, Covariance& P0)
{
	StateLayout layout;
	layout.tangent_names = tangentNames();
	layout.stored_names = storedNames();
	for (const LabelledModel& m : models)
	{
		const std::vector<PluginState*> handles = handlesOf(m);
		const bool legacy = handles.empty();
		std::vector<StateBlockSpec> specs;
		if (legacy)
			specs = legacyBlocksOf(m);
		else
			for (const PluginState* h : handles)
			{
				if (h->bound())
					throw PluginError(sensorPrefix(m) + "state block '" + h->spec().name +
					                  "' is bound already (a handle shared between models?)");
				specs.push_back(h->spec());
			}
		if (specs.empty()) continue;
		checkUniqueNames(m, specs);
		const int first_extra = pm.dim() - idx::core_dim;
		for (std::size_t k = 0; k < specs.size(); ++k)
		{
			const int at_extra = appendBlock(m, specs[k], pm, P0, layout);
			if (!legacy) PluginStateBinder::bind(*handles[k], at_extra);
		}
		if (legacy) legacyBind(m.model, first_extra);
		PluginStateBinder::setBoundExtraEnd(m.model, pm.dim() - idx::core_dim);
	}
	return layout;
}

std::pair<TangentVector, TangentVector> sigmaLimitsFromConfig(const config::Node& limits,
                                                              const StateLayout& layout, const Covariance& P0)
{
	const auto& names = layout.tangent_names;
	// What a key may name, each [first, count).
	std::map<std::string, std::pair<int, int>> targets;
	for (const auto& b : coreStateBlocks()) targets[b.prefix] = {b.begin, b.size};
	for (const auto& b : layout.plugin_blocks) targets[b.sensor + "." + b.name] = {b.offset, b.dim};
	for (int i = 0; i < static_cast<int>(names.size()); ++i) targets.emplace(names[i], std::make_pair(i, 1));
	std::vector<std::string> keys;
	keys.reserve(targets.size());
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
