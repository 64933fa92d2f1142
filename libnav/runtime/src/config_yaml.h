#pragma once
// Internal to config.h's Node: YAML text to MRPT's tree (libyaml's parser,
// with the checks of config.h) and back (libyaml's emitter).
#include <auvnav/config.h>
#include <mrpt/containers/yaml.h>

#include <string>

namespace auvnav::config::detail
{
/** A plain untagged scalar with this text is null (YAML 1.2 core schema). */
bool readsAsNull(const std::string& text);

/** Parses `text` with libyaml into a tree, refusing in one line
 *  "ORIGIN:LINE:COLUMN: [KEY.PATH: ]what" what the structure check refuses
 *  (duplicate keys, a second document, aliases, non-scalar keys) and
 *  libyaml's syntax errors. False if the text holds no document. */
bool parseDocument(const std::string& text, const std::string& origin, mrpt::containers::yaml::node_t& root);

/** `root` as block YAML text; `where` names it in errors (ConfigError). */
std::string emitDocument(const mrpt::containers::yaml::node_t& root, const std::string& where);

}  // namespace auvnav::config::detail
