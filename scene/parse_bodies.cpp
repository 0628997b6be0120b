// Scene file parsing, the bodies (SceneParser, parser.hpp): materials named by each body, the
// geometries and their bounds against the grid, footings resting on other bodies, initial state.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "scene/keys.hpp"
#include "scene/parser.hpp"

namespace swmpm::scene::detail {

// -- bodies ---------------------------------------------------------------------------------------

void SceneParser::parse_bodies(const json& arr, const std::string& path) {
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
void SceneParser::check_saturated_solid(std::size_t idx, const Body& b, const std::string& body_path) {
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
std::string SceneParser::dimension_problem(const std::string& type) const {
  if (dim() == 3 && type == "polygon") return "got \"polygon\" in a 3D scene, expected \"box\" (polygon is 2D only)";
  if (dim() == 3 && type == "slope")
    return "got \"slope\" in a 3D scene, expected a 3D geometry (box, footing, gmsh, surface-mesh); slope is 2D only";
  if (dim() == 2 && type == "surface-mesh")
    return "got \"surface-mesh\" in a 2D scene, expected a 2D geometry (box, polygon, slope, footing, gmsh); "
           "surface-mesh is 3D only";
  return {};
}

const Table* SceneParser::type_table(const std::string& type) {
  if (type == "box") return &box_table();
  if (type == "polygon") return &polygon_table();
  if (type == "slope") return &slope_table();
  if (type == "footing") return &footing_table();
  if (type == "gmsh") return &gmsh_table();
  if (type == "surface-mesh") return &surface_mesh_table();
  return nullptr;
}

/// The geometry's typed values and, when they are known before preprocess, its bounds.
std::optional<Bounds> SceneParser::parse_geometry(const json& j, const std::string& path, Geometry& g) {
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

std::optional<Bounds> SceneParser::parse_box(const Obj& o, Geometry& g) {
  g.min = o.vec("min");
  g.max = o.vec("max");
  if (!o.ok("min") || !o.ok("max") || !check_min_max(g.min, g.max, o.at("max"))) return std::nullopt;
  return Bounds{g.min, g.max};
}

std::optional<Bounds> SceneParser::parse_polygon(const Obj& o, Geometry& g) {
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
bool SceneParser::one_of(const Obj& o, const std::string& a, const std::string& b, const std::string& what) {
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

std::optional<Bounds> SceneParser::parse_slope(const Obj& o, Geometry& g) {
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

std::optional<Bounds> SceneParser::parse_footing(const Obj& o, Geometry& g) {
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

Bounds SceneParser::footing_bounds(const Geometry& g) const {
  return {{g.center_x - g.width / 2, g.base_y, g.center_z - g.length / 2},
          {g.center_x + g.width / 2, g.base_y + g.height, g.center_z + g.length / 2}};
}

/// Footings that rest `on` another body stand on its top (the highest point of its bounds). A
/// footing may rest on a footing; the passes stop when no more can be placed (cycles).
void SceneParser::resolve_footings() {
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

void SceneParser::check_inside_grid(const Bounds& b, const std::string& path) {
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

void SceneParser::parse_initial(const json& j, const std::string& path, Body& b) {
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

}  // namespace swmpm::scene::detail
