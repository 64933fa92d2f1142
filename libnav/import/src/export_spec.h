#pragma once
// Internal to the exporter: the import spec text that reads its CSV files back.
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace auvnav::import::detail
{
/** The spec for `labels_and_classes`, each read from its file in `files`
 *  (default: fileSafe(label).csv), thrusters in their `thruster_units`
 *  (default: N); `optional_sensors`: every sensor `optional: true`. */
std::string specText(const std::vector<std::pair<std::string, std::string>>& labels_and_classes,
                     const std::map<std::string, std::string>& files,
                     const std::map<std::string, std::string>& thruster_units, bool optional_sensors);

}  // namespace auvnav::import::detail
