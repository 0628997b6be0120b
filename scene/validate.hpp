// The validation engine of scene files (internal to swmpm_scene; interface.md §2; style.md
// items 4–6).
//
// How it works
// ------------
// Every object kind of the scene file (top level, grid, material, body, ...) declares its keys ONCE
// in a `Table` (keys.cpp): name, type, default (or required), allowed range or values, unit and a
// one-line meaning. Those tables drive three things, so they cannot drift apart:
//   1. validation  — `check_object` (validate.cpp) walks a JSON object against its tables: unknown
//                    keys (with a "did you mean"), wrong types, out-of-range values, unknown
//                    enumeration strings, missing required keys; defaults are filled in;
//   2. the reference — `schema_markdown()` (docs.cpp) prints the tables that docs/scene-format.md
//                    contains verbatim (a unit test holds the two together);
//   3. `schema_keys()` — every declared key, for the documentation test.
// Rules that involve more than one key (a body naming a material, a geometry inside the grid, ...)
// are checked by the section parsers after the tables (parser.hpp: parse.cpp, parse_bodies.cpp).
// Problems are collected, not thrown one at a time; at the end the parser throws one SceneError
// with one line per problem:
//     "<label>: <JSON pointer>: got <what was found>, expected <what is allowed> [<unit>]".
// Writing a scene back (to_json) is write.cpp.
#pragma once

#include <cstddef>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace swmpm::scene::detail {

using json = nlohmann::json;
constexpr double inf = std::numeric_limits<double>::infinity();

// ------------------------------------------------------------------------------------------------
// Small text helpers for messages.
// ------------------------------------------------------------------------------------------------

bool contains(const std::vector<std::string>& v, const std::string& s);
std::string join(const std::vector<std::string>& v, const std::string& sep = ", ");
std::string fmt_g(double x);
/// A JSON value as the user wrote it, shortened for a message.
std::string shown(const json& v);
std::string in_quotes(const std::string& s);
std::string fmt_vec(const Vec3& v, int dim);
/// JSON pointer escaping of one reference token (RFC 6901).
std::string escape(const std::string& key);
std::string item(const std::string& path, std::size_t i);
std::string lower(std::string s);
std::string did_you_mean(const std::string& s, const std::vector<std::string>& candidates);
/// A JSON pointer for a message: each reference token of more than 60 characters shortened.
std::string shown_pointer(const std::string& pointer);

// ------------------------------------------------------------------------------------------------
// The schema.
// ------------------------------------------------------------------------------------------------

/// Collects problems; knows the scene dimension once it has been read (0 while unknown, in which
/// case vectors may have 2 or 3 components).
struct Ctx {
  std::string label;
  int dim = 0;
  std::vector<std::string> errors;
  void error(const std::string& path, const std::string& what) {
    errors.push_back(label + ": " + (path.empty() ? std::string("(top level)") : shown_pointer(path)) + ": " + what);
  }
};

enum class Type {
  number,   // a JSON number within `range`
  integer,  // a whole number within `range`
  boolean,
  string,   // a non-empty string
  choice,   // one string of `values`
  vector,   // exactly `dimension` numbers
  object,   // checked by its own table
  objects,  // an array of objects, each checked by its own table
  choices,  // an array of strings, each one of `values`
  custom    // checked by `check`
};

struct Range {
  double lo = -inf;
  double hi = inf;
  bool lo_open = false;
  bool hi_open = false;
  bool contains(double x) const {
    return (lo_open ? x > lo : x >= lo) && (hi_open ? x < hi : x <= hi);
  }
};
constexpr Range any_number{};
constexpr Range positive{0.0, inf, true, false};
constexpr Range non_negative{0.0, inf, false, false};
constexpr Range closed(double a, double b) { return {a, b, false, false}; }
constexpr Range half_open(double a, double b) { return {a, b, false, true}; }  // [a, b)
constexpr Range open(double a, double b) { return {a, b, true, true}; }        // (a, b)
constexpr Range left_open(double a, double b) { return {a, b, true, false}; }  // (a, b]
constexpr Range at_least(double a) { return {a, inf, false, false}; }

struct Key;
/// Checks a value of a `custom` key; reports its own problems and returns whether it is valid.
using CustomCheck = bool (*)(Ctx&, const json& value, const std::string& path, const Key& key);

struct Key {
  std::string name;
  Type type = Type::number;
  bool required = false;
  json def;                          // default when absent (null: none)
  Range range;                       // number, integer
  std::vector<std::string> values;   // choice, choices
  std::string unit;                  // SI unit; "-" dimensionless; "" not a quantity
  std::string meaning;               // one line, for the reference
  std::string type_text;             // reference "type" column (custom types)
  std::string expect;                // "expected ..." text of messages (custom types, overrides)
  std::string allowed;               // reference "allowed" column (overrides the generated one)
  std::string default_text;          // reference "default" column (overrides the generated one)
  CustomCheck check = nullptr;       // custom
  bool nonempty = false;             // objects, choices
};

struct Table {
  std::string title;  // reference heading
  std::string where;  // where the object sits in the scene file
  std::vector<Key> keys;
};

// -- phrases generated from a key, shared by messages and the reference ---------------------------

std::string range_text(const Range& r, bool integer);
std::string vector_phrase(int dim);

// -- custom checks --------------------------------------------------------------------------------

bool is_integral(const json& v);
bool check_dir_name(Ctx& c, const json& v, const std::string& path, const Key& k);
bool check_monitor_name(Ctx& c, const json& v, const std::string& path, const Key& k);
/// A monitor's `at`: 1 to 3 numbers here; parse_output, which knows the monitor's quantities, checks
/// for `dimension` of them, or `dimension` − 1 in a water_level gauge (its vertical line).
bool check_monitor_at(Ctx& c, const json& v, const std::string& path, const Key& k);
bool check_dt(Ctx& c, const json& v, const std::string& path, const Key& k);
bool check_pore_pressure(Ctx& c, const json& v, const std::string& path, const Key& k);
bool check_stress(Ctx& c, const json& v, const std::string& path, const Key& k);
bool check_load_value(Ctx& c, const json& v, const std::string& path, const Key& k);
bool check_velocity(Ctx& c, const json& v, const std::string& path, const Key& k);
bool check_time_expression(Ctx& c, const json& v, const std::string& path, const Key& k);
/// The value of an expression (valid: it passed check_velocity or check_time_expression) with
/// the variables `vars` (up to three) set to `values`; inf or NaN when so it evaluates.
double expression_value(const std::string& expr, const std::vector<std::string>& vars, const Vec3& values);
bool check_time_table(Ctx& c, const json& v, const std::string& path, const Key& k);
bool check_vertices(Ctx& c, const json& v, const std::string& path, const Key& k);
/// A geometry file path as written, resolved against the folder of the scene file `label`.
std::filesystem::path resolve_file(const std::string& label, const std::string& file);
/// A path, relative to the scene file's folder, to an existing file with one of the extensions
/// in `k.values`.
bool check_file(Ctx& c, const json& v, const std::string& path, const Key& k);
/// gmsh parameters: {"name": number}, names usable as .geo variables (they are written into a .geo
/// prelude, so nothing else may get through).
bool check_parameters(Ctx& c, const json& v, const std::string& path, const Key& k);
/// initialisation.materials: an object of objects (material name -> its parameters); the names and
/// parameters are checked against the scene's materials by the parser (parse_initialisation).
bool check_phase_materials(Ctx& c, const json& v, const std::string& path, const Key& k);

// ------------------------------------------------------------------------------------------------
// Checking one object against its tables.
// ------------------------------------------------------------------------------------------------

/// A checked JSON object: its valid values with defaults filled in, and what the file wrote.
struct Obj {
  std::string path;
  bool is_object = false;
  std::map<std::string, json> v;  // valid values and defaults
  std::set<std::string> given;    // keys written in the file, valid or not

  bool ok(const std::string& k) const { return v.count(k) != 0; }
  bool has(const std::string& k) const { return given.count(k) != 0; }
  const json& get(const std::string& k) const { return v.at(k); }
  double num(const std::string& k, double fallback = 0.0) const {
    return ok(k) && v.at(k).is_number() ? v.at(k).get<double>() : fallback;
  }
  std::string str(const std::string& k, const std::string& fallback = "") const {
    return ok(k) && v.at(k).is_string() ? v.at(k).get<std::string>() : fallback;
  }
  Vec3 vec(const std::string& k) const {
    Vec3 out{0.0, 0.0, 0.0};
    if (!ok(k) || !v.at(k).is_array()) return out;
    const json& a = v.at(k);
    for (std::size_t d = 0; d < a.size() && d < 3; ++d) out[d] = a[d].get<double>();
    return out;
  }
  std::string at(const std::string& k) const { return path + "/" + escape(k); }
};

/// Checks `j` against the union of `tables`. With report_unknown false, keys not in the tables are
/// passed over (used when the tables themselves are unknown, e.g. a material with a bad model).
Obj check_object(Ctx& c, const json& j, const std::string& path,
                 const std::vector<const Table*>& tables, bool report_unknown = true);

}  // namespace swmpm::scene::detail
