// Scene parsing and validation (scene/parse.cpp, validate.cpp, keys.cpp): typed values and
// defaults of valid scenes, the to_json round trip, one test per class of user error (each
// asserting the JSON path and a key phrase of the message), and the agreement of
// docs/scene-format.md with the schema tables.
// Pure parsing: no files except the load_scene tests and the docs check.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <cmath>
#include <limits>

#include "scene/input.hpp"
#include "scene/scene.hpp"
#include "support/mpm_fem_scene.hpp"
#include "support/pond_scene.hpp"

namespace {

using nlohmann::json;
using namespace swmpm::scene;

/// A valid coupled 2D scene (the interface's Terzaghi example, plus a polygon body).
json scene_2d() {
  return json::parse(R"json({
    "name": "terzaghi-1d",
    "dimension": 2,
    "formulation": "explicit-single-point",
    "gravity": [0.0, -9.81],
    "grid": { "cell_size": 0.05, "min": [0.0, 0.0], "max": [0.1, 1.2], "shape_function": "gimp" },
    "materials": [
      { "name": "sand", "model": "linear-elastic", "grain_density": 2650.0, "youngs_modulus": 1.0e7,
        "poisson_ratio": 0.0, "porosity": 0.3, "hydraulic_conductivity": 1.0e-3 },
      { "name": "water", "model": "fluid", "density": 1000.0, "bulk_modulus": 2.2e9 }
    ],
    "bodies": [
      { "name": "column", "geometry": { "type": "box", "min": [0.0, 0.0], "max": [0.1, 1.0] },
        "solid": "sand", "fluid": "water", "particles_per_cell": 2,
        "initial": { "pore_pressure": 1.0e4, "velocity": [0, "0.1*sin(pi*y)"] } },
      { "name": "wedge", "geometry": { "type": "polygon", "vertices": [[0, 1.0], [0.1, 1.0], [0.05, 1.1]] },
        "solid": "sand", "fluid": "water" }
    ],
    "boundaries": [
      { "on": "x_min", "solid": "roller", "fluid": "impermeable" },
      { "on": "x_max", "solid": "friction", "coefficient": 0.3 },
      { "on": "y_min", "solid": "fixed",  "fluid": "pressure", "value": 5.0 }
    ],
    "loads": [ { "type": "traction", "body": "column", "face": "y_max", "value": [0.0, -1.0e4],
                 "table": [[0, 0], [1, 1]] } ],
    "time": { "end": 2.0, "dt": 1.0e-5 },
    "output": {
      "interval": 0.1,
      "monitors": [ { "name": "base", "at": [0.05, 0.0125], "phase": "fluid", "quantities": ["pore_pressure"] } ]
    }
  })json");
}

/// A valid dry 3D scene with defaults left out.
json scene_3d() {
  return json::parse(R"json({
    "name": "block.3d",
    "dimension": 3,
    "grid": { "cell_size": 0.1, "min": [0, 0, 0], "max": [1, 1, 0.95] },
    "materials": [
      { "name": "clay", "model": "mohr-coulomb", "density": 1800, "youngs_modulus": 5e6,
        "poisson_ratio": 0.3, "friction_angle": 25 }
    ],
    "bodies": [
      { "name": "block", "solid": "clay",
        "geometry": { "type": "box", "min": [0.2, 0.2, 0], "max": [0.8, 0.8, 0.5] },
        "initial": { "stress": "geostatic", "k0": 0.6 } }
    ],
    "boundaries": [ { "on": "z_min", "solid": "fixed" } ],
    "loads": [ { "type": "pressure", "body": "block", "face": "z_max", "value": 2e4,
                 "region": { "min": [0.3, 0.3, 0.4], "max": [0.7, 0.7, 0.5] },
                 "function": "1 - cos(2*pi*t)", "ramp": 0.1 } ],
    "time": { "end": 1.0 },
    "output": { "monitors": [ { "name": "energy", "quantities": ["kinetic_energy", "strain_energy"] },
                              { "name": "top", "particle": 12, "quantities": ["velocity_z", "stress_yz"] } ] },
    "solver": { "stabilisation": { "fbar": "modified" } }
  })json");
}

/// The problem lines of parsing `j` (empty when it parses).
std::vector<std::string> problems(const json& j) {
  try {
    parse_scene(j, "t.json");
  } catch (const SceneError& e) {
    return e.lines();
  }
  return {};
}

std::string dump_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += "\n  " + l;
  return out.empty() ? "\n  (no problems)" : out;
}

/// A line "t.json: <path>: ..." containing `phrase` is among the problems of `j`.
::testing::AssertionResult reports(const json& j, const std::string& path, const std::string& phrase) {
  const auto lines = problems(j);
  const std::string prefix = "t.json: " + path + ": ";
  for (const auto& l : lines) {
    if (l.rfind(prefix, 0) == 0 && l.find(phrase) != std::string::npos) {
      return ::testing::AssertionSuccess();
    }
  }
  return ::testing::AssertionFailure() << "no line \"" << prefix << "...\" containing \"" << phrase
                                       << "\"; got:" << dump_lines(lines);
}

// ---- valid scenes -------------------------------------------------------------------------------

TEST(Scene, Valid2DParsesToTypedValues) {
  const Scene s = parse_scene(scene_2d(), "t.json");
  EXPECT_EQ(s.name, "terzaghi-1d");
  EXPECT_EQ(s.dimension, 2);
  EXPECT_EQ(s.formulation, Formulation::explicit_single_point);
  EXPECT_DOUBLE_EQ(s.gravity[1], -9.81);
  EXPECT_DOUBLE_EQ(s.gravity[2], 0.0);
  EXPECT_DOUBLE_EQ(s.grid.cell_size, 0.05);
  EXPECT_DOUBLE_EQ(s.grid.max[1], 1.2);  // 24 whole cells: not moved
  EXPECT_EQ(s.grid.shape_function, ShapeFunction::gimp);

  ASSERT_EQ(s.materials.size(), 2u);
  const Material& sand = s.material("sand");
  EXPECT_EQ(sand.model, MaterialModel::linear_elastic);
  EXPECT_DOUBLE_EQ(sand.at("youngs_modulus"), 1.0e7);
  EXPECT_DOUBLE_EQ(sand.at("porosity"), 0.3);
  EXPECT_EQ(sand.permeability_law, "constant");
  EXPECT_FALSE(sand.has("density"));
  EXPECT_DOUBLE_EQ(sand.solid_bulk_density(), 0.7 * 2650.0);
  const Material& water = s.material("water");
  EXPECT_EQ(water.model, MaterialModel::fluid);
  EXPECT_DOUBLE_EQ(water.at("dynamic_viscosity"), 1.0e-3);  // default filled in
  EXPECT_EQ(s.material_index("water"), 1);
  EXPECT_EQ(s.material_index("nothing"), -1);

  ASSERT_EQ(s.bodies.size(), 2u);
  const Body& col = s.bodies[0];
  EXPECT_EQ(col.geometry.type, "box");
  EXPECT_DOUBLE_EQ(col.geometry.max[1], 1.0);
  EXPECT_EQ(col.geometry.raw["type"], "box");
  EXPECT_EQ(col.solid, "sand");
  EXPECT_EQ(col.fluid, "water");
  ASSERT_TRUE(col.initial.pore_pressure.has_value());
  EXPECT_DOUBLE_EQ(*col.initial.pore_pressure, 1.0e4);
  EXPECT_FALSE(col.initial.hydrostatic);
  EXPECT_EQ(col.initial.velocity[0], "0");
  EXPECT_EQ(col.initial.velocity[1], "0.1*sin(pi*y)");
  EXPECT_EQ(col.initial.velocity[2], "0");
  const Body& wedge = s.bodies[1];
  EXPECT_EQ(wedge.geometry.type, "polygon");
  ASSERT_EQ(wedge.geometry.vertices.size(), 3u);
  EXPECT_DOUBLE_EQ(wedge.geometry.vertices[2][1], 1.1);
  EXPECT_EQ(wedge.particles_per_cell, 2);  // default

  ASSERT_EQ(s.boundaries.size(), 3u);
  EXPECT_EQ(s.boundaries[0].solid, SolidBc::roller);
  EXPECT_EQ(s.boundaries[0].fluid, FluidBc::impermeable);
  EXPECT_EQ(s.boundaries[1].solid, SolidBc::friction);
  EXPECT_DOUBLE_EQ(s.boundaries[1].coefficient, 0.3);
  EXPECT_FALSE(s.boundaries[1].fluid.has_value());
  EXPECT_EQ(s.boundaries[2].fluid, FluidBc::pressure);
  EXPECT_DOUBLE_EQ(s.boundaries[2].fluid_value, 5.0);

  ASSERT_EQ(s.loads.size(), 1u);
  EXPECT_EQ(s.loads[0].type, "traction");
  EXPECT_DOUBLE_EQ(s.loads[0].value[1], -1.0e4);
  ASSERT_EQ(s.loads[0].function.table.size(), 2u);
  EXPECT_DOUBLE_EQ(s.loads[0].function.ramp, 0.0);

  EXPECT_DOUBLE_EQ(s.time.end, 2.0);
  ASSERT_TRUE(s.time.dt.has_value());
  EXPECT_DOUBLE_EQ(*s.time.dt, 1.0e-5);
  EXPECT_DOUBLE_EQ(s.time.cfl, 0.5);
  EXPECT_DOUBLE_EQ(s.output.interval, 0.1);
  EXPECT_DOUBLE_EQ(s.output.monitor_interval, 0.0);
  ASSERT_EQ(s.output.monitors.size(), 1u);
  EXPECT_EQ(s.output.monitors[0].phase, "fluid");
  ASSERT_TRUE(s.output.monitors[0].at.has_value());
  EXPECT_DOUBLE_EQ((*s.output.monitors[0].at)[1], 0.0125);

  EXPECT_DOUBLE_EQ(s.solver.flip, 0.99);
  EXPECT_DOUBLE_EQ(s.solver.damping, 0.0);
  EXPECT_EQ(s.solver.kinematics, "finite-strain");
  EXPECT_EQ(s.solver.checkpoint_every, 50);
  EXPECT_TRUE(s.solver.stabilisation.strain_smoothing);
  EXPECT_EQ(s.solver.stabilisation.pressure, "mfvp-linear");  // the explicit-single-point default
  EXPECT_TRUE(s.has_fluid());
  EXPECT_EQ(s.source_file, "t.json");
}

TEST(Scene, Valid3DParsesWithDefaults) {
  const Scene s = parse_scene(scene_3d(), "t.json");
  EXPECT_EQ(s.dimension, 3);
  EXPECT_EQ(s.formulation, Formulation::dry);  // "auto" without a fluid
  EXPECT_NE(s.formulation_reason.find("no body has a fluid"), std::string::npos);
  EXPECT_FALSE(s.has_fluid());
  EXPECT_EQ(s.gravity, (Vec3{0, 0, 0}));
  EXPECT_DOUBLE_EQ(s.grid.max[2], 1.0);  // 9.5 cells rounded up to 10
  EXPECT_DOUBLE_EQ(s.grid.max[0], 1.0);

  const Material& clay = s.material("clay");
  EXPECT_EQ(clay.model, MaterialModel::mohr_coulomb);
  EXPECT_DOUBLE_EQ(clay.at("cohesion"), 0.0);
  EXPECT_DOUBLE_EQ(clay.at("dilation_angle"), 0.0);
  EXPECT_DOUBLE_EQ(clay.at("strength_reduction_factor"), 1.0);
  EXPECT_DOUBLE_EQ(clay.at("tension_cutoff"), 0.0);
  EXPECT_DOUBLE_EQ(clay.solid_bulk_density(), 1800.0);
  EXPECT_THROW((void)clay.at("shear_modulus"), std::out_of_range);
  EXPECT_THROW((void)s.material("sand"), std::out_of_range);

  const Body& b = s.bodies[0];
  EXPECT_TRUE(b.initial.geostatic);
  EXPECT_DOUBLE_EQ(b.initial.k0, 0.6);
  EXPECT_DOUBLE_EQ(b.geometry.max[2], 0.5);

  const Load& l = s.loads[0];
  EXPECT_EQ(l.type, "pressure");
  EXPECT_DOUBLE_EQ(l.value[0], 2e4);
  ASSERT_TRUE(l.region.has_value());
  EXPECT_DOUBLE_EQ(l.region->first[2], 0.4);
  EXPECT_EQ(l.function.expression, "1 - cos(2*pi*t)");
  EXPECT_DOUBLE_EQ(l.function.ramp, 0.1);

  EXPECT_FALSE(s.time.dt.has_value());  // "auto"
  ASSERT_EQ(s.output.monitors.size(), 2u);
  EXPECT_FALSE(s.output.monitors[0].at.has_value());
  EXPECT_EQ(s.output.monitors[1].particle, 12);
  EXPECT_EQ(s.solver.stabilisation.fbar, "modified");
}

// Its fixed dt (1e-5 s) is below both single-point limits: the same steps, so the cheaper step
// (tests/unit/test_auto_formulation.cpp has the rest of "auto").
TEST(Scene, AutoFormulationWithFluidPicksExplicitSinglePoint) {
  json j = scene_2d();
  j["formulation"] = "auto";
  const Scene s = parse_scene(j, "t.json");
  EXPECT_EQ(s.formulation, Formulation::explicit_single_point);
  EXPECT_NE(s.formulation_reason.find("column"), std::string::npos);
}

TEST(Scene, ToJsonRoundTripReproducesTheScene) {
  for (const json& j : {scene_2d(), scene_3d()}) {
    const Scene s = parse_scene(j, "t.json");
    const json resolved = to_json(s);
    const Scene r = parse_scene(resolved, "t.json");
    EXPECT_EQ(to_json(r), resolved);
    // and some typed values directly
    EXPECT_EQ(r.formulation, s.formulation);
    EXPECT_EQ(r.grid.max, s.grid.max);
    ASSERT_EQ(r.materials.size(), s.materials.size());
    for (std::size_t i = 0; i < s.materials.size(); ++i) EXPECT_EQ(r.materials[i].params, s.materials[i].params);
    EXPECT_EQ(r.bodies[0].initial.velocity, s.bodies[0].initial.velocity);
    EXPECT_EQ(r.bodies[0].initial.k0, s.bodies[0].initial.k0);
    EXPECT_EQ(r.loads[0].function.table, s.loads[0].function.table);
    EXPECT_EQ(r.output.monitors[0].quantities, s.output.monitors[0].quantities);
    EXPECT_EQ(r.time.dt, s.time.dt);
  }
  // Every default is written out.
  const json resolved = to_json(parse_scene(scene_3d(), "t.json"));
  EXPECT_EQ(resolved["solver"]["flip"], 0.99);
  EXPECT_EQ(resolved["time"]["dt"], "auto");
  EXPECT_EQ(resolved["materials"][0]["cohesion"], 0.0);
  EXPECT_EQ(resolved["bodies"][0]["particles_per_cell"], 2);
  EXPECT_EQ(resolved["formulation"], "dry");
}

TEST(Scene, NumericVelocityIsStoredAsAFullPrecisionString) {
  json j = scene_2d();
  j["bodies"][0]["initial"]["velocity"] = {0.1, -2};
  const Scene s = parse_scene(j, "t.json");
  EXPECT_EQ(std::stod(s.bodies[0].initial.velocity[0]), 0.1);
  EXPECT_EQ(s.bodies[0].initial.velocity[1], "-2");
}

TEST(Scene, ToStringGivesTheUserStrings) {
  EXPECT_EQ(to_string(Formulation::semi_implicit_double_point), "semi-implicit-double-point");
  EXPECT_EQ(to_string(Formulation::mpm_fem), "mpm-fem");
  EXPECT_EQ(to_string(Formulation::automatic), "auto");
  EXPECT_EQ(to_string(ShapeFunction::bspline3), "bspline3");
  EXPECT_EQ(to_string(MaterialModel::nor_sand), "nor-sand");
  EXPECT_EQ(to_string(MaterialModel::drucker_prager), "drucker-prager");
}

// ---- files ----------------------------------------------------------------------------------------

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(SceneFile, LoadsAValidFile) {
  const std::string path = write_temp("swmpm_valid_scene.json", scene_2d().dump(2));
  const Scene s = load_scene(path);
  EXPECT_EQ(s.name, "terzaghi-1d");
  EXPECT_EQ(s.source_file, path);
}

TEST(SceneFile, UnreadableFileNamesTheFile) {
  try {
    load_scene("/nonexistent/dir/scene.json");
    FAIL() << "no error";
  } catch (const SceneError& e) {
    ASSERT_EQ(e.lines().size(), 1u);
    EXPECT_NE(e.lines()[0].find("/nonexistent/dir/scene.json: cannot read"), std::string::npos);
  }
}

TEST(SceneFile, SyntaxErrorNamesFileLineAndColumn) {
  const std::string path = write_temp("swmpm_bad_syntax.json", "{\n  \"name\": \"x\",\n  \"dimension\": 2,,\n}\n");
  try {
    load_scene(path);
    FAIL() << "no error";
  } catch (const SceneError& e) {
    ASSERT_EQ(e.lines().size(), 1u);
    const std::string& l = e.lines()[0];
    EXPECT_EQ(l.rfind(path + ": invalid JSON at line 3, column 18", 0), 0u) << l;
    EXPECT_NE(l.find("byte"), std::string::npos) << l;
  }
}

TEST(SceneFile, DuplicateKeysAreReportedWithTheirPath) {
  const std::string path = write_temp("swmpm_duplicate_key.json", R"json({
    "name": "dup", "dimension": 2,
    "grid": { "cell_size": 0.1, "min": [0, 0], "max": [1, 1] },
    "materials": [ { "name": "a", "model": "linear-elastic", "density": 1, "youngs_modulus": 1,
                     "poisson_ratio": 0.2 },
                   { "name": "b", "model": "linear-elastic", "density": 1, "youngs_modulus": 1,
                     "poisson_ratio": 0.2, "poisson_ratio": 0.3 } ],
    "bodies": [ { "name": "x", "solid": "c", "geometry": { "type": "box", "min": [0, 0], "max": [1, 1] } } ],
    "time": { "end": 1 }
  })json");
  try {
    load_scene(path);
    FAIL() << "no error";
  } catch (const SceneError& e) {
    const auto& lines = e.lines();
    ASSERT_EQ(lines.size(), 2u) << dump_lines(lines);
    EXPECT_EQ(lines[0], path + ": /materials/1/poisson_ratio: got key \"poisson_ratio\" twice in one object, "
                               "expected each key once");
    EXPECT_NE(lines[1].find(": /bodies/0/solid: got \"c\""), std::string::npos) << lines[1];
  }
}

// ---- parser robustness (issue 27, item 6) -----------------------------------------------------

namespace {

/// The lines of the SceneError load_scene throws for `text` written to `name` (none: no error).
std::vector<std::string> load_errors(const std::string& name, const std::string& text, std::string* path = nullptr) {
  const std::string file = write_temp(name, text);
  if (path) *path = file;
  try {
    load_scene(file);
  } catch (const SceneError& e) {
    return e.lines();
  }
  return {};
}

/// "line L, column C" of byte `at` of `text` (1-based line and column).
std::string line_column(const std::string& text, std::size_t at) {
  const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<long>(at), '\n'));
  const std::size_t start = text.rfind('\n', at == 0 ? 0 : at - 1);
  const std::size_t column = start == std::string::npos || at == 0 ? at + 1 : at - start;
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

}  // namespace

// 65,000 levels of arrays or objects at a known key crashed with SIGSEGV (recursion on the value
// while the message was built). Nesting is limited to 64 levels while the text is read.
TEST(SceneFile, DeepNestingIsRefusedWithTheFileAndThePath) {
  const std::string arrays = std::string(65000, '[') + std::string(65000, ']');
  std::string objects;
  for (int i = 0; i < 65000; ++i) objects += "{\"a\": ";
  objects += "1" + std::string(65000, '}');
  for (const auto& [deep, pointer] : {std::pair{arrays, std::string("/solver/0/0/0")}, std::pair{objects, std::string("/solver/a/a/a")}}) {
    std::string text = scene_2d().dump(2);
    text.insert(1, "\"solver\": " + deep + ",");
    std::string path;
    const auto lines = load_errors("swmpm_deep.json", text, &path);
    ASSERT_EQ(lines.size(), 1u) << dump_lines(lines);
    EXPECT_EQ(lines[0].rfind(path + ": " + pointer, 0), 0u) << lines[0].substr(0, 300);
    EXPECT_NE(lines[0].find(": got arrays and objects nested deeper than 64 levels, expected at most 64 (line 1, column "),
              std::string::npos) << lines[0].substr(0, 300);
    EXPECT_LT(lines[0].size(), 600u);
  }
  // The limit itself: 64 levels are read, 65 are not.
  EXPECT_NO_THROW(parse_json(std::string(64, '[') + std::string(64, ']'), "x.json"));
  EXPECT_THROW(parse_json(std::string(65, '[') + std::string(65, ']'), "x.json"), InputError);
}

// 1e400 gave nlohmann's raw exception text; now the file, the JSON path, the line and the column.
TEST(SceneFile, NumberOutOfRangeNamesThePath) {
  std::string text = scene_2d().dump(2);
  const std::size_t key = text.find("\"cell_size\": 0.05");
  ASSERT_NE(key, std::string::npos);
  const std::size_t at = key + 13;
  text.replace(at, 4, "1e400");
  std::string path;
  auto lines = load_errors("swmpm_1e400.json", text, &path);
  ASSERT_EQ(lines.size(), 1u) << dump_lines(lines);
  EXPECT_EQ(lines[0], path + ": /grid/cell_size: got 1e400, which is out of the range of a double; expected a finite "
                             "number (" + line_column(text, at) + ")");
  // In an array: the element's index.
  text = scene_2d().dump();
  const std::size_t g = text.find("-9.81");
  ASSERT_NE(g, std::string::npos);
  text.replace(g, 5, "-1e999");
  lines = load_errors("swmpm_1e999.json", text, &path);
  ASSERT_EQ(lines.size(), 1u) << dump_lines(lines);
  EXPECT_EQ(lines[0], path + ": /gravity/1: got -1e999, which is out of the range of a double; expected a finite number (" +
                          line_column(text, g) + ")");
}

// Other syntax errors keep the file and a line:column, and say inside which value they are.
TEST(SceneFile, TruncatedFileAndTrailingCommaGiveLineAndColumn) {
  std::string text = scene_2d().dump(2);
  const std::size_t comma = text.find("-9.81") + 5;
  text.insert(comma, ",");
  std::string path;
  auto lines = load_errors("swmpm_trailing_comma.json", text, &path);
  ASSERT_EQ(lines.size(), 1u) << dump_lines(lines);
  // The error is at the first character after the comma that cannot start a value: the ']'.
  const std::size_t bracket = text.find(']', comma);
  EXPECT_EQ(lines[0].rfind(path + ": invalid JSON at " + line_column(text, bracket) + " (byte " +
                               std::to_string(bracket + 1) + ") in /gravity: syntax error",
                           0),
            0u)
      << lines[0];

  const std::string whole = scene_2d().dump(2);
  const std::string cut = whole.substr(0, whole.find("\"materials\"") + 20);
  lines = load_errors("swmpm_truncated.json", cut, &path);
  ASSERT_EQ(lines.size(), 1u) << dump_lines(lines);
  EXPECT_EQ(lines[0].rfind(path + ": invalid JSON at " + line_column(cut, cut.size()), 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find("unexpected end of input"), std::string::npos) << lines[0];
}

// "Did you mean" compared a 200 kB value with every name in O(n m) time and memory (10 s, 3.2 GB);
// messages echoed the whole value. Now bounded: quick, and each line short.
TEST(SceneErrors, LongStringsAreQuickAndShortInMessages) {
  json j = scene_2d();
  const std::string long_key(1'000'000, 'k'), long_value(1'000'000, 'g');
  j["grid"][long_key] = 1;
  j["grid"]["shape_function"] = long_value;
  j["bodies"][0]["solid"] = long_value;
  j["loads"][0]["body"] = long_value;
  const auto start = std::chrono::steady_clock::now();
  const auto lines = problems(j);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_LT(seconds, 1.0);
  ASSERT_GE(lines.size(), 4u) << dump_lines(lines);
  for (const auto& l : lines) EXPECT_LT(l.size(), 600u) << l.substr(0, 600);
  EXPECT_TRUE(reports(j, "/grid/" + long_key.substr(0, 60) + "… (1000000 characters)",
                      "unknown key \"" + long_key.substr(0, 60) + "… (1000000 characters)\", expected one of: "));
  EXPECT_TRUE(reports(j, "/grid/shape_function",
                      "got \"" + long_value.substr(0, 60) + "… (1000000 characters)\", expected one of: linear"));
  EXPECT_TRUE(reports(j, "/bodies/0/solid", "got \"" + long_value.substr(0, 60) + "… (1000000 characters)\""));
  EXPECT_TRUE(reports(j, "/loads/0/body", "got \"" + long_value.substr(0, 60) + "… (1000000 characters)\""));
  // Suggestions still work for ordinary typos.
  json k = scene_2d();
  k["grid"]["shape_function"] = "gimpp";
  EXPECT_TRUE(reports(k, "/grid/shape_function", "(did you mean \"gimp\"?)"));
  k["grid"]["cel_size"] = 0.1;
  EXPECT_TRUE(reports(k, "/grid/cel_size", "did you mean \"cell_size\"?"));
}

// An expression that is inf or NaN passed validation and the run diverged at step 1 ("J <= 0").
// Initial velocities are evaluated at the corners and the centre of the body's bounds, load
// functions at nine times from 0 to time.end.
TEST(SceneErrors, ExpressionsMustHaveFiniteValues) {
  json j = scene_2d();
  j["bodies"][0]["initial"]["velocity"] = {"1/x", "sqrt(y - 0.5)"};
  EXPECT_TRUE(reports(j, "/bodies/0/initial/velocity/0",
                      "got \"1/x\", which is inf at (x, y) = (0, 0) m; expected an expression with a finite value over "
                      "the body (evaluated at the corners and the centre of its bounds [0, 0]..[0.1, 1] m) [m/s]"));
  EXPECT_TRUE(reports(j, "/bodies/0/initial/velocity/1", "got \"sqrt(y - 0.5)\", which is nan at (x, y) = (0, 0) m"));
  for (const char* f : {"1/0", "exp(1e6)", "sqrt(t - 1)", "1/(t - 2)"}) {
    json k = scene_2d();
    k["loads"][0].erase("table");
    k["loads"][0]["function"] = f;
    EXPECT_TRUE(reports(k, "/loads/0/function", std::string("got \"") + f + "\", which is ")) << f << dump_lines(problems(k));
    EXPECT_TRUE(reports(k, "/loads/0/function", "; expected an expression with a finite value over the run (evaluated "
                                                "at 9 times from 0 to 2 s)"))
        << f;
  }
  json k = scene_2d();
  k["loads"][0].erase("table");
  k["loads"][0]["function"] = "1/(t + 1)";
  k["bodies"][0]["initial"]["velocity"] = {"y > 0.5 ? 1 : -1", "exp(-x)"};
  EXPECT_TRUE(problems(k).empty()) << dump_lines(problems(k));
}

// ---- one test per class of error -------------------------------------------------------------

TEST(SceneErrors, MessageHasTheDocumentedForm) {
  json j = scene_2d();
  j["materials"][0]["poisson_ratio"] = 0.7;
  const auto lines = problems(j);
  ASSERT_EQ(lines.size(), 1u) << dump_lines(lines);
  EXPECT_EQ(lines[0], "t.json: /materials/0/poisson_ratio: got 0.7, expected a number in [-1, 0.5) [-]");
}

TEST(SceneErrors, UnknownKeySuggestsTheClosestKey) {
  json j = scene_2d();
  j["materials"][0]["youngs_modulu"] = j["materials"][0]["youngs_modulus"];
  j["materials"][0].erase("youngs_modulus");
  EXPECT_TRUE(reports(j, "/materials/0/youngs_modulu",
                      "unknown key \"youngs_modulu\", did you mean \"youngs_modulus\"?"));
  json k = scene_2d();
  k["grid"]["zzzzzzzz"] = 1;
  EXPECT_TRUE(reports(k, "/grid/zzzzzzzz", "unknown key \"zzzzzzzz\", expected one of: cell_size, min"));
  EXPECT_FALSE(reports(k, "/grid/zzzzzzzz", "did you mean"));
  json m = scene_2d();
  m["timee"] = m["time"];
  EXPECT_TRUE(reports(m, "/timee", "did you mean \"time\"?"));
  json n = scene_3d();  // a parameter of another model is unknown for this one
  n["materials"][0]["model"] = "nor-sand";
  EXPECT_TRUE(reports(n, "/materials/0/youngs_modulus", "unknown key \"youngs_modulus\""));
  EXPECT_TRUE(reports(n, "/materials/0/shear_modulus", "missing required key"));
}

TEST(SceneErrors, WrongTypes) {
  json j = scene_2d();
  j["grid"]["cell_size"] = "0.05";
  EXPECT_TRUE(reports(j, "/grid/cell_size", "got \"0.05\", expected a positive number [m]"));
  json k = scene_2d();
  k["gravity"] = {0, -9.81, 0};
  EXPECT_TRUE(reports(k, "/gravity", "(3 components), expected a vector of 2 numbers (one per dimension) [m/s^2]"));
  json l = scene_3d();
  l["bodies"][0]["geometry"]["min"] = {0.2, 0.2};
  EXPECT_TRUE(reports(l, "/bodies/0/geometry/min", "expected a vector of 3 numbers"));
  json m = scene_2d();
  m["materials"] = json::object();
  EXPECT_TRUE(reports(m, "/materials", "expected a non-empty array of objects"));
  json n = scene_3d();
  n["solver"]["stabilisation"]["strain_smoothing"] = "yes";
  EXPECT_TRUE(reports(n, "/solver/stabilisation/strain_smoothing", "expected true or false"));
  json o = scene_3d();
  o["bodies"][0]["particles_per_cell"] = 2.5;
  EXPECT_TRUE(reports(o, "/bodies/0/particles_per_cell", "expected an integer in 1..32"));
  json p = scene_2d();
  p["loads"][0]["value"] = 5.0;  // a traction needs a vector
  EXPECT_TRUE(reports(p, "/loads/0/value", "for a traction [Pa]"));
  json q = scene_3d();
  q["loads"][0]["value"] = {1, 2, 3};  // a pressure is a number
  EXPECT_TRUE(reports(q, "/loads/0/value", "expected a number for a pressure [Pa]"));
}

TEST(SceneErrors, OutOfRangeValues) {
  struct Case {
    const char* pointer;
    json value;
    const char* path;
    const char* phrase;
  };
  const std::vector<Case> cases{
      {"/grid/cell_size", -0.1, "/grid/cell_size", "got -0.1, expected a positive number [m]"},
      {"/materials/0/poisson_ratio", 0.5, "/materials/0/poisson_ratio", "[-1, 0.5) [-]"},
      {"/materials/0/porosity", 1.0, "/materials/0/porosity", "expected a number in (0, 1) [-]"},
      {"/materials/0/porosity", 0, "/materials/0/porosity", "in (0, 1)"},
      {"/solver/flip", 1.5, "/solver/flip", "expected a number in [0, 1] [-]"},
      {"/bodies/0/particles_per_cell", 33, "/bodies/0/particles_per_cell", "an integer in 1..32"},
      {"/bodies/0/particles_per_cell", 0, "/bodies/0/particles_per_cell", "an integer in 1..32"},
      {"/time/dt", 0.0, "/time/dt", "expected a positive number or \"auto\" [s]"},
      {"/time/end", 0.0, "/time/end", "expected a positive number [s]"},
      {"/time/cfl", 0.0, "/time/cfl", "in (0, 1]"},
      {"/dimension", 4, "/dimension", "got 4, expected 2 or 3"},
      {"/gravity_ramp", -1, "/gravity_ramp", "non-negative"},
      {"/solver/damping", 1.0, "/solver/damping", "[0, 1)"},
      {"/solver/checkpoint_every", 0, "/solver/checkpoint_every", "an integer >= 1"},
  };
  for (const Case& c : cases) {
    json j = scene_2d();
    j["solver"] = json::object();
    j[json::json_pointer(c.pointer)] = c.value;
    EXPECT_TRUE(reports(j, c.path, c.phrase)) << c.pointer;
  }
  json j = scene_3d();
  j["materials"][0]["friction_angle"] = 90;
  EXPECT_TRUE(reports(j, "/materials/0/friction_angle", "[0, 90) [deg]"));
  json k = scene_3d();
  k["bodies"][0]["initial"]["k0"] = 11;
  EXPECT_TRUE(reports(k, "/bodies/0/initial/k0", "[0, 10]"));
}

TEST(SceneErrors, UnknownEnumerationValuesListTheValidOnes) {
  json j = scene_2d();
  j["formulation"] = "explicit";
  EXPECT_TRUE(reports(j, "/formulation", "got \"explicit\", expected one of: dry, explicit-single-point"));
  json k = scene_2d();
  k["grid"]["shape_function"] = "gimpp";
  EXPECT_TRUE(reports(k, "/grid/shape_function", "linear, gimp, bspline2, bspline3 (did you mean \"gimp\"?)"));
  json l = scene_2d();
  l["materials"][0]["model"] = "elastic";
  EXPECT_TRUE(reports(l, "/materials/0/model", "linear-elastic, hencky, mohr-coulomb, drucker-prager, nor-sand, fluid"));
  json m = scene_2d();
  m["bodies"][0]["geometry"]["type"] = "sphere";
  EXPECT_TRUE(reports(m, "/bodies/0/geometry/type", "box, polygon, slope, gmsh, surface-mesh"));
  json n = scene_2d();
  n["boundaries"][0]["solid"] = "pinned";
  EXPECT_TRUE(reports(n, "/boundaries/0/solid", "fixed, roller, free, friction"));
  json o = scene_2d();
  o["boundaries"][0]["fluid"] = "closed";
  EXPECT_TRUE(reports(o, "/boundaries/0/fluid", "impermeable, drained, pressure"));
  json p = scene_2d();
  p["boundaries"][0]["on"] = "left";
  EXPECT_TRUE(reports(p, "/boundaries/0/on", "x_min, x_max, y_min, y_max"));
  json q = scene_2d();
  q["output"]["monitors"][0]["quantities"] = {"pore_pressure", "pore_presure"};
  EXPECT_TRUE(reports(q, "/output/monitors/0/quantities/1", "did you mean \"pore_pressure\"?"));
  json r = scene_2d();
  r["output"]["monitors"][0]["phase"] = "water";
  EXPECT_TRUE(reports(r, "/output/monitors/0/phase", "expected one of: solid, fluid"));
  json w = scene_2d();
  w["output"]["compression"] = "gzip";
  EXPECT_TRUE(reports(w, "/output/compression", "got \"gzip\", expected one of: zlib, lz4, none"));
  json s = scene_3d();
  s["solver"]["stabilisation"]["pressure"] = "mfvp";
  EXPECT_TRUE(reports(s, "/solver/stabilisation/pressure", "mfvp-constant, mfvp-linear"));
  json t = scene_2d();
  t["solver"]["escaped_water"] = "drain";
  EXPECT_TRUE(reports(t, "/solver/escaped_water", "expected one of: keep, remove"));
  json u = scene_2d();  // only the double-point water points can leave
  u["solver"]["escaped_water"] = "remove";
  EXPECT_TRUE(reports(u, "/solver/escaped_water", "does not read this switch (read by semi-implicit-double-point)"));
  json v = scene_2d();  // the predictor's drag belongs to the semi-implicit formulations
  v["solver"]["drag_integration"] = "implicit";
  EXPECT_TRUE(reports(v, "/solver/drag_integration", "read by semi-implicit-single-point, semi-implicit-double-point, mpm-fem"));
  v["formulation"] = "semi-implicit-double-point";
  v["solver"]["drag_integration"] = "explicit";  // mpm-fem's value, not the semi-implicit formulations'
  EXPECT_TRUE(reports(v, "/solver/drag_integration", "which semi-implicit-double-point does not have; expected one of implicit, semi-implicit"));
  v["solver"]["drag_integration"] = "sideways";
  EXPECT_TRUE(reports(v, "/solver/drag_integration", "expected one of: implicit, semi-implicit, explicit"));
  // The conservative continuity belongs to the two-phase formulations (explicit-single-point too).
  json c = scene_2d();
  c["solver"]["continuity"] = "conservative";
  c["solver"]["stabilisation"]["pressure"] = "cell-constant";
  EXPECT_TRUE(problems(c).empty()) << dump_lines(problems(c));
  json d = scene_2d();
  d["formulation"] = "dry";
  d["solver"]["continuity"] = "conservative";
  EXPECT_TRUE(reports(d, "/solver/continuity", "dry does not read this switch"));
}

TEST(SceneErrors, MissingRequiredKeys) {
  json j = scene_2d();
  j.erase("time");
  EXPECT_TRUE(reports(j, "/time", "missing required key, expected an object"));
  json k = scene_2d();
  k["materials"][0].erase("youngs_modulus");
  EXPECT_TRUE(reports(k, "/materials/0/youngs_modulus", "missing required key, expected a positive number [Pa]"));
  json l = scene_2d();
  l["bodies"][0].erase("geometry");
  EXPECT_TRUE(reports(l, "/bodies/0/geometry", "missing required key"));
  json m = scene_2d();
  m["bodies"][0]["geometry"].erase("max");
  EXPECT_TRUE(reports(m, "/bodies/0/geometry/max", "missing required key"));
  json n = scene_2d();
  n["materials"][1].erase("bulk_modulus");
  EXPECT_TRUE(reports(n, "/materials/1/bulk_modulus", "missing required key"));
}

TEST(SceneErrors, DanglingAndDuplicateNames) {
  json j = scene_2d();
  j["bodies"][0]["solid"] = "snad";
  EXPECT_TRUE(reports(j, "/bodies/0/solid", "no material has that name"));
  EXPECT_TRUE(reports(j, "/bodies/0/solid", "(defined: sand, water) (did you mean \"sand\"?)"));
  json k = scene_2d();
  k["bodies"][0]["solid"] = "water";
  EXPECT_TRUE(reports(k, "/bodies/0/solid", "a material of model \"fluid\"; expected a solid material (solids: sand)"));
  json l = scene_2d();
  l["bodies"][0]["fluid"] = "sand";
  EXPECT_TRUE(reports(l, "/bodies/0/fluid", "expected a fluid material"));
  json m = scene_2d();
  m["loads"][0]["body"] = "colum";
  EXPECT_TRUE(reports(m, "/loads/0/body", "expected the name of a body (defined: column, wedge)"));
  json n = scene_2d();
  n["materials"][1]["name"] = "sand";
  EXPECT_TRUE(reports(n, "/materials/1/name", "\"sand\" again (also /materials/0/name)"));
  json o = scene_2d();
  o["bodies"][1]["name"] = "column";
  EXPECT_TRUE(reports(o, "/bodies/1/name", "expected unique body names"));
  json p = scene_3d();
  p["output"]["monitors"][1]["name"] = "energy";
  EXPECT_TRUE(reports(p, "/output/monitors/1/name", "expected unique monitor names"));
  json q = scene_2d();
  q["bodies"][1].erase("solid");
  q["bodies"][1].erase("fluid");
  EXPECT_TRUE(reports(q, "/bodies/1", "has neither \"solid\" nor \"fluid\""));
}

TEST(SceneErrors, BodyOutsideTheGrid) {
  json j = scene_2d();
  j["bodies"][0]["geometry"]["max"] = {0.1, 1.3};
  EXPECT_TRUE(reports(j, "/bodies/0/geometry", "got bounds [0, 0]..[0.1, 1.3], expected a geometry inside the grid [0, 0]..[0.1, 1.2]"));
  json k = scene_2d();
  k["bodies"][1]["geometry"]["vertices"][2] = {-0.05, 1.1};
  EXPECT_TRUE(reports(k, "/bodies/1/geometry", "inside the grid"));
  json l = scene_2d();  // on the boundary within round-off is inside
  l["bodies"][0]["geometry"]["max"] = {0.1 + 1e-12, 1.0};
  EXPECT_TRUE(problems(l).empty()) << dump_lines(problems(l));
}

TEST(SceneErrors, DegenerateGeometryAndGrid) {
  json j = scene_2d();
  j["bodies"][0]["geometry"]["max"] = {0.1, 0.0};
  EXPECT_TRUE(reports(j, "/bodies/0/geometry/max", "expected every component > min [0, 0] [m]"));
  json k = scene_2d();
  k["bodies"][1]["geometry"]["vertices"] = {{0, 1}, {0.1, 1}};
  EXPECT_TRUE(reports(k, "/bodies/1/geometry/vertices", "got 2 vertices, expected at least 3"));
  json l = scene_2d();
  l["bodies"][1]["geometry"]["vertices"] = {{0, 1}, {0.05, 1}, {0.1, 1}};
  EXPECT_TRUE(reports(l, "/bodies/1/geometry/vertices", "zero area"));
  json m = scene_2d();
  m["grid"]["max"] = {0.0, 1.2};
  EXPECT_TRUE(reports(m, "/grid/max", "expected every component > min"));
  json n = scene_3d();
  n["bodies"][0]["geometry"] = {{"type", "polygon"}, {"vertices", {{0, 0}, {1, 0}, {0, 1}}}};
  EXPECT_TRUE(reports(n, "/bodies/0/geometry/type", "polygon is 2D only"));
  json o = scene_2d();  // a grid that is not a whole number of cells is rounded up, not an error
  o["grid"]["max"] = {0.12, 1.2};
  const Scene s = parse_scene(o, "t.json");
  EXPECT_NEAR(s.grid.max[0], 0.15, 1e-12);
}

TEST(SceneErrors, GeometryFileMustExist) {  // more geometry rules: tests/unit/test_geometry.cpp
  json j = scene_2d();
  j["bodies"][0]["geometry"] = {{"type", "gmsh"}, {"file", "no-such-slope.geo"}};
  const auto lines = problems(j);
  EXPECT_TRUE(reports(j, "/bodies/0/geometry/file", "no such file"));
  EXPECT_EQ(lines.size(), 1u) << dump_lines(lines);  // one line, no noise about the other keys
}

TEST(SceneErrors, FaceNamesDependOnDimension) {
  json j = scene_2d();
  j["boundaries"][0]["on"] = "z_min";
  EXPECT_TRUE(reports(j, "/boundaries/0/on", "got \"z_min\", expected one of: x_min, x_max, y_min, y_max"));
  json k = scene_2d();
  k["loads"][0]["face"] = "z_max";
  EXPECT_TRUE(reports(k, "/loads/0/face", "z faces exist only in 3D"));
  json l = scene_2d();
  l["boundaries"][1]["on"] = "x_min";
  EXPECT_TRUE(reports(l, "/boundaries/1/on", "\"x_min\" again (also /boundaries/0/on)"));
}

TEST(SceneErrors, MonitorRules) {
  json j = scene_2d();
  j["output"]["monitors"][0]["particle"] = 3;
  EXPECT_TRUE(reports(j, "/output/monitors/0/particle", "got both \"at\" and \"particle\""));
  json k = scene_2d();
  k["output"]["monitors"][0].erase("at");
  EXPECT_TRUE(reports(k, "/output/monitors/0/quantities/0", "a point quantity, but the monitor has neither"));
  json l = scene_3d();
  l["output"]["monitors"][1]["quantities"] = {"kinetic_energy"};
  EXPECT_TRUE(reports(l, "/output/monitors/1/quantities/0", "a global quantity, expected a point quantity"));
  json m = scene_2d();
  m["output"]["monitors"][0]["quantities"] = {"pore_pressure", "velocity_z"};
  EXPECT_TRUE(reports(m, "/output/monitors/0/quantities/1", "in a 2D scene"));
  json n = scene_3d();
  n["output"]["monitors"][1]["quantities"] = {"pore_pressure"};
  EXPECT_TRUE(reports(n, "/output/monitors/1/quantities/0", "the scene has no fluid phase"));
  json o = scene_3d();
  o["output"]["monitors"][1]["phase"] = "fluid";
  EXPECT_TRUE(reports(o, "/output/monitors/1/phase", "the scene has no fluid phase"));
  json p = scene_2d();
  p["output"]["monitors"][0]["at"] = {0.5, 0.5};
  EXPECT_TRUE(reports(p, "/output/monitors/0/at", "expected a point inside the grid"));
  json q = scene_2d();  // stress_zz exists in plane strain
  q["output"]["monitors"][0]["quantities"] = {"stress_zz", "pore_pressure"};
  EXPECT_TRUE(problems(q).empty()) << dump_lines(problems(q));
  json r = scene_2d();  // `dimension` - 1 numbers only in a water_level gauge
  r["output"]["monitors"][0]["at"] = {0.05};
  EXPECT_TRUE(reports(r, "/output/monitors/0/at", "(1 components), expected a vector of 2 numbers"));
}

/// A pond of free water (explicit-double-point) with a water_level gauge, in 2D or 3D.
json pond(int dim) { return swmpm::testing::pond_scene(dim); }

TEST(Scene, WaterLevelGaugeKeepsItsVerticalLineThroughTheRoundTrip) {
  for (int dim : {2, 3}) {
    const Scene s = parse_scene(pond(dim), "t.json");
    const Monitor& m = s.output.monitors[0];
    ASSERT_TRUE(m.gauge);
    EXPECT_EQ(*m.gauge, (Vec3{0.1, 0.0, dim == 3 ? 0.05 : 0.0}));
    EXPECT_FALSE(m.at);
    EXPECT_FALSE(m.particle);
    const json resolved = to_json(s);
    EXPECT_EQ(resolved["output"]["monitors"][0]["at"], dim == 3 ? json({0.1, 0.05}) : json::array({0.1}));
    EXPECT_FALSE(resolved["output"]["monitors"][0].contains("phase"));
    const Scene r = parse_scene(resolved, "t.json");
    EXPECT_EQ(to_json(r), resolved);
    EXPECT_EQ(r.output.monitors[0].gauge, m.gauge);
    EXPECT_EQ(r.output.monitors[0].quantities, m.quantities);
  }
}

TEST(SceneErrors, WaterLevelGaugeRules) {
  json j = pond(2);  // [x] in 2D
  j["output"]["monitors"][0]["at"] = {0.1, 0.2};
  EXPECT_TRUE(reports(j, "/output/monitors/0/at", "(2 components), expected 1 number, x of the water_level gauge"));
  json k = pond(3);  // [x, z] in 3D
  k["output"]["monitors"][0]["at"] = {0.1};
  EXPECT_TRUE(reports(k, "/output/monitors/0/at", "(1 components), expected 2 numbers, x and z"));
  k["output"]["monitors"][0]["at"] = {0.1, 0.2, 0.05};
  EXPECT_TRUE(reports(k, "/output/monitors/0/at", "(3 components), expected 2 numbers, x and z"));
  json l = pond(2);  // water_level alone
  l["output"]["monitors"][0]["quantities"] = {"velocity_x", "water_level"};
  EXPECT_TRUE(reports(l, "/output/monitors/0/quantities/0", "in a water_level gauge, expected only \"water_level\""));
  using KeyValue = std::pair<std::string, json>;
  for (const auto& [key, value] : {KeyValue{"phase", "fluid"}, KeyValue{"points", "water"}, KeyValue{"particle", 3}}) {
    json m = pond(2);
    m["output"]["monitors"][0][key] = value;
    EXPECT_TRUE(reports(m, "/output/monitors/0/" + key, "in a water_level gauge, expected none of"));
  }
  json n = pond(2);
  n["output"]["monitors"][0].erase("at");
  EXPECT_TRUE(reports(n, "/output/monitors/0/at", "missing, expected the vertical line of the water_level gauge"));
  json o = pond(2);  // inside the grid
  o["output"]["monitors"][0]["at"] = {0.3};
  EXPECT_TRUE(reports(o, "/output/monitors/0/at", "expected a vertical line inside the grid: x in [0, 0.2]"));
  json p = pond(3);
  p["output"]["monitors"][0]["at"] = {0.1, -0.01};
  EXPECT_TRUE(reports(p, "/output/monitors/0/at", "z in [0, 0.1]"));
  // Only the formulations with liquid points read it.
  json q = scene_2d();
  q["output"]["monitors"][0] = {{"name", "gauge"}, {"at", {0.05}}, {"quantities", {"water_level"}}};
  EXPECT_TRUE(reports(q, "/output/monitors/0/quantities/0",
                      "got \"water_level\", but formulation \"explicit-single-point\" has no liquid points; expected "
                      "a formulation that reads it: semi-implicit-double-point, explicit-double-point"));
  json r = scene_3d();  // and a fluid
  r["output"]["monitors"][0] = {{"name", "gauge"}, {"at", {0.5, 0.5}}, {"quantities", {"water_level"}}};
  EXPECT_TRUE(reports(r, "/output/monitors/0/quantities/0", "the scene has no fluid phase"));
}

TEST(SceneErrors, MaterialRules) {
  json j = scene_3d();
  j["materials"][0]["grain_density"] = 2650;
  EXPECT_TRUE(reports(j, "/materials/0/grain_density", "got both \"density\" and \"grain_density\""));
  json k = scene_3d();
  k["materials"][0].erase("density");
  EXPECT_TRUE(reports(k, "/materials/0/density", "missing, expected \"density\" (a dry body) or \"grain_density\""));
  json l = scene_3d();
  l["materials"][0].erase("density");
  l["materials"][0]["grain_density"] = 2650;
  EXPECT_TRUE(reports(l, "/materials/0/porosity", "together with \"grain_density\""));
  json m = scene_3d();
  m["materials"][0]["dilation_angle"] = 30;
  EXPECT_TRUE(reports(m, "/materials/0/dilation_angle", "expected a number in [0, friction_angle = 25] [deg]"));
  json n = scene_2d();
  n["materials"][0]["intrinsic_permeability"] = 1e-12;
  EXPECT_TRUE(reports(n, "/materials/0/intrinsic_permeability", "expected at most one"));
  json o = scene_2d();
  o["materials"][0].erase("hydraulic_conductivity");
  EXPECT_TRUE(reports(o, "/materials/0", "is the solid of saturated body \"column\" (/bodies/0), expected \"hydraulic_conductivity\" or \"intrinsic_permeability\""));
  json p = scene_2d();
  p["materials"][0].erase("grain_density");
  p["materials"][0].erase("porosity");
  p["materials"][0]["density"] = 2000;
  EXPECT_TRUE(reports(p, "/materials/0", "expected \"grain_density\" and \"porosity\" (a porous skeleton) instead of \"density\""));
  json q = scene_2d();
  q["materials"][0]["permeability_law"] = "kozeny";
  EXPECT_TRUE(reports(q, "/materials/0/permeability_law", "constant, kozeny-carman"));
}

TEST(SceneErrors, InitialStateRules) {
  json j = scene_2d();
  j["bodies"][0]["initial"]["velocity"] = {"2*x +", 0};
  EXPECT_TRUE(reports(j, "/bodies/0/initial/velocity/0", "expected an expression in x, y, z (muParser: "));
  json k = scene_2d();
  k["bodies"][0]["initial"]["velocity"] = {"t", 0};  // t is not a variable of initial values
  EXPECT_TRUE(reports(k, "/bodies/0/initial/velocity/0", "muParser"));
  json l = scene_2d();
  l["bodies"][0]["initial"]["water_table"] = 1.0;
  EXPECT_TRUE(reports(l, "/bodies/0/initial/water_table", "unless pore_pressure is \"hydrostatic\""));
  l["bodies"][0]["initial"]["pore_pressure"] = "hydrostatic";
  EXPECT_TRUE(problems(l).empty()) << dump_lines(problems(l));
  json m = scene_2d();
  m["bodies"][0]["initial"]["k0"] = 0.4;
  EXPECT_TRUE(reports(m, "/bodies/0/initial/k0", "unless stress is \"geostatic\""));
  json n = scene_2d();
  n["bodies"][0]["initial"]["stress"] = {1, 2, 3};
  EXPECT_TRUE(reports(n, "/bodies/0/initial/stress", "\"geostatic\" or an array of 6 numbers"));
  json o = scene_2d();
  o["bodies"][0]["initial"]["pore_pressure"] = "hydrostatik";
  EXPECT_TRUE(reports(o, "/bodies/0/initial/pore_pressure", "expected a number or \"hydrostatic\" [Pa]"));
  json p = scene_3d();
  p["bodies"][0]["initial"]["pore_pressure"] = 1e3;
  EXPECT_TRUE(reports(p, "/bodies/0/initial/pore_pressure", "without a fluid"));
}

TEST(SceneErrors, BoundaryRules) {
  json j = scene_2d();
  j["boundaries"][1].erase("coefficient");
  EXPECT_TRUE(reports(j, "/boundaries/1/coefficient", "missing, expected a non-negative number with solid \"friction\""));
  json k = scene_2d();
  k["boundaries"][0]["coefficient"] = 0.2;
  EXPECT_TRUE(reports(k, "/boundaries/0/coefficient", "unless solid is \"friction\""));
  json l = scene_2d();
  l["boundaries"][2].erase("value");
  EXPECT_TRUE(reports(l, "/boundaries/2/value", "missing, expected a number with fluid \"pressure\" [Pa]"));
  json m = scene_3d();
  m["boundaries"][0]["fluid"] = "drained";
  EXPECT_TRUE(reports(m, "/boundaries/0/fluid", "the scene has no fluid phase"));
}

TEST(SceneErrors, LoadRules) {
  json j = scene_2d();
  j["loads"][0]["function"] = "sin(t)";
  EXPECT_TRUE(reports(j, "/loads/0/table", "got both \"function\" and \"table\""));
  json k = scene_3d();
  k["loads"][0]["function"] = "sin(x)";
  EXPECT_TRUE(reports(k, "/loads/0/function", "expected an expression in t (muParser: "));
  json l = scene_2d();
  l["loads"][0]["table"] = {{0, 0}, {1, 1}, {1, 2}};
  EXPECT_TRUE(reports(l, "/loads/0/table/2", "got t = 1 after t = 1, expected strictly increasing times"));
  json m = scene_3d();
  m["loads"][0]["region"]["max"] = {0.7, 0.2, 0.5};
  EXPECT_TRUE(reports(m, "/loads/0/region/max", "expected every component > min"));
  json n = scene_3d();
  n["loads"][0]["ramp"] = -1;
  EXPECT_TRUE(reports(n, "/loads/0/ramp", "non-negative number [s]"));
}

TEST(SceneErrors, FormulationMustMatchThePhases) {
  json j = scene_2d();
  j["formulation"] = "dry";
  EXPECT_TRUE(reports(j, "/formulation", "body \"column\" (/bodies/0) has a fluid"));
  json k = scene_3d();
  k["formulation"] = "semi-implicit-double-point";
  EXPECT_TRUE(reports(k, "/formulation", "no body has a fluid; expected \"dry\""));
}

TEST(SceneErrors, SceneNameMustBeADirectoryName) {
  json j = scene_2d();
  j["name"] = "my scene/1";
  EXPECT_TRUE(reports(j, "/name", "a name usable as a directory"));
}

TEST(SceneErrors, AllProblemsAreReportedTogether) {
  json j = scene_2d();
  j["grid"]["cell_size"] = -1;
  j["materials"][0]["poisson_ratio"] = 0.7;
  j["materials"][0]["youngs_modulu"] = 1;
  j["bodies"][0]["solid"] = "rock";
  j["time"]["end"] = 0;
  const auto lines = problems(j);
  EXPECT_EQ(lines.size(), 5u) << dump_lines(lines);
  EXPECT_TRUE(reports(j, "/grid/cell_size", "positive"));
  EXPECT_TRUE(reports(j, "/materials/0/poisson_ratio", "0.5"));
  EXPECT_TRUE(reports(j, "/materials/0/youngs_modulu", "did you mean"));
  EXPECT_TRUE(reports(j, "/bodies/0/solid", "rock"));
  EXPECT_TRUE(reports(j, "/time/end", "positive"));
  try {
    parse_scene(j, "t.json");
  } catch (const SceneError& e) {
    const std::string what = e.what();  // all lines joined by '\n'
    EXPECT_EQ(std::count(what.begin(), what.end(), '\n'), 4);
  }
}

// ---- mpm-fem's keys: solver.air, solver.phase_field, grain_diameter, water_level -----------------

TEST(Scene, MpmFemAirAndPhaseFieldDefaultsAndRoundTrip) {
  const Scene s = parse_scene(swmpm::testing::mpm_fem_scene(), "t.json");
  EXPECT_EQ(s.formulation, Formulation::mpm_fem);
  EXPECT_DOUBLE_EQ(s.solver.air.density, 1.2);               // kg/m^3
  EXPECT_DOUBLE_EQ(s.solver.air.dynamic_viscosity, 1.8e-5);  // Pa s
  EXPECT_FALSE(s.solver.phase_field.interface_width);        // the solver's choice
  EXPECT_FALSE(s.solver.phase_field.mobility);
  EXPECT_DOUBLE_EQ(s.materials[0].at("grain_diameter"), 0.003);
  const json resolved = to_json(s);
  EXPECT_EQ(resolved["solver"]["air"], json({{"density", 1.2}, {"domain", "active"}, {"dynamic_viscosity", 1.8e-5}}));
  EXPECT_FALSE(s.solver.air.whole_grid);
  EXPECT_EQ(resolved["solver"]["phase_field"], json({{"lsic", false}, {"volume_correction", true}}));
  EXPECT_EQ(resolved["materials"][0]["grain_diameter"], 0.003);
  EXPECT_EQ(to_json(parse_scene(resolved, "t.json")), resolved);

  json j = swmpm::testing::mpm_fem_scene();
  j["solver"] = {{"air", {{"density", 1.25}, {"dynamic_viscosity", 2e-5}, {"domain", "grid"}}},
                 {"phase_field", {{"interface_width", 0.06}, {"mobility", 200}}}};
  const Scene t = parse_scene(j, "t.json");
  EXPECT_DOUBLE_EQ(t.solver.air.density, 1.25);
  EXPECT_DOUBLE_EQ(t.solver.air.dynamic_viscosity, 2e-5);
  EXPECT_TRUE(t.solver.air.whole_grid);
  ASSERT_TRUE(t.solver.phase_field.interface_width && t.solver.phase_field.mobility);
  EXPECT_DOUBLE_EQ(*t.solver.phase_field.interface_width, 0.06);
  EXPECT_DOUBLE_EQ(*t.solver.phase_field.mobility, 200);
  const json r = to_json(t);
  EXPECT_EQ(r["solver"]["phase_field"],
            json({{"interface_width", 0.06}, {"lsic", false}, {"mobility", 200}, {"volume_correction", true}}));
  EXPECT_EQ(to_json(parse_scene(r, "t.json")), r);
}

TEST(SceneErrors, AirAndPhaseFieldAreReadByMpmFemOnly) {
  json j = scene_2d();  // explicit-single-point
  j["solver"] = {{"air", {{"density", 1.2}}}, {"phase_field", json::object()}};
  EXPECT_TRUE(reports(j, "/solver/air", "got a value, but explicit-single-point does not read this key (read by "
                                        "mpm-fem); remove the key"));
  EXPECT_TRUE(reports(j, "/solver/phase_field", "explicit-single-point does not read this key (read by mpm-fem)"));
  json k = scene_3d();  // dry
  k["solver"]["air"] = {{"dynamic_viscosity", 1e-5}};
  EXPECT_TRUE(reports(k, "/solver/air", "dry does not read this key (read by mpm-fem)"));
  // Not written back where they are not read.
  const json resolved = to_json(parse_scene(scene_2d(), "t.json"));
  EXPECT_FALSE(resolved["solver"].contains("air"));
  EXPECT_FALSE(resolved["solver"].contains("phase_field"));
  // grain_diameter: explicit-double-point and mpm-fem.
  json l = scene_2d();
  l["materials"][0]["grain_diameter"] = 0.001;
  EXPECT_TRUE(reports(l, "/materials/0/grain_diameter", "(read by explicit-double-point, mpm-fem)"));
}

TEST(SceneErrors, AirAndPhaseFieldValues) {
  const auto with = [](const std::string& object, const std::string& key, const json& v) {
    json j = swmpm::testing::mpm_fem_scene();
    j["solver"][object][key] = v;
    return j;
  };
  EXPECT_TRUE(reports(with("air", "density", -1.2), "/solver/air/density", "got -1.2, expected a positive number [kg/m^3]"));
  EXPECT_TRUE(reports(with("air", "dynamic_viscosity", 0), "/solver/air/dynamic_viscosity", "expected a positive number [Pa s]"));
  EXPECT_TRUE(reports(with("phase_field", "interface_width", 0), "/solver/phase_field/interface_width",
                      "expected a positive number [m]"));
  EXPECT_TRUE(reports(with("phase_field", "mobility", "fast"), "/solver/phase_field/mobility",
                      "expected a positive number [1/s]"));
  // Finite: a number too large for a double reads as infinity.
  EXPECT_TRUE(reports(with("phase_field", "mobility", std::numeric_limits<double>::infinity()),
                      "/solver/phase_field/mobility", "expected a positive number"));
  EXPECT_TRUE(reports(with("air", "densty", 1.2), "/solver/air/densty", "did you mean \"density\""));
  json j = swmpm::testing::mpm_fem_scene();
  j["solver"]["air"] = 1.2;
  EXPECT_TRUE(reports(j, "/solver/air", "expected an object"));
}

TEST(Scene, WaterLevelGaugeIsReadByMpmFem) {
  // The grid's phase field gives the level (monitors.hpp); the gauge parses as in double-point.
  json j = swmpm::testing::mpm_fem_scene();
  j["output"]["monitors"] = {{{"name", "gauge"}, {"at", {0.2}}, {"quantities", {"water_level"}}}};
  const Scene s = parse_scene(j, "t.json");
  ASSERT_TRUE(s.output.monitors[0].gauge);
  EXPECT_EQ((*s.output.monitors[0].gauge)[0], 0.2);
}

// ---- initialisation.materials -------------------------------------------------------------------

TEST(Scene, InitialisationMaterialsOverrideTheModelParameters) {
  json j = scene_3d();  // "clay": mohr-coulomb, cohesion 0 by default
  j["initialisation"] = {{"duration", 1.0}, {"plasticity", true},
                         {"materials", {{"clay", {{"cohesion", 1e5}, {"friction_angle", 40}}}}}};
  const Scene s = parse_scene(j, "t.json");
  ASSERT_EQ(s.initialisation.materials.size(), 1u);
  EXPECT_EQ(s.initialisation.materials.at("clay"), (std::map<std::string, double>{{"cohesion", 1e5}, {"friction_angle", 40}}));
  EXPECT_DOUBLE_EQ(s.materials[0].at("cohesion"), 0.0);  // the scene's own value stays
  const json resolved = to_json(s);
  EXPECT_EQ(resolved["initialisation"]["materials"], json({{"clay", {{"cohesion", 1e5}, {"friction_angle", 40.0}}}}));
  EXPECT_EQ(to_json(parse_scene(resolved, "t.json")), resolved);
  // Absent: none, and not written.
  EXPECT_FALSE(to_json(parse_scene(scene_3d(), "t.json")).contains("initialisation"));
}

TEST(SceneErrors, InitialisationMaterialsRules) {
  const auto with = [](const json& materials) {
    json j = scene_2d();  // "sand" linear-elastic (saturated), "water" fluid
    j["initialisation"] = {{"duration", 1.0}, {"materials", materials}};
    return j;
  };
  EXPECT_TRUE(reports(with({{"snad", {{"youngs_modulus", 2e7}}}}), "/initialisation/materials/snad",
                      "got material \"snad\", but no material has that name; expected a solid material (defined: "
                      "sand) (did you mean \"sand\"?)"));
  EXPECT_TRUE(reports(with({{"water", {{"bulk_modulus", 1e9}}}}), "/initialisation/materials/water",
                      "a fluid; expected a solid material"));
  EXPECT_TRUE(reports(with({{"sand", {{"youngs_modulu", 2e7}}}}), "/initialisation/materials/sand/youngs_modulu",
                      "did you mean \"youngs_modulus\""));
  // A key of the model's tables the constitutive law does not read, and one of another model.
  EXPECT_TRUE(reports(with({{"sand", {{"porosity", 0.5}}}}), "/initialisation/materials/sand/porosity",
                      "got \"porosity\", which linear-elastic's constitutive model does not read"));
  EXPECT_TRUE(reports(with({{"sand", {{"cohesion", 1e5}}}}), "/initialisation/materials/sand/cohesion",
                      "unknown key \"cohesion\""));
  EXPECT_TRUE(reports(with({{"sand", {{"poisson_ratio", 0.5}}}}), "/initialisation/materials/sand/poisson_ratio",
                      "expected a number in [-1, 0.5) [-]"));
  EXPECT_TRUE(reports(with({{"sand", 3}}), "/initialisation/materials/sand", "expected an object of material"));
  EXPECT_TRUE(reports(with(json::array({1})), "/initialisation/materials", "expected an object of objects"));
  // The rules across keys hold for the parameters the phase runs with.
  json k = scene_3d();  // friction_angle 25
  k["initialisation"] = {{"duration", 1.0}, {"materials", {{"clay", {{"friction_angle", 10}}}}}};
  k["materials"][0]["dilation_angle"] = 20;
  EXPECT_TRUE(reports(k, "/initialisation/materials/clay/friction_angle",
                      "got dilation_angle 20 > friction_angle 10 during the phase"));
  // mpm-fem reads it too (seed 004's large cohesion while gravity ramps up).
  json m = swmpm::testing::mpm_fem_scene();
  m["initialisation"] = {{"duration", 1.0}, {"materials", {{"beads", {{"cohesion", 1e5}}}}}};
  EXPECT_EQ(dump_lines(problems(m)), "\n  (no problems)") << "mpm-fem swaps the phase's models in";
}

// ---- the reference documentation agrees with the schema -----------------------------------------

std::string read_docs() {
  std::ifstream in(SWMPM_SOURCE_DIR "/docs/scene-format.md");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(SceneDocs, EveryDeclaredKeyIsDocumented) {
  const std::string docs = read_docs();
  ASSERT_FALSE(docs.empty()) << "cannot read " SWMPM_SOURCE_DIR "/docs/scene-format.md";
  const auto keys = schema_keys();
  EXPECT_GT(keys.size(), 60u);
  for (const auto& k : keys) EXPECT_NE(docs.find("`" + k + "`"), std::string::npos) << k;
}

TEST(SceneDocs, SchemaTablesAppearVerbatim) {
  const std::string docs = read_docs();
  std::istringstream generated(schema_markdown());
  std::string line;
  int rows = 0;
  while (std::getline(generated, line)) {
    if (line.rfind("| `", 0) != 0) continue;
    ++rows;
    EXPECT_NE(docs.find("\n" + line + "\n"), std::string::npos)
        << "docs/scene-format.md lacks this row of the schema tables (swmpm::scene::schema_markdown() "
           "prints the current tables):\n"
        << line;
  }
  EXPECT_GT(rows, 60);
}

TEST(SceneDocs, TheExampleParses) {
  const std::string docs = read_docs();
  const auto begin = docs.find("```json\n");
  ASSERT_NE(begin, std::string::npos);
  const auto end = docs.find("```", begin + 8);
  ASSERT_NE(end, std::string::npos);
  const Scene s = parse_scene(json::parse(docs.substr(begin + 8, end - begin - 8)), "scene-format.md");
  EXPECT_EQ(s.formulation, Formulation::explicit_single_point);
  EXPECT_EQ(s.output.monitors.size(), 2u);
}

}  // namespace
