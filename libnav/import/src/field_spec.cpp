#include "field_spec.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace auvnav::import::detail
{
namespace
{
std::string replaceAll(std::string s, const std::string& from, const std::string& to)
{
	for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size()))
		s.replace(p, from.size(), to);
	return s;
}

void parseCommon(const config::Node& q, ScalarSpec& s, UnitKind kind)
{
	const std::string unit = q.string("unit", kind == UnitKind::Dimensionless ? "1" : "");
	if (unit.empty())
		q.fail("unit", "missing unit (" + std::string(kindName(kind)) + ": " + unitsOfKind(kind) + ")");
	try
	{
		s.unit = unitFor(unit, kind, q.where("unit"));
	}
	catch (const ImportError& e)
	{
		throw config::ConfigError(e.what());
	}
	s.optional = q.boolean("optional", false);
	if (q.has("invalid")) s.invalid_raw = q.numbers("invalid");
}
}  // namespace

std::string ScalarSpec::fieldFor(int index) const
{
	if (field.find('{') == std::string::npos) return field;
	return replaceAll(replaceAll(field, "{i}", std::to_string(index)), "{n}", std::to_string(index + 1));
}

ScalarSpec parseScalar(const config::Node& n, const std::string& key, UnitKind kind)
{
	ScalarSpec s;
	s.where = n.where(key);
	if (!n.has(key)) return s;
	s.present = true;
	if (n.isScalar(key))
	{
		// Shorthand for a dimensionless field: `valid: beam_valid`.
		if (kind != UnitKind::Dimensionless)
			n.fail(key, "expected {field: NAME, unit: UNIT} or {value: NUMBER, unit: UNIT}");
		s.field = n.string(key);
		return s;
	}
	const config::Node q = n.child(key);
	q.allowOnly({"field", "value", "unit", "optional", "invalid"});
	if (q.has("field") == q.has("value")) n.fail(key, "give exactly one of 'field' and 'value'");
	parseCommon(q, s, kind);
	if (q.has("field"))
		s.field = q.string("field");
	else
	{
		s.is_constant = true;
		s.constant_si = s.unit.toSi(q.number("value"));
	}
	return s;
}

std::vector<ScalarSpec> parseVector(const config::Node& n, const std::string& key, UnitKind kind,
                                    std::size_t count)
{
	std::vector<ScalarSpec> out(count);
	for (auto& s : out) s.where = n.where(key);
	if (!n.has(key)) return out;
	const config::Node q = n.child(key);
	q.allowOnly({"fields", "values", "unit", "optional", "invalid"});
	if (q.has("fields") == q.has("values")) n.fail(key, "give exactly one of 'fields' and 'values'");
	ScalarSpec common;
	parseCommon(q, common, kind);
	common.present = true;
	common.where = n.where(key);
	// Either list gives exactly one entry per element.
	const auto checkLength = [&](const char* list, std::size_t length, const char* what)
	{
		if (length != count)
			q.fail(list,
			       "expected " + std::to_string(count) + " " + what + ", got " + std::to_string(length));
	};
	if (q.has("fields"))
	{
		const auto names = q.strings("fields");
		checkLength("fields", names.size(), "names");
		for (std::size_t i = 0; i < count; ++i)
		{
			out[i] = common;
			out[i].field = names[i];
		}
	}
	else
	{
		const auto values = q.numbers("values");
		checkLength("values", values.size(), "numbers");
		for (std::size_t i = 0; i < count; ++i)
		{
			out[i] = common;
			out[i].is_constant = true;
			out[i].constant_si = common.unit.toSi(values[i]);
		}
	}
	return out;
}

int Columns::index(const Record& r, const std::string& name)
{
	if (r.layout_id != layout_)
	{
		cache_.clear();
		layout_ = r.layout_id;
	}
	for (const auto& [n, i] : cache_)
		if (n == name) return i;
	const int i = r.indexOf(name);
	cache_.emplace_back(name, i);
	return i;
}

Read readNumber(const Value& v, double& out, std::string& why)
{
	switch (v.kind)
	{
		case Value::Kind::Missing:
			return Read::Missing;
		case Value::Kind::Number:
			out = v.number;
			return Read::Ok;
		case Value::Kind::Time:
			why = "is a time stamp, not a number";
			return Read::Bad;
		case Value::Kind::Text:
		{
			const char* b = v.text.c_str();
			char* e = nullptr;
			out = std::strtod(b, &e);
			while (e && (*e == ' ' || *e == '\t')) ++e;
			// The whole cell must be the number (an embedded NUL ends c_str early).
			if (e == b || !e || e != b + v.text.size())
			{
				if (v.text == "true" || v.text == "True" || v.text == "TRUE")
				{
					out = 1;
					return Read::Ok;
				}
				if (v.text == "false" || v.text == "False" || v.text == "FALSE")
				{
					out = 0;
					return Read::Ok;
				}
				why = "'" + v.text.substr(0, 40) + "' is not a number";
				return Read::Bad;
			}
			return Read::Ok;
		}
	}
	return Read::Bad;
}

Read readScalar(const ScalarSpec& s, const Record& r, Columns& cols, double& out_si, std::string& why,
                int index, double* raw_out)
{
	if (!s.present) return Read::Missing;
	if (s.is_constant)
	{
		out_si = s.constant_si;
		if (raw_out) *raw_out = (s.constant_si - s.unit.offset) / s.unit.factor;
		return Read::Ok;
	}
	const std::string name = s.fieldFor(index);
	const int i = cols.index(r, name);
	if (i < 0)
	{
		if (s.optional) return Read::Missing;
		why = "no field '" + name + "'";
		return Read::Bad;
	}
	double raw = 0;
	const Read res = readNumber(r.values[static_cast<std::size_t>(i)], raw, why);
	if (res == Read::Bad) why = "field '" + name + "': " + why;
	if (res != Read::Ok) return res;
	// Relative tolerance: a driver's -32768 × 0.001 need not be the double nearest -32.768.
	for (double bad : s.invalid_raw)
		if (std::abs(raw - bad) <= 1e-9 * std::max(1.0, std::abs(bad))) return Read::Missing;
	out_si = s.unit.toSi(raw);
	if (raw_out) *raw_out = raw;
	return Read::Ok;
}

bool readOptional(const ScalarSpec& s, const Record& r, Columns& cols, double& out_si, std::string& why)
{
	out_si = NAN;
	return readScalar(s, r, cols, out_si, why) != Read::Bad;
}

TextSpec parseText(const config::Node& n, const std::string& key)
{
	TextSpec t;
	t.where = n.where(key);
	if (!n.has(key)) return t;
	t.present = true;
	if (n.isScalar(key))
	{
		t.constant = n.string(key);
		return t;
	}
	const config::Node q = n.child(key);
	q.allowOnly({"field", "map"});
	t.is_constant = false;
	t.field = q.string("field");
	if (q.has("map"))
	{
		const config::Node m = q.child("map");
		for (const auto& k : m.keys()) t.map.emplace_back(k, m.string(k));
	}
	return t;
}

bool readText(const TextSpec& t, const Record& r, Columns& cols, std::string& out, std::string& why,
              bool empty_ok)
{
	if (t.is_constant)
	{
		out = t.constant;
		return true;
	}
	const int i = cols.index(r, t.field);
	if (i < 0)
	{
		why = "no field '" + t.field + "'";
		return false;
	}
	const Value& v = r.values[static_cast<std::size_t>(i)];
	std::string raw;
	if (v.kind == Value::Kind::Text)
		raw = v.text;
	else if (v.kind == Value::Kind::Number)
	{
		// Integers as integers, so that `map: {"3": earth_enu}` matches 3.0.
		const double x = v.number;
		raw = (std::floor(x) == x && std::abs(x) < 1e15) ? std::to_string(static_cast<long long>(x))
		                                                 : std::to_string(x);
	}
	else if (empty_ok && t.map.empty())
	{
		out.clear();
		return true;
	}
	else
	{
		why = "field '" + t.field + "' is empty";
		return false;
	}
	if (t.map.empty())
	{
		out = raw;
		return true;
	}
	// A numeric text cell ("3" or "3.0") matches an integer key.
	std::string key = raw;
	{
		char* e = nullptr;
		const double x = std::strtod(raw.c_str(), &e);
		if (e && *e == '\0' && e != raw.c_str() && std::floor(x) == x && std::abs(x) < 1e15)
			key = std::to_string(static_cast<long long>(x));
	}
	for (const auto& [from, to] : t.map)
		if (from == raw || from == key)
		{
			out = to;
			return true;
		}
	why = "field '" + t.field + "': value '" + raw + "' is not in its map";
	return false;
}

}  // namespace auvnav::import::detail
