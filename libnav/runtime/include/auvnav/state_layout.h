#pragma once
/** @file state_layout.h
 *  The filter's state as configured: the paper's 43 tangent coordinates,
 *  then the blocks the sensors' plugins own (MeasurementModel::states,
 *  plugin_state.h), in `sensors:` order. Names, offsets and σ limits. This
 *  is the one place that checks a plugin's blocks and binds its handles.
 */
#include <auvnav/config.h>
#include <auvnav/measurement_model.h>
#include <auvnav/process_model.h>

#include <string>
#include <utility>
#include <vector>

namespace auvnav
{
/** A block of plugin-owned states in the filter's state (tangent index). */
struct PluginStateBlock
{
	std::string sensor, name;
	int offset = 0, dim = 0;
};

struct StateLayout
{
	//! Tangent coordinates: tangentNames() then "<label>.<block>_<component>".
	std::vector<std::string> tangent_names;
	//! NavState::euclidean()'s stored values: storedNames() then the same plugin names.
	std::vector<std::string> stored_names;
	std::vector<PluginStateBlock> plugin_blocks;
};

/** A sensor's model with the label and plugin name its errors quote. */
struct LabelledModel
{
	const std::string& label;
	const std::string& plugin;
	MeasurementModel& model;
};

/** Appends every model's state blocks to `pm` and `P0` (their σ on the
 *  diagonal), binds each model's PluginState handles (or, for a model with
 *  no handles, its deprecated stateBlocks()/bindStates()) and names them.
 *  Checks each block once: StateBlockSpec::problem(), a name unique within
 *  the sensor, room in the state; disabled handles are skipped, a handle
 *  bound already (by another model or an earlier layout) is refused. Throws
 *  PluginError naming the sensor and block when a model's blocks are
 *  unusable. */
StateLayout appendPluginStates(const std::vector<LabelledModel>& models, ProcessModel& pm, Covariance& P0);

/** `filter.sigma_limits`: {<block or state>: {min, max}} [the state's units]:
 *  a block of the paper's state (att, pos, M, …), a plugin's block
 *  ("<label>.<block>") or one state (a tangent name); a state's own entry
 *  wins over its block's. Returns (min σ, max σ) per tangent coordinate.
 *  Throws ConfigError if an initial σ (P0) lies outside its limits. */
std::pair<TangentVector, TangentVector> sigmaLimitsFromConfig(const config::Node& limits,
                                                              const StateLayout& layout,
                                                              const Covariance& P0);

}  // namespace auvnav
