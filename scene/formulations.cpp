#include "scene/formulations.hpp"

#include <algorithm>
#include <stdexcept>

namespace swmpm::scene {
namespace {

const std::vector<std::string> kExplicitPressures = {"none", "mfvp-constant", "mfvp-linear", "mfvp-quadratic",
                                                     "cell-constant"};
const std::vector<std::string> kSemiImplicitPressures = {"node-remap", "mfvp-linear", "none"};
const std::vector<std::string> kContinuity = {"non-conservative", "conservative"};

/// The semi-implicit formulations (seed 001): what their pressure solve and B-spline quadrature
/// cannot take.
void check_semi_implicit(const Scene& s, std::vector<Problem>& problems) {
  const std::string name = to_string(s.formulation);
  const bool bspline = s.grid.shape_function == ShapeFunction::bspline2 || s.grid.shape_function == ShapeFunction::bspline3;
  // One point per cell and axis under-integrates the B-spline supports (3 or 4 cells wide): B1
  // diverges within 4-9 steps at every cell size, both variants (bench/results/
  // speed-vs-error-b1-*-2026-12-01.md). Two or more points per cell work.
  if (bspline)
    for (std::size_t b = 0; b < s.bodies.size(); ++b)
      if (s.bodies[b].particles_per_cell == 1)
        problems.push_back({"/bodies/" + std::to_string(b) + "/particles_per_cell",
                            "got 1, which is not available with " + to_string(s.grid.shape_function) + " in " + name +
                                " (one point per cell and axis diverges within 10 steps); expected 2 or more, or "
                                "grid.shape_function \"gimp\""});
  // Free water (a body with a fluid and no solid) in semi-implicit-double-point: a scene of free
  // water alone had no soil points to solve on ("particles/solid.vtu: cannot open file"), and a
  // dam break (0.1 x 0.2 m of water on a 2 cm saturated bed, bspline2) followed Martin & Moyce
  // within 5-13 % to T = 1.95, then stopped at t = 0.14 s creating energy (issue 27, item 8). The
  // formulations that model free water are explicit-double-point and mpm-fem.
  if (s.formulation == Formulation::semi_implicit_double_point)
    for (std::size_t b = 0; b < s.bodies.size(); ++b)
      if (s.bodies[b].solid.empty() && !s.bodies[b].fluid.empty())
        problems.push_back({"/bodies/" + std::to_string(b),
                            "body \"" + s.bodies[b].name + "\" is free water (a fluid without a solid), which " + name +
                                " does not model (free water alone fails at solve, a dam break creates energy); "
                                "expected \"explicit-double-point\" or \"mpm-fem\" for free water, or a solid in this body"});
  for (std::size_t i = 0; i < s.boundaries.size(); ++i) {
    const Boundary& b = s.boundaries[i];
    if (b.fluid && *b.fluid == FluidBc::pressure && grid_face_index(b.on) < 0)
      problems.push_back({"/boundaries/" + std::to_string(i) + "/fluid",
                          "a prescribed pore pressure on a named surface (\"" + b.on + "\") is not implemented in " +
                              name + " yet; expected a grid face (x_min ... z_max)"});
  }
}

/// mpm-fem integrates its fluid cell by cell with the grid's B-splines.
void check_mpm_fem(const Scene& s, std::vector<Problem>& problems) {
  if (s.grid.shape_function != ShapeFunction::bspline2 && s.grid.shape_function != ShapeFunction::bspline3)
    problems.push_back({"/grid/shape_function", "got \"" + to_string(s.grid.shape_function) +
                                                    "\"; mpm-fem solves its water on the grid's B-splines: expected "
                                                    "\"bspline2\" (the seed's) or \"bspline3\""});
}

/// The scene field behind a string switch (nullptr for a boolean one).
std::string* string_field(Scene& s, const std::string& path) {
  if (path == "/solver/stabilisation/pressure") return &s.solver.stabilisation.pressure;
  if (path == "/solver/continuity") return &s.solver.continuity;
  if (path == "/solver/drag_integration") return &s.solver.drag_integration;
  if (path == "/solver/escaped_water") return &s.solver.escaped_water;
  if (path == "/solver/drag") return &s.solver.drag;
  return nullptr;
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& x : v) out += (out.empty() ? "" : ", ") + x;
  return out;
}

std::vector<FormulationRow> make_rows() {
  std::vector<FormulationRow> rows;
  // initialisation.materials: the formulations whose set_initialisation swaps the phase's material
  // models in (PhaseMaterials, solver/materials/material.hpp): all of them.
  const std::vector<std::string> phase_materials = {"/initialisation/materials"};
  rows.push_back({.id = Formulation::dry,
                  .name = "dry",
                  .paper = "",
                  .implemented = true,
                  .coupled = false,
                  .water = {},
                  .switches = {},
                  .check = nullptr,
                  .material_keys = {"bulk_modulus"},  // a fluid material in a dry scene is unused, as written
                  .keys = phase_materials,
                  .cost = {.bytes_per_point = 800.0, .bytes_per_node = 60.0, .node_bytes_3d = 1.5, .us_per_point_step = 0.15, .us_per_node_step = 0.002}});
  rows.push_back({.id = Formulation::explicit_single_point,
                  .name = "explicit-single-point",
                  .paper = "seed 000",
                  .implemented = true,
                  .coupled = true,
                  .water = {.pore_fluid_on_solid = true},
                  // The seeds' choices: seed 000 runs strain smoothing with the multi-field variational
                  // pressure (basis not stated; the linear one is the smallest that keeps A5 bounded
                  // with FLIP 0.99, docs/verification.md).
                  .switches = {{"/solver/stabilisation/pressure", kExplicitPressures, "mfvp-linear"},
                               {"/solver/stabilisation/strain_smoothing", {"true", "false"}, "true"},
                               {"/solver/continuity", kContinuity, "non-conservative"}},
                  .check = nullptr,
                  .material_keys = {"bulk_modulus"},
                  .keys = phase_materials,
                  .cost = {.bytes_per_point = 1000.0, .bytes_per_node = 100.0, .node_bytes_3d = 1.5,
                           // 0.357 µs: the saturated GIMP box, 100k particles, one thread, best of 3
                           // (bench/results/explicit-single-point-box-2026-12-02.md)
                           .us_per_point_step = 0.357, .us_per_node_step = 0.002}});
  // Semi-implicit: the node-wise projection with a linear basis (seed 001's eq. 77 is its
  // constant-basis case, which biases free-surface nodes: 3.4 % pressure error and 1e-3 m/s of
  // spurious flow in a hydrostatic layer at rest, where the linear one is exact; docs/verification.md).
  const std::vector<Switch> semi_implicit = {{"/solver/stabilisation/pressure", kSemiImplicitPressures, "mfvp-linear"},
                                             {"/solver/continuity", kContinuity, "conservative"},
                                             {"/solver/drag_integration", {"implicit", "semi-implicit"}, "implicit"}};
  rows.push_back({.id = Formulation::semi_implicit_single_point,
                  .name = "semi-implicit-single-point",
                  .paper = "seed 001",
                  .implemented = true,
                  .coupled = true,
                  .water = {.pore_fluid_on_solid = true},
                  .switches = semi_implicit,
                  .check = check_semi_implicit,
                  .material_keys = {"bulk_modulus"},
                  .keys = phase_materials,
                  .cost = {.bytes_per_point = 900.0, .bytes_per_node = 150.0, .node_bytes_3d = 3.0,
                           // 1.38 µs: the same box, one thread, best of 3, CHOLMOD's factor reused
                           // (bench/results/semi-implicit-box-2026-12-02.md; B4's slope on bspline2:
                           // 0.62, bench/results/bspline-closed-form-2026-12-02.md)
                           .us_per_point_step = 1.38, .us_per_node_step = 0.01}});
  std::vector<Switch> double_point = semi_implicit;
  double_point.push_back({"/solver/escaped_water", {"keep", "remove"}, "keep"});
  double_point.push_back({"/initialisation/tie_water", {"true", "false"}, "true"});
  rows.push_back({.id = Formulation::semi_implicit_double_point,
                  .name = "semi-implicit-double-point",
                  .paper = "seed 001",
                  .implemented = true,
                  .coupled = true,
                  .water = {.fluid_particles = true},
                  .switches = double_point,
                  .check = check_semi_implicit,
                  .material_keys = {"bulk_modulus"},
                  .keys = phase_materials,
                  .cost = {.bytes_per_point = 700.0, .bytes_per_node = 150.0, .node_bytes_3d = 3.0,
                           // 0.89 µs per point (soil and water points of the saturated box, 200k
                           // points, one thread; bench/results/semi-implicit-box-2026-12-02.md)
                           .us_per_point_step = 0.89, .us_per_node_step = 0.01}});
  rows.push_back({.id = Formulation::explicit_double_point,
                  .name = "explicit-double-point",
                  .paper = "seed 003",
                  .implemented = true,
                  .coupled = true,
                  .water = {.fluid_particles = true},
                  .switches = {{"/initialisation/tie_water", {"true", "false"}, "true"},
                               {"/solver/drag", {"darcy", "ergun"}, "ergun"},
                               {"/solver/stabilisation/pressure", {"none", "mfvp-constant", "mfvp-linear"}, "mfvp-linear"}},
                  .check = nullptr,
                  .material_keys = {"bulk_modulus", "grain_diameter", "ergun_a", "ergun_b", "maximum_porosity", "cavitation_threshold"},
                  .keys = phase_materials,
                  .cost = {.bytes_per_point = 700.0, .bytes_per_node = 100.0, .node_bytes_3d = 1.5,
                           // 0.198 µs per point (99 856 solid + 99 856 liquid points, one thread,
                           // best of 3; bench/results/explicit-double-point-box-2026-12-04.md)
                           .us_per_point_step = 0.198, .us_per_node_step = 0.002}});
  rows.push_back({.id = Formulation::mpm_fem,
                  .name = "mpm-fem",
                  .paper = "seed 004",
                  .implemented = true,
                  .coupled = true,
                  .water = {.pore_fluid_on_solid = true, .free_water_on_grid = true},
                  // PSPG on the seed's full momentum residual (default) or on its increment over
                  // the step, which holds water at rest exactly but leaves a steady through-flow a
                  // row-to-row mode (docs/formulations.md, "mpm-fem").
                  // The drag implicit in the fluid's v^{L+1} (default) or the seed's explicit one,
                  // stable only for dt < 2 n rho / (n^2 mu / k): 6e-5 s for 0.1 mm grains.
                  .switches = {{"/solver/stabilisation/pressure", {"pspg", "pspg-increment"}, "pspg"},
                               {"/solver/drag_integration", {"implicit", "explicit"}, "implicit"}},
                  .check = check_mpm_fem,
                  .material_keys = {"grain_diameter", "ergun_a", "ergun_b"},
                  // The air and the phase field of the grid's fluid.
                  .keys = {"/solver/air", "/solver/phase_field", "/solver/soil_substeps", "/initialisation/materials"},
                  .cost = {.bytes_per_point = 900.0, .bytes_per_node = 1500.0, .node_bytes_3d = 5.0, .us_per_point_step = 1.0, .us_per_node_step = 15.0}});
  return rows;
}

}  // namespace

const Switch* FormulationRow::find(const std::string& path) const {
  for (const Switch& w : switches)
    if (w.path == path) return &w;
  return nullptr;
}

bool FormulationRow::reads(const std::string& path) const {
  return std::find(keys.begin(), keys.end(), path) != keys.end();
}

const std::vector<FormulationRow>& formulation_rows() {
  static const std::vector<FormulationRow> rows = make_rows();
  return rows;
}

const FormulationRow& row_of(Formulation f) {
  for (const FormulationRow& r : formulation_rows())
    if (r.id == f) return r;
  throw std::logic_error("formulation \"" + to_string(f) + "\" has no row (\"auto\" is resolved by the parser)");
}

std::vector<std::string> formulation_switch_paths() {
  std::vector<std::string> paths;
  for (const FormulationRow& r : formulation_rows())
    for (const Switch& w : r.switches)
      if (std::find(paths.begin(), paths.end(), w.path) == paths.end()) paths.push_back(w.path);
  return paths;
}

std::string implemented_formulations() {
  std::string out;
  for (const FormulationRow& r : formulation_rows())
    if (r.implemented) out += (out.empty() ? "" : ", ") + r.name;
  return out;
}

std::vector<Problem> check_formulation(const nlohmann::json& raw, const Scene& s) {
  std::vector<Problem> problems;
  const FormulationRow& row = row_of(s.formulation);
  for (const std::string& path : formulation_switch_paths()) {
    const nlohmann::json::json_pointer ptr(path);
    if (!raw.contains(ptr)) continue;
    const nlohmann::json& v = raw.at(ptr);
    if (!v.is_string() && !v.is_boolean()) continue;  // a type error, which the schema reports
    const std::string value = v.is_string() ? v.get<std::string>() : (v.get<bool>() ? "true" : "false");
    const Switch* w = row.find(path);
    if (!w) {
      std::vector<std::string> readers;
      for (const FormulationRow& r : formulation_rows())
        if (r.find(path)) readers.push_back(r.name);
      problems.push_back({path, "got " + v.dump() + ", but " + row.name + " does not read this switch (read by " +
                                    join(readers) + "); remove the key"});
    } else if (std::find(w->values.begin(), w->values.end(), value) == w->values.end()) {
      problems.push_back({path, "got " + v.dump() + ", which " + row.name + " does not have; expected one of " +
                                    join(w->values)});
    }
  }
  // Keys that only some formulations read (the tables list them for all).
  std::vector<std::string> key_paths;
  for (const FormulationRow& r : formulation_rows())
    for (const std::string& path : r.keys)
      if (std::find(key_paths.begin(), key_paths.end(), path) == key_paths.end()) key_paths.push_back(path);
  for (const std::string& path : key_paths) {
    if (row.reads(path) || !raw.contains(nlohmann::json::json_pointer(path))) continue;
    std::vector<std::string> readers;
    for (const FormulationRow& r : formulation_rows())
      if (r.reads(path)) readers.push_back(r.name);
    problems.push_back({path, "got a value, but " + row.name + " does not read this key (read by " + join(readers) +
                                  "); remove the key"});
  }
  // Material keys that only some formulations read (the material tables list them for all).
  if (raw.contains("materials") && raw["materials"].is_array())
    for (std::size_t i = 0; i < raw["materials"].size(); ++i) {
      const nlohmann::json& m = raw["materials"][i];
      if (!m.is_object()) continue;
      for (const FormulationRow& r : formulation_rows())
        for (const std::string& key : r.material_keys) {
          if (!m.contains(key) || std::find(row.material_keys.begin(), row.material_keys.end(), key) != row.material_keys.end())
            continue;
          const std::string path = "/materials/" + std::to_string(i) + "/" + key;
          if (std::any_of(problems.begin(), problems.end(), [&](const Problem& p) { return p.path == path; })) continue;
          std::vector<std::string> readers;
          for (const FormulationRow& q : formulation_rows())
            if (std::find(q.material_keys.begin(), q.material_keys.end(), key) != q.material_keys.end())
              readers.push_back(q.name);
          problems.push_back({path, "got " + m[key].dump() + ", but " + row.name +
                                        " does not read this material key (read by " + join(readers) + "); remove the key"});
        }
    }
  // The fluid's bulk modulus: required where a formulation reads it (weakly compressible water).
  const bool reads_K = std::find(row.material_keys.begin(), row.material_keys.end(), "bulk_modulus") != row.material_keys.end();
  if (reads_K && raw.contains("materials") && raw["materials"].is_array())
    for (std::size_t i = 0; i < raw["materials"].size(); ++i) {
      const nlohmann::json& m = raw["materials"][i];
      // (a model that is not a string is the parser's error; value("model", "") would throw on it)
      const bool fluid = m.is_object() && m.contains("model") && m["model"] == "fluid";
      if (fluid && !m.contains("bulk_modulus"))
        problems.push_back({"/materials/" + std::to_string(i) + "/bulk_modulus",
                            "missing required key, expected a positive number [Pa] (" + row.name +
                                " models the water as weakly compressible)"});
    }
  if (row.check) row.check(s, problems);
  return problems;
}

void apply_formulation_defaults(Scene& s) {
  const FormulationRow& row = row_of(s.formulation);
  for (const Switch& w : row.switches)
    if (std::string* f = string_field(s, w.path); f && f->empty()) *f = w.def;
  if (s.solver.stabilisation.pressure.empty()) s.solver.stabilisation.pressure = "none";
  if (s.solver.continuity.empty()) s.solver.continuity = "non-conservative";
}

}  // namespace swmpm::scene
