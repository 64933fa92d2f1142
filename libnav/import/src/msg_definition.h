#pragma once
/** @file msg_definition.h
 *  ROS message definitions as bags store them, and the decoder that turns one
 *  serialized message into flat record fields (record.h). Shared by the ROS 1
 *  and ROS 2 bag readers; private to the importer.
 *
 *  Definition text: the main type's fields, then one section per dependency,
 *  each introduced by a line of '=' and a line `MSG: pkg/Type` (ROS 1) or
 *  `MSG: pkg/msg/Type` (ROS 2). Per line: `type name` (a field; ROS 2 may add a
 *  default value after the name), `type NAME=value` (a constant: not a field),
 *  `# comment`. Types: the builtins, `T[N]` (fixed array), `T[]` and `T[<=N]`
 *  (sequences), `string<=N`, `pkg/Type`, `Type` (same package as the type that
 *  uses it) and `Header` (std_msgs/Header).
 *
 *  Type names are kept in the ROS 1 spelling `pkg/Type`: `pkg/msg/Type` is
 *  normalised, so both spellings name the same section.
 *
 *  ROS 2 `builtin_interfaces/Time` and `Duration` are treated as builtins, like
 *  ROS 1 `time` and `duration`: one Time value each (record.h).
 */
#include <auvnav/import/record.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace auvnav::import::msg
{
/** Nested message depth: deeper is taken for a corrupt definition (by the
 *  parser and, as a guard, by the decoder). */
constexpr std::size_t kMaxNesting = 64;

/** Which builtin names exist and what `byte` means (ROS 1: int8, ROS 2: uint8). */
enum class Dialect : uint8_t
{
	Ros1,
	Ros2
};

enum class FieldType : uint8_t
{
	Bool,
	Int8,
	UInt8,
	Int16,
	UInt16,
	Int32,
	UInt32,
	Int64,
	UInt64,
	Float32,
	Float64,
	String,
	Time,      //!< ROS 1 `time`, ROS 2 builtin_interfaces/Time
	Duration,  //!< ROS 1 `duration`, ROS 2 builtin_interfaces/Duration
	Message
};

enum class ArrayKind : uint8_t
{
	None,
	Fixed,    //!< `T[N]`: N elements, no count on the wire
	Sequence  //!< `T[]`, `T[<=N]`: a uint32 count, then the elements
};

struct MessageDef;

struct FieldDef
{
	std::string name;
	FieldType type = FieldType::Bool;
	std::string type_name;                //!< builtin spelling, or the resolved `pkg/Type` of a Message
	const MessageDef* message = nullptr;  //!< FieldType::Message
	ArrayKind array = ArrayKind::None;
	uint32_t fixed_size = 0;  //!< ArrayKind::Fixed
};

struct MessageDef
{
	std::string name;  //!< `pkg/Type`
	std::vector<FieldDef> fields;
	std::size_t index = 0;  //!< position in Schema::messages()
};

/** A definition that cannot be parsed or resolved; the message says which type,
 *  line and token. */
class DefinitionError : public std::runtime_error
{
 public:
	using std::runtime_error::runtime_error;
};

/** Supplies the definition text (own fields only, no `MSG:` sections) of a type
 *  the bag does not define, or nullptr. Called with normalised `pkg/Type`. */
using DefinitionFallback = std::function<const char*(const std::string& type_name)>;

/** `pkg/msg/Type` -> `pkg/Type`; other names unchanged. */
std::string normalizeTypeName(std::string_view name);

/** The parsed main type and every type it uses, linked. Immutable. */
class Schema
{
 public:
	/** Parses `text` as the definition of `type_name` (either spelling). Types
	 *  that the text uses but does not define are asked of `fallback`. Throws
	 *  DefinitionError on bad syntax, an unknown type, a recursive type or an
	 *  unsupported builtin (wstring). Only types reachable from the main type
	 *  are parsed: a broken unused section is ignored. */
	static std::shared_ptr<const Schema> parse(std::string_view type_name, std::string_view text,
	                                           Dialect dialect, const DefinitionFallback& fallback = {});

	const MessageDef& root() const { return *messages_.front(); }
	const std::vector<std::unique_ptr<MessageDef>>& messages() const { return messages_; }
	Dialect dialect() const { return dialect_; }

 private:
	Schema() = default;
	friend class SchemaBuilder;
	std::vector<std::unique_ptr<MessageDef>> messages_;  // root first
	Dialect dialect_ = Dialect::Ros1;
};

/** How the bytes of a message are laid out. */
enum class WireFormat : uint8_t
{
	Ros1,  //!< little endian, packed; strings: uint32 length + bytes; time: uint32 sec + uint32 nsec
	Cdr    //!< 4-byte encapsulation header, then XCDR1 (aligned; strings NUL-terminated;
	       //!< Time: int32 sec + uint32 nanosec); little or big endian
};

/** A message that does not match its definition. `what()` names the field (as
 *  flattened: `bottom.velocity.x`), its type and the byte offset. */
class DecodeError : public std::runtime_error
{
 public:
	using std::runtime_error::runtime_error;
};

/** Decodes serialized messages of one schema into Records (record.h flattening:
 *  `a.b`, `a[i]`, `a[]` before the elements; Time values in integer ns; arrays
 *  of 1-byte integers (byte, char, int8, uint8) longer than kMaxFlattenedArray
 *  give `a[]` only). Keeps the field names of the last layout: they are
 *  rebuilt, and the Record's layout_id changes, only when a sequence length
 *  differs from the previous message's. layout_ids are unique in the process
 *  (counted from 2^40, away from small per-source counters). */
class FlatDecoder
{
 public:
	FlatDecoder(std::shared_ptr<const Schema> schema, WireFormat format);

	/** Fills out.names, out.values and out.layout_id from one message (for CDR
	 *  including its encapsulation header). Leaves the other Record members
	 *  alone. `out.names` is left as it is when out.layout_id already is the
	 *  current layout (the caller reuses the Record). Throws DecodeError when the
	 *  bytes end inside a field, a count exceeds the remaining bytes, the
	 *  encapsulation is not plain CDR (XCDR1), or bytes are left over (ROS 1:
	 *  any; CDR: more than the 7 that end padding may explain). */
	void decode(const uint8_t* data, std::size_t size, Record& out);

	const Schema& schema() const { return *schema_; }

 private:
	// One pass over the bytes; collects the names too when `names` is given
	// (and then the field path for error messages).
	void run(const uint8_t* data, std::size_t size, std::vector<Value>& values,
	         std::vector<std::string>* names);
	[[noreturn]] void explainFailure(const uint8_t* data, std::size_t size, const DecodeError& first);

	std::shared_ptr<const Schema> schema_;
	WireFormat format_;
	std::vector<std::size_t> min_size_;     // lower bound of each message's wire size, by index
	std::vector<uint32_t> lengths_;         // sequence lengths of the message being decoded
	std::vector<uint32_t> layout_lengths_;  // ... of the current layout
	std::vector<std::string> names_;        // current layout
	uint64_t layout_id_ = 0;                // 0: none yet
};

}  // namespace auvnav::import::msg
