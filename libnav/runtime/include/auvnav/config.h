#pragma once
/** @file config.h
 *  Typed, checked access to YAML configuration.
 *
 *  One YAML library end to end: libyaml parses (the parser whose checks
 *  accept a document is the one that builds the tree) and libyaml's emitter
 *  writes toYaml(); MRPT's yaml is only the in-memory tree. Scalars are
 *  strings; a plain empty value, ~ or null is a null scalar. Comments are
 *  read and dropped.
 *
 *  Every accessor validates what it returns (present, right type, finite,
 *  in range) and throws ConfigError whose message names the file and the full
 *  key path, e.g. "config/missions/x.yaml: vehicle.mass_kg: expected a
 *  positive number, got '-3'". Nodes are values: a child copies its subtree.
 *
 *  Unknown keys: a node and the children taken from it share one access
 *  record of the keys read (any accessor, has() of a present key,
 *  allowOnly). Once its owner has read everything, checkAllKeysUsed() refuses
 *  the first key nobody read, with the nearest key read or asked for at that
 *  map level: "x.yaml: filter.initial.heading_dg: unknown key (did you mean
 *  'heading_deg'?)". Maps whose content is someone else's (a plugin's config,
 *  comments, metadata) are marked with markFreeForm(). The record is shared
 *  by copies and not synchronised: read one document from one thread.
 */
#include <mrpt/containers/yaml.h>
#include <Eigen/Core>

#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace auvnav::config
{
class ConfigError : public std::runtime_error
{
 public:
	using std::runtime_error::runtime_error;
};

class Node
{
 public:
	/** An empty map node (for default-constructed holders). */
	Node() = default;
	/** Parses a YAML file; throws ConfigError if missing or malformed, with
	 *  one line naming file:line:column. Malformed includes what a YAML
	 *  reader might take silently: a duplicate key (the last would win), a
	 *  second document ('---', '...'), an alias (*name), a key that is not a
	 *  scalar; and a top level that is not a map. */
	static Node load(const std::string& file);
	/** Wraps an in-memory YAML text (for tests); `origin` names it in errors. */
	static Node fromText(const std::string& text, const std::string& origin = "<text>");

	bool has(const std::string& key) const;
	bool isMap() const { return y_.isMap(); }
	/** The value under `key` is a scalar / a list / a map (false if absent). */
	bool isScalar(const std::string& key) const;
	bool isSequence(const std::string& key) const;
	bool isMapAt(const std::string& key) const;
	/** The keys of this map (sorted: MRPT keeps maps ordered). */
	std::vector<std::string> keys() const;
	/** Throws ConfigError naming the first key not in `allowed` (a misspelled
	 *  key must not fall back to a default silently). The allowed keys count
	 *  as read for checkAllKeysUsed(). */
	void allowOnly(const std::vector<std::string>& allowed) const;
	/** The subtree under `key` (if present) is not checked by
	 *  checkAllKeysUsed(): free text, or checked by another reader. */
	void markFreeForm(const std::string& key) const;
	/** Throws ConfigError for the first key of this subtree that was not read
	 *  (nor marked free-form), naming file and key path and suggesting the
	 *  nearest key read or asked for at the same level. Top-level keys in
	 *  `except` (read by someone else later) are skipped with their subtrees. */
	void checkAllKeysUsed(const std::vector<std::string>& except = {}) const;
	/** Required sub-map. */
	Node child(const std::string& key) const;
	/** Required sequence of maps/scalars, as nodes. */
	std::vector<Node> sequence(const std::string& key) const;

	/** Required finite number; optionally within [lo, hi]. */
	double number(const std::string& key) const;
	double number(const std::string& key, double default_value) const;
	double positive(const std::string& key) const;
	double positive(const std::string& key, double default_value) const;
	double nonNegative(const std::string& key) const;
	double nonNegative(const std::string& key, double default_value) const;
	double inRange(const std::string& key, double lo, double hi) const;
	double inRange(const std::string& key, double lo, double hi, double default_value) const;
	int integer(const std::string& key) const;
	int integer(const std::string& key, int default_value) const;
	bool boolean(const std::string& key, bool default_value) const;
	std::string string(const std::string& key) const;
	std::string string(const std::string& key, const std::string& default_value) const;
	/** Required sequence of exactly 3 finite numbers. */
	Eigen::Vector3d vector3(const std::string& key) const;
	Eigen::Vector3d vector3(const std::string& key, const Eigen::Vector3d& default_value) const;
	/** Required sequence of strings (any length >= 1). */
	std::vector<std::string> strings(const std::string& key) const;
	/** Required sequence of finite numbers (any length >= 1). */
	std::vector<double> numbers(const std::string& key) const;

	/** The path given under `key`, resolved relative to the folder of this
	 *  node's file unless it is absolute (file references inside configs). */
	std::string filePath(const std::string& key) const;
	/** The configuration file given under `key` (filePath), loaded; one it
	 *  cannot open fails naming the key, the path and the folder it is
	 *  relative to. */
	Node loadFile(const std::string& key) const;
	/** This subtree as YAML text (to hand a plugin its configuration),
	 *  written by libyaml's emitter: strings are quoted where needed, comments
	 *  are gone, and fromText() of it gives the same tree. */
	std::string toYaml() const;
	/** Sets `dotted.key.path` to the scalar `value` (creating maps on the way),
	 *  for command-line overrides such as `--set filter.initial.heading_deg=25`.
	 *  A list on the way is entered by the `label` of an element or by its
	 *  index: `--set sensors.SONAR.config.mode=update`. */
	void set(const std::string& dotted_path, const std::string& value);

	const std::string& file() const { return file_; }
	/** "file: path.to.key" for error messages. */
	std::string where(const std::string& key) const;
	[[noreturn]] void fail(const std::string& key, const std::string& what) const;

 private:
	/** Which keys of one document were read, shared by a node and its children.
	 *  Paths are full ("filter.initial.heading_deg", "sensors[1].label");
	 *  `asked` keys the names queried per level with list indices dropped
	 *  ("sensors[]"), the candidates for suggestions. */
	struct Access
	{
		std::set<std::string> used, free_form, overridden;
		std::map<std::string, std::set<std::string>> asked;
	};
	Node(const mrpt::containers::yaml& y, std::string file, std::string path, std::shared_ptr<Access> access);
	std::string scalarText(const std::string& key) const;
	std::string fullPath(const std::string& key) const;
	/** Records that `key` was asked for here; present keys become "used". */
	void noteAccess(const std::string& key) const;
	void checkUnder(const mrpt::containers::yaml& y, const std::string& path,
	                const std::vector<std::string>& except) const;

	mrpt::containers::yaml y_;
	std::string file_;
	std::string path_;
	std::shared_ptr<Access> access_ = std::make_shared<Access>();
};

}  // namespace auvnav::config
