// The validation engine of scene files: message phrases, "did you mean", the custom value checks
// and check_object, which checks one JSON object against its key tables (see validate.hpp).
#include <muParser.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "scene/input.hpp"
#include "scene/validate.hpp"

namespace swmpm::scene::detail {

// ------------------------------------------------------------------------------------------------
// Small text helpers for messages.
// ------------------------------------------------------------------------------------------------

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

std::string join(const std::vector<std::string>& v, const std::string& sep) {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? sep : "") + v[i];
  return out;
}

std::string fmt_g(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", x);
  return buf;
}

std::string shown(const json& v) {
  // A long string keeps its first 60 characters and says how long it was (a 1 MB value must not
  // make a 1 MB message).
  if (v.is_string() && v.get_ref<const std::string&>().size() > 60) {
    const std::string cut = shortened(v.get_ref<const std::string&>(), 60);
    const auto mark = cut.rfind("… (");
    std::string s = json(cut.substr(0, mark)).dump(-1, ' ', false, json::error_handler_t::replace);
    return s.insert(s.size() - 1, cut.substr(mark));  // "abc… (N characters)"
  }
  std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

std::string in_quotes(const std::string& s) { return "\"" + shortened(s) + "\""; }

std::string fmt_vec(const Vec3& v, int dim) {
  std::string out = "[";
  for (int d = 0; d < dim; ++d) out += (d ? ", " : "") + fmt_g(v[static_cast<std::size_t>(d)]);
  return out + "]";
}

std::string escape(const std::string& key) {
  std::string out;
  for (char ch : key) {
    if (ch == '~') out += "~0";
    else if (ch == '/') out += "~1";
    else out += ch;
  }
  return out;
}

std::string shown_pointer(const std::string& pointer) {
  if (pointer.size() <= 60) return pointer;
  std::string out;
  std::size_t begin = 0;
  while (begin < pointer.size()) {
    const std::size_t slash = pointer.find('/', begin + 1);
    const std::size_t end = slash == std::string::npos ? pointer.size() : slash;
    out += '/';
    out += shortened(pointer.substr(begin + 1, end - begin - 1));
    begin = end;
  }
  return out;
}

std::string item(const std::string& path, std::size_t i) { return path + "/" + std::to_string(i); }

std::string lower(std::string s) {
  for (char& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

namespace {

/// Longest names "did you mean" compares: declared keys and values are short; a longer string is
/// no typo of one (and comparing a 1 MB value with each name took seconds and gigabytes).
constexpr std::size_t kMaxSuggestLength = 64;

/// Edit distance with adjacent transpositions (optimal string alignment): "snad" -> "sand" is 1.
/// Three rows of the table, O(min(|a|, |b|)) memory.
std::size_t edit_distance(const std::string& a_in, const std::string& b_in) {
  const std::string& a = a_in.size() >= b_in.size() ? a_in : b_in;
  const std::string& b = a_in.size() >= b_in.size() ? b_in : a_in;  // the shorter one
  std::vector<std::size_t> before(b.size() + 1), prev(b.size() + 1), row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      row[j] = std::min({prev[j] + 1, row[j - 1] + 1, prev[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) row[j] = std::min(row[j], before[j - 2] + 1);
    }
    std::swap(before, prev);
    std::swap(prev, row);
  }
  return prev[b.size()];
}

/// The closest candidate to `s`, if close enough to be a plausible typo.
std::optional<std::string> closest(const std::string& s, const std::vector<std::string>& candidates) {
  // Up to one edit per three characters, at least one, at most three.
  const std::size_t limit = std::clamp<std::size_t>(s.size() / 3, 1, 3);
  if (s.size() > kMaxSuggestLength) return std::nullopt;
  std::optional<std::string> best;
  std::size_t best_d = std::numeric_limits<std::size_t>::max();
  for (const auto& c : candidates) {
    // The distance is at least the difference of the lengths: skip what cannot be close.
    if (c.size() > kMaxSuggestLength || (c.size() > s.size() ? c.size() - s.size() : s.size() - c.size()) > limit)
      continue;
    const std::size_t d = edit_distance(lower(s), lower(c));
    if (d < best_d) best_d = d, best = c;
  }
  if (best && best_d <= limit) return best;
  return std::nullopt;
}

}  // namespace

std::string did_you_mean(const std::string& s, const std::vector<std::string>& candidates) {
  const auto c = closest(s, candidates);
  return c ? " (did you mean " + in_quotes(*c) + "?)" : "";
}

// -- phrases generated from a key, shared by messages and the reference ---------------------------

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

namespace {

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

}  // namespace

// -- expressions (muParser) -------------------------------------------------------------------

namespace {

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

}  // namespace

double expression_value(const std::string& expr, const std::vector<std::string>& vars, const Vec3& values) {
  Vec3 v = values;
  mu::Parser p;
  for (std::size_t i = 0; i < vars.size() && i < v.size(); ++i) p.DefineVar(vars[i], &v[i]);
  p.DefineConst("pi", std::numbers::pi);
  p.SetExpr(expr);
  return p.Eval();
}

// -- custom checks --------------------------------------------------------------------------------

bool is_integral(const json& v) {
  if (v.is_number_integer() || v.is_number_unsigned()) return true;
  if (!v.is_number_float()) return false;
  const double x = v.get<double>();
  return std::isfinite(x) && std::floor(x) == x;
}

namespace {

bool is_number_array(const json& v, std::size_t n) {
  return v.is_array() && v.size() == n &&
         std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); });
}

bool dim_ok(const Ctx& c, std::size_t n) {
  return c.dim == 0 ? (n == 2 || n == 3) : n == static_cast<std::size_t>(c.dim);
}

}  // namespace

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

bool check_monitor_at(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (v.is_array() && !v.empty() && v.size() <= 3 &&
      std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); }))
    return true;  // the number of components: parse_output
  c.error(path, "got " + shown(v) + ", expected " + vector_phrase(c.dim) + ", or one fewer in a water_level gauge [" +
                    k.unit + "]");
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

std::filesystem::path resolve_file(const std::string& label, const std::string& file) {
  namespace fs = std::filesystem;
  fs::path p(file);
  if (p.is_relative()) p = fs::path(label).parent_path() / p;
  std::error_code ec;
  const fs::path abs = fs::absolute(p, ec);
  return (ec ? p : abs).lexically_normal();
}

namespace {

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

}  // namespace

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

bool check_phase_materials(Ctx& c, const json& v, const std::string& path, const Key& k) {
  if (!v.is_object()) {
    report(c, v, path, k);
    return false;
  }
  bool ok = true;
  for (const auto& [name, value] : v.items())
    if (!value.is_object()) {
      c.error(path + "/" + escape(name), "got " + shown(value) + ", expected an object of material " +
                                             in_quotes(name) + "'s parameters, e.g. {\"cohesion\": 1e5}");
      ok = false;
    }
  return ok;
}

// ------------------------------------------------------------------------------------------------
// Checking one object against its tables.
// ------------------------------------------------------------------------------------------------

namespace {

bool check_value(Ctx& c, const Key& k, const json& v, const std::string& path) {
  switch (k.type) {
    case Type::number:  // finite: a number too large for a double (1e400) reads as infinity
      if (v.is_number() && std::isfinite(v.get<double>()) && k.range.contains(v.get<double>())) return true;
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

}  // namespace

Obj check_object(Ctx& c, const json& j, const std::string& path,
                 const std::vector<const Table*>& tables, bool report_unknown) {
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

}  // namespace swmpm::scene::detail
