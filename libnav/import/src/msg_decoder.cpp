// The message decoder (msg_definition.h's FlatDecoder): walks serialized ROS 1
// or CDR bytes along a Schema into flat record fields.
#include <atomic>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>

#include "msg_definition.h"
#include "msg_wire_reader.h"

namespace auvnav::import::msg
{
namespace
{
// Values per message; a count beyond this is taken for corrupt data.
constexpr std::size_t kMaxFields = std::size_t{1} << 22;
// Elements of a sequence whose element type has no bytes (an empty ROS 1
// message) cannot be checked against the remaining bytes; cap them instead.
constexpr uint32_t kMaxEmptyElements = 1u << 20;
// CDR writers may pad the end of a message up to the next 4 or 8 bytes.
constexpr std::size_t kMaxCdrTrailingPadding = 7;

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
