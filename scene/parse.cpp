// Scene file parsing and validation (interface.md §2; style.md items 4–6).
//
// How it works
// ------------
// Every object kind of the scene file (top level, grid, material, body, ...) declares its keys ONCE
// in a `Table` below: name, type, default (or required), allowed range or values, unit and a one-line
// meaning. Those tables drive three things, so they cannot drift apart:
//   1. validation  — `check_object` walks a JSON object against its tables: unknown keys (with a
//                    "did you mean"), wrong types, out-of-range values, unknown enumeration strings,
//                    missing required keys; defaults are filled in;
//   2. the reference — `schema_markdown()` prints the tables that docs/scene-format.md contains
//                    verbatim (a unit test holds the two together);
//   3. `schema_keys()` — every declared key, for the documentation test.
// Rules that involve more than one key (a body naming a material, a geometry inside the grid, ...)
// are checked by the section parsers after the tables. Problems are collected, not thrown one at a
// time; at the end the parser throws one SceneError with one line per problem:
//     "<label>: <JSON pointer>: got <what was found>, expected <what is allowed> [<unit>]".
#include <muParser.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace swmpm::scene {
namespace {

using json = nlohmann::json;
constexpr double inf = std::numeric_limits<double>::infinity();

// ------------------------------------------------------------------------------------------------
// Registries: the exact strings a user writes. Enumerations with a to_string() in scene.cpp are
// matched against it, so each of those strings exists once.
// ------------------------------------------------------------------------------------------------

constexpr std::array kFormulations{Formulation::dry,
                                   Formulation::explicit_single_point,
                                   Formulation::semi_implicit_single_point,
                                   Formulation::semi_implicit_double_point,
                                   Formulation::explicit_double_point,
                                   Formulation::mpm_fem,
                                   Formulation::automatic};
constexpr std::array kShapeFunctions{ShapeFunction::linear, ShapeFunction::gimp,
                                     ShapeFunction::bspline2, ShapeFunction::bspline3};
constexpr std::array kModels{MaterialModel::linear_elastic, MaterialModel::hencky,
                             MaterialModel::mohr_coulomb,   MaterialModel::drucker_prager,
                             MaterialModel::nor_sand,       MaterialModel::fluid};

template <class E, std::size_t N>
std::vector<std::string> names_of(const std::array<E, N>& all) {
  std::vector<std::string> out;
  for (E e : all) out.push_back(to_string(e));
  return out;
}

template <class E, std::size_t N>
std::optional<E> from_string(const std::array<E, N>& all, const std::string& s) {
  for (E e : all) {
    if (to_string(e) == s) return e;
  }
  return std::nullopt;
}

// Ordered as the enumerators of SolidBc / FluidBc: the index is the enumerator.
const std::vector<std::string>& solid_bc_names() {
  static const std::vector<std::string> v{"fixed", "roller", "free", "friction"};
  return v;
}
const std::vector<std::string>& fluid_bc_names() {
  static const std::vector<std::string> v{"impermeable", "drained", "pressure"};
  return v;
}
const std::vector<std::string>& face_names() {
  static const std::vector<std::string> v{"x_min", "x_max", "y_min", "y_max", "z_min", "z_max"};
  return v;
}
const std::vector<std::string>& geometry_types() {
  static const std::vector<std::string> v{"box", "polygon", "slope", "gmsh", "surface-mesh", "footing"};
  return v;
}
// Quantities of one followed particle (monitor with `at` or `particle`).
const std::vector<std::string>& point_quantities() {
  static const std::vector<std::string> v{
      "pore_pressure", "displacement_x", "displacement_y", "displacement_z", "velocity_x",
      "velocity_y",    "velocity_z",     "stress_xx",      "stress_yy",      "stress_zz",
      "stress_xy",     "stress_yz",      "stress_xz",      "mean_effective_stress",
      "deviatoric_stress", "porosity",   "plastic_strain", "water_level"};
  return v;
}
// Quantities of the whole model (monitor with neither `at` nor `particle`).
const std::vector<std::string>& global_quantities() {
  static const std::vector<std::string> v{"kinetic_energy", "strain_energy", "total_energy",
                                          "external_work"};
  return v;
}
const std::vector<std::string>& all_quantities() {
  static const std::vector<std::string> v = [] {
    auto all = point_quantities();
    for (const auto& q : global_quantities()) all.push_back(q);
    return all;
  }();
  return v;
}
// Components that do not exist in a 2D (plane strain) scene. stress_zz does: it is the
// out-of-plane normal stress of plane strain.
bool is_3d_only_quantity(const std::string& q) {
  return q == "displacement_z" || q == "velocity_z" || q == "stress_yz" || q == "stress_xz";
}
bool needs_fluid_quantity(const std::string& q) {
  return q == "pore_pressure" || q == "porosity" || q == "water_level";
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

std::string join(const std::vector<std::string>& v, const std::string& sep = ", ") {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? sep : "") + v[i];
  return out;
}

// ------------------------------------------------------------------------------------------------
// Small text helpers for messages.
// ------------------------------------------------------------------------------------------------

std::string fmt_g(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", x);
  return buf;
}

/// A JSON value as the user wrote it, shortened for a message.
std::string shown(const json& v) {
  std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

std::string in_quotes(const std::string& s) { return "\"" + s + "\""; }

std::string fmt_vec(const Vec3& v, int dim) {
  std::string out = "[";
  for (int d = 0; d < dim; ++d) out += (d ? ", " : "") + fmt_g(v[static_cast<std::size_t>(d)]);
  return out + "]";
}

/// JSON pointer escaping of one reference token (RFC 6901).
std::string escape(const std::string& key) {
  std::string out;
  for (char ch : key) {
    if (ch == '~') out += "~0";
    else if (ch == '/') out += "~1";
    else out += ch;
  }
  return out;
}

std::string item(const std::string& path, std::size_t i) { return path + "/" + std::to_string(i); }

/// Edit distance with adjacent transpositions (optimal string alignment): "snad" -> "sand" is 1.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

std::string lower(std::string s) {
  for (char& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

/// The closest candidate to `s`, if close enough to be a plausible typo.
std::optional<std::string> closest(const std::string& s, const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(lower(s), lower(c));
    if (d < best_d) best_d = d, best = c;
  }
  // Up to one edit per three characters, at least one, at most three.
  const std::size_t limit = std::clamp<std::size_t>(s.size() / 3, 1, 3);
  if (best && best_d <= limit) return best;
  return std::nullopt;
}

std::string did_you_mean(const std::string& s, const std::vector<std::string>& candidates) {
  const auto c = closest(s, candidates);
  return c ? " (did you mean " + in_quotes(*c) + "?)" : "";
}

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
    errors.push_back(label + ": " + (path.empty() ? std::string("(top level)") : path) + ": " + what);
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

std::string number_phrase(const Range& r, bool integer) {
  const std::string a = integer ? "an integer" : "a number";
  const bool has_lo = r.lo != -inf, has_hi = r.hi != inf;
  if (!has_lo && !has_hi) return a;
  if (!integer && has_lo && !has_hi && r.lo == 0.0) {
    return r.lo_open ? "a positive number" : "a non-negative number";
  }
  if (has_lo && !has_hi) return a + (r.lo_open ? " > " : " >= ") + fmt_g(r.lo);
  if (!has_lo && has_hi) return a + (r.hi_open ? " < " : " <= ") + fmt_g(r.hi);
  if (integer) return a + " in " + fmt_g(r.lo) + ".." + fmt_g(r.hi);
  return a + " in " + (r.lo_open ? "(" : "[") + fmt_g(r.lo) + ", " + fmt_g(r.hi) +
         (r.hi_open ? ")" : "]");
}

std::string range_text(const Range& r, bool integer) {
  const bool has_lo = r.lo != -inf, has_hi = r.hi != inf;
  if (!has_lo && !has_hi) return "any";
  if (has_lo && !has_hi) return std::string(r.lo_open ? "> " : "≥ ") + fmt_g(r.lo);
  if (!has_lo && has_hi) return std::string(r.hi_open ? "< " : "≤ ") + fmt_g(r.hi);
  if (integer) return fmt_g(r.lo) + ".." + fmt_g(r.hi);
  return (r.lo_open ? "(" : "[") + fmt_g(r.lo) + ", " + fmt_g(r.hi) + (r.hi_open ? ")" : "]");
}

std::string vector_phrase(int dim) {
  return dim == 0 ? "a vector of 2 or 3 numbers (one per dimension)"
                  : "a vector of " + std::to_string(dim) + " numbers (one per dimension)";
}

/// "expected ..." part of a message for a key, with its unit.
std::string expected(const Key& k, const Ctx& c) {
  std::string e;
  if (!k.expect.empty()) {
    e = k.expect;
  } else {
    switch (k.type) {
      case Type::number: e = number_phrase(k.range, false); break;
      case Type::integer: e = number_phrase(k.range, true); break;
      case Type::boolean: e = "true or false"; break;
      case Type::string: e = "a non-empty string"; break;
      case Type::choice: e = "one of: " + join(k.values); break;
      case Type::vector: e = vector_phrase(c.dim); break;
      case Type::object: e = "an object"; break;
      case Type::objects: e = k.nonempty ? "a non-empty array of objects" : "an array of objects"; break;
      case Type::choices: e = "a non-empty array of strings, each one of: " + join(k.values); break;
      case Type::custom: e = "a valid value"; break;
    }
  }
  if (!k.unit.empty()) e += " [" + k.unit + "]";
  return e;
}

void report(Ctx& c, const json& v, const std::string& path, const Key& k) {
  c.error(path, "got " + shown(v) + ", expected " + expected(k, c));
}

// -- expressions (muParser) -------------------------------------------------------------------

/// Empty when `expr` parses with the given variables and the constant pi; else muParser's message.
std::string expression_problem(const std::string& expr, const std::vector<std::string>& vars) {
  if (expr.find_first_not_of(" \t") == std::string::npos) return "the expression is empty";
  try {
    mu::Parser p;
    std::array<double, 3> values{0.0, 0.0, 0.0};
    for (std::size_t i = 0; i < vars.size() && i < values.size(); ++i) p.DefineVar(vars[i], &values[i]);
    p.DefineConst("pi", std::numbers::pi);
    p.SetExpr(expr);
    (void)p.Eval();
  } catch (const mu::Parser::exception_type& e) {
    return e.GetMsg();
  }
  return {};
}

// -- custom checks --------------------------------------------------------------------------------

bool is_integral(const json& v) {
  if (v.is_number_integer() || v.is_number_unsigned()) return true;
  if (!v.is_number_float()) return false;
  const double x = v.get<double>();
  return std::isfinite(x) && std::floor(x) == x;
}

bool is_number_array(const json& v, std::size_t n) {
  return v.is_array() && v.size() == n &&
         std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); });
}

bool dim_ok(const Ctx& c, std::size_t n) {
  return c.dim == 0 ? (n == 2 || n == 3) : n == static_cast<std::size_t>(c.dim);
}

bool check_dir_name(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (v.is_string()) {
    const auto& s = v.get_ref<const std::string&>();
    const bool chars_ok = !s.empty() && std::all_of(s.begin(), s.end(), [](char ch) {
      return std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '_' || ch == '-';
    });
    if (chars_ok && s != "." && s != "..") return true;
  }
  report(c, v, path, k);
  return false;
}

bool check_monitor_name(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (v.is_string()) {
    const auto& s = v.get_ref<const std::string&>();
    if (!s.empty() && std::all_of(s.begin(), s.end(), [](char ch) {
          return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-';
        })) {
      return true;
    }
  }
  report(c, v, path, k);
  return false;
}

bool check_dt(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if ((v.is_number() && v.get<double>() > 0.0) || v == "auto") return true;
  report(c, v, path, k);
  return false;
}

bool check_pore_pressure(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (v.is_number() || v == "hydrostatic") return true;
  report(c, v, path, k);
  return false;
}

bool check_stress(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (v == "geostatic" || is_number_array(v, 6)) return true;
  report(c, v, path, k);
  return false;
}

bool check_load_value(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (v.is_number()) return true;
  if (v.is_array() && std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); }) &&
      dim_ok(c, v.size())) {
    return true;
  }
  report(c, v, path, k);
  return false;
}

bool check_velocity(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (!v.is_array() || !dim_ok(c, v.size())) {
    report(c, v, path, k);
    return false;
  }
  bool ok = true;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const json& e = v[i];
    if (e.is_number()) continue;
    if (!e.is_string()) {
      c.error(item(path, i), "got " + shown(e) + ", expected a number or an expression in x, y, z [m/s]");
      ok = false;
      continue;
    }
    const std::string problem = expression_problem(e.get<std::string>(), {"x", "y", "z"});
    if (!problem.empty()) {
      c.error(item(path, i), "got " + shown(e) + ", expected an expression in x, y, z (muParser: " +
                                 problem + ")");
      ok = false;
    }
  }
  return ok;
}

bool check_time_expression(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (!v.is_string()) {
    report(c, v, path, k);
    return false;
  }
  const std::string problem = expression_problem(v.get<std::string>(), {"t"});
  if (problem.empty()) return true;
  c.error(path, "got " + shown(v) + ", expected an expression in t (muParser: " + problem + ")");
  return false;
}

bool check_time_table(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (!v.is_array() || v.empty() ||
      !std::all_of(v.begin(), v.end(), [](const json& p) { return is_number_array(p, 2); })) {
    report(c, v, path, k);
    return false;
  }
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double t0 = v[i - 1][0].get<double>(), t1 = v[i][0].get<double>();
    if (!(t1 > t0)) {
      c.error(item(path, i), "got t = " + fmt_g(t1) + " after t = " + fmt_g(t0) +
                                 ", expected strictly increasing times [s]");
      return false;
    }
  }
  return true;
}

bool check_vertices(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (!v.is_array() ||
      !std::all_of(v.begin(), v.end(), [](const json& p) { return is_number_array(p, 2); })) {
    report(c, v, path, k);
    return false;
  }
  if (v.size() < 3) {
    c.error(path, "got " + std::to_string(v.size()) + " vertices, expected at least 3 [x, y] pairs [m]");
    return false;
  }
  return true;
}

/// A geometry file path as written, resolved against the folder of the scene file `label`.
std::filesystem::path resolve_file(const std::string& label, const std::string& file) {
  namespace fs = std::filesystem;
  fs::path p(file);
  if (p.is_relative()) p = fs::path(label).parent_path() / p;
  std::error_code ec;
  const fs::path abs = fs::absolute(p, ec);
  return (ec ? p : abs).lexically_normal();
}

/// " (did you mean "x"?)" naming a file in the folder of `missing` with one of `extensions`.
std::string did_you_mean_file(const std::filesystem::path& missing, const std::vector<std::string>& extensions) {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(missing.parent_path(), ec), end; !ec && it != end; it.increment(ec)) {
    if (contains(extensions, lower(it->path().extension().string()))) names.push_back(it->path().filename().string());
  }
  return did_you_mean(missing.filename().string(), names);
}

/// A path, relative to the scene file's folder, to an existing file with one of the extensions
/// in `k.values`.
bool check_file(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (!v.is_string() || v.get_ref<const std::string&>().empty()) {
    report(c, v, path, k);
    return false;
  }
  const std::string file = v.get<std::string>();
  if (!contains(k.values, lower(std::filesystem::path(file).extension().string()))) {
    c.error(path, "got " + shown(v) + " (extension not recognised), expected " + expected(k, c));
    return false;
  }
  const std::filesystem::path full = resolve_file(c.label, file);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(full, ec)) {
    c.error(path, "got " + shown(v) + ", no such file (" + full.string() + "), expected " + expected(k, c) +
                      " relative to the scene file's folder" + did_you_mean_file(full, k.values));
    return false;
  }
  return true;
}

/// gmsh parameters: {"name": number}, names usable as .geo variables (they are written into a .geo
/// prelude, so nothing else may get through).
bool check_parameters(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (!v.is_object()) {
    report(c, v, path, k);
    return false;
  }
  bool ok = true;
  for (const auto& [name, value] : v.items()) {
    const bool identifier = !name.empty() && !std::isdigit(static_cast<unsigned char>(name[0])) &&
                            std::all_of(name.begin(), name.end(), [](char ch) {
                              return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_';
                            });
    if (!identifier) {
      c.error(path + "/" + escape(name), "got parameter name " + in_quotes(name) +
                                             ", expected a gmsh variable name (letters, digits, '_')");
      ok = false;
    } else if (!value.is_number() || !std::isfinite(value.get<double>())) {
      c.error(path + "/" + escape(name), "got " + shown(value) + ", expected a number");
      ok = false;
    }
  }
  return ok;
}

// -- the tables -----------------------------------------------------------------------------------
// Keys are written with designated initializers; fields left out keep their defaults on purpose.
// GCC before 14 warns about that under -Wextra, hence the pragma around the tables only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"

const Table& scene_table() {
  static const Table t{
      "Top level", "the scene object",
      {
          {.name = "name", .type = Type::custom, .required = true,
           .meaning = "Scene name; the default run directory is `runs/<name>`.",
           .type_text = "string", .expect = "a name usable as a directory: letters, digits, '.', '_', '-'",
           .allowed = "`[A-Za-z0-9._-]+`", .check = check_dir_name},
          {.name = "dimension", .type = Type::integer, .required = true, .range = closed(2, 3),
           .meaning = "2 (plane strain) or 3.", .expect = "2 or 3", .allowed = "2 or 3"},
          {.name = "formulation", .type = Type::choice, .def = "auto", .values = names_of(kFormulations),
           .meaning = "Solution scheme; `auto` picks one from the scene and says why."},
          {.name = "gravity", .type = Type::vector, .unit = "m/s^2",
           .meaning = "Gravitational acceleration.", .default_text = "zeros"},
          {.name = "gravity_ramp", .def = 0.0, .range = non_negative, .unit = "s",
           .meaning = "Gravity grows linearly from zero over this time (0: at once)."},
          {.name = "grid", .type = Type::object, .required = true,
           .meaning = "The background grid, see [grid](#grid)."},
          {.name = "materials", .type = Type::objects, .required = true,
           .meaning = "Materials, see [material](#material-every-model).", .nonempty = true},
          {.name = "bodies", .type = Type::objects, .required = true,
           .meaning = "Bodies, see [body](#body).", .nonempty = true},
          {.name = "boundaries", .type = Type::objects, .def = json::array(),
           .meaning = "Grid-face conditions, see [boundary](#boundary)."},
          {.name = "loads", .type = Type::objects, .def = json::array(),
           .meaning = "Surface loads on bodies, see [load](#load)."},
          {.name = "time", .type = Type::object, .required = true,
           .meaning = "End time and time step, see [time](#time)."},
          {.name = "output", .type = Type::object,
           .meaning = "Frames and monitors, see [output](#output).", .default_text = "all defaults"},
          {.name = "solver", .type = Type::object,
           .meaning = "Scheme switches, see [solver](#solver).", .default_text = "all defaults"},
          {.name = "initialisation", .type = Type::object,
           .meaning = "A phase before t = 0 that brings the bodies to equilibrium under gravity, see "
                      "[initialisation](#initialisation).",
           .default_text = "none"},
      }};
  return t;
}

const Table& grid_table() {
  static const Table t{
      "Grid", "`grid`",
      {
          {.name = "cell_size", .required = true, .range = positive, .unit = "m",
           .meaning = "Edge length of the square (2D) or cubic (3D) cells."},
          {.name = "min", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Lower corner of the grid."},
          {.name = "max", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Upper corner; > `min`; rounded up to a whole number of cells."},
          {.name = "shape_function", .type = Type::choice, .def = "gimp",
           .values = names_of(kShapeFunctions), .meaning = "Grid basis functions."},
      }};
  return t;
}

const Table& material_table() {
  static const Table t{
      "Material (every model)", "`materials[]`",
      {
          {.name = "name", .type = Type::string, .required = true,
           .meaning = "Unique name; bodies refer to it in `solid` / `fluid`."},
          {.name = "model", .type = Type::choice, .required = true, .values = names_of(kModels),
           .meaning = "Constitutive model; selects the parameter tables below."},
      }};
  return t;
}

const Table& solid_table() {
  static const Table t{
      "Solid skeleton (every model except `fluid`)", "`materials[]`",
      {
          {.name = "density", .range = positive, .unit = "kg/m^3",
           .meaning = "Bulk density of a dry body (instead of `grain_density` + `porosity`)."},
          {.name = "grain_density", .range = positive, .unit = "kg/m^3",
           .meaning = "Density of the grains; a porous skeleton, needs `porosity`."},
          {.name = "porosity", .range = open(0, 1), .unit = "-",
           .meaning = "Porosity n (pore volume / total volume)."},
          {.name = "hydraulic_conductivity", .range = positive, .unit = "m/s",
           .meaning = "Hydraulic conductivity k (or `intrinsic_permeability`, not both)."},
          {.name = "intrinsic_permeability", .range = positive, .unit = "m^2",
           .meaning = "Intrinsic permeability κ = k μ / (ρ_w g) (or `hydraulic_conductivity`)."},
          {.name = "permeability_law", .type = Type::choice, .def = "constant",
           .values = {"constant", "kozeny-carman", "xie-leo"},
           .meaning = "Permeability constant, varying with porosity (Kozeny–Carman: k = C1 n³/(1 − n)², C1 from the "
                      "initial n0 and k0), or with the volume ratio (`xie-leo`: k = k0 J², J = (1 − n0)/(1 − n), the law "
                      "behind Xie & Leo's large-strain consolidation closed form)."},
      }};
  return t;
}

const Table& elastic_table() {
  static const Table t{
      "Elasticity (`linear-elastic`, `hencky`, `mohr-coulomb`, `drucker-prager`)", "`materials[]`",
      {
          {.name = "youngs_modulus", .required = true, .range = positive, .unit = "Pa",
           .meaning = "Young's modulus E."},
          {.name = "poisson_ratio", .required = true, .range = half_open(-1, 0.5), .unit = "-",
           .meaning = "Poisson's ratio ν."},
      }};
  return t;
}

const Table& strength_table() {
  static const Table t{
      "Strength (`mohr-coulomb`, `drucker-prager`)", "`materials[]`",
      {
          {.name = "cohesion", .def = 0.0, .range = non_negative, .unit = "Pa",
           .meaning = "Cohesion c."},
          {.name = "friction_angle", .required = true, .range = half_open(0, 90), .unit = "deg",
           .meaning = "Friction angle φ."},
          {.name = "dilation_angle", .def = 0.0, .range = half_open(0, 90), .unit = "deg",
           .meaning = "Dilation angle ψ (0: no dilatancy).", .allowed = "[0, `friction_angle`]"},
          {.name = "strength_reduction_factor", .def = 1.0, .range = positive, .unit = "-",
           .meaning = "c and tan φ are divided by it (slope stability; 1: none)."},
          {.name = "tension_cutoff", .def = 0.0, .range = non_negative, .unit = "Pa",
           .meaning = "Tensile strength limit on the mean stress (0: no tension)."},
      }};
  return t;
}

const Table& nor_sand_table() {
  static const Table t{
      "Nor-Sand (`nor-sand`)", "`materials[]`",
      {
          {.name = "shear_modulus", .required = true, .range = positive, .unit = "Pa",
           .meaning = "Elastic shear modulus μ0 (G; the shear modulus at zero `shear_modulus_coupling`)."},
          {.name = "shear_modulus_coupling", .def = 0.0, .range = non_negative, .unit = "-",
           .meaning = "α0 of Borja & Andrade's hyperelasticity: μ_e = μ0 + α0 p̂ (0: constant shear modulus)."},
          {.name = "swelling_index", .required = true, .range = positive, .unit = "-",
           .meaning = "Elastic compressibility κ̃ = −dε_v^e / d ln p′ (logarithmic strain; ≈ κ / v)."},
          {.name = "reference_pressure", .def = 2.0e3, .range = positive, .unit = "Pa",
           .meaning = "Pressure p_ref of the hyperelastic law at `reference_elastic_volumetric_strain`."},
          {.name = "reference_elastic_volumetric_strain", .def = 0.0, .range = any_number, .unit = "-",
           .meaning = "Elastic volumetric strain ε_v0^e at `reference_pressure` (tension positive)."},
          {.name = "compression_index", .required = true, .range = positive, .unit = "-",
           .meaning = "Slope λ̃ of the critical state line in v–ln p′."},
          {.name = "reference_specific_volume", .required = true, .range = positive, .unit = "-",
           .meaning = "Specific volume v_c0 of the critical state line at `csl_reference_pressure`."},
          {.name = "csl_reference_pressure", .def = 1.0e3, .range = positive, .unit = "Pa",
           .meaning = "Pressure unit of the critical state line: v_c = v_c0 − λ̃ ln(p′ / p_csl)."},
          {.name = "critical_state_ratio", .required = true, .range = positive, .unit = "-",
           .meaning = "Critical state stress ratio M (triaxial compression)."},
          {.name = "yield_coefficient", .required = true, .range = half_open(0, 1), .unit = "-",
           .meaning = "Shape coefficient N of the yield surface (0: the logarithmic form)."},
          {.name = "potential_coefficient", .required = true, .range = half_open(0, 1), .unit = "-",
           .meaning = "Shape coefficient N̄ of the plastic potential (N̄ = N: associated)."},
          {.name = "hardening_modulus", .required = true, .range = positive, .unit = "-",
           .meaning = "Hardening coefficient h of the image pressure: π̇_i = h (π_i* − π_i) ε̇_s^p."},
          {.name = "dilatancy_multiplier", .required = true, .range = any_number, .unit = "-",
           .meaning = "α of the maximum plastic dilatancy α ψ_i (negative, e.g. −3.5)."},
          {.name = "initial_specific_volume", .required = true, .range = positive, .unit = "-",
           .meaning = "Specific volume v0 = 1 + e0 at F = I; v = J v0."},
          {.name = "overconsolidation_ratio", .def = 1.0, .range = at_least(1), .unit = "-",
           .meaning = "OCR: the initial image pressure is OCR × the one that puts the first stress on the yield surface."},
          {.name = "dilatancy_cutoff_start", .def = 1.0, .range = positive, .unit = "-",
           .meaning = "Accumulated deviatoric plastic strain Ē_d^p where ψ_i starts fading to 0 (1 = 100 %)."},
          {.name = "dilatancy_cutoff_end", .def = 1.5, .range = positive, .unit = "-",
           .meaning = "Ē_d^p where ψ_i reaches 0 (≥ `dilatancy_cutoff_start`)."},
          {.name = "gas_specific_volume_ratio", .def = 1.6, .range = positive, .unit = "-",
           .meaning = "v_crit / v0: above v_crit the stress is zero (gas-like, reversible)."},
      }};
  return t;
}

const Table& fluid_table() {
  static const Table t{
      "Fluid (`fluid`)", "`materials[]`",
      {
          {.name = "density", .required = true, .range = positive, .unit = "kg/m^3",
           .meaning = "Fluid density ρ_w."},
          {.name = "bulk_modulus", .required = true, .range = positive, .unit = "Pa",
           .meaning = "Fluid bulk modulus K_w."},
          {.name = "dynamic_viscosity", .def = 1.0e-3, .range = positive, .unit = "Pa s",
           .meaning = "Dynamic viscosity μ (turns `intrinsic_permeability` into conductivity)."},
      }};
  return t;
}

const Table& body_table() {
  static const Table t{
      "Body", "`bodies[]`",
      {
          {.name = "name", .type = Type::string, .required = true,
           .meaning = "Unique name; loads refer to it."},
          {.name = "geometry", .type = Type::object, .required = true,
           .meaning = "Where the body is, see [geometry](#geometry-every-type)."},
          {.name = "solid", .type = Type::string,
           .meaning = "Name of a solid material (the skeleton)."},
          {.name = "fluid", .type = Type::string,
           .meaning = "Name of a `fluid` material (pore fluid, or free fluid without `solid`)."},
          {.name = "particles_per_cell", .type = Type::integer, .def = 2, .range = closed(1, 32),
           .meaning = "Particles per cell and direction (n^dimension per cell)."},
          {.name = "initial", .type = Type::object,
           .meaning = "Initial state, see [initial state](#initial-state).", .default_text = "all defaults"},
      }};
  return t;
}

const Table& geometry_table() {
  static const Table t{
      "Geometry (every type)", "`bodies[].geometry`",
      {
          {.name = "type", .type = Type::choice, .required = true, .values = geometry_types(),
           .meaning = "Kind of geometry; its keys are in the table of that type below."},
      }};
  return t;
}

const Table& box_table() {
  static const Table t{
      "Box (`box`)", "`bodies[].geometry`",
      {
          {.name = "min", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Lower corner; inside the grid."},
          {.name = "max", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Upper corner; > `min` in every component, inside the grid."},
      }};
  return t;
}

const Table& polygon_table() {
  static const Table t{
      "Polygon (`polygon`, 2D only)", "`bodies[].geometry`",
      {
          {.name = "vertices", .type = Type::custom, .required = true, .unit = "m",
           .meaning = "Corners in order (either orientation); non-zero area, inside the grid.",
           .type_text = "array of [x, y]", .expect = "an array of at least 3 [x, y] pairs",
           .allowed = "≥ 3 vertices", .check = check_vertices},
      }};
  return t;
}

const Table& slope_table() {
  static const Table t{
      "Slope (`slope`, 2D only)", "`bodies[].geometry`",
      {
          {.name = "foundation_depth", .required = true, .range = positive, .unit = "m",
           .meaning = "Thickness of the foundation layer, from its base up to the toe."},
          {.name = "height", .required = true, .range = positive, .unit = "m",
           .meaning = "Height of the slope, from the toe up to the crest."},
          {.name = "angle", .range = open(0, 90), .unit = "deg",
           .meaning = "Inclination of the slope face from the horizontal (or `ratio`, exactly one)."},
          {.name = "ratio", .range = positive, .unit = "-",
           .meaning = "Slope face gradient horizontal : vertical, e.g. 2 for 1V:2H (or `angle`)."},
          {.name = "crest_length", .required = true, .range = positive, .unit = "m",
           .meaning = "Horizontal length of the crest, from the top of the face to the right side."},
          {.name = "toe_length", .required = true, .range = positive, .unit = "m",
           .meaning = "Horizontal length of the ground in front of the toe, from the left side."},
          {.name = "origin", .type = Type::vector, .unit = "m",
           .meaning = "Lower-left corner of the foundation.", .default_text = "grid `min`"},
      }};
  return t;
}

const Table& footing_table() {
  static const Table t{
      "Footing (`footing`)", "`bodies[].geometry`",
      {
          {.name = "width", .required = true, .range = positive, .unit = "m",
           .meaning = "Extent along x."},
          {.name = "height", .required = true, .range = positive, .unit = "m",
           .meaning = "Extent along y (the block's thickness)."},
          {.name = "center_x", .required = true, .range = any_number, .unit = "m",
           .meaning = "x of the block's centre."},
          {.name = "center_z", .range = any_number, .unit = "m",
           .meaning = "z of the block's centre; required in 3D, only there."},
          {.name = "length", .range = positive, .unit = "m",
           .meaning = "Extent along z; required in 3D, only there."},
          {.name = "on", .type = Type::string,
           .meaning = "Name of the body the block rests on: its base is that body's top (highest point); "
                      "or give `base_y`."},
          {.name = "base_y", .range = any_number, .unit = "m",
           .meaning = "Height of the block's base (instead of `on`)."},
      }};
  return t;
}

const Table& gmsh_table() {
  static const Table t{
      "Gmsh (`gmsh`)", "`bodies[].geometry`",
      {
          {.name = "file", .type = Type::custom, .required = true, .values = {".geo", ".msh"},
           .meaning = "Gmsh file, relative to the scene file's folder; a `.geo` is meshed when preprocess reads it.",
           .type_text = "string", .expect = "a path to an existing .geo or .msh file",
           .allowed = "`.geo`, `.msh`", .check = check_file},
          {.name = "parameters", .type = Type::custom, .def = json::object(), .unit = "as in the file",
           .meaning = "Values for the `.geo` file's `DefineConstant` variables, by name (not with `.msh`).",
           .type_text = "object of numbers", .expect = "an object of numbers keyed by DefineConstant names",
           .allowed = "`DefineConstant` names", .default_text = "none", .check = check_parameters},
          {.name = "physical", .type = Type::string,
           .meaning = "Physical group forming the body: a surface group (2D) or volume group (3D); "
                      "default: every surface (2D) / volume (3D) of the file."},
      }};
  return t;
}

const Table& surface_mesh_table() {
  static const Table t{
      "Surface mesh (`surface-mesh`, 3D only)", "`bodies[].geometry`",
      {
          {.name = "file", .type = Type::custom, .required = true, .values = {".off", ".stl", ".obj"},
           .meaning = "Closed, not self-intersecting surface mesh, relative to the scene file's folder.",
           .type_text = "string", .expect = "a path to an existing .off, .stl or .obj file",
           .allowed = "`.off`, `.stl`, `.obj`", .check = check_file},
      }};
  return t;
}

const Table& initial_table() {
  static const Table t{
      "Initial state", "`bodies[].initial`",
      {
          {.name = "pore_pressure", .type = Type::custom, .unit = "Pa",
           .meaning = "Initial pore pressure (compression positive), or hydrostatic; needs a body `fluid`.",
           .type_text = "number or string", .expect = "a number or \"hydrostatic\"",
           .allowed = "any, or `\"hydrostatic\"`", .check = check_pore_pressure},
          {.name = "water_table", .range = any_number, .unit = "m",
           .meaning = "Height of the free water surface for `\"hydrostatic\"` (default: top of the body)."},
          {.name = "stress", .type = Type::custom, .unit = "Pa",
           .meaning = "Initial effective stress: `\"geostatic\"`, or constant Voigt [xx, yy, zz, xy, yz, xz], tension positive.",
           .type_text = "string or 6 numbers", .expect = "\"geostatic\" or an array of 6 numbers (xx, yy, zz, xy, yz, xz)",
           .allowed = "`\"geostatic\"` or 6 numbers", .check = check_stress},
          {.name = "k0", .def = 0.5, .range = closed(0, 10), .unit = "-",
           .meaning = "Lateral earth pressure coefficient (only with `\"geostatic\"`)."},
          {.name = "porosity", .range = open(0, 1), .unit = "-",
           .meaning = "Initial porosity; overrides the material's."},
          {.name = "velocity", .type = Type::custom, .unit = "m/s",
           .meaning = "Initial velocity; each component a number or a muParser expression in x, y, z (`pi` defined).",
           .type_text = "`dimension` numbers or strings",
           .expect = "an array of one number or expression per dimension", .allowed = "expressions in x, y, z",
           .default_text = "zeros", .check = check_velocity},
      }};
  return t;
}

const Table& boundary_table() {
  static const Table t{
      "Boundary", "`boundaries[]`",
      {
          {.name = "on", .type = Type::string, .required = true,
           .meaning = "Grid face (`z_min`, `z_max` only in 3D), or a geometry's named surface (a rigid "
                      "wall along it); each at most once.",
           .allowed = "`x_min`, `x_max`, `y_min`, `y_max`, `z_min`, `z_max`, or a named surface"},
          {.name = "solid", .type = Type::choice, .def = "free", .values = solid_bc_names(),
           .meaning = "Solid velocity condition: fixed (all components), roller (normal), free, friction."},
          {.name = "coefficient", .range = non_negative, .unit = "-",
           .meaning = "Coulomb friction coefficient; required with `friction`, only there."},
          {.name = "fluid", .type = Type::choice, .values = fluid_bc_names(),
           .meaning = "Fluid condition: no flow, p = 0, or p = `value`; needs a fluid in the scene."},
          {.name = "value", .range = any_number, .unit = "Pa",
           .meaning = "Prescribed pore pressure; required with `pressure`, only there."},
      }};
  return t;
}

const Table& load_table() {
  static const Table t{
      "Load", "`loads[]`",
      {
          {.name = "type", .type = Type::choice, .required = true, .values = {"traction", "pressure"},
           .meaning = "A traction vector, or a pressure normal to the face."},
          {.name = "body", .type = Type::string, .required = true,
           .meaning = "Name of the loaded body."},
          {.name = "face", .type = Type::string, .required = true,
           .meaning = "The body's surface layer facing that way (`z_*` only in 3D), or along one of its "
                      "named surfaces.",
           .allowed = "`x_min`, `x_max`, `y_min`, `y_max`, `z_min`, `z_max`, or a named surface"},
          {.name = "value", .type = Type::custom, .required = true, .unit = "Pa",
           .meaning = "traction: a `dimension`-vector; pressure: a number, positive pushing onto the face.",
           .type_text = "vector or number", .expect = "a vector of one number per dimension (traction) or a number (pressure)",
           .allowed = "any", .check = check_load_value},
          {.name = "region", .type = Type::object,
           .meaning = "Load only the face particles inside this box at t = 0, see [region](#region)."},
          {.name = "ramp", .def = 0.0, .range = non_negative, .unit = "s",
           .meaning = "The load grows linearly from zero over this time (0: at once)."},
          {.name = "function", .type = Type::custom, .unit = "-",
           .meaning = "Multiplier f(t): a muParser expression in t (`pi` defined), e.g. `\"sin(5*pi*t)\"`.",
           .type_text = "string", .expect = "an expression in t", .allowed = "expression in t",
           .check = check_time_expression},
          {.name = "table", .type = Type::custom, .unit = "-",
           .meaning = "Multiplier f(t) as [t, f] pairs, piecewise linear, clamped; not with `function`.",
           .type_text = "array of [t, f]", .expect = "a non-empty array of [t, f] pairs",
           .allowed = "t strictly increasing", .check = check_time_table},
      }};
  return t;
}

const Table& region_table() {
  static const Table t{
      "Region", "`loads[].region`",
      {
          {.name = "min", .type = Type::vector, .required = true, .unit = "m", .meaning = "Lower corner."},
          {.name = "max", .type = Type::vector, .required = true, .unit = "m",
           .meaning = "Upper corner; > `min` in every component."},
      }};
  return t;
}

const Table& time_table() {
  static const Table t{
      "Time", "`time`",
      {
          {.name = "end", .required = true, .range = positive, .unit = "s", .meaning = "Simulated end time."},
          {.name = "dt", .type = Type::custom, .def = "auto", .unit = "s",
           .meaning = "Time step, or `\"auto\"`: the critical step of the formulation times `cfl`.",
           .type_text = "number or string", .expect = "a positive number or \"auto\"",
           .allowed = "> 0 or `\"auto\"`", .check = check_dt},
          {.name = "cfl", .def = 0.5, .range = left_open(0, 1), .unit = "-",
           .meaning = "Courant number used with `\"auto\"`."},
      }};
  return t;
}

const Table& output_table() {
  static const Table t{
      "Output", "`output`",
      {
          {.name = "interval", .def = 0.0, .range = non_negative, .unit = "s",
           .meaning = "Simulated time between VTU frames (0: first and last only)."},
          {.name = "monitor_interval", .def = 0.0, .range = non_negative, .unit = "s",
           .meaning = "Simulated time between rows of monitors.csv (0: every step)."},
          {.name = "compression", .type = Type::choice, .def = "zlib", .values = {"zlib", "lz4", "none"},
           .meaning = "Compression of the VTU frames' binary data: `zlib` (level 1; read by every VTU reader), "
                      "`lz4` (frames written about 7 times faster, files about 35 % larger; VTK-based readers "
                      "such as ParaView read it, some standalone readers do not) or `none` (fastest, files about "
                      "2.3 times zlib's). B4 12^2 double-point frame (172k points): 0.34 / 0.048 / 0.035 s "
                      "(docs/verification.md)."},
          {.name = "checkpoint_interval", .range = positive, .unit = "s",
           .meaning = "Simulated time between restart checkpoints on disk (`RUN_DIR/checkpoint.bin`, the latest "
                      "only), from which `swmpm solve RUN_DIR --resume` continues; absent: one with every frame. "
                      "Not `solver.checkpoint_every`, the in-memory last-good snapshots.",
           .default_text = "with every frame"},
          {.name = "monitors", .type = Type::objects, .def = json::array(),
           .meaning = "Time histories, see [monitor](#monitor)."},
      }};
  return t;
}

const Table& monitor_table() {
  static const Table t{
      "Monitor", "`output.monitors[]`",
      {
          {.name = "name", .type = Type::custom, .required = true,
           .meaning = "Unique; CSV columns are `<name>.<quantity>`.", .type_text = "string",
           .expect = "a name of letters, digits, '_', '-'", .allowed = "`[A-Za-z0-9_-]+`",
           .check = check_monitor_name},
          {.name = "at", .type = Type::vector, .unit = "m",
           .meaning = "Follow the particle of `phase` nearest to this point at t = 0."},
          {.name = "particle", .type = Type::integer, .range = at_least(0),
           .meaning = "Or follow this particle id (not with `at`)."},
          {.name = "phase", .type = Type::choice, .def = "solid", .values = {"solid", "fluid"},
           .meaning = "Which phase's particle (`fluid` needs a fluid in the scene). In the double-point formulations "
                      "every point monitor follows a soil point, whatever `phase` says: the soil points carry the "
                      "water's pore pressure and velocity interpolated from the water points (docs/architecture.md), "
                      "and the log names the soil particle followed."},
          {.name = "points", .type = Type::choice, .def = "soil", .values = {"soil", "water"},
           .meaning = "Which particle set a point monitor follows: `water` follows a water point of a double-point "
                      "formulation (`at`: the nearest at t = 0, or `particle`: its id), e.g. one at a free surface, "
                      "and may record `displacement_*`, `velocity_*` (the water's), `pore_pressure`, `porosity`."},
          {.name = "quantities", .type = Type::choices, .required = true, .values = all_quantities(),
           .meaning = "What to record; see [monitor rules](#monitor-rules) for which need what.", .nonempty = true},
      }};
  return t;
}

const Table& solver_table() {
  static const Table t{
      "Solver", "`solver`",
      {
          {.name = "flip", .def = 0.99, .range = closed(0, 1), .unit = "-",
           .meaning = "FLIP fraction of the FLIP/PIC velocity update (1: pure FLIP)."},
          {.name = "damping", .def = 0.0, .range = half_open(0, 1), .unit = "-",
           .meaning = "Local (Cundall) damping coefficient."},
          {.name = "kinematics", .type = Type::choice, .def = "finite-strain",
           .values = {"small-strain", "finite-strain"}, .meaning = "Strain measure of the `mohr-coulomb` update (`nor-sand`: finite strain only); refused when no material reads it."},
          {.name = "continuity", .type = Type::choice,
           .values = {"non-conservative", "conservative"},
           .meaning = "Two-phase mixture volume balance: `non-conservative` (1 − n) div v_s + n div v_w "
                      "(the seeds' eq. 9 / eq. 60) or `conservative` div[(1 − n) v_s + n v_w], which adds "
                      "(v_w − v_s)·grad n (needed at large strain, A2 and B2; see docs/formulations.md); in "
                      "explicit-single-point it also adds the interaction force p grad n between the phases; "
                      "default by formulation: `conservative` (semi-implicit), `non-conservative` otherwise "
                      "(explicit-single-point: the seed's eq. 9)."},
          {.name = "escaped_water", .type = Type::choice, .def = "keep", .values = {"keep", "remove"},
           .meaning = "Double-point only: water points that have left the soil (the soil's volume fraction "
                      "interpolated at the point below one half) stay as free water (`keep`) or leave the "
                      "run (`remove`: an outflow through a drained free surface into a reservoir that is not "
                      "modelled, as in B2; see docs/formulations.md)."},
          {.name = "drag_integration", .type = Type::choice, .values = {"implicit", "semi-implicit"},
           .meaning = "Semi-implicit formulations: the soil–water drag of the predictor implicit in both "
                      "phases' velocities (`implicit`, the default) or in the water's only, the soil taking "
                      "it from v_w* and its own v_s^t (`semi-implicit`, seed 001 eqs. 52–53). The seed's "
                      "form amplifies the relative velocity by about M_w/M_s where the drag is stiff, so a "
                      "node with much more water than soil (free water over soil, a seepage exit) diverges; "
                      "see docs/formulations.md, \"Implicit drag\"."},
          {.name = "checkpoint_every", .type = Type::integer, .def = 50, .range = at_least(1),
           .meaning = "Steps between in-memory snapshots of the last good state."},
          {.name = "stabilisation", .type = Type::object,
           .meaning = "See [stabilisation](#stabilisation).", .default_text = "all defaults"},
      }};
  return t;
}

const Table& initialisation_table() {
  static const Table t{
      "Initialisation", "`initialisation`",
      {
          {.name = "duration", .required = true, .range = positive, .unit = "s",
           .meaning = "Length of the phase; it runs from t = −duration to 0, the analysis from 0 to `time.end`."},
          {.name = "gravity_ramp", .range = non_negative, .unit = "s",
           .meaning = "Gravity grows linearly from zero over this time from the start of the phase (≤ `duration`); "
                      "the top-level `gravity_ramp` must then be 0.",
           .default_text = "`duration`"},
          {.name = "plasticity", .type = Type::boolean, .def = false,
           .meaning = "Plastic flow during the phase (false: every material responds elastically; Nor-Sand's image "
                      "pressure is set from the stress at t = 0)."},
          {.name = "hydraulic_conductivity", .range = positive, .unit = "m/s",
           .meaning = "Hydraulic conductivity of every porous material during the phase (e.g. 1 m/s: the pore "
                      "pressures dissipate as gravity grows).",
           .default_text = "the materials' own"},
          {.name = "tie_water", .type = Type::boolean, .def = true,
           .meaning = "Double-point formulations: each water point follows its coincident soil point during the "
                      "phase (no seepage of the points; the grid still solves the flow)."},
          {.name = "damping", .range = half_open(0, 1), .unit = "-",
           .meaning = "Local damping during the phase.", .default_text = "`solver.damping`"},
          {.name = "reset_displacement", .type = Type::boolean, .def = true,
           .meaning = "Displacements (frames, monitors) are measured from the state at t = 0."},
      }};
  return t;
}

const Table& stabilisation_table() {
  static const Table t{
      "Stabilisation", "`solver.stabilisation`",
      {
          {.name = "strain_smoothing", .type = Type::boolean, .def = true,
           .meaning = "Smooth volumetric strain over cells."},
          {.name = "pressure", .type = Type::choice,
           .values = {"none", "mfvp-constant", "mfvp-linear", "mfvp-quadratic", "node-remap", "cell-constant"},
           .meaning = "Pore-pressure stabilisation; default by formulation: `mfvp-linear` "
                      "(explicit-single-point and semi-implicit), `none` otherwise. `cell-constant` "
                      "(explicit-single-point): one pressure per grid cell, its rate the exact transpose of "
                      "the pressure forces (docs/formulations.md)."},
          {.name = "fbar", .type = Type::choice, .def = "none", .values = {"none", "standard", "modified"},
           .meaning = "F-bar treatment of volumetric locking (seed 001 §4.4.2, every formulation): `standard` "
                      "scales ΔF by the node-wise average of det ΔF (eqs. 79-80); `modified` also averages the "
                      "elastic J^e over fixed patches (eqs. 81-83)."},
          {.name = "fbar_patch", .range = closed(1, 4), .unit = "-",
           .meaning = "Modified F-bar: patch side h_patch / h of the fixed lattice of squares (cubes) from "
                      "`grid.min` over which J^e is averaged (1: cell-wise; read only with `fbar: modified`).",
           .default_text = "1 (linear, gimp), 1.5 (bspline2, bspline3)"},
      }};
  return t;
}

#pragma GCC diagnostic pop

/// Every table, in the order of the reference.
std::vector<const Table*> all_tables() {
  return {&scene_table(),     &grid_table(),     &material_table(),  &solid_table(),
          &elastic_table(),   &strength_table(), &nor_sand_table(),  &fluid_table(),
          &body_table(),      &geometry_table(), &box_table(),       &polygon_table(),
          &slope_table(),     &footing_table(),  &gmsh_table(),      &surface_mesh_table(),
          &initial_table(),   &boundary_table(), &load_table(),      &region_table(),
          &time_table(),      &output_table(),   &monitor_table(),   &solver_table(),
          &stabilisation_table(), &initialisation_table()};
}

/// The parameter tables of a material model, besides material_table().
std::vector<const Table*> model_tables(MaterialModel m) {
  switch (m) {
    case MaterialModel::linear_elastic:
    case MaterialModel::hencky: return {&solid_table(), &elastic_table()};
    case MaterialModel::mohr_coulomb:
    case MaterialModel::drucker_prager: return {&solid_table(), &elastic_table(), &strength_table()};
    case MaterialModel::nor_sand: return {&solid_table(), &nor_sand_table()};
    case MaterialModel::fluid: return {&fluid_table()};
  }
  return {};
}

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

bool check_value(Ctx& c, const Key& k, const json& v, const std::string& path) {
  switch (k.type) {
    case Type::number:
      if (v.is_number() && k.range.contains(v.get<double>())) return true;
      break;
    case Type::integer:
      if (is_integral(v) && k.range.contains(v.get<double>())) return true;
      break;
    case Type::boolean:
      if (v.is_boolean()) return true;
      break;
    case Type::string:
      if (v.is_string() && !v.get_ref<const std::string&>().empty()) return true;
      break;
    case Type::choice:
      if (v.is_string() && contains(k.values, v.get<std::string>())) return true;
      if (v.is_string()) {
        c.error(path, "got " + shown(v) + ", expected " + expected(k, c) +
                          did_you_mean(v.get<std::string>(), k.values));
        return false;
      }
      break;
    case Type::vector:
      if (v.is_array() && std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); })) {
        if (dim_ok(c, v.size())) return true;
        c.error(path, "got " + shown(v) + " (" + std::to_string(v.size()) + " components), expected " +
                          expected(k, c));
        return false;
      }
      break;
    case Type::object:
      if (v.is_object()) return true;
      break;
    case Type::objects:
      if (v.is_array() && !(k.nonempty && v.empty())) return true;
      break;
    case Type::choices: {
      if (!v.is_array() || v.empty()) break;
      bool ok = true;
      for (std::size_t i = 0; i < v.size(); ++i) {
        const json& e = v[i];
        if (e.is_string() && contains(k.values, e.get<std::string>())) continue;
        ok = false;
        c.error(item(path, i), "got " + shown(e) + ", expected one of: " + join(k.values) +
                                   (e.is_string() ? did_you_mean(e.get<std::string>(), k.values) : ""));
      }
      return ok;
    }
    case Type::custom:
      return k.check(c, v, path, k);
  }
  report(c, v, path, k);
  return false;
}

std::string unknown_key_message(const std::string& name, const std::vector<const Key*>& keys) {
  std::vector<std::string> names;
  for (const Key* k : keys) names.push_back(k->name);
  if (const auto c = closest(name, names)) {
    return "unknown key " + in_quotes(name) + ", did you mean " + in_quotes(*c) + "?";
  }
  return "unknown key " + in_quotes(name) + ", expected one of: " + join(names);
}

/// Checks `j` against the union of `tables`. With report_unknown false, keys not in the tables are
/// passed over (used when the tables themselves are unknown, e.g. a material with a bad model).
Obj check_object(Ctx& c, const json& j, const std::string& path,
                 const std::vector<const Table*>& tables, bool report_unknown = true) {
  Obj o;
  o.path = path;
  if (!j.is_object()) {
    c.error(path, "got " + shown(j) + ", expected an object");
    return o;
  }
  o.is_object = true;
  std::vector<const Key*> keys;
  for (const Table* t : tables) {
    for (const Key& k : t->keys) keys.push_back(&k);
  }
  std::vector<std::string> names;
  for (const Key* k : keys) names.push_back(k->name);

  // Unknown keys first, to learn which declared keys they are probably misspellings of: a
  // required key is then not also reported missing. Their lines go after the declared keys'.
  std::vector<std::pair<std::string, std::string>> unknown;  // path, message
  std::set<std::string> suggested;
  for (const auto& [name, value] : j.items()) {
    o.given.insert(name);
    if (!report_unknown || contains(names, name)) continue;
    unknown.emplace_back(o.at(name), unknown_key_message(name, keys));
    if (const auto guess = closest(name, names)) suggested.insert(*guess);
  }
  // Declared keys in table order, so that messages follow the reference.
  for (const Key* k : keys) {
    if (j.contains(k->name)) {
      if (check_value(c, *k, j[k->name], o.at(k->name))) o.v[k->name] = j[k->name];
    } else if (k->required) {
      if (suggested.count(k->name) == 0) {
        c.error(o.at(k->name), "missing required key, expected " + expected(*k, c));
      }
    } else if (!k->def.is_null()) {
      o.v[k->name] = k->def;
    }
  }
  for (const auto& [p, message] : unknown) c.error(p, message);
  return o;
}

// ------------------------------------------------------------------------------------------------
// The section parsers: typed values out of checked objects, and the rules across keys.
// ------------------------------------------------------------------------------------------------

/// Axis-aligned bounds of a geometry [m].
struct Bounds {
  Vec3 min{0, 0, 0}, max{0, 0, 0};
};

class SceneParser {
 public:
  SceneParser(const json& root, const std::string& label) : root_(root) { c_.label = label; }

  Scene parse() {
    s_.source_file = c_.label;
    if (!root_.is_object()) {
      c_.error("", "got " + shown(root_) + ", expected a JSON object (the scene)");
      throw SceneError(c_.errors);
    }
    // The dimension first: every vector's length depends on it.
    const json* dim = root_.contains("dimension") ? &root_["dimension"] : nullptr;
    if (dim != nullptr && is_integral(*dim) && (*dim == 2 || *dim == 3)) c_.dim = dim->get<int>();

    const Obj top = check_object(c_, root_, "", {&scene_table()});
    s_.name = top.str("name");
    s_.dimension = c_.dim == 0 ? 2 : c_.dim;
    s_.gravity = top.vec("gravity");
    s_.gravity_ramp = top.num("gravity_ramp");

    if (top.ok("grid")) parse_grid(top.get("grid"), top.at("grid"));
    if (top.ok("materials")) parse_materials(top.get("materials"), top.at("materials"));
    if (top.ok("bodies")) parse_bodies(top.get("bodies"), top.at("bodies"));
    if (top.ok("boundaries")) parse_boundaries(top.get("boundaries"), top.at("boundaries"));
    if (top.ok("loads")) parse_loads(top.get("loads"), top.at("loads"));
    if (top.ok("time")) parse_time(top.get("time"), top.at("time"));
    parse_output(top.ok("output") ? top.get("output") : json::object(), top.at("output"));
    parse_solver(top.ok("solver") ? top.get("solver") : json::object(), top.at("solver"));
    if (top.ok("formulation")) resolve_formulation(top.str("formulation"), top.at("formulation"));
    for (const auto& at : water_monitors_)
      if (s_.formulation != Formulation::semi_implicit_double_point &&
          s_.formulation != Formulation::explicit_double_point)
        c_.error(at, "got \"water\", but only the double-point formulations have water points; expected \"soil\"");
    const bool semi_implicit = s_.formulation == Formulation::semi_implicit_single_point ||
                               s_.formulation == Formulation::semi_implicit_double_point;
    if (s_.solver.continuity.empty()) s_.solver.continuity = semi_implicit ? "conservative" : "non-conservative";
    if (s_.solver.continuity == "conservative" && !semi_implicit &&
        s_.formulation != Formulation::explicit_single_point)
      c_.error(top.at("solver") + "/continuity",
               "got \"conservative\", which the two-phase formulations implement; this scene's formulation "
               "has no pore water (remove the key)");
    if (s_.solver.escaped_water == "remove" && s_.formulation != Formulation::semi_implicit_double_point)
      c_.error(top.at("solver") + "/escaped_water",
               "got \"remove\", which applies to the water points of semi-implicit-double-point; this scene's "
               "formulation has none (remove the key)");
    if (!s_.solver.drag_integration.empty() && !semi_implicit)
      c_.error(top.at("solver") + "/drag_integration",
               "got \"" + s_.solver.drag_integration +
                   "\", which applies to the semi-implicit formulations' predictor; this scene's formulation "
                   "does not use it (remove the key)");
    if (s_.solver.drag_integration.empty() && semi_implicit) s_.solver.drag_integration = "implicit";
    if (top.ok("initialisation")) parse_initialisation(top.get("initialisation"), top.at("initialisation"), top);
    if (s_.solver.stabilisation.fbar_patch == 0.0)
      s_.solver.stabilisation.fbar_patch = default_fbar_patch(s_.grid.shape_function);
    if (s_.solver.stabilisation.pressure.empty()) {
      // The seeds' choices: seed 000 runs strain smoothing with the multi-field variational
      // pressure (basis not stated; the linear one is the smallest that keeps A5 bounded with FLIP
      // 0.99, docs/verification.md), seed 001 the node-wise map/remap of the pressure.
      switch (s_.formulation) {
        case Formulation::explicit_single_point: s_.solver.stabilisation.pressure = "mfvp-linear"; break;
        // Semi-implicit: the node-wise projection with a linear basis (eq. 77 is its constant-basis
        // case, which biases free-surface nodes: 3.4 % pressure error and 1e-3 m/s of spurious
        // flow in a hydrostatic layer at rest, where the linear one is exact; docs/verification.md).
        case Formulation::semi_implicit_single_point:
        case Formulation::semi_implicit_double_point: s_.solver.stabilisation.pressure = "mfvp-linear"; break;
        default: s_.solver.stabilisation.pressure = "none"; break;
      }
    }

    if (!c_.errors.empty()) {
      std::vector<std::string> unique;
      for (const auto& e : c_.errors) {
        if (!contains(unique, e)) unique.push_back(e);
      }
      throw SceneError(unique);
    }
    return s_;
  }

 private:
  struct MaterialInfo {
    std::string path;
    bool known = false;  // model known (parameters checked)
    bool gives_density = false, gives_grain_density = false, gives_porosity = false;
    bool gives_permeability = false;
    bool saturated_reported = false;
  };

  Ctx c_;
  const json& root_;
  Scene s_;
  bool grid_ok_ = false;
  Vec3 grid_min_{0, 0, 0}, grid_max_{0, 0, 0};  // as written (before rounding up) [m]
  std::vector<MaterialInfo> material_info_;
  std::vector<std::string> body_paths_;
  std::vector<std::string> water_monitors_;  // JSON paths of monitors with points "water"
  std::vector<std::optional<Bounds>> body_bounds_;  // per body, when known before preprocess
  struct PendingFooting {
    std::size_t body;
    std::string on, path;  // the body it rests on; the footing's geometry path
  };
  std::vector<PendingFooting> pending_footings_;  // footings with `on`, resolved after all bodies
  std::vector<std::string> surface_names_;        // named surfaces referred to (face bits 6..)

  int dim() const { return s_.dimension; }

  /// Face names of this scene's dimension.
  std::vector<std::string> faces() const {
    std::vector<std::string> f(face_names().begin(), face_names().begin() + (dim() == 3 ? 6 : 4));
    return f;
  }

  /// An axis face of this dimension, or a named surface among `named` (the surfaces known now).
  /// With `deferred` (a gmsh geometry, whose names preprocess reads from its file) any other
  /// name passes here and is checked there. `none` says whose surfaces are missing.
  bool check_face(const std::string& face, const std::string& path, const std::vector<std::string>& named,
                  bool deferred, const std::string& none) {
    if (contains(faces(), face)) return true;
    if (contains(face_names(), face)) {
      c_.error(path, "got " + in_quotes(face) + ", expected one of: " + join(faces()) +
                         " (z faces exist only in 3D scenes)");
      return false;
    }
    if (!contains(named, face) && !deferred) {
      std::vector<std::string> all = faces();
      all.insert(all.end(), named.begin(), named.end());
      c_.error(path, "got " + in_quotes(face) + ", expected one of: " + join(faces()) +
                         (named.empty() ? " (" + none + ")" : ", or a named surface: " + join(named)) +
                         did_you_mean(face, all));
      return false;
    }
    // A named surface gets a face bit; there are 26 of them.
    if (!contains(surface_names_, face)) {
      if (surface_names_.size() == static_cast<std::size_t>(kMaxNamedSurfaces)) {
        c_.error(path, "got " + in_quotes(face) + ", a named surface beyond the " +
                           std::to_string(kMaxNamedSurfaces) + " a scene may refer to (face bits " +
                           std::to_string(kFirstSurfaceBit) + "..31), expected one already used: " +
                           join(surface_names_));
        return false;
      }
      surface_names_.push_back(face);
    }
    return true;
  }

  /// `max` > `min` in every component; reports at `max_path`.
  bool check_min_max(const Vec3& mn, const Vec3& mx, const std::string& max_path) {
    for (int d = 0; d < dim(); ++d) {
      const auto i = static_cast<std::size_t>(d);
      if (!(mx[i] > mn[i])) {
        c_.error(max_path, "got " + fmt_vec(mx, dim()) + ", expected every component > min " +
                               fmt_vec(mn, dim()) + " [m]");
        return false;
      }
    }
    return true;
  }

  // -- grid -----------------------------------------------------------------------------------

  void parse_grid(const json& j, const std::string& path) {
    const Obj g = check_object(c_, j, path, {&grid_table()});
    Grid& grid = s_.grid;
    grid.cell_size = g.num("cell_size");
    grid.min = g.vec("min");
    grid.max = g.vec("max");
    grid.shape_function =
        from_string(kShapeFunctions, g.str("shape_function")).value_or(ShapeFunction::gimp);
    if (!g.ok("min") || !g.ok("max") || !check_min_max(grid.min, grid.max, g.at("max"))) return;
    grid_ok_ = true;
    grid_min_ = grid.min;
    grid_max_ = grid.max;
    if (!g.ok("cell_size")) return;
    // An extent that is not a whole number of cells is rounded up: the grid grows past `max` to the
    // next cell boundary (documented in docs/scene-format.md).
    for (int d = 0; d < dim(); ++d) {
      const auto i = static_cast<std::size_t>(d);
      const double cells = (grid.max[i] - grid.min[i]) / grid.cell_size;
      if (std::abs(cells - std::round(cells)) > 1e-9 * std::max(1.0, cells)) {
        grid.max[i] = grid.min[i] + std::ceil(cells) * grid.cell_size;
      }
    }
  }

  // -- materials ------------------------------------------------------------------------------

  void parse_materials(const json& arr, const std::string& path) {
    std::map<std::string, std::string> first;  // name -> path
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const std::string p = item(path, i);
      const json& j = arr[i];
      std::optional<MaterialModel> model;
      if (j.is_object() && j.contains("model") && j["model"].is_string()) {
        model = from_string(kModels, j["model"].get<std::string>());
      }
      std::vector<const Table*> tables{&material_table()};
      if (model) {
        for (const Table* t : model_tables(*model)) tables.push_back(t);
      }
      const Obj o = check_object(c_, j, p, tables, model.has_value());

      Material m;
      m.name = o.str("name");
      m.model = model.value_or(MaterialModel::linear_elastic);
      for (const Table* t : tables) {
        for (const Key& k : t->keys) {
          if (k.type == Type::number && o.ok(k.name)) m.params[k.name] = o.get(k.name).get<double>();
        }
      }
      if (model && *model != MaterialModel::fluid) m.permeability_law = o.str("permeability_law", "constant");

      MaterialInfo info;
      info.path = p;
      info.known = model.has_value();
      info.gives_density = o.has("density");
      info.gives_grain_density = o.has("grain_density");
      info.gives_porosity = o.has("porosity");
      info.gives_permeability = o.has("hydraulic_conductivity") || o.has("intrinsic_permeability");
      if (model && *model != MaterialModel::fluid && o.is_object) check_solid_material(o, m);

      if (!m.name.empty()) {
        if (first.count(m.name) != 0) {
          c_.error(o.at("name"), "got " + in_quotes(m.name) + " again (also " + first[m.name] +
                                     "), expected unique material names");
        } else {
          first[m.name] = o.at("name");
        }
      }
      s_.materials.push_back(m);
      material_info_.push_back(info);
    }
  }

  void check_solid_material(const Obj& o, const Material& m) {
    const std::string either =
        "\"density\" (a dry body) or \"grain_density\" with \"porosity\" (a porous skeleton)";
    if (o.has("density") && o.has("grain_density")) {
      c_.error(o.at("grain_density"), "got both \"density\" and \"grain_density\", expected one of " + either);
    } else if (!o.has("density") && !o.has("grain_density")) {
      c_.error(o.at("density"), "missing, expected " + either + " [kg/m^3]");
    } else if (o.has("grain_density") && !o.has("porosity")) {
      c_.error(o.at("porosity"), "missing, expected \"porosity\" together with \"grain_density\" [-]");
    }
    if (o.has("hydraulic_conductivity") && o.has("intrinsic_permeability")) {
      c_.error(o.at("intrinsic_permeability"),
               "got both \"hydraulic_conductivity\" and \"intrinsic_permeability\", expected at most one");
    }
    if (m.has("dilatancy_cutoff_start") && m.has("dilatancy_cutoff_end") &&
        m.at("dilatancy_cutoff_end") < m.at("dilatancy_cutoff_start")) {
      c_.error(o.at("dilatancy_cutoff_end"), "got " + fmt_g(m.at("dilatancy_cutoff_end")) +
                                                 ", expected a number >= dilatancy_cutoff_start = " +
                                                 fmt_g(m.at("dilatancy_cutoff_start")) + " [-]");
    }
    if (m.has("friction_angle") && m.has("dilation_angle") && m.at("dilation_angle") > m.at("friction_angle")) {
      c_.error(o.at("dilation_angle"), "got " + fmt_g(m.at("dilation_angle")) +
                                           ", expected a number in [0, friction_angle = " +
                                           fmt_g(m.at("friction_angle")) + "] [deg]");
    }
  }

  std::vector<std::string> material_names(bool fluid) const {
    std::vector<std::string> out;
    for (std::size_t i = 0; i < s_.materials.size(); ++i) {
      const Material& m = s_.materials[i];
      if (!m.name.empty() && material_info_[i].known && (m.model == MaterialModel::fluid) == fluid) {
        out.push_back(m.name);
      }
    }
    return out;
  }

  /// A body's `solid` (fluid = false) or `fluid` reference; returns the material index or -1.
  int check_material_ref(const Obj& o, const std::string& key, bool fluid) {
    if (!o.ok(key)) return -1;
    const std::string name = o.str(key);
    const int idx = s_.material_index(name);
    const std::vector<std::string> wanted = material_names(fluid);
    const std::string kind = fluid ? "a fluid material (model \"fluid\")" : "a solid material";
    if (idx < 0) {
      std::vector<std::string> all;
      for (const auto& m : s_.materials) {
        if (!m.name.empty()) all.push_back(m.name);
      }
      c_.error(o.at(key), "got " + in_quotes(name) + ", no material has that name; expected " + kind +
                              " (defined: " + (all.empty() ? std::string("none") : join(all)) + ")" +
                              did_you_mean(name, all));
      return -1;
    }
    const auto i = static_cast<std::size_t>(idx);
    if (!material_info_[i].known) return -1;  // its own model error was reported
    if ((s_.materials[i].model == MaterialModel::fluid) != fluid) {
      c_.error(o.at(key), "got " + in_quotes(name) + ", a material of model \"" +
                              to_string(s_.materials[i].model) + "\"; expected " + kind + " (" +
                              (fluid ? "fluids" : "solids") + ": " +
                              (wanted.empty() ? std::string("none") : join(wanted)) + ")");
      return -1;
    }
    return idx;
  }

  // -- bodies ---------------------------------------------------------------------------------

  void parse_bodies(const json& arr, const std::string& path) {
    std::map<std::string, std::string> first;
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const std::string p = item(path, i);
      const Obj o = check_object(c_, arr[i], p, {&body_table()});
      Body b;
      b.name = o.str("name");
      b.solid = o.str("solid");
      b.fluid = o.str("fluid");
      b.particles_per_cell = static_cast<int>(o.num("particles_per_cell", 2.0));
      if (o.is_object && !o.has("solid") && !o.has("fluid")) {
        c_.error(p, "body " + in_quotes(b.name) +
                        " has neither \"solid\" nor \"fluid\", expected at least one material name");
      }
      const int solid = check_material_ref(o, "solid", false);
      check_material_ref(o, "fluid", true);
      if (solid >= 0 && !b.fluid.empty()) check_saturated_solid(static_cast<std::size_t>(solid), b, p);

      std::optional<Bounds> bounds;
      if (o.ok("geometry")) {
        bounds = parse_geometry(o.get("geometry"), o.at("geometry"), b.geometry);
        if (bounds) check_inside_grid(*bounds, o.at("geometry"));
      }
      body_bounds_.push_back(bounds);
      parse_initial(o.ok("initial") ? o.get("initial") : json::object(), o.at("initial"), b);

      if (!b.name.empty()) {
        if (first.count(b.name) != 0) {
          c_.error(o.at("name"), "got " + in_quotes(b.name) + " again (also " + first[b.name] +
                                     "), expected unique body names");
        } else {
          first[b.name] = o.at("name");
        }
      }
      s_.bodies.push_back(b);
      body_paths_.push_back(p);
    }
    resolve_footings();
  }

  /// The solid of a saturated body is a porous skeleton with a permeability. Reported once per
  /// material, at the material.
  void check_saturated_solid(std::size_t idx, const Body& b, const std::string& body_path) {
    MaterialInfo& info = material_info_[idx];
    if (info.saturated_reported) return;
    const std::string used = "material " + in_quotes(s_.materials[idx].name) +
                             " is the solid of saturated body " + in_quotes(b.name) + " (" + body_path + ")";
    if (!info.gives_grain_density || !info.gives_porosity) {
      c_.error(info.path, used + ", expected \"grain_density\" and \"porosity\" (a porous skeleton)" +
                              (info.gives_density ? " instead of \"density\"" : ""));
      info.saturated_reported = true;
    }
    if (!info.gives_permeability) {
      c_.error(info.path, used + ", expected \"hydraulic_conductivity\" or \"intrinsic_permeability\"");
      info.saturated_reported = true;
    }
  }

  /// Why `type` cannot be used in this scene's dimension ("" when it can).
  std::string dimension_problem(const std::string& type) const {
    if (dim() == 3 && type == "polygon") return "got \"polygon\" in a 3D scene, expected \"box\" (polygon is 2D only)";
    if (dim() == 3 && type == "slope")
      return "got \"slope\" in a 3D scene, expected a 3D geometry (box, footing, gmsh, surface-mesh); slope is 2D only";
    if (dim() == 2 && type == "surface-mesh")
      return "got \"surface-mesh\" in a 2D scene, expected a 2D geometry (box, polygon, slope, footing, gmsh); "
             "surface-mesh is 3D only";
    return {};
  }

  static const Table* type_table(const std::string& type) {
    if (type == "box") return &box_table();
    if (type == "polygon") return &polygon_table();
    if (type == "slope") return &slope_table();
    if (type == "footing") return &footing_table();
    if (type == "gmsh") return &gmsh_table();
    if (type == "surface-mesh") return &surface_mesh_table();
    return nullptr;
  }

  /// The geometry's typed values and, when they are known before preprocess, its bounds.
  std::optional<Bounds> parse_geometry(const json& j, const std::string& path, Geometry& g) {
    g.raw = j;
    const std::string type = j.contains("type") && j["type"].is_string() ? j["type"].get<std::string>() : "";
    const Table* table = type_table(type);
    const std::string problem = table ? dimension_problem(type) : "";
    const bool usable = table && problem.empty();
    std::vector<const Table*> tables{&geometry_table()};
    if (usable) tables.push_back(table);
    const Obj o = check_object(c_, j, path, tables, usable);
    g.type = o.str("type");
    if (!o.ok("type")) return std::nullopt;
    if (!usable) {
      c_.error(o.at("type"), problem);
      return std::nullopt;
    }
    if (type == "box") return parse_box(o, g);
    if (type == "polygon") return parse_polygon(o, g);
    if (type == "slope") return parse_slope(o, g);
    if (type == "footing") return parse_footing(o, g);
    // gmsh, surface-mesh: the bounds come from the file (preprocess checks them against the grid).
    if (o.ok("file")) g.file = resolve_file(c_.label, o.str("file")).string();
    if (type == "gmsh") {
      if (o.ok("parameters")) {
        for (const auto& [name, value] : o.get("parameters").items()) g.parameters[name] = value.get<double>();
      }
      g.physical = o.str("physical");
      if (!g.parameters.empty() && lower(std::filesystem::path(g.file).extension().string()) == ".msh") {
        c_.error(o.at("parameters"), "got parameters for a .msh file, expected none (only a .geo file has "
                                     "DefineConstant parameters; a .msh is a finished mesh)");
      }
    }
    return std::nullopt;
  }

  std::optional<Bounds> parse_box(const Obj& o, Geometry& g) {
    g.min = o.vec("min");
    g.max = o.vec("max");
    if (!o.ok("min") || !o.ok("max") || !check_min_max(g.min, g.max, o.at("max"))) return std::nullopt;
    return Bounds{g.min, g.max};
  }

  std::optional<Bounds> parse_polygon(const Obj& o, Geometry& g) {
    if (!o.ok("vertices")) return std::nullopt;
    Bounds b{{inf, inf, 0}, {-inf, -inf, 0}};
    double twice_area = 0.0;
    const json& vs = o.get("vertices");
    for (std::size_t i = 0; i < vs.size(); ++i) {
      const std::array<double, 2> v{vs[i][0].get<double>(), vs[i][1].get<double>()};
      const std::array<double, 2> w{vs[(i + 1) % vs.size()][0].get<double>(),
                                    vs[(i + 1) % vs.size()][1].get<double>()};
      g.vertices.push_back(v);
      twice_area += v[0] * w[1] - w[0] * v[1];  // shoelace
      for (std::size_t d = 0; d < 2; ++d) {
        b.min[d] = std::min(b.min[d], v[d]);
        b.max[d] = std::max(b.max[d], v[d]);
      }
    }
    const double scale = std::max(b.max[0] - b.min[0], b.max[1] - b.min[1]);
    if (!(std::abs(twice_area) > 1e-12 * scale * scale)) {
      c_.error(o.at("vertices"), "got a polygon of zero area, expected at least 3 vertices enclosing an area");
      return std::nullopt;
    }
    return b;
  }

  /// Exactly one of two keys: reports at `b` when both are given, at `a` when neither is.
  bool one_of(const Obj& o, const std::string& a, const std::string& b, const std::string& what) {
    if (o.has(a) && o.has(b)) {
      c_.error(o.at(b), "got both " + in_quotes(a) + " and " + in_quotes(b) + ", expected one of them");
      return false;
    }
    if (!o.has(a) && !o.has(b)) {
      c_.error(o.at(a), "missing, expected " + what);
      return false;
    }
    return o.ok(a) || o.ok(b);
  }

  std::optional<Bounds> parse_slope(const Obj& o, Geometry& g) {
    g.foundation_depth = o.num("foundation_depth");
    g.height = o.num("height");
    g.angle = o.num("angle");
    g.ratio = o.num("ratio");
    g.crest_length = o.num("crest_length");
    g.toe_length = o.num("toe_length");
    const Vec3 origin = o.ok("origin") ? o.vec("origin") : grid_min_;
    g.origin = {origin[0], origin[1]};
    const bool inclination = one_of(o, "angle", "ratio",
                                    "\"angle\" (degrees from the horizontal) or \"ratio\" (horizontal : vertical)");
    for (const char* k : {"foundation_depth", "height", "crest_length", "toe_length"}) {
      if (!o.ok(k)) return std::nullopt;
    }
    if (!inclination) return std::nullopt;
    const double run = g.ratio > 0.0 ? g.height * g.ratio : g.height / std::tan(g.angle * std::numbers::pi / 180.0);
    const double length = g.toe_length + run + g.crest_length;
    return Bounds{{g.origin[0], g.origin[1], 0.0},
                  {g.origin[0] + length, g.origin[1] + g.foundation_depth + g.height, 0.0}};
  }

  std::optional<Bounds> parse_footing(const Obj& o, Geometry& g) {
    g.width = o.num("width");
    g.height = o.num("height");
    g.center_x = o.num("center_x");
    g.center_z = o.num("center_z");
    g.length = o.num("length");
    g.base_y = o.num("base_y");
    bool ok = o.ok("width") && o.ok("height") && o.ok("center_x");
    for (const char* k : {"center_z", "length"}) {
      if (dim() == 3 && !o.has(k)) {
        c_.error(o.at(k), std::string("missing, expected a number for a footing in 3D [m]"));
        ok = false;
      } else if (dim() == 2 && o.has(k)) {
        c_.error(o.at(k), std::string("got \"") + k + "\" in a 2D scene, expected none (the block spans x and y)");
        ok = false;
      }
      ok = ok && (dim() == 2 || o.ok(k));
    }
    if (!one_of(o, "on", "base_y", "\"on\" (the body the footing rests on) or \"base_y\" [m]")) return std::nullopt;
    if (o.ok("on")) {
      // Resolved once every body is known: the body below may come later in the list.
      if (ok) pending_footings_.push_back({s_.bodies.size(), o.str("on"), o.path});
      return std::nullopt;
    }
    if (!ok) return std::nullopt;
    return footing_bounds(g);
  }

  Bounds footing_bounds(const Geometry& g) const {
    return {{g.center_x - g.width / 2, g.base_y, g.center_z - g.length / 2},
            {g.center_x + g.width / 2, g.base_y + g.height, g.center_z + g.length / 2}};
  }

  /// Footings that rest `on` another body stand on its top (the highest point of its bounds). A
  /// footing may rest on a footing; the passes stop when no more can be placed (cycles).
  void resolve_footings() {
    std::vector<std::string> names;
    for (const Body& b : s_.bodies) names.push_back(b.name);
    std::vector<PendingFooting> left = pending_footings_;
    for (bool progress = true; progress && !left.empty();) {
      progress = false;
      std::vector<PendingFooting> still;
      for (const PendingFooting& f : left) {
        const auto it = std::find(names.begin(), names.end(), f.on);
        const std::string on_path = f.path + "/on";
        if (it == names.end() || static_cast<std::size_t>(it - names.begin()) == f.body) {
          std::vector<std::string> others = names;
          others.erase(others.begin() + static_cast<std::ptrdiff_t>(f.body));
          c_.error(on_path, "got " + in_quotes(f.on) + ", expected the name of another body (defined: " +
                                (others.empty() ? std::string("none") : join(others)) + ")" +
                                did_you_mean(f.on, others));
          continue;
        }
        const auto below = static_cast<std::size_t>(it - names.begin());
        const std::string& type = s_.bodies[below].geometry.type;
        if (type == "gmsh" || type == "surface-mesh") {
          c_.error(on_path, "got " + in_quotes(f.on) + ", a " + type + " geometry whose top is known only when "
                            "preprocess reads its file; expected a box, polygon, slope or footing body, or "
                            "\"base_y\" instead of \"on\"");
          continue;
        }
        if (!body_bounds_[below]) {
          still.push_back(f);  // not placed (yet), or invalid: reported at its own path
          continue;
        }
        Geometry& g = s_.bodies[f.body].geometry;
        g.base_y = body_bounds_[below]->max[1];
        body_bounds_[f.body] = footing_bounds(g);
        check_inside_grid(*body_bounds_[f.body], f.path);
        progress = true;
      }
      left = still;
    }
    // What is left waits, directly or not, for a footing that is also left: a cycle. (A footing on
    // an invalid body is not in `left` when that body is not; its body's problem is reported.)
    for (const PendingFooting& f : left) {
      const bool on_waiting = std::any_of(left.begin(), left.end(), [&](const PendingFooting& g) {
        return s_.bodies[g.body].name == f.on;
      });
      if (!on_waiting) continue;
      c_.error(f.path + "/on", "got " + in_quotes(f.on) + ", but footings resting on each other form a cycle; "
                               "expected \"base_y\" for one of them");
    }
  }

  void check_inside_grid(const Bounds& b, const std::string& path) {
    if (!grid_ok_) return;
    for (int d = 0; d < dim(); ++d) {
      const auto i = static_cast<std::size_t>(d);
      const double tol = 1e-9 * (grid_max_[i] - grid_min_[i]);
      if (b.min[i] < grid_min_[i] - tol || b.max[i] > grid_max_[i] + tol) {
        c_.error(path, "got bounds " + fmt_vec(b.min, dim()) + ".." + fmt_vec(b.max, dim()) +
                           ", expected a geometry inside the grid " + fmt_vec(grid_min_, dim()) + ".." +
                           fmt_vec(grid_max_, dim()) + " [m]");
        return;
      }
    }
  }

  void parse_initial(const json& j, const std::string& path, Body& b) {
    const Obj o = check_object(c_, j, path, {&initial_table()});
    InitialState& in = b.initial;
    if (o.ok("pore_pressure")) {
      const json& pp = o.get("pore_pressure");
      if (pp.is_number()) in.pore_pressure = pp.get<double>();
      else in.hydrostatic = true;
      if (b.fluid.empty()) {
        c_.error(o.at("pore_pressure"), "got " + shown(pp) + " for body " + in_quotes(b.name) +
                                            " without a fluid, expected no pore_pressure (or a body \"fluid\")");
      }
    }
    if (o.has("water_table") && !in.hydrostatic) {
      c_.error(o.at("water_table"), "got " + shown(j["water_table"]) +
                                        ", expected no water_table unless pore_pressure is \"hydrostatic\"");
    } else if (o.ok("water_table")) {
      in.water_table = o.num("water_table");
    }
    if (o.ok("stress")) {
      const json& st = o.get("stress");
      if (st.is_string()) {
        in.geostatic = true;
      } else {
        std::array<double, 6> voigt{};
        for (std::size_t k = 0; k < 6; ++k) voigt[k] = st[k].get<double>();
        in.stress = voigt;
      }
    }
    if (o.has("k0") && !in.geostatic) {
      c_.error(o.at("k0"), "got " + shown(j["k0"]) + ", expected no k0 unless stress is \"geostatic\"");
    }
    in.k0 = o.num("k0", 0.5);
    if (o.ok("porosity")) in.porosity = o.num("porosity");
    if (o.ok("velocity")) {
      const json& v = o.get("velocity");
      for (std::size_t d = 0; d < v.size() && d < 3; ++d) {
        in.velocity[d] = v[d].is_number() ? v[d].dump() : v[d].get<std::string>();
      }
    }
  }

  // -- boundaries and loads --------------------------------------------------------------------

  /// A boundary's `on`: an axis face, or a named surface of any body's geometry.
  bool check_boundary_on(const std::string& on, const std::string& path) {
    std::vector<std::string> named;
    bool deferred = false;
    for (const Body& b : s_.bodies) {
      for (const auto& n : named_surfaces(b.geometry, dim())) {
        if (!contains(named, n)) named.push_back(n);
      }
      deferred = deferred || b.geometry.type == "gmsh";
    }
    return check_face(on, path, named, deferred, "no body's geometry has named surfaces");
  }

  /// A load's `face`: an axis face, or a named surface of the loaded body's geometry.
  void check_load_face(const Load& l, const std::string& path) {
    const auto body = std::find_if(s_.bodies.begin(), s_.bodies.end(), [&](const Body& b) { return b.name == l.body; });
    if (body == s_.bodies.end()) {
      if (!contains(faces(), l.face)) check_face(l.face, path, {}, true, "");  // the body is reported
      return;
    }
    const Geometry& g = body->geometry;
    check_face(l.face, path, named_surfaces(g, dim()), g.type == "gmsh",
               "body " + in_quotes(body->name) + " (" + (g.type.empty() ? "no geometry" : g.type) +
                   ") has no named surfaces");
  }

  void parse_boundaries(const json& arr, const std::string& path) {
    std::map<std::string, std::string> first;
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const Obj o = check_object(c_, arr[i], item(path, i), {&boundary_table()});
      Boundary bc;
      bc.on = o.str("on");
      if (o.ok("on") && check_boundary_on(bc.on, o.at("on"))) {
        if (first.count(bc.on) != 0) {
          c_.error(o.at("on"), "got " + in_quotes(bc.on) + " again (also " + first[bc.on] +
                                   "), expected each face at most once");
        } else {
          first[bc.on] = o.at("on");
        }
      }
      const auto& solids = solid_bc_names();
      const auto s = std::find(solids.begin(), solids.end(), o.str("solid", "free"));
      bc.solid = static_cast<SolidBc>(s - solids.begin());
      const bool friction = o.ok("solid") && bc.solid == SolidBc::friction;
      if (friction && !o.has("coefficient")) {
        c_.error(o.at("coefficient"), "missing, expected a non-negative number with solid \"friction\" [-]");
      } else if (o.has("coefficient") && o.ok("solid") && !friction) {
        c_.error(o.at("coefficient"), "got " + shown(arr[i]["coefficient"]) +
                                          ", expected no coefficient unless solid is \"friction\"");
      }
      bc.coefficient = o.num("coefficient");
      if (o.ok("fluid")) {
        const auto& fluids = fluid_bc_names();
        bc.fluid = static_cast<FluidBc>(std::find(fluids.begin(), fluids.end(), o.str("fluid")) - fluids.begin());
        if (!s_.has_fluid()) {
          c_.error(o.at("fluid"), "got " + in_quotes(o.str("fluid")) +
                                      ", but the scene has no fluid phase (no body has a \"fluid\"); "
                                      "expected no fluid condition");
        }
      }
      const bool pressure = bc.fluid == FluidBc::pressure;
      if (pressure && !o.has("value")) {
        c_.error(o.at("value"), "missing, expected a number with fluid \"pressure\" [Pa]");
      } else if (o.has("value") && !pressure && (o.ok("fluid") || !o.has("fluid"))) {
        c_.error(o.at("value"), "got " + shown(arr[i]["value"]) +
                                    ", expected no value unless fluid is \"pressure\"");
      }
      bc.fluid_value = o.num("value");
      s_.boundaries.push_back(bc);
    }
  }

  void parse_loads(const json& arr, const std::string& path) {
    std::vector<std::string> bodies;
    for (const auto& b : s_.bodies) {
      if (!b.name.empty()) bodies.push_back(b.name);
    }
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const Obj o = check_object(c_, arr[i], item(path, i), {&load_table()});
      Load l;
      l.type = o.str("type");
      l.body = o.str("body");
      l.face = o.str("face");
      if (o.ok("body") && !contains(bodies, l.body)) {
        c_.error(o.at("body"), "got " + in_quotes(l.body) + ", expected the name of a body (defined: " +
                                   (bodies.empty() ? std::string("none") : join(bodies)) + ")" +
                                   did_you_mean(l.body, bodies));
      }
      if (o.ok("face")) check_load_face(l, o.at("face"));
      if (o.ok("value") && o.ok("type")) {
        const json& v = o.get("value");
        if (l.type == "traction" && !v.is_array()) {
          c_.error(o.at("value"), "got " + shown(v) + ", expected " + vector_phrase(c_.dim) +
                                      " for a traction [Pa]");
        } else if (l.type == "pressure" && !v.is_number()) {
          c_.error(o.at("value"), "got " + shown(v) + ", expected a number for a pressure [Pa]");
        } else if (v.is_number()) {
          l.value[0] = v.get<double>();
        } else {
          l.value = o.vec("value");
        }
      }
      if (o.ok("region")) {
        const Obj r = check_object(c_, o.get("region"), o.at("region"), {&region_table()});
        if (r.ok("min") && r.ok("max") && check_min_max(r.vec("min"), r.vec("max"), r.at("max"))) {
          l.region = std::make_pair(r.vec("min"), r.vec("max"));
        }
      }
      l.function.ramp = o.num("ramp");
      if (o.has("function") && o.has("table")) {
        c_.error(o.at("table"), "got both \"function\" and \"table\", expected at most one of them");
      }
      l.function.expression = o.str("function");
      if (o.ok("table")) {
        for (const json& p : o.get("table")) l.function.table.push_back({p[0].get<double>(), p[1].get<double>()});
      }
      s_.loads.push_back(l);
    }
  }

  // -- time, output, solver --------------------------------------------------------------------

  void parse_time(const json& j, const std::string& path) {
    const Obj o = check_object(c_, j, path, {&time_table()});
    s_.time.end = o.num("end");
    if (o.ok("dt") && o.get("dt").is_number()) s_.time.dt = o.num("dt");
    s_.time.cfl = o.num("cfl", 0.5);
  }

  void parse_output(const json& j, const std::string& path) {
    const Obj o = check_object(c_, j, path, {&output_table()});
    s_.output.interval = o.num("interval");
    s_.output.monitor_interval = o.num("monitor_interval");
    s_.output.compression = o.str("compression", "zlib");
    if (o.ok("checkpoint_interval")) s_.output.checkpoint_interval = o.num("checkpoint_interval");
    if (!o.ok("monitors")) return;
    const json& arr = o.get("monitors");
    std::map<std::string, std::string> first;
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const Obj m = check_object(c_, arr[i], item(o.at("monitors"), i), {&monitor_table()});
      Monitor mon;
      mon.name = m.str("name");
      if (m.ok("at")) mon.at = m.vec("at");
      if (m.ok("particle")) mon.particle = static_cast<long>(m.get("particle").get<double>());
      mon.phase = m.str("phase", "solid");
      mon.points = m.str("points", "soil");
      if (mon.points == "water") water_monitors_.push_back(m.at("points"));  // checked with the formulation
      if (m.has("at") && m.has("particle")) {
        c_.error(m.at("particle"), "got both \"at\" and \"particle\", expected one of them "
                                   "(or neither, for a global monitor)");
      }
      const bool global = !m.has("at") && !m.has("particle");
      if (mon.phase == "fluid" && !s_.has_fluid()) {
        c_.error(m.at("phase"), "got \"fluid\", but the scene has no fluid phase (no body has a "
                                "\"fluid\"); expected \"solid\"");
      }
      if (mon.at && grid_ok_) {
        for (int d = 0; d < dim(); ++d) {
          const auto k = static_cast<std::size_t>(d);
          if ((*mon.at)[k] < grid_min_[k] || (*mon.at)[k] > grid_max_[k]) {
            c_.error(m.at("at"), "got " + fmt_vec(*mon.at, dim()) + ", expected a point inside the grid " +
                                     fmt_vec(grid_min_, dim()) + ".." + fmt_vec(grid_max_, dim()) + " [m]");
            break;
          }
        }
      }
      if (m.ok("quantities")) {
        const json& qs = m.get("quantities");
        for (std::size_t k = 0; k < qs.size(); ++k) {
          const std::string q = qs[k].get<std::string>();
          const std::string qp = item(m.at("quantities"), k);
          check_quantity(q, global, qp);
          if (contains(mon.quantities, q)) {
            c_.error(qp, "got " + in_quotes(q) + " twice, expected each quantity at most once");
          }
          mon.quantities.push_back(q);
        }
      }
      if (!mon.name.empty()) {
        if (first.count(mon.name) != 0) {
          c_.error(m.at("name"), "got " + in_quotes(mon.name) + " again (also " + first[mon.name] +
                                     "), expected unique monitor names");
        } else {
          first[mon.name] = m.at("name");
        }
      }
      s_.output.monitors.push_back(mon);
    }
  }

  void check_quantity(const std::string& q, bool global, const std::string& path) {
    const bool is_global = contains(global_quantities(), q);
    if (global && !is_global) {
      c_.error(path, "got " + in_quotes(q) + ", a point quantity, but the monitor has neither \"at\" nor "
                     "\"particle\"; expected \"at\" or \"particle\", or a global quantity (" +
                         join(global_quantities()) + ")");
    } else if (!global && is_global) {
      c_.error(path, "got " + in_quotes(q) + ", a global quantity, expected a point quantity (global "
                     "quantities belong to a monitor without \"at\" and \"particle\")");
    }
    if (dim() == 2 && is_3d_only_quantity(q)) {
      c_.error(path, "got " + in_quotes(q) + " in a 2D scene, expected a quantity without a z component "
                     "(z components exist only in 3D; stress_zz is the plane-strain out-of-plane stress)");
    }
    if (needs_fluid_quantity(q) && !s_.has_fluid()) {
      c_.error(path, "got " + in_quotes(q) + ", but the scene has no fluid phase (no body has a \"fluid\"); "
                     "expected a solid quantity");
    }
  }

  void parse_solver(const json& j, const std::string& path) {
    const Obj o = check_object(c_, j, path, {&solver_table()});
    Solver& sv = s_.solver;
    sv.flip = o.num("flip", 0.99);
    sv.damping = o.num("damping");
    sv.kinematics = o.str("kinematics", "finite-strain");
    sv.continuity = o.str("continuity", "");  // "": the formulation's default (after resolve_formulation)
    sv.escaped_water = o.str("escaped_water", "keep");
    sv.drag_integration = o.str("drag_integration", "");  // "": resolved by formulation in parse()
    sv.checkpoint_every = static_cast<int>(o.num("checkpoint_every", 50.0));
    const Obj st = check_object(c_, o.ok("stabilisation") ? o.get("stabilisation") : json::object(),
                                o.at("stabilisation"), {&stabilisation_table()});
    sv.stabilisation.strain_smoothing = st.ok("strain_smoothing") ? st.get("strain_smoothing").get<bool>() : true;
    sv.stabilisation.pressure = st.str("pressure", "");  // "": the formulation's default (default_pressure_stabilisation)
    sv.stabilisation.fbar = st.str("fbar", "none");
    sv.stabilisation.fbar_patch = st.num("fbar_patch", 0.0);  // 0: by shape function, resolved in parse()
  }

  void parse_initialisation(const json& j, const std::string& path, const Obj& top) {
    const Obj o = check_object(c_, j, path, {&initialisation_table()});
    Initialisation& in = s_.initialisation;
    in.duration = o.num("duration");
    in.gravity_ramp = o.has("gravity_ramp") ? o.num("gravity_ramp") : in.duration;
    in.plasticity = o.ok("plasticity") && o.get("plasticity").get<bool>();
    if (o.has("hydraulic_conductivity") && o.ok("hydraulic_conductivity"))
      in.hydraulic_conductivity = o.num("hydraulic_conductivity");
    in.tie_water = !o.ok("tie_water") || o.get("tie_water").get<bool>();
    if (o.has("damping") && o.ok("damping")) in.damping = o.num("damping");
    in.reset_displacement = !o.ok("reset_displacement") || o.get("reset_displacement").get<bool>();
    if (o.ok("gravity_ramp") && o.ok("duration") && in.gravity_ramp > in.duration)
      c_.error(o.at("gravity_ramp"), "got " + fmt_g(in.gravity_ramp) + ", expected a number in [0, duration = " +
                                         fmt_g(in.duration) + "] [s]");
    if (top.has("gravity_ramp") && s_.gravity_ramp > 0.0)
      c_.error(top.at("gravity_ramp"), "got " + fmt_g(s_.gravity_ramp) + ", expected 0 with an initialisation phase "
                                           "(gravity is full from t = 0; ramp it with initialisation.gravity_ramp)");
    if (o.has("hydraulic_conductivity") && !s_.has_fluid())
      c_.error(o.at("hydraulic_conductivity"), "got a value, but no body has a fluid; remove the key");
    const bool double_point = s_.formulation == Formulation::semi_implicit_double_point ||
                              s_.formulation == Formulation::explicit_double_point;
    if (o.has("tie_water") && !double_point)
      c_.error(o.at("tie_water"), "got a value, but only double-point formulations have water points to tie "
                                  "(formulation \"" + to_string(s_.formulation) + "\"); remove the key");
  }

  // -- formulation -----------------------------------------------------------------------------

  void resolve_formulation(const std::string& name, const std::string& path) {
    const Formulation f = from_string(kFormulations, name).value_or(Formulation::automatic);
    std::string fluid_body, fluid_body_path;
    for (std::size_t i = 0; i < s_.bodies.size(); ++i) {
      if (!s_.bodies[i].fluid.empty()) {
        fluid_body = s_.bodies[i].name;
        fluid_body_path = body_paths_[i];
        break;
      }
    }
    const bool fluid = !fluid_body_path.empty();
    if (f == Formulation::automatic) {
      s_.formulation = fluid ? Formulation::explicit_single_point : Formulation::dry;
      s_.formulation_reason =
          fluid ? "body \"" + fluid_body + "\" has a fluid, so the scene is coupled soil-water; \"auto\" "
                  "picks \"explicit-single-point\", the general explicit coupled scheme"
                : "no body has a fluid, so the scene is dry; \"auto\" picks \"dry\" (solid phase only)";
      return;
    }
    s_.formulation = f;
    s_.formulation_reason = in_quotes(name) + " as named in the scene file";
    if (f == Formulation::dry && fluid) {
      c_.error(path, "got \"dry\", but body " + in_quotes(fluid_body) + " (" + fluid_body_path +
                         ") has a fluid; expected a coupled formulation (e.g. \"explicit-single-point\") "
                         "or \"auto\"");
    } else if (f != Formulation::dry && !fluid) {
      c_.error(path, "got " + in_quotes(name) + ", but no body has a fluid; expected \"dry\" (or \"auto\")");
    }
  }
};

// ------------------------------------------------------------------------------------------------
// Writing a scene back.
// ------------------------------------------------------------------------------------------------

json vec_json(const Vec3& v, int dim) {
  json a = json::array();
  for (int d = 0; d < dim; ++d) a.push_back(v[static_cast<std::size_t>(d)]);
  return a;
}

/// The resolved geometry of the types beyond box and polygon: defaults written out (slope
/// `origin`), footing `on` resolved to `base_y`, file paths absolute.
json geometry_json(const Geometry& g, int dim) {
  if (g.type == "slope") {
    json j = {{"type", "slope"},          {"foundation_depth", g.foundation_depth}, {"height", g.height},
              {"crest_length", g.crest_length}, {"toe_length", g.toe_length},
              {"origin", {g.origin[0], g.origin[1]}}};
    if (g.ratio > 0.0) j["ratio"] = g.ratio;
    else j["angle"] = g.angle;
    return j;
  }
  if (g.type == "footing") {
    json j = {{"type", "footing"}, {"width", g.width}, {"height", g.height}, {"center_x", g.center_x},
              {"base_y", g.base_y}};
    if (dim == 3) {
      j["center_z"] = g.center_z;
      j["length"] = g.length;
    }
    return j;
  }
  if (g.type == "gmsh") {
    json j = {{"type", "gmsh"}, {"file", g.file}, {"parameters", json::object()}};
    for (const auto& [name, value] : g.parameters) j["parameters"][name] = value;
    if (!g.physical.empty()) j["physical"] = g.physical;
    return j;
  }
  if (g.type == "surface-mesh") return {{"type", "surface-mesh"}, {"file", g.file}};
  return g.raw;
}

std::string markdown_default(const Key& k) {
  if (k.required) return "required";
  if (!k.default_text.empty()) return k.default_text;
  if (!k.def.is_null()) return "`" + k.def.dump() + "`";
  return "—";
}

std::string markdown_type(const Key& k) {
  if (!k.type_text.empty()) return k.type_text;
  switch (k.type) {
    case Type::number: return "number";
    case Type::integer: return "integer";
    case Type::boolean: return "boolean";
    case Type::string: return "string";
    case Type::choice: return "string";
    case Type::vector: return "vector";
    case Type::object: return "object";
    case Type::objects: return "array of objects";
    case Type::choices: return "array of strings";
    case Type::custom: return "see meaning";
  }
  return "";
}

std::string markdown_allowed(const Key& k) {
  if (!k.allowed.empty()) return k.allowed;
  switch (k.type) {
    case Type::number: return range_text(k.range, false);
    case Type::integer: return range_text(k.range, true);
    case Type::boolean: return "`true`, `false`";
    case Type::choice:
    case Type::choices: {
      std::vector<std::string> v;
      for (const auto& s : k.values) v.push_back("`" + s + "`");
      return join(v);
    }
    case Type::vector: return "`dimension` numbers";
    case Type::objects: return k.nonempty ? "≥ 1 entry" : "";
    default: return "";
  }
}

/// Finds keys written twice in one object while the text is parsed (a JSON value keeps only the
/// last, which would silently drop the first). Tracks the JSON pointer of the current position.
struct DuplicateKeys {
  std::string label;
  std::vector<std::string> lines;
  struct Frame {
    bool array = false;
    std::string key;          // object: the current key
    std::size_t index = 0;    // array: the index of the current element
    std::set<std::string> keys;
  };
  std::vector<Frame> frames;

  std::string pointer() const {
    std::string p;
    for (const Frame& f : frames) p += "/" + (f.array ? std::to_string(f.index) : escape(f.key));
    return p;
  }
  void element_done() {
    if (!frames.empty() && frames.back().array) ++frames.back().index;
  }
  void on_event(json::parse_event_t event, const json& parsed) {
    using E = json::parse_event_t;
    switch (event) {
      case E::object_start: frames.push_back({false, "", 0, {}}); break;
      case E::array_start: frames.push_back({true, "", 0, {}}); break;
      case E::key: {
        Frame& f = frames.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second) {
          lines.push_back(label + ": " + pointer() + ": got key " + in_quotes(f.key) +
                          " twice in one object, expected each key once");
        }
        break;
      }
      case E::object_end:
      case E::array_end:
        frames.pop_back();
        element_done();
        break;
      case E::value: element_done(); break;
    }
  }
};

}  // namespace

int grid_face_index(const std::string& name) {
  const auto& faces = face_names();
  const auto it = std::find(faces.begin(), faces.end(), name);
  return it == faces.end() ? -1 : static_cast<int>(it - faces.begin());
}

Scene parse_scene(const nlohmann::json& j, const std::string& label) {
  return SceneParser(j, label).parse();
}

Scene load_scene(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw SceneError({path + ": is a directory, expected a scene file (JSON)"});
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw SceneError({path + ": cannot read the scene file (" + std::strerror(errno) + ")"});
  }
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw SceneError({path + ": cannot read the scene file"});
  const std::string text = buf.str();
  json j;
  DuplicateKeys duplicates;
  duplicates.label = path;
  try {
    j = json::parse(text, [&duplicates](int, json::parse_event_t event, json& parsed) {
      duplicates.on_event(event, parsed);
      return true;
    });
  } catch (const json::parse_error& e) {
    // Line and column of the byte where parsing failed (e.byte is 1-based).
    const std::size_t byte = e.byte == 0 ? 0 : e.byte - 1;
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i < byte && i < text.size(); ++i) {
      if (text[i] == '\n') ++line, column = 1;
      else ++column;
    }
    std::string why = e.what();
    const auto at = why.find(": ", why.find("parse error"));
    if (at != std::string::npos) why = why.substr(at + 2);
    throw SceneError({path + ": invalid JSON at line " + std::to_string(line) + ", column " +
                      std::to_string(column) + " (byte " + std::to_string(e.byte) + "): " + why});
  }
  try {
    Scene scene = parse_scene(j, path);
    if (!duplicates.lines.empty()) throw SceneError(duplicates.lines);
    return scene;
  } catch (const SceneError& e) {
    if (duplicates.lines.empty()) throw;
    std::vector<std::string> lines = duplicates.lines;
    for (const auto& l : e.lines()) {
      if (!contains(lines, l)) lines.push_back(l);
    }
    throw SceneError(lines);
  }
}

bool reads_switch(const Scene& s, const std::string& key) {
  const bool dry = s.formulation == Formulation::dry;
  if (key == "strain_smoothing") return s.formulation == Formulation::explicit_single_point;
  if (key == "pressure") return !dry;
  if (key == "fbar_patch") return s.solver.stabilisation.fbar == "modified";
  if (key == "kinematics") {
    // mohr-coulomb and nor-sand read it (nor-sand: finite strain only), in every formulation; the
    // other models follow their own kinematics (linear-elastic: Jaumann rate, hencky: finite).
    for (const auto& m : s.materials)
      if (m.model == MaterialModel::mohr_coulomb || m.model == MaterialModel::nor_sand) return true;
    return false;
  }
  return true;
}

nlohmann::json to_json(const Scene& s) {
  const int dim = s.dimension;
  json j;
  j["name"] = s.name;
  j["dimension"] = dim;
  j["formulation"] = to_string(s.formulation);
  j["gravity"] = vec_json(s.gravity, dim);
  j["gravity_ramp"] = s.gravity_ramp;
  j["grid"] = {{"cell_size", s.grid.cell_size},
               {"min", vec_json(s.grid.min, dim)},
               {"max", vec_json(s.grid.max, dim)},
               {"shape_function", to_string(s.grid.shape_function)}};

  j["materials"] = json::array();
  for (const Material& m : s.materials) {
    json mj = {{"name", m.name}, {"model", to_string(m.model)}};
    for (const auto& [key, value] : m.params) mj[key] = value;
    if (m.model != MaterialModel::fluid) mj["permeability_law"] = m.permeability_law;
    j["materials"].push_back(mj);
  }

  j["bodies"] = json::array();
  for (const Body& b : s.bodies) {
    json bj = {{"name", b.name}, {"particles_per_cell", b.particles_per_cell}};
    const Geometry& g = b.geometry;
    if (g.type == "box") {
      bj["geometry"] = {{"type", "box"}, {"min", vec_json(g.min, dim)}, {"max", vec_json(g.max, dim)}};
    } else if (g.type == "polygon") {
      json vs = json::array();
      for (const auto& v : g.vertices) vs.push_back({v[0], v[1]});
      bj["geometry"] = {{"type", "polygon"}, {"vertices", vs}};
    } else {
      bj["geometry"] = geometry_json(g, dim);
    }
    if (!b.solid.empty()) bj["solid"] = b.solid;
    if (!b.fluid.empty()) bj["fluid"] = b.fluid;
    const InitialState& in = b.initial;
    json ij = json::object();
    if (in.hydrostatic) ij["pore_pressure"] = "hydrostatic";
    else if (in.pore_pressure) ij["pore_pressure"] = *in.pore_pressure;
    if (in.water_table) ij["water_table"] = *in.water_table;
    if (in.geostatic) {
      ij["stress"] = "geostatic";
      ij["k0"] = in.k0;
    } else if (in.stress) {
      ij["stress"] = *in.stress;
    }
    if (in.porosity) ij["porosity"] = *in.porosity;
    ij["velocity"] = json::array();
    for (int d = 0; d < dim; ++d) ij["velocity"].push_back(in.velocity[static_cast<std::size_t>(d)]);
    bj["initial"] = ij;
    j["bodies"].push_back(bj);
  }

  j["boundaries"] = json::array();
  for (const Boundary& bc : s.boundaries) {
    json bj = {{"on", bc.on}, {"solid", solid_bc_names()[static_cast<std::size_t>(bc.solid)]}};
    if (bc.solid == SolidBc::friction) bj["coefficient"] = bc.coefficient;
    if (bc.fluid) {
      bj["fluid"] = fluid_bc_names()[static_cast<std::size_t>(*bc.fluid)];
      if (*bc.fluid == FluidBc::pressure) bj["value"] = bc.fluid_value;
    }
    j["boundaries"].push_back(bj);
  }

  j["loads"] = json::array();
  for (const Load& l : s.loads) {
    json lj = {{"type", l.type}, {"body", l.body}, {"face", l.face}, {"ramp", l.function.ramp}};
    lj["value"] = l.type == "pressure" ? json(l.value[0]) : vec_json(l.value, dim);
    if (l.region) lj["region"] = {{"min", vec_json(l.region->first, dim)}, {"max", vec_json(l.region->second, dim)}};
    if (!l.function.expression.empty()) lj["function"] = l.function.expression;
    if (!l.function.table.empty()) lj["table"] = l.function.table;
    j["loads"].push_back(lj);
  }

  if (s.initialisation.enabled()) {
    const Initialisation& in = s.initialisation;
    json ij = {{"duration", in.duration}, {"gravity_ramp", in.gravity_ramp}, {"plasticity", in.plasticity},
               {"reset_displacement", in.reset_displacement}};
    if (in.hydraulic_conductivity) ij["hydraulic_conductivity"] = *in.hydraulic_conductivity;
    if (in.damping) ij["damping"] = *in.damping;
    if (s.formulation == Formulation::semi_implicit_double_point || s.formulation == Formulation::explicit_double_point)
      ij["tie_water"] = in.tie_water;
    j["initialisation"] = ij;
  }

  j["time"] = {{"end", s.time.end}, {"cfl", s.time.cfl}};
  j["time"]["dt"] = s.time.dt ? json(*s.time.dt) : json("auto");

  json monitors = json::array();
  for (const Monitor& m : s.output.monitors) {
    json mj = {{"name", m.name}, {"phase", m.phase}, {"quantities", m.quantities}};
    if (m.at) mj["at"] = vec_json(*m.at, dim);
    if (m.particle) mj["particle"] = *m.particle;
    if (m.points != "soil") mj["points"] = m.points;
    monitors.push_back(mj);
  }
  j["output"] = {{"interval", s.output.interval},
                 {"monitor_interval", s.output.monitor_interval},
                 {"compression", s.output.compression},
                 {"monitors", monitors}};
  if (s.output.checkpoint_interval) j["output"]["checkpoint_interval"] = *s.output.checkpoint_interval;

  const Solver& sv = s.solver;
  j["solver"] = {{"flip", sv.flip},
                 {"damping", sv.damping},
                 {"continuity", sv.continuity},
                 {"escaped_water", sv.escaped_water},
                 {"checkpoint_every", sv.checkpoint_every},
                 {"stabilisation", {{"fbar", sv.stabilisation.fbar}}}};
  if (reads_switch(s, "kinematics")) j["solver"]["kinematics"] = sv.kinematics;
  json& stab = j["solver"]["stabilisation"];
  if (reads_switch(s, "strain_smoothing")) stab["strain_smoothing"] = sv.stabilisation.strain_smoothing;
  if (reads_switch(s, "pressure")) stab["pressure"] = sv.stabilisation.pressure;
  if (reads_switch(s, "fbar_patch")) stab["fbar_patch"] = sv.stabilisation.fbar_patch;
  if (!sv.drag_integration.empty()) j["solver"]["drag_integration"] = sv.drag_integration;  // semi-implicit only
  return j;
}

std::vector<std::string> named_surfaces(const Geometry& g, int dimension) {
  if (g.type == "slope") return {"surface", "base", "left", "right", "toe", "slope_face", "crest"};
  if (g.type == "footing") {
    if (dimension == 3) return {"bottom", "top", "left", "right", "back", "front"};
    return {"bottom", "top", "left", "right"};
  }
  return {};
}

std::vector<std::string> surface_bit_names(const Scene& s) {
  std::vector<std::string> names;
  auto note = [&](const std::string& n) {
    if (!contains(face_names(), n) && !contains(names, n)) names.push_back(n);
  };
  for (const Boundary& b : s.boundaries) note(b.on);
  for (const Load& l : s.loads) note(l.face);
  return names;
}

std::vector<std::string> schema_keys() {
  std::set<std::string> keys;
  for (const Table* t : all_tables()) {
    for (const Key& k : t->keys) keys.insert(k.name);
  }
  return {keys.begin(), keys.end()};
}

std::string schema_markdown() {
  std::string out;
  for (const Table* t : all_tables()) {
    out += "### " + t->title + "\n\nIn " + t->where + ".\n\n";
    out += "| key | type | unit | default | allowed | meaning |\n";
    out += "|---|---|---|---|---|---|\n";
    for (const Key& k : t->keys) {
      out += "| `" + k.name + "` | " + markdown_type(k) + " | " + k.unit + " | " + markdown_default(k) +
             " | " + markdown_allowed(k) + " | " + k.meaning + " |\n";
    }
    out += "\n";
  }
  return out;
}

}  // namespace swmpm::scene
