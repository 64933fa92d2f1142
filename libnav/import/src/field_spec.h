#pragma once
// Internal to the importer: how a spec names a value (a field of the record
// or a constant, with its unit), and reading it from a record.
#include <auvnav/config.h>
#include <auvnav/import/record.h>
#include <auvnav/import/units.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace auvnav::import::detail
{
/** Outcome of reading one value from a record. */
enum class Read
{
	Ok,
	Missing,  //!< empty cell, absent optional field, or a declared invalid value
	Bad       //!< present but unusable (why set)
};

/** One scalar: `{field: name, unit: u}` or `{value: 3.2, unit: u}`. The
 *  field name may hold `{i}` (0-based) or `{n}` (1-based) for array elements. */
struct ScalarSpec
{
	bool present = false;
	bool is_constant = false;
	bool optional = false;  //!< the field may be absent from the source or empty
	std::string field;
	double constant_si = 0;
	Unit unit{"1", UnitKind::Dimensionless, 1};
	std::vector<double> invalid_raw;  //!< source values meaning "no data" (e.g. PD0 -32768)
	std::string where;                //!< "spec.yaml: sensors[0].angular_velocity"

	std::string fieldFor(int index) const;
};

/** Parses key `key` of `n` as a scalar of unit kind `kind`. Absent key →
 *  present = false (the caller decides whether that is allowed). */
ScalarSpec parseScalar(const config::Node& n, const std::string& key, UnitKind kind);
/** `{fields: [a, b, c], unit: u}` or `{values: [...], unit: u}`: `count` scalars. */
std::vector<ScalarSpec> parseVector(const config::Node& n, const std::string& key, UnitKind kind,
                                    std::size_t count);

/** Column indices of a record layout, cached per layout id. */
class Columns
{
 public:
	/** Index of `name` in `r` (−1 if absent), memoised per layout. */
	int index(const Record& r, const std::string& name);

 private:
	uint64_t layout_ = 0;
	std::vector<std::pair<std::string, int>> cache_;
};

/** Reads a raw number (no unit) from `v`. */
Read readNumber(const Value& v, double& out, std::string& why);

/** Reads `s` (element `index` when templated) from `r` in SI. */
Read readScalar(const ScalarSpec& s, const Record& r, Columns& cols, double& out_si, std::string& why,
                int index = 0, double* raw_out = nullptr);

/** Reads an optional scalar in SI: `out_si` is NaN when it is missing; false
 *  (and `why`) only when it is present but unusable. */
bool readOptional(const ScalarSpec& s, const Record& r, Columns& cols, double& out_si, std::string& why);

/** A text-valued setting, constant (`frame: earth_enu`) or per record
 *  (`frame: {field: coord_sys, map: {"3": earth_enu}}`). */
struct TextSpec
{
	bool present = false;
	bool is_constant = true;
	std::string constant;
	std::string field;
	std::vector<std::pair<std::string, std::string>> map;  //!< source text → value
	std::string where;
};
TextSpec parseText(const config::Node& n, const std::string& key);
/** The text in `r` (mapped), or the constant; false and `why` if missing or
 *  unmapped. `empty_ok`: an empty cell is the text "" (unmapped). */
bool readText(const TextSpec& t, const Record& r, Columns& cols, std::string& out, std::string& why,
              bool empty_ok = false);

}  // namespace auvnav::import::detail
