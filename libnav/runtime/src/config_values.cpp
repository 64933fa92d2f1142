// Node's typed accessors (config.h): sections, lists and scalars, each checked
// (present, right type, finite, in range) before it is returned.
#include <auvnav/config.h>

#include <cmath>
#include <cstdlib>
#include <sstream>

namespace auvnav::config
{
using mrpt::containers::yaml;

bool Node::isScalar(const std::string& key) const
{
	return has(key) && yaml(y_[key].node()).isScalar();
}
bool Node::isSequence(const std::string& key) const
{
	return has(key) && yaml(y_[key].node()).isSequence();
}
bool Node::isMapAt(const std::string& key) const
{
	return has(key) && yaml(y_[key].node()).isMap();
}

std::vector<std::string> Node::keys() const
{
	std::vector<std::string> out;
	if (!y_.isMap()) return out;
	for (const auto& kv : y_.asMap()) out.push_back(kv.first.as<std::string>());
	return out;
}

Node Node::child(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required section");
	yaml sub(y_[key].node());
	if (!sub.isMap()) fail(key, "expected a map of keys");
	return Node(sub, file_, fullPath(key), access_);
}

std::vector<Node> Node::sequence(const std::string& key) const
{
	if (!has(key)) fail(key, "missing required list");
	yaml sub(y_[key].node());
	if (!sub.isSequence()) fail(key, "expected a list");
	std::vector<Node> out;
	const auto& seq = sub.asSequence();
	for (std::size_t i = 0; i < seq.size(); ++i)
		out.push_back(Node(yaml(seq[i]), file_, fullPath(key) + "[" + std::to_string(i) + "]", access_));
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
double Node::number(const std::string& key, double d) const
{
	return has(key) ? number(key) : d;
}

double Node::positive(const std::string& key) const
{
	const double v = number(key);
	if (!(v > 0)) fail(key, "expected a positive number, got '" + scalarText(key) + "'");
	return v;
}
double Node::positive(const std::string& key, double d) const
{
	return has(key) ? positive(key) : d;
}

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
int Node::integer(const std::string& key, int d) const
{
	return has(key) ? integer(key) : d;
}

bool Node::boolean(const std::string& key, bool d) const
{
	if (!has(key)) return d;
	const std::string s = scalarText(key);
	if (s == "true" || s == "True" || s == "yes" || s == "1") return true;
	if (s == "false" || s == "False" || s == "no" || s == "0") return false;
	fail(key, "expected true or false, got '" + s + "'");
}

std::string Node::string(const std::string& key) const
{
	return scalarText(key);
}
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
