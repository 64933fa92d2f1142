#pragma once
/** @file process_model_config.h
 *  The process model from the navigator configuration's
 *  `filter.process_noise` section (units as the keys name them: deg/√h,
 *  deg/h, mg, m/s; docs/configuration.md). Kept apart from process_model.h
 *  so that the filter core does not depend on the configuration reader.
 */
#include <auvnav/config.h>
#include <auvnav/process_model.h>

namespace auvnav
{
/** Throws config::ConfigError naming the file and key of the first missing
 *  or out-of-range value. The parameters' noise scales with `prior_mean`'s
 *  damping and inertia entries (the off-diagonal couplings). */
ProcessModel processModelFromConfig(const config::Node& process_noise, const TangentVector& prior_mean);
}  // namespace auvnav
