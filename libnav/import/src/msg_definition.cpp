// The ROS message-definition parser (msg_definition.h): definition text split
// into sections, type tokens and builtins resolved, linked into a Schema.
#include "msg_definition.h"

#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace auvnav::import::msg
{
namespace
{
// Larger fixed arrays are taken for a corrupt definition.
constexpr uint32_t kMaxFixedArray = 1u << 24;

// ---------------------------------------------------------------- text helpers

std::string_view trim(std::string_view s)
{
	const auto first = s.find_first_not_of(" \t\r\n");
	if (first == std::string_view::npos) return {};
	const auto last = s.find_last_not_of(" \t\r\n");
	return s.substr(first, last - first + 1);
}

bool isIdentChar(char c)
{
	return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

bool isSeparatorLine(std::string_view line)
{
	line = trim(line);
	return line.size() >= 3 && line.find_first_not_of('=') == std::string_view::npos;
}

std::optional<uint32_t> parseCount(std::string_view digits)
{
	if (digits.empty() || digits.size() > 10) return std::nullopt;
	uint64_t v = 0;
	for (char c : digits)
	{
		if (c < '0' || c > '9') return std::nullopt;
		v = v * 10 + static_cast<uint64_t>(c - '0');
	}
	if (v > std::numeric_limits<uint32_t>::max()) return std::nullopt;
	return static_cast<uint32_t>(v);
}

std::string packageOf(const std::string& type_name)
{
	const auto slash = type_name.find('/');
	return slash == std::string::npos ? std::string() : type_name.substr(0, slash);
}

// ---------------------------------------------------------------- builtins

struct Builtin
{
	const char* name;
	FieldType type;
};

std::optional<FieldType> builtinType(std::string_view name, Dialect dialect)
{
	static const Builtin kCommon[] = {
	    {"bool", FieldType::Bool},     {"char", FieldType::UInt8},      {"int8", FieldType::Int8},
	    {"uint8", FieldType::UInt8},   {"int16", FieldType::Int16},     {"uint16", FieldType::UInt16},
	    {"int32", FieldType::Int32},   {"uint32", FieldType::UInt32},   {"int64", FieldType::Int64},
	    {"uint64", FieldType::UInt64}, {"float32", FieldType::Float32}, {"float64", FieldType::Float64},
	    {"string", FieldType::String}, {"time", FieldType::Time},       {"duration", FieldType::Duration},
	};
	for (const Builtin& b : kCommon)
		if (name == b.name) return b.type;
	// ROS 1 `byte` is a deprecated int8; ROS 2 `byte` is an octet.
	if (name == "byte") return dialect == Dialect::Ros1 ? FieldType::Int8 : FieldType::UInt8;
	if (dialect == Dialect::Ros2)
	{
		if (name == "builtin_interfaces/Time") return FieldType::Time;
		if (name == "builtin_interfaces/Duration") return FieldType::Duration;
	}
	return std::nullopt;
}

// ---------------------------------------------------------------- sections

/** One type's text inside a definition. */
struct Section
{
	std::string_view text;
	int first_line = 1;  // line number of `text`'s first line in the whole definition
	std::string origin;  // "definition of pkg/Main" or "bundled definition of pkg/T"
};

/** Splits a full definition into the main type's section and the `MSG:` ones. */
std::map<std::string, Section> splitSections(const std::string& main_type, std::string_view text)
{
	std::map<std::string, Section> sections;
	const std::string origin = "definition of " + main_type;
	std::string current = main_type;
	std::size_t section_start = 0;
	int section_line = 1;
	int line_no = 0;
	std::size_t pos = 0;
	bool expect_header = false;  // after a separator: the next non-empty line is `MSG: ...`
	auto closeSection = [&](std::size_t end)
	{
		if (!current.empty() && !sections.count(current))
			sections[current] =
			    Section{text.substr(section_start, end - section_start), section_line, origin};
	};
	while (pos <= text.size())
	{
		const std::size_t eol = std::min(text.find('\n', pos), text.size());
		const std::string_view line = text.substr(pos, eol - pos);
		++line_no;
		const std::size_t next = eol + 1;
		if (expect_header)
		{
			const std::string_view t = trim(line);
			if (!t.empty())
			{
				if (t.substr(0, 4) == "IDL:")
					throw DefinitionError(origin + ", line " + std::to_string(line_no) +
					                      ": IDL sections are not supported (only .msg syntax)");
				if (t.substr(0, 4) != "MSG:")
					throw DefinitionError(origin + ", line " + std::to_string(line_no) +
					                      ": expected 'MSG: pkg/Type' after the '=' line, found '" +
					                      std::string(t) + "'");
				current = normalizeTypeName(trim(t.substr(4)));
				if (current.empty())
					throw DefinitionError(origin + ", line " + std::to_string(line_no) +
					                      ": 'MSG:' without a type name");
				section_start = std::min(next, text.size());
				section_line = line_no + 1;
				expect_header = false;
			}
		}
		else if (isSeparatorLine(line))
		{
			closeSection(pos);
			expect_header = true;
		}
		pos = next;
	}
	if (!expect_header) closeSection(text.size());
	return sections;
}

// ---------------------------------------------------------------- type tokens

struct TypeToken
{
	std::string base;  // `string<=N` reduced to `string`
	ArrayKind array = ArrayKind::None;
	uint32_t fixed_size = 0;
};

std::optional<TypeToken> parseTypeToken(std::string_view token)
{
	TypeToken t;
	std::string_view base = token;
	const auto bracket = token.find('[');
	if (bracket != std::string_view::npos)
	{
		if (token.back() != ']') return std::nullopt;
		base = token.substr(0, bracket);
		const std::string_view inner = token.substr(bracket + 1, token.size() - bracket - 2);
		if (inner.empty() || inner.substr(0, 2) == "<=")
		{
			if (!inner.empty() && !parseCount(inner.substr(2))) return std::nullopt;
			t.array = ArrayKind::Sequence;
		}
		else
		{
			const auto n = parseCount(inner);
			if (!n || *n > kMaxFixedArray) return std::nullopt;
			t.array = ArrayKind::Fixed;
			t.fixed_size = *n;
		}
	}
	const auto bound = base.find("<=");
	if (bound != std::string_view::npos)
	{
		// Only strings may be bounded: `string<=N`, `wstring<=N`.
		const std::string_view b = base.substr(0, bound);
		if ((b != "string" && b != "wstring") || !parseCount(base.substr(bound + 2))) return std::nullopt;
		base = b;
	}
	if (base.empty()) return std::nullopt;
	t.base = std::string(base);
	return t;
}

}  // namespace

std::string normalizeTypeName(std::string_view name)
{
	name = trim(name);
	const auto first = name.find('/');
	if (first != std::string_view::npos)
	{
		const auto second = name.find('/', first + 1);
		if (second != std::string_view::npos && name.substr(first + 1, second - first - 1) == "msg")
			return std::string(name.substr(0, first + 1)) + std::string(name.substr(second + 1));
	}
	return std::string(name);
}

// ---------------------------------------------------------------- schema builder

/** Parses and links the types reachable from the main type, depth first. */
class SchemaBuilder
{
 public:
	SchemaBuilder(std::string_view type_name, std::string_view text, Dialect dialect,
	              const DefinitionFallback& fallback)
	    : main_(normalizeTypeName(type_name)), dialect_(dialect), fallback_(fallback)
	{
		if (main_.empty()) throw DefinitionError("message definition without a type name");
		sections_ = splitSections(main_, text);
	}

	std::shared_ptr<const Schema> build()
	{
		schema_.reset(new Schema());
		schema_->dialect_ = dialect_;
		resolve(main_, "", 0);
		return schema_;
	}

 private:
	const MessageDef* resolve(const std::string& name, const std::string& used_by, std::size_t depth)
	{
		const auto done = index_.find(name);
		if (done != index_.end())
		{
			if (in_progress_.count(name))
				throw DefinitionError("type " + name + " contains itself (through " + used_by + ")");
			return schema_->messages_[done->second].get();
		}
		if (depth > kMaxNesting)
			throw DefinitionError("types nested more than " + std::to_string(kMaxNesting) + " deep at " +
			                      name);
		const Section section = findSection(name, used_by);

		auto def = std::make_unique<MessageDef>();
		def->name = name;
		def->index = schema_->messages_.size();
		MessageDef* raw = def.get();
		index_[name] = raw->index;
		schema_->messages_.push_back(std::move(def));
		in_progress_.insert(name);
		parseFields(section, *raw, depth);
		in_progress_.erase(name);
		return raw;
	}

	Section findSection(const std::string& name, const std::string& used_by)
	{
		const auto it = sections_.find(name);
		if (it != sections_.end()) return it->second;
		if (fallback_)
			if (const char* text = fallback_(name))
				return Section{std::string_view(text), 1, "bundled definition of " + name};
		throw DefinitionError("no definition of type " + name +
		                      (used_by.empty() ? std::string() : " (used by " + used_by + ")"));
	}

	void parseFields(const Section& section, MessageDef& def, std::size_t depth)
	{
		int line_no = section.first_line;
		std::size_t pos = 0;
		const std::string_view text = section.text;
		while (pos < text.size())
		{
			const std::size_t eol = std::min(text.find('\n', pos), text.size());
			parseLine(text.substr(pos, eol - pos), section, line_no, def, depth);
			pos = eol + 1;
			++line_no;
		}
	}

	void parseLine(std::string_view line, const Section& section, int line_no, MessageDef& def,
	               std::size_t depth)
	{
		const auto fail = [&](const std::string& why)
		{ throw DefinitionError(section.origin + ", line " + std::to_string(line_no) + ": " + why); };
		const auto hash = line.find('#');
		if (hash != std::string_view::npos) line = line.substr(0, hash);
		line = trim(line);
		if (line.empty()) return;

		const auto space = line.find_first_of(" \t");
		if (space == std::string_view::npos) fail("expected 'type name', found '" + std::string(line) + "'");
		const std::string_view type_token = line.substr(0, space);
		const std::string_view rest = trim(line.substr(space));
		std::size_t name_len = 0;
		while (name_len < rest.size() && isIdentChar(rest[name_len])) ++name_len;
		const std::string_view after = trim(rest.substr(name_len));
		if (!after.empty() && after.front() == '=') return;  // a constant, not a field
		if (name_len == 0) fail("expected a field name after '" + std::string(type_token) + "'");

		const auto type = parseTypeToken(type_token);
		if (!type) fail("cannot read type '" + std::string(type_token) + "'");
		FieldDef field;
		field.name = std::string(rest.substr(0, name_len));
		field.array = type->array;
		field.fixed_size = type->fixed_size;
		resolveType(*type, field, def, depth, fail);
		def.fields.push_back(std::move(field));
	}

	template <class Fail>
	void resolveType(const TypeToken& token, FieldDef& field, const MessageDef& owner, std::size_t depth,
	                 const Fail& fail)
	{
		if (token.base == "wstring") fail("type wstring is not supported");
		const std::string base = normalizeTypeName(token.base);
		if (const auto builtin = builtinType(base, dialect_))
		{
			field.type = *builtin;
			field.type_name = base;
			return;
		}
		field.type = FieldType::Message;
		if (base.find('/') != std::string::npos)
			field.type_name = base;
		else if (base == "Header")
			field.type_name = "std_msgs/Header";
		else
		{
			const std::string package = packageOf(owner.name);
			field.type_name = package.empty() ? base : package + "/" + base;
		}
		field.message = resolve(field.type_name, owner.name + "." + field.name, depth + 1);
	}

	std::string main_;
	Dialect dialect_;
	const DefinitionFallback& fallback_;
	std::map<std::string, Section> sections_;
	std::map<std::string, std::size_t> index_;
	std::set<std::string> in_progress_;  // being parsed: meeting one again is a cycle
	std::shared_ptr<Schema> schema_;
};

std::shared_ptr<const Schema> Schema::parse(std::string_view type_name, std::string_view text,
                                            Dialect dialect, const DefinitionFallback& fallback)
{
	return SchemaBuilder(type_name, text, dialect, fallback).build();
}

}  // namespace auvnav::import::msg
