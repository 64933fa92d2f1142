#include "msg_definition.h"

#include <atomic>
#include <cstring>
#include <iomanip>
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
// Values per message; a count beyond this is taken for corrupt data.
constexpr std::size_t kMaxFields = std::size_t{1} << 22;
// Elements of a sequence whose element type has no bytes (an empty ROS 1
// message) cannot be checked against the remaining bytes; cap them instead.
constexpr uint32_t kMaxEmptyElements = 1u << 20;
// CDR writers may pad the end of a message up to the next 4 or 8 bytes.
constexpr std::size_t kMaxCdrTrailingPadding = 7;
// Nested message depth: deeper is taken for a corrupt definition.
constexpr std::size_t kMaxNesting = 64;

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

// ---------------------------------------------------------------- wire readers

namespace
{
constexpr bool kHostLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

template <class T>
T byteSwapped(T v)
{
	unsigned char b[sizeof(T)];
	std::memcpy(b, &v, sizeof(T));
	for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
	std::memcpy(&v, b, sizeof(T));
	return v;
}

/** Bounds-checked reads of one message. kCdr: XCDR1 alignment relative to the
 *  byte after the encapsulation header, NUL-terminated strings, ROS 2 Time.
 *  Every read returns false, consuming nothing, when the bytes run out. */
template <bool kCdr>
class WireReader
{
 public:
	WireReader(const uint8_t* data, std::size_t size, std::size_t origin, bool swap)
	    : data_(data), size_(size), pos_(origin), origin_(origin), swap_(swap)
	{
	}

	std::size_t offset() const { return pos_; }
	std::size_t size() const { return size_; }
	std::size_t remaining() const { return size_ - pos_; }

	template <class T>
	bool get(T& v)
	{
		const std::size_t start = aligned(sizeof(T));
		if (start > size_ || size_ - start < sizeof(T)) return false;
		std::memcpy(&v, data_ + start, sizeof(T));
		if (swap_) v = byteSwapped(v);
		pos_ = start + sizeof(T);
		return true;
	}

	bool skip(std::size_t n)
	{
		if (remaining() < n) return false;
		pos_ += n;
		return true;
	}

	/** A string's bytes (without CDR's terminating NUL). */
	bool string(const char*& text, std::size_t& len)
	{
		const std::size_t start = pos_;
		uint32_t n = 0;
		if (!get(n) || remaining() < n)
		{
			pos_ = start;
			return false;
		}
		text = reinterpret_cast<const char*>(data_ + pos_);
		len = n;
		pos_ += n;
		if (kCdr && len > 0 && text[len - 1] == '\0') --len;
		return true;
	}

	/** ROS 1 time: uint32 sec, uint32 nsec; duration: int32, int32. ROS 2
	 *  Time and Duration: int32 sec, uint32 nanosec. */
	bool time(bool duration, TimeNs& out)
	{
		const std::size_t start = pos_;
		uint32_t sec = 0, nsec = 0;
		if (!get(sec) || !get(nsec))
		{
			pos_ = start;
			return false;
		}
		constexpr int64_t kNs = 1000000000;
		const bool signed_sec = kCdr || duration;
		const int64_t s =
		    signed_sec ? static_cast<int64_t>(static_cast<int32_t>(sec)) : static_cast<int64_t>(sec);
		const int64_t ns = (!kCdr && duration) ? static_cast<int64_t>(static_cast<int32_t>(nsec))
		                                       : static_cast<int64_t>(nsec);
		out = s * kNs + ns;
		return true;
	}

 private:
	std::size_t aligned(std::size_t n) const
	{
		if (!kCdr) return pos_;
		const std::size_t a = n > 8 ? 8 : n;
		const std::size_t rel = pos_ - origin_;
		return pos_ + (a - rel % a) % a;
	}

	const uint8_t* data_;
	std::size_t size_;
	std::size_t pos_;
	std::size_t origin_;
	bool swap_;
};

const char* typeLabel(const FieldDef& f)
{
	return f.type_name.c_str();
}

std::size_t primitiveSize(FieldType t)
{
	switch (t)
	{
		case FieldType::Bool:
		case FieldType::Int8:
		case FieldType::UInt8:
			return 1;
		case FieldType::Int16:
		case FieldType::UInt16:
			return 2;
		case FieldType::Int32:
		case FieldType::UInt32:
		case FieldType::Float32:
		case FieldType::String:
			return 4;  // the length
		case FieldType::Int64:
		case FieldType::UInt64:
		case FieldType::Float64:
		case FieldType::Time:
		case FieldType::Duration:
			return 8;
		case FieldType::Message:
			return 0;
	}
	return 0;
}

bool isByteType(FieldType t)
{
	return t == FieldType::Int8 || t == FieldType::UInt8;
}

std::size_t saturatingMul(std::size_t a, std::size_t b)
{
	if (a != 0 && b > std::numeric_limits<std::size_t>::max() / a)
		return std::numeric_limits<std::size_t>::max();
	return a * b;
}

std::size_t saturatingAdd(std::size_t a, std::size_t b)
{
	return b > std::numeric_limits<std::size_t>::max() - a ? std::numeric_limits<std::size_t>::max() : a + b;
}

/** Walks one message along its definition, appending values (and names). */
template <class Reader>
class Walker
{
 public:
	Walker(Reader& in, const std::vector<std::size_t>& min_size, std::vector<Value>& values,
	       std::vector<std::string>* names, std::vector<uint32_t>& lengths, bool cdr)
	    : in_(in), min_size_(min_size), values_(values), names_(names), lengths_(lengths), cdr_(cdr)
	{
	}

	void message(const MessageDef& m)
	{
		// A ROS 2 message without fields still has one (unlisted) byte.
		if (cdr_ && m.fields.empty())
		{
			uint8_t dummy = 0;
			if (!in_.get(dummy)) fail("empty message", 1);
			return;
		}
		for (const FieldDef& f : m.fields) field(f);
	}

	void finish()
	{
		values_.resize(count_);
		const std::size_t left = in_.remaining();
		if (left > (cdr_ ? kMaxCdrTrailingPadding : 0))
		{
			std::ostringstream msg;
			msg << left << " bytes left after the last field (" << in_.size()
			    << "-byte message; the definition does not match the data)";
			throw DecodeError(msg.str());
		}
	}

 private:
	void field(const FieldDef& f)
	{
		const std::size_t len = path_.size();
		if (names_)
		{
			if (!path_.empty()) path_ += '.';
			path_ += f.name;
		}
		if (f.array == ArrayKind::None)
			element(f);
		else
			array(f);
		if (names_) path_.resize(len);
	}

	void array(const FieldDef& f)
	{
		uint32_t count = f.fixed_size;
		if (f.array == ArrayKind::Sequence)
		{
			if (!in_.get(count)) fail(f, "sequence length", 4);
			checkCount(f, count);
			lengths_.push_back(count);
		}
		withSuffix("[]", [&] { number(static_cast<double>(count)); });
		if (isByteType(f.type) && count > kMaxFlattenedArray)
		{
			if (!in_.skip(count)) fail(f, "bytes", count);
			return;
		}
		const std::size_t len = path_.size();
		for (uint32_t i = 0; i < count; ++i)
		{
			if (names_)
			{
				path_ += '[';
				path_ += std::to_string(i);
				path_ += ']';
			}
			element(f);
			if (names_) path_.resize(len);
		}
	}

	void checkCount(const FieldDef& f, uint32_t count)
	{
		const std::size_t each =
		    f.type == FieldType::Message ? min_size_[f.message->index] : primitiveSize(f.type);
		const bool too_many = each == 0 ? count > kMaxEmptyElements : count > in_.remaining() / each;
		if (!too_many) return;
		std::ostringstream msg;
		if (each == 0)
		{
			msg << "field '" << path_ << "' (" << typeLabel(f) << "[]) has " << count
			    << " elements of an empty type, more than " << kMaxEmptyElements << " (corrupt count?)";
			throw DecodeError(msg.str());
		}
		msg << "message too short: field '" << path_ << "' (" << typeLabel(f) << "[]) has " << count
		    << " elements, which need at least " << saturatingMul(count, each) << " bytes at byte "
		    << in_.offset() << ", the message ends at byte " << in_.size();
		throw DecodeError(msg.str());
	}

	void element(const FieldDef& f)
	{
		switch (f.type)
		{
			case FieldType::Bool:
				number(read<uint8_t>(f) != 0 ? 1.0 : 0.0);
				break;
			case FieldType::Int8:
				number(read<int8_t>(f));
				break;
			case FieldType::UInt8:
				number(read<uint8_t>(f));
				break;
			case FieldType::Int16:
				number(read<int16_t>(f));
				break;
			case FieldType::UInt16:
				number(read<uint16_t>(f));
				break;
			case FieldType::Int32:
				number(read<int32_t>(f));
				break;
			case FieldType::UInt32:
				number(read<uint32_t>(f));
				break;
			case FieldType::Int64:
				number(static_cast<double>(read<int64_t>(f)));
				break;
			case FieldType::UInt64:
				number(static_cast<double>(read<uint64_t>(f)));
				break;
			case FieldType::Float32:
				number(read<float>(f));
				break;
			case FieldType::Float64:
				number(read<double>(f));
				break;
			case FieldType::String:
				text(f);
				break;
			case FieldType::Time:
			case FieldType::Duration:
				time(f);
				break;
			case FieldType::Message:
				if (++depth_ > kMaxNesting) fail(f, "nesting", 0);
				message(*f.message);
				--depth_;
				break;
		}
	}

	template <class T>
	T read(const FieldDef& f)
	{
		T v{};
		if (!in_.get(v)) fail(f, "value", sizeof(T));
		return v;
	}

	void text(const FieldDef& f)
	{
		const char* s = nullptr;
		std::size_t n = 0;
		if (!in_.string(s, n)) failString(f);
		Value& v = slot();
		v.kind = Value::Kind::Text;
		v.text.assign(s, n);
	}

	void time(const FieldDef& f)
	{
		TimeNs t = 0;
		if (!in_.time(f.type == FieldType::Duration, t)) fail(f, "value", 8);
		Value& v = slot();
		v.kind = Value::Kind::Time;
		v.time_ns = t;
		v.text.clear();
	}

	void number(double x)
	{
		Value& v = slot();
		v.kind = Value::Kind::Number;
		v.number = x;
		v.text.clear();
	}

	Value& slot()
	{
		if (count_ >= kMaxFields)
			throw DecodeError("more than " + std::to_string(kMaxFields) + " values in one message");
		if (count_ == values_.size()) values_.emplace_back();
		if (names_) names_->push_back(path_);
		return values_[count_++];
	}

	template <class F>
	void withSuffix(const char* suffix, const F& f)
	{
		const std::size_t len = path_.size();
		if (names_) path_ += suffix;
		f();
		if (names_) path_.resize(len);
	}

	[[noreturn]] void failString(const FieldDef& f)
	{
		uint32_t n = 0;
		Reader probe = in_;
		if (!probe.get(n)) fail(f, "string length", 4);
		std::ostringstream msg;
		msg << "message too short: field '" << path_ << "' (" << typeLabel(f) << ") has " << n
		    << " bytes of text at byte " << probe.offset() << ", the message ends at byte " << in_.size();
		throw DecodeError(msg.str());
	}

	[[noreturn]] void fail(const FieldDef& f, const char* what, std::size_t needed)
	{
		std::ostringstream msg;
		msg << "message too short: field '" << path_ << "' (" << typeLabel(f) << ") needs " << needed
		    << " bytes for its " << what << " at byte " << in_.offset() << ", the message ends at byte "
		    << in_.size();
		throw DecodeError(msg.str());
	}

	[[noreturn]] void fail(const char* what, std::size_t needed)
	{
		std::ostringstream msg;
		msg << "message too short: '" << path_ << "' needs " << needed << " bytes for its " << what
		    << " at byte " << in_.offset() << ", the message ends at byte " << in_.size();
		throw DecodeError(msg.str());
	}

	Reader& in_;
	const std::vector<std::size_t>& min_size_;
	std::vector<Value>& values_;
	std::vector<std::string>* names_;
	std::vector<uint32_t>& lengths_;
	bool cdr_;
	std::string path_;
	std::size_t count_ = 0;
	std::size_t depth_ = 0;
};

/** Lower bound of a message's wire size (alignment only adds), for checking
 *  sequence counts against the bytes left before looping over them. */
std::size_t minWireSize(const MessageDef& m, bool cdr, std::vector<std::optional<std::size_t>>& memo)
{
	if (memo[m.index]) return *memo[m.index];
	std::size_t total = 0;
	for (const FieldDef& f : m.fields)
	{
		const std::size_t each =
		    f.type == FieldType::Message ? minWireSize(*f.message, cdr, memo) : primitiveSize(f.type);
		switch (f.array)
		{
			case ArrayKind::None:
				total = saturatingAdd(total, each);
				break;
			case ArrayKind::Fixed:
				total = saturatingAdd(total, saturatingMul(each, f.fixed_size));
				break;
			case ArrayKind::Sequence:
				total = saturatingAdd(total, 4);
				break;
		}
	}
	if (cdr && m.fields.empty()) total = 1;
	memo[m.index] = total;
	return total;
}

// Process-wide, so that Records from different sources never share a layout
// id. Starts far above the small counters other sources may use.
std::atomic<uint64_t> g_next_layout_id{uint64_t{1} << 40};

}  // namespace

// ---------------------------------------------------------------- decoder

FlatDecoder::FlatDecoder(std::shared_ptr<const Schema> schema, WireFormat format)
    : schema_(std::move(schema)), format_(format)
{
	std::vector<std::optional<std::size_t>> memo(schema_->messages().size());
	min_size_.resize(memo.size());
	for (const auto& m : schema_->messages())
		min_size_[m->index] = minWireSize(*m, format_ == WireFormat::Cdr, memo);
}

void FlatDecoder::run(const uint8_t* data, std::size_t size, std::vector<Value>& values,
                      std::vector<std::string>* names)
{
	lengths_.clear();
	if (format_ == WireFormat::Ros1)
	{
		WireReader<false> in(data, size, 0, !kHostLittleEndian);
		Walker<WireReader<false>> walker(in, min_size_, values, names, lengths_, false);
		walker.message(schema_->root());
		walker.finish();
		return;
	}
	// Encapsulation: 0x00 0x00 = CDR big endian, 0x00 0x01 = CDR little endian,
	// then two option bytes. Anything else (parameter lists, XCDR2) is refused.
	if (size < 4)
		throw DecodeError("message too short for the CDR header (" + std::to_string(size) + " bytes)");
	if (data[0] != 0 || data[1] > 1)
	{
		std::ostringstream msg;
		msg << "unsupported CDR encapsulation 0x" << std::hex << std::setw(4) << std::setfill('0')
		    << (int{data[0]} << 8 | data[1]) << " (only plain CDR, 0x0000 and 0x0001)";
		throw DecodeError(msg.str());
	}
	const bool little = data[1] == 1;
	WireReader<true> in(data, size, 4, little != kHostLittleEndian);
	Walker<WireReader<true>> walker(in, min_size_, values, names, lengths_, true);
	walker.message(schema_->root());
	walker.finish();
}

void FlatDecoder::explainFailure(const uint8_t* data, std::size_t size, const DecodeError& first)
{
	// The fast pass keeps no field path; decoding again with names gives the
	// same failure, now naming the field.
	std::vector<Value> values;
	std::vector<std::string> names;
	run(data, size, values, &names);
	throw first;
}

void FlatDecoder::decode(const uint8_t* data, std::size_t size, Record& out)
{
	try
	{
		run(data, size, out.values, nullptr);
	}
	catch (const DecodeError& e)
	{
		explainFailure(data, size, e);
	}
	if (layout_id_ == 0 || lengths_ != layout_lengths_)
	{
		std::vector<std::string> names;
		run(data, size, out.values, &names);
		names_ = std::move(names);
		layout_lengths_ = lengths_;
		layout_id_ = g_next_layout_id.fetch_add(1);
	}
	if (out.layout_id != layout_id_ || out.names.size() != names_.size()) out.names = names_;
	out.layout_id = layout_id_;
}

}  // namespace auvnav::import::msg
