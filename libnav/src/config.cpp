#include <algorithm>
#include <auvnav/config.h>
#include <yaml.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace auvnav::config
{
using mrpt::containers::yaml;

Node::Node(yaml y, std::string file, std::string path)
	: y_(std::move(y)), file_(std::move(file)), path_(std::move(path))
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

namespace
{
/** MRPT's YAML reader reports some syntax errors on stderr and returns a
 *  partial document; run libyaml's parser first so a broken file is refused
 *  with its line and column. */
void checkSyntax(const std::string& text, const std::string& origin)
{
	yaml_parser_t parser;
	if (!yaml_parser_initialize(&parser)) throw ConfigError(origin + ": cannot initialise the YAML parser");
	yaml_parser_set_input_string(&parser, reinterpret_cast<const unsigned char*>(text.data()), text.size());
	std::string error;
	for (bool done = false; !done;)
	{
		yaml_event_t event;
		if (!yaml_parser_parse(&parser, &event))
		{
			std::ostringstream m;
			m << origin << ":" << parser.problem_mark.line + 1 << ":" << parser.problem_mark.column + 1
			  << ": malformed YAML: " << (parser.problem ? parser.problem : "syntax error");
			if (parser.context) m << " " << parser.context;
			error = m.str();
			break;
		}
		done = event.type == YAML_STREAM_END_EVENT;
		yaml_event_delete(&event);
	}
	yaml_parser_delete(&parser);
	if (!error.empty()) throw ConfigError(error);
}
}  // namespace

Node Node::fromText(const std::string& text, const std::string& origin)
{
	checkSyntax(text, origin);
	try
	{
		yaml y = yaml::FromText(text);
		if (!y.isMap()) throw ConfigError(origin + ": top level must be a YAML map");
		return Node(std::move(y), origin, "");
	}
	catch (const ConfigError&)
	{
		throw;
	}
	catch (const std::exception& e)
	{
		throw ConfigError(origin + ": malformed YAML: " + e.what());
	}
}

std::string Node::filePath(const std::string& key) const
{
	const std::string p = string(key);
	if (p.empty()) fail(key, "expected a file path");
	if (p[0] == '/') return p;
	const auto slash = file_.find_last_of('/');
	return slash == std::string::npos ? p : file_.substr(0, slash + 1) + p;
}

std::string Node::toYaml() const
{
	if (y_.isNullNode() || (y_.isMap() && y_.empty())) return "{}\n";
	std::ostringstream o;
	y_.printAsYAML(o);
	return o.str();
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
				if (numeric && std::stoul(keys[i]) == j) found = &seq[j];
				else if (seq[j].isMap())
				{
					const auto& m = seq[j].asMap();
					const auto it = m.find(yaml::node_t("label"));
					if (it != m.end() && it->second.isScalar() && it->second.as<std::string>() == keys[i]) found = &seq[j];
				}
			}
			if (!found)
				throw ConfigError(file_ + ": override '" + dotted_path + "': no element '" + keys[i] + "' (label or index) in '" +
								  walked + "'");
			n = found;
			walked += (walked.empty() ? "" : ".") + keys[i];
			continue;
		}
		if (n->isNullNode()) n->d.emplace<yaml::map_t>();
		if (!n->isMap())
			throw ConfigError(file_ + ": override '" + dotted_path + "': '" + walked + "' is not a map");
		auto& m = n->asMap();
		n = &m[yaml::node_t(keys[i])];
		walked += (walked.empty() ? "" : ".") + keys[i];
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

bool Node::has(const std::string& key) const { return y_.isMap() && y_.has(key); }
bool Node::isScalar(const std::string& key) const { return has(key) && yaml(y_[key].node()).isScalar(); }
bool Node::isSequence(const std::string& key) const { return has(key) && yaml(y_[key].node()).isSequence(); }
bool Node::isMapAt(const std::string& key) const { return has(key) && yaml(y_[key].node()).isMap(); }

std::vector<std::string> Node::keys() const
{
	std::vector<std::string> out;
	if (!y_.isMap()) return out;
	for (const auto& kv : y_.asMap()) out.push_back(kv.first.as<std::string>());
	return out;
}

void Node::allowOnly(const std::vector<std::string>& allowed) const
{
	for (const auto& k : keys())
		if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
		{
			std::string list;
			for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
			fail(k, "unknown key (expected one of: " + list + ")");
		}
}

Node Node::child(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required section");
	yaml sub(y_[key].node());
	if (!sub.isMap()) fail(key, "expected a map of keys");
	return Node(std::move(sub), file_, path_.empty() ? key : path_ + "." + key);
}

std::vector<Node> Node::sequence(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required list");
	yaml sub(y_[key].node());
	if (!sub.isSequence()) fail(key, "expected a list");
	std::vector<Node> out;
	const auto& seq = sub.asSequence();
	for (std::size_t i = 0; i < seq.size(); ++i)
		out.push_back(Node(yaml(seq[i]), file_,
						   (path_.empty() ? key : path_ + "." + key) + "[" + std::to_string(i) + "]"));
	return out;
}

std::string Node::scalarText(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required value");
	const yaml v = y_[key];
	if (!v.isScalar()) fail(key, "expected a single value");
	try
	{
		return v.as<std::string>();
	}
	catch (const std::exception&)
	{
		fail(key, "unreadable value");
	}
}

namespace
{
bool parseFinite(const std::string& s, double& out)
{
	const char* b = s.c_str();
	char* e = nullptr;
	out = std::strtod(b, &e);
	while (e && *e == ' ') ++e;
	return e != b && e && *e == '\0' && std::isfinite(out);
}
}  // namespace

double Node::number(const std::string& key) const
{
	const std::string s = scalarText(key);
	double v = 0;
	if (!parseFinite(s, v)) fail(key, "expected a finite number, got '" + s + "'");
	return v;
}
double Node::number(const std::string& key, double d) const { return has(key) ? number(key) : d; }

double Node::positive(const std::string& key) const
{
	const double v = number(key);
	if (!(v > 0)) fail(key, "expected a positive number, got '" + scalarText(key) + "'");
	return v;
}
double Node::positive(const std::string& key, double d) const { return has(key) ? positive(key) : d; }

double Node::nonNegative(const std::string& key) const
{
	const double v = number(key);
	if (!(v >= 0)) fail(key, "expected a number >= 0, got '" + scalarText(key) + "'");
	return v;
}
double Node::nonNegative(const std::string& key, double d) const
{
	return has(key) ? nonNegative(key) : d;
}

double Node::inRange(const std::string& key, double lo, double hi) const
{
	const double v = number(key);
	if (v < lo || v > hi)
	{
		std::ostringstream m;
		m << "expected a number in [" << lo << ", " << hi << "], got '" << scalarText(key) << "'";
		fail(key, m.str());
	}
	return v;
}
double Node::inRange(const std::string& key, double lo, double hi, double d) const
{
	return has(key) ? inRange(key, lo, hi) : d;
}

int Node::integer(const std::string& key) const
{
	const double v = number(key);
	if (std::floor(v) != v || std::abs(v) > 2e9)
		fail(key, "expected an integer, got '" + scalarText(key) + "'");
	return static_cast<int>(v);
}
int Node::integer(const std::string& key, int d) const { return has(key) ? integer(key) : d; }

bool Node::boolean(const std::string& key, bool d) const
{
	if (!has(key)) return d;
	const std::string s = scalarText(key);
	if (s == "true" || s == "True" || s == "yes" || s == "1") return true;
	if (s == "false" || s == "False" || s == "no" || s == "0") return false;
	fail(key, "expected true or false, got '" + s + "'");
}

std::string Node::string(const std::string& key) const { return scalarText(key); }
std::string Node::string(const std::string& key, const std::string& d) const
{
	return has(key) ? string(key) : d;
}

std::vector<double> Node::numbers(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required list of numbers");
	yaml sub(y_[key].node());
	if (!sub.isSequence() || sub.asSequence().empty()) fail(key, "expected a non-empty list of numbers");
	std::vector<double> out;
	for (const auto& n : sub.asSequence())
	{
		double v = 0;
		std::string s;
		try
		{
			s = yaml(n).as<std::string>();
		}
		catch (const std::exception&)
		{
			fail(key, "expected a list of numbers");
		}
		if (!parseFinite(s, v)) fail(key, "expected finite numbers, got '" + s + "'");
		out.push_back(v);
	}
	return out;
}

std::vector<std::string> Node::strings(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required list");
	yaml sub(y_[key].node());
	if (!sub.isSequence() || sub.asSequence().empty()) fail(key, "expected a non-empty list");
	std::vector<std::string> out;
	for (const auto& n : sub.asSequence())
	{
		if (!yaml(n).isScalar()) fail(key, "expected a list of names");
		out.push_back(yaml(n).as<std::string>());
	}
	return out;
}

Eigen::Vector3d Node::vector3(const std::string& key) const
{
	const auto v = numbers(key);
	if (v.size() != 3) fail(key, "expected exactly 3 numbers, got " + std::to_string(v.size()));
	return {v[0], v[1], v[2]};
}
Eigen::Vector3d Node::vector3(const std::string& key, const Eigen::Vector3d& d) const
{
	return has(key) ? vector3(key) : d;
}

}  // namespace auvnav::config
