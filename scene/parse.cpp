// Scene file parsing (json -> Scene): SceneParser (parser.hpp) for the top level, grid, materials,
// boundaries, loads, time, output, solver, initialisation and formulation (the bodies are in
// parse_bodies.cpp); load_scene, which reads a scene file (scene/input.hpp: bounded size and
// nesting) and reports keys written twice.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "scene/auto_formulation.hpp"
#include "scene/budget.hpp"
#include "scene/formulations.hpp"
#include "scene/input.hpp"
#include "scene/keys.hpp"
#include "scene/parser.hpp"

namespace swmpm::scene::detail {

Scene SceneParser::parse() {
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
  check_expression_values();
  parse_output(top.ok("output") ? top.get("output") : json::object(), top.at("output"));
  parse_solver(top.ok("solver") ? top.get("solver") : json::object(), top.at("solver"));
  if (top.ok("formulation")) resolve_formulation(top.str("formulation"), top.at("formulation"));
  // The resolved scene.json of a run directory: how "auto" chose, kept for solve's log and run.json.
  if (root_.contains("formulation_choice") && root_["formulation_choice"].is_object()) {
    const json& fc = root_["formulation_choice"];
    const bool recorded = fc.contains("chosen") && fc["chosen"] == to_string(s_.formulation) &&
                          fc.contains("reason") && fc["reason"].is_string() && s_.formulation_choice.is_null();
    if (!recorded) {
      c_.error(top.at("formulation_choice"), "got " + shown(fc) + ", expected the record preprocess writes of how \"auto\" "
                                             "chose formulation " + in_quotes(to_string(s_.formulation)) +
                                             " (a scene file leaves it out)");
    } else {
      s_.formulation_choice = fc;
      if (fc.contains("automatic") && fc["automatic"] == true) s_.formulation_reason = fc["reason"].get<std::string>();
    }
  }
  // A key the formulation does not read, where "auto" chose it: the message says so, and how to choose.
  const std::string chosen_note =
      s_.formulation_choice.is_object() && !root_.contains("formulation_choice")
          ? " (formulation " + in_quotes(to_string(s_.formulation)) + " was chosen automatically by \"auto\", rule \"" +
                s_.formulation_choice.value("rule", std::string()) +
                "\"; `swmpm preprocess --explain` says why; name a formulation in /formulation to use this key)"
          : std::string();
  for (const auto& at : water_monitors_)
    if (s_.formulation != Formulation::automatic && !row_of(s_.formulation).water.fluid_particles)
      c_.error(at, "got \"water\", but only the double-point formulations have water points; expected \"soil\"" +
                       chosen_note);
  // A water_level gauge reads the liquid points (double-point) or the grid's phase field (mpm-fem).
  const auto has_liquid = [](const WaterLayout& w) { return w.fluid_particles || w.free_water_on_grid; };
  if (s_.formulation != Formulation::automatic && s_.has_fluid() && !has_liquid(row_of(s_.formulation).water)) {
    std::vector<std::string> readers;  // formulations with liquid points or a grid fluid
    for (const FormulationRow& r : formulation_rows())
      if (r.implemented && has_liquid(r.water)) readers.push_back(r.name);
    for (const auto& at : gauges_)
      c_.error(at, "got \"water_level\", but formulation " + in_quotes(to_string(s_.formulation)) +
                       " has no liquid points; expected a formulation that reads it: " + join(readers));
  }
  // Formulation-specific switches against the formulation's row (scene/formulations.hpp): refused
  // where the formulation does not read them or lacks the value; unset ones take the row's default.
  if (s_.formulation != Formulation::automatic) {
    for (const Problem& p : check_formulation(root_, s_)) c_.error(p.path, p.message + chosen_note);
    apply_formulation_defaults(s_);
  }
  if (top.ok("initialisation")) parse_initialisation(top.get("initialisation"), top.at("initialisation"), top);
  if (s_.solver.stabilisation.fbar_patch == 0.0)
    s_.solver.stabilisation.fbar_patch = default_fbar_patch(s_.grid.shape_function);

  if (!c_.errors.empty()) {
    std::vector<std::string> unique;
    for (const auto& e : c_.errors) {
      if (!contains(unique, e)) unique.push_back(e);
    }
    throw SceneError(unique);
  }
  return s_;
}

/// Face names of this scene's dimension.
std::vector<std::string> SceneParser::faces() const {
  std::vector<std::string> f(face_names().begin(), face_names().begin() + (dim() == 3 ? 6 : 4));
  return f;
}

/// An axis face of this dimension, or a named surface among `named` (the surfaces known now).
/// With `deferred` (a gmsh geometry, whose names preprocess reads from its file) any other
/// name passes here and is checked there. `none` says whose surfaces are missing.
bool SceneParser::check_face(const std::string& face, const std::string& path,
                             const std::vector<std::string>& named, bool deferred, const std::string& none) {
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
bool SceneParser::check_min_max(const Vec3& mn, const Vec3& mx, const std::string& max_path) {
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

// -- grid -----------------------------------------------------------------------------------------

void SceneParser::parse_grid(const json& j, const std::string& path) {
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
  // The solver indexes nodes with 32-bit integers per axis: a count past kMaxCellsPerAxis is refused
  // here (a grid max of 1e12 m once wrapped around to a wrong count, reported only at solve).
  for (int d = 0; d < dim(); ++d) {
    const auto i = static_cast<std::size_t>(d);
    const double cells = (grid.max[i] - grid.min[i]) / grid.cell_size;
    if (!(cells <= kMaxCellsPerAxis)) {
      const bool tiny_cells = grid.cell_size < 1e-6;  // the likelier culprit
      c_.error(tiny_cells ? g.at("cell_size") : g.at("max"),
               "the grid would have " + fmt_g(cells) + " cells along axis " + std::to_string(d) + " ((max - min) / " +
                   "cell_size = " + fmt_g(grid.max[i] - grid.min[i]) + " m / " + fmt_g(grid.cell_size) +
                   " m); expected at most " + fmt_g(kMaxCellsPerAxis) + " per axis");
      return;
    }
  }
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

// -- materials ------------------------------------------------------------------------------------

void SceneParser::parse_materials(const json& arr, const std::string& path) {
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
    info.gives_permeability =
      o.has("hydraulic_conductivity") || o.has("intrinsic_permeability") || o.has("grain_diameter");
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

void SceneParser::check_solid_material(const Obj& o, const Material& m) {
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

std::vector<std::string> SceneParser::material_names(bool fluid) const {
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
int SceneParser::check_material_ref(const Obj& o, const std::string& key, bool fluid) {
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

// -- boundaries and loads -------------------------------------------------------------------------

/// A boundary's `on`: an axis face, or a named surface of any body's geometry.
bool SceneParser::check_boundary_on(const std::string& on, const std::string& path) {
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
void SceneParser::check_load_face(const Load& l, const std::string& path) {
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

void SceneParser::parse_boundaries(const json& arr, const std::string& path) {
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

void SceneParser::parse_loads(const json& arr, const std::string& path) {
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

// -- expressions ---------------------------------------------------------------------------------

// An expression that is inf or NaN (1/0, exp(1e6), sqrt(-1)) passed the syntax check and made the
// run diverge at its first step, blamed on "J <= 0". Each is evaluated here where it will be used:
// an initial velocity at the corners and the centre of its body's bounds (the grid's when the
// bounds are known only after meshing), a load function at nine times from 0 to time.end. The
// solver and preprocess check every value again where they use it.
namespace {

std::string value_text(double v) { return std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf"; }

}  // namespace

void SceneParser::check_expression_values() {
  const int d = dim();
  for (std::size_t i = 0; i < s_.bodies.size(); ++i) {
    const std::optional<Bounds> known = i < body_bounds_.size() ? body_bounds_[i] : std::nullopt;
    const Bounds box = known ? *known : Bounds{grid_min_, grid_max_};
    std::vector<Vec3> points;
    for (int corner = 0; corner < (1 << d); ++corner) {
      Vec3 x{0.0, 0.0, 0.0};
      for (int a = 0; a < d; ++a) {
        const auto k = static_cast<std::size_t>(a);
        x[k] = (corner >> a) & 1 ? box.max[k] : box.min[k];
      }
      points.push_back(x);
    }
    Vec3 centre{0.0, 0.0, 0.0};
    for (std::size_t k = 0; k < 3; ++k) centre[k] = 0.5 * (box.min[k] + box.max[k]);
    points.push_back(centre);
    for (std::size_t a = 0; a < s_.bodies[i].initial.velocity.size(); ++a) {
      const std::string& expr = s_.bodies[i].initial.velocity[a];  // a number is an expression too
      for (const Vec3& x : points) {
        const double v = expression_value(expr, {"x", "y", "z"}, x);
        if (std::isfinite(v)) continue;
        const std::string at = fmt_vec(x, d);  // "[x, y]"
        const std::string where = (known ? "its bounds " : "the grid ") + fmt_vec(box.min, d) + ".." + fmt_vec(box.max, d);
        c_.error(body_paths_[i] + "/initial/velocity/" + std::to_string(a),
                 "got " + in_quotes(expr) + ", which is " + value_text(v) + " at " + (d == 2 ? "(x, y)" : "(x, y, z)") +
                     " = (" + at.substr(1, at.size() - 2) + ") m; expected an expression with a finite value over " +
                     "the body (evaluated at the corners and the centre of " + where + " m) [m/s]");
        break;
      }
    }
  }
  const double end = s_.time.end > 0.0 ? s_.time.end : 0.0;
  for (std::size_t i = 0; i < s_.loads.size(); ++i) {
    const std::string& expr = s_.loads[i].function.expression;
    if (expr.empty()) continue;
    for (int k = 0; k <= 8; ++k) {
      const double t = end * k / 8.0;
      const double v = expression_value(expr, {"t"}, {t, 0.0, 0.0});
      if (std::isfinite(v)) continue;
      c_.error("/loads/" + std::to_string(i) + "/function",
               "got " + in_quotes(expr) + ", which is " + value_text(v) + " at t = " + fmt_g(t) +
                   " s; expected an expression with a finite value over the run (evaluated at 9 times from 0 to " +
                   fmt_g(end) + " s)");
      break;
    }
  }
}

// -- time, output, solver -------------------------------------------------------------------------

void SceneParser::parse_time(const json& j, const std::string& path) {
  const Obj o = check_object(c_, j, path, {&time_table()});
  s_.time.end = o.num("end");
  if (o.ok("dt") && o.get("dt").is_number()) s_.time.dt = o.num("dt");
  s_.time.cfl = o.num("cfl", 0.5);
}

void SceneParser::parse_output(const json& j, const std::string& path) {
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
    // A monitor asking for water_level is a gauge: it reads the liquid on a vertical line, not one
    // particle (found in the raw quantities, so that a misspelt neighbour does not hide it).
    const json& raw = arr[i];
    const bool gauge = raw.is_object() && raw.contains("quantities") && raw["quantities"].is_array() &&
                       std::find(raw["quantities"].begin(), raw["quantities"].end(), json("water_level")) !=
                           raw["quantities"].end();
    if (gauge) parse_gauge(m, mon);
    else parse_point_or_global(m, mon);
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

/// A point monitor (`at` or `particle`: one particle followed) or a global one (neither).
void SceneParser::parse_point_or_global(const Obj& m, Monitor& mon) {
  // The number of components once the dimension is known (c_.dim; 0: the scene's is invalid).
  if (m.ok("at") && c_.dim != 0 && m.get("at").size() != static_cast<std::size_t>(dim())) {
    c_.error(m.at("at"), "got " + shown(m.get("at")) + " (" + std::to_string(m.get("at").size()) +
                             " components), expected " + vector_phrase(dim()) + " [m] (" + std::to_string(dim() - 1) +
                             " only in a water_level gauge)");
  } else if (m.ok("at")) {
    mon.at = m.vec("at");
  }
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
}

/// A water_level gauge (monitors.hpp): `at` is its vertical line, x in 2D, (x, z) in 3D, inside
/// the grid; it records water_level alone and follows no particle. Which formulations read it is
/// checked once the formulation is known (parse()).
void SceneParser::parse_gauge(const Obj& m, Monitor& mon) {
  for (const char* key : {"particle", "points", "phase"})
    if (m.has(key))
      c_.error(m.at(key), "got " + in_quotes(key) + " in a water_level gauge, expected none of \"particle\", "
                              "\"points\", \"phase\" (a gauge reads the liquid points near its vertical line, "
                              "not one particle)");
  const std::string line = dim() == 2 ? "1 number, x" : "2 numbers, x and z";
  if (!m.has("at")) {
    c_.error(m.at("at"), "missing, expected the vertical line of the water_level gauge: " + line + " [m]");
  } else if (m.ok("at") && c_.dim != 0) {  // 0: the scene's dimension is invalid, reported there
    const json& a = m.get("at");
    if (a.size() + 1 != static_cast<std::size_t>(dim())) {
      c_.error(m.at("at"), "got " + shown(a) + " (" + std::to_string(a.size()) + " components), expected " + line +
                               " of the water_level gauge's vertical line (y is vertical) [m]");
    } else {
      // (x, ·, z): the file's [x] or [x, z]; y unused.
      const Vec3 g{a[0].get<double>(), 0.0, dim() == 3 ? a[1].get<double>() : 0.0};
      mon.gauge = g;
      const auto within = [&](std::size_t k) { return g[k] >= grid_min_[k] && g[k] <= grid_max_[k]; };
      if (grid_ok_ && !(within(0) && (dim() == 2 || within(2)))) {
        c_.error(m.at("at"), "got " + shown(a) + ", expected a vertical line inside the grid: x in [" +
                                 fmt_g(grid_min_[0]) + ", " + fmt_g(grid_max_[0]) + "]" +
                                 (dim() == 3 ? ", z in [" + fmt_g(grid_min_[2]) + ", " + fmt_g(grid_max_[2]) + "]"
                                             : std::string()) +
                                 " [m]");
      }
    }
  }
  if (!m.ok("quantities")) return;
  const json& qs = m.get("quantities");
  for (std::size_t k = 0; k < qs.size(); ++k) {
    const std::string q = qs[k].get<std::string>();
    const std::string qp = item(m.at("quantities"), k);
    if (q != "water_level") {
      c_.error(qp, "got " + in_quotes(q) + " in a water_level gauge, expected only \"water_level\" (a gauge "
                   "follows no particle; record other quantities in another monitor)");
    } else if (contains(mon.quantities, q)) {
      c_.error(qp, "got " + in_quotes(q) + " twice, expected each quantity at most once");
    } else {
      check_quantity(q, false, qp);
      gauges_.push_back(qp);
    }
    mon.quantities.push_back(q);
  }
}

void SceneParser::check_quantity(const std::string& q, bool global, const std::string& path) {
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

void SceneParser::parse_solver(const json& j, const std::string& path) {
  const Obj o = check_object(c_, j, path, {&solver_table()});
  Solver& sv = s_.solver;
  sv.flip = o.num("flip", 0.99);
  sv.damping = o.num("damping");
  sv.kinematics = o.str("kinematics", "finite-strain");
  sv.continuity = o.str("continuity", "");  // "": the formulation's default (after resolve_formulation)
  sv.escaped_water = o.str("escaped_water", "keep");
  sv.drag_integration = o.str("drag_integration", "");  // "": resolved by formulation in parse()
  sv.drag = o.str("drag", "");  // "": resolved by formulation in parse()
  sv.checkpoint_every = static_cast<int>(o.num("checkpoint_every", 50.0));
  sv.soil_substeps = static_cast<int>(o.num("soil_substeps", 1.0));
  const Obj st = check_object(c_, o.ok("stabilisation") ? o.get("stabilisation") : json::object(),
                              o.at("stabilisation"), {&stabilisation_table()});
  sv.stabilisation.strain_smoothing = st.ok("strain_smoothing") ? st.get("strain_smoothing").get<bool>() : true;
  sv.stabilisation.pressure = st.str("pressure", "");  // "": the formulation's default (default_pressure_stabilisation)
  sv.stabilisation.fbar = st.str("fbar", "none");
  sv.stabilisation.fbar_patch = st.num("fbar_patch", 0.0);  // 0: by shape function, resolved in parse()
  // mpm-fem's air and phase field (refused in the other formulations by their rows, parse()).
  const Obj air = check_object(c_, o.ok("air") ? o.get("air") : json::object(), o.at("air"), {&air_table()});
  sv.air.density = air.num("density", sv.air.density);
  sv.air.dynamic_viscosity = air.num("dynamic_viscosity", sv.air.dynamic_viscosity);
  sv.air.whole_grid = air.str("domain", "active") == "grid";
  const Obj pf = check_object(c_, o.ok("phase_field") ? o.get("phase_field") : json::object(), o.at("phase_field"),
                              {&phase_field_table()});
  if (pf.ok("interface_width")) sv.phase_field.interface_width = pf.num("interface_width");
  if (pf.ok("mobility")) sv.phase_field.mobility = pf.num("mobility");
  if (pf.ok("lsic")) sv.phase_field.lsic = pf.get("lsic").get<bool>();
  if (pf.ok("volume_correction")) sv.phase_field.volume_correction = pf.get("volume_correction").get<bool>();
}

void SceneParser::parse_initialisation(const json& j, const std::string& path, const Obj& top) {
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
  if (o.ok("materials")) parse_phase_materials(o.get("materials"), o.at("materials"));
}

/// initialisation.materials: each name a solid material of the scene, each key a parameter of
/// that material's constitutive model, range-checked as in the material's own tables (none
/// required: a parameter the phase does not give keeps the scene's value); the rules across keys
/// hold for the parameters the phase runs with.
void SceneParser::parse_phase_materials(const json& j, const std::string& path) {
  for (const auto& [name, value] : j.items()) {
    const std::string p = path + "/" + escape(name);
    const int idx = s_.material_index(name);
    if (idx < 0) {
      const std::vector<std::string> solids = material_names(false);
      c_.error(p, "got material " + in_quotes(name) + ", but no material has that name; expected a solid material "
                  "(defined: " + (solids.empty() ? std::string("none") : join(solids)) + ")" + did_you_mean(name, solids));
      continue;
    }
    const Material& m = s_.materials[static_cast<std::size_t>(idx)];
    if (!material_info_[static_cast<std::size_t>(idx)].known) continue;  // its model is reported with it
    const std::vector<const Table*> own = constitutive_tables(m.model);
    if (own.empty()) {
      c_.error(p, "got material " + in_quotes(name) + ", a fluid; expected a solid material (the phase changes the "
                  "parameters of constitutive models only)");
      continue;
    }
    // The model's tables with nothing required and no defaults.
    std::vector<Table> optional;
    for (const Table* t : own) {
      optional.push_back(*t);
      for (Key& k : optional.back().keys) k.required = false, k.def = nullptr;
    }
    std::vector<const Table*> tables;
    for (const Table& t : optional) tables.push_back(&t);
    // The material's other keys (density, porosity, permeability: read by preprocess and the
    // formulations, not by the model) are named as such rather than as unknown.
    json given = value;
    std::vector<std::string> parameters;
    for (const Table* t : own)
      for (const Key& k : t->keys) parameters.push_back(k.name);
    for (const Table* t : model_tables(m.model))
      for (const Key& k : t->keys)
        if (given.contains(k.name) && !contains(parameters, k.name)) {
          c_.error(p + "/" + escape(k.name), "got " + in_quotes(k.name) + ", which " + to_string(m.model) +
                                                 "'s constitutive model does not read (it is fixed at t0 by preprocess "
                                                 "or read by the formulation); expected one of: " + join(parameters));
          given.erase(k.name);
        }
    const Obj o = check_object(c_, given, p, tables);
    Material phase = m;
    for (const auto& [key, v] : o.v) {
      phase.params[key] = v.get<double>();
      s_.initialisation.materials[name][key] = v.get<double>();
    }
    if (phase.has("friction_angle") && phase.has("dilation_angle") &&
        phase.at("dilation_angle") > phase.at("friction_angle"))
      c_.error(o.at(o.ok("dilation_angle") ? "dilation_angle" : "friction_angle"),
               "got dilation_angle " + fmt_g(phase.at("dilation_angle")) + " > friction_angle " +
                   fmt_g(phase.at("friction_angle")) + " during the phase, expected dilation_angle <= friction_angle [deg]");
    if (phase.has("dilatancy_cutoff_start") && phase.has("dilatancy_cutoff_end") &&
        phase.at("dilatancy_cutoff_end") < phase.at("dilatancy_cutoff_start"))
      c_.error(o.at(o.ok("dilatancy_cutoff_end") ? "dilatancy_cutoff_end" : "dilatancy_cutoff_start"),
               "got dilatancy_cutoff_end " + fmt_g(phase.at("dilatancy_cutoff_end")) + " < dilatancy_cutoff_start " +
                   fmt_g(phase.at("dilatancy_cutoff_start")) + " during the phase, expected end >= start [-]");
  }
}

// -- formulation ----------------------------------------------------------------------------------

void SceneParser::resolve_formulation(const std::string& name, const std::string& path) {
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
    // The materials, bodies, grid and time are parsed; a scene whose errors so far leave them
    // incomplete is reported as it is, with the formulation left to a scene without errors.
    if (!c_.errors.empty()) {
      s_.formulation = fluid ? Formulation::explicit_single_point : Formulation::dry;
      return;
    }
    const FormulationChoice choice = choose_formulation(s_);
    s_.formulation = choice.chosen;
    s_.formulation_reason = choice.reason;
    s_.formulation_choice = to_json(choice);
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

}  // namespace swmpm::scene::detail

namespace swmpm::scene {

using namespace detail;

Scene parse_scene(const nlohmann::json& j, const std::string& label) {
  return SceneParser(j, label).parse();
}

Scene load_scene(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw SceneError({path + ": is a directory, expected a scene file (JSON)"});
  json j;
  std::vector<std::string> duplicates;
  try {
    j = parse_json(read_input_file(path, "scene file"), path, &duplicates);
  } catch (const InputError& e) {
    throw SceneError({e.what()});
  }
  try {
    Scene scene = parse_scene(j, path);
    if (!duplicates.empty()) throw SceneError(duplicates);
    return scene;
  } catch (const SceneError& e) {
    if (duplicates.empty()) throw;
    std::vector<std::string> lines = duplicates;
    for (const auto& l : e.lines()) {
      if (!contains(lines, l)) lines.push_back(l);
    }
    throw SceneError(lines);
  }
}

}  // namespace swmpm::scene
