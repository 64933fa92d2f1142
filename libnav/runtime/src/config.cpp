// Node (config.h): loading a file or text, paths and error places, the YAML
// text of a subtree, and command-line overrides. Parsing and emitting:
// config_yaml_*.cpp; key bookkeeping: config_keys.cpp; accessors:
// config_values.cpp.
#include <auvnav/config.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "config_yaml.h"

namespace auvnav::config
{
using mrpt::containers::yaml;

Node::Node(const yaml& y, std::string file, std::string path, std::shared_ptr<Access> access)
    : y_(y), file_(std::move(file)), path_(std::move(path)), access_(std::move(access))
{
}

Node Node::load(const std::string& file)
{
	std::ifstream f(file);
	if (!f) throw ConfigError(file + ": cannot open configuration file");
	std::stringstream ss;
	ss << f.rdbuf();
	return fromText(ss.str(), file);
}

Node Node::fromText(const std::string& text, const std::string& origin)
{
	yaml::node_t root;
	if (!detail::parseDocument(text, origin, root) || !root.isMap())
		throw ConfigError(origin + ": top level must be a YAML map");
	yaml y;
	y.node() = root;
	return Node(y, origin, "", std::make_shared<Access>());
}

std::string Node::filePath(const std::string& key) const
{
	std::string p = string(key);
	if (p.empty()) fail(key, "expected a file path");
	if (p[0] == '/') return p;
	const auto slash = file_.find_last_of('/');
	return slash == std::string::npos ? p : file_.substr(0, slash + 1) + p;
}

Node Node::loadFile(const std::string& key) const
{
	const std::string path = filePath(key);
	if (!std::ifstream(path))
	{
		const std::string given = string(key);
		std::error_code ec;
		const auto absolute = std::filesystem::absolute(path, ec);
		fail(key,
		     "cannot open '" + given + "'" +
		         (given[0] == '/' ? std::string()
		                          : " (looked for " + (ec ? path : absolute.lexically_normal().string()) +
		                                ": a relative path is taken from the folder of " + file_ + ")"));
	}
	return load(path);
}

std::string Node::toYaml() const
{
	if (y_.isNullNode() || (y_.isMap() && y_.empty())) return "{}\n";
	return detail::emitDocument(y_.node(), file_ + (path_.empty() ? "" : ": " + path_));
}

void Node::set(const std::string& dotted_path, const std::string& value)
{
	std::vector<std::string> keys;
	std::stringstream ss(dotted_path);
	for (std::string k; std::getline(ss, k, '.');)
	{
		if (k.empty()) throw ConfigError("override '" + dotted_path + "': empty key");
		keys.push_back(k);
	}
	if (keys.empty()) throw ConfigError("override: empty key path");
	yaml::node_t* n = &y_.node();
	std::string walked;
	std::string canonical = path_;  // list elements by index, as checkAllKeysUsed() names them
	for (std::size_t i = 0; i < keys.size(); ++i)
	{
		if (n->isSequence())
		{
			// A list is entered by an element's `label` (sensors.SONAR.config.mode)
			// or by its index.
			yaml::node_t* found = nullptr;
			auto& seq = n->asSequence();
			const bool numeric = keys[i].find_first_not_of("0123456789") == std::string::npos;
			for (std::size_t j = 0; j < seq.size() && !found; ++j)
			{
				if (numeric && std::stoul(keys[i]) == j)
					found = &seq[j];
				else if (seq[j].isMap())
				{
					const auto& m = seq[j].asMap();
					const auto it = m.find(yaml::node_t("label"));
					if (it != m.end() && it->second.isScalar() && it->second.as<std::string>() == keys[i])
						found = &seq[j];
				}
			}
			if (!found)
				throw ConfigError(file_ + ": override '" + dotted_path + "': no element '" + keys[i] +
				                  "' (label or index) in '" + walked + "'");
			n = found;
			walked += (walked.empty() ? "" : ".") + keys[i];
			canonical += "[" + std::to_string(found - &seq[0]) + "]";
			continue;
		}
		if (n->isNullNode()) n->d.emplace<yaml::map_t>();
		if (!n->isMap())
			throw ConfigError(file_ + ": override '" + dotted_path + "': '" + walked + "' is not a map");
		auto& m = n->asMap();
		n = &m[yaml::node_t(keys[i])];
		walked += (walked.empty() ? "" : ".") + keys[i];
		canonical += (canonical.empty() ? "" : ".") + keys[i];
		access_->overridden.insert(canonical);
	}
	n->d.emplace<yaml::scalar_t>().emplace<std::string>(value);
}

std::string Node::where(const std::string& key) const
{
	return file_ + ": " + (path_.empty() ? key : path_ + "." + key);
}

void Node::fail(const std::string& key, const std::string& what) const
{
	throw ConfigError(where(key) + ": " + what);
}

std::string Node::fullPath(const std::string& key) const
{
	return path_.empty() ? key : path_ + "." + key;
}

}  // namespace auvnav::config
