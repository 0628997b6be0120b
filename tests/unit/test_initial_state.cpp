// Seeding of phases and the initial state (preprocess/preprocess.cpp, preprocess/initial_state.cpp):
// geostatic stress against the weight of the material above (box, slope polygon, stacked bodies,
// 3D), hydrostatic pore pressure with and without a water table, effective stress from the buoyant
// weight, the particle files each formulation gets (single-point arrays, double-point solid + fluid,
// free water), and the errors for scenes a formulation cannot represent. Scenes are parsed in
// process; file tests run preprocess() into a scratch folder and read the VTU back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "preprocess/preprocess.hpp"
#include "scene/files.hpp"
#include "scene/pointcloud.hpp"
#include "scene/scene.hpp"
#include "solver/output/particle_io.hpp"
#include "solver/run.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::scene::PointCloud;

constexpr double g = 9.81;         // m/s^2
constexpr double rho_w = 1000.0;   // kg/m^3
constexpr double rho_s = 2650.0;   // kg/m^3, grains
constexpr double n0 = 0.4;         // -, porosity of "sand"

/// A 2D scene with a dry soil, a porous sand and water; bodies and formulation left to the test.
json base_scene(const std::string& formulation) {
  return json::parse(R"json({
    "name": "initial", "dimension": 2, "formulation": ")json" + formulation + R"json(",
    "gravity": [0.0, -9.81],
    "grid": { "cell_size": 0.1, "min": [0.0, 0.0], "max": [10.0, 6.0] },
    "materials": [
      { "name": "soil", "model": "linear-elastic", "density": 2000.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3 },
      { "name": "fill", "model": "linear-elastic", "density": 1500.0, "youngs_modulus": 1e7, "poisson_ratio": 0.3 },
      { "name": "sand", "model": "linear-elastic", "grain_density": 2650.0, "porosity": 0.4,
        "youngs_modulus": 1e7, "poisson_ratio": 0.3, "hydraulic_conductivity": 1e-4 },
      { "name": "water", "model": "fluid", "density": 1000.0, "bulk_modulus": 2.2e9 }
    ],
    "bodies": [],
    "time": { "end": 1.0 }
  })json");
}

json box_body(const std::string& name, double x0, double y0, double x1, double y1) {
  return {{"name", name}, {"geometry", {{"type", "box"}, {"min", {x0, y0}}, {"max", {x1, y1}}}}};
}

swmpm::scene::Scene parse(const json& j) { return swmpm::scene::parse_scene(j, "scene.json"); }

const std::vector<double>& values(const PointCloud& c, const std::string& name) {
  return c.get(name, "test cloud").values;
}

/// Runs preprocess on `scene` into a fresh scratch run directory and returns it.
fs::path preprocess_into(const json& scene, const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / "swmpm-tests" / ("initial-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "scene.json") << scene.dump(2);
  return swmpm::pre::preprocess((dir / "scene.json").string(), (dir / "run").string(), true);
}

/// The message of the SceneError that seeding `j` throws ("" when it does not throw).
std::string seeding_error(const json& j) {
  try {
    swmpm::pre::seed_phases(parse(j));
  } catch (const swmpm::scene::SceneError& e) {
    return e.what();
  }
  return "";
}

// ---- geostatic stress ---------------------------------------------------------------------------

TEST(InitialState, GeostaticBoxIsTheWeightAboveAndK0Sideways) {
  json j = base_scene("dry");
  j["bodies"] = json::array({box_body("ground", 0, 0, 1, 4)});
  j["bodies"][0]["solid"] = "soil";
  j["bodies"][0]["initial"] = {{"stress", "geostatic"}, {"k0", 0.6}};
  const PointCloud c = swmpm::pre::seed_phases(parse(j)).solid;
  ASSERT_GT(c.size(), 0u);
  const auto& st = values(c, "stress");
  double worst = 0.0;
  for (std::size_t p = 0; p < c.size(); ++p) {
    const double expected = -2000.0 * g * (4.0 - c.points[p][1]);  // Pa, depth from the top of the box
    worst = std::max(worst, std::abs(st[6 * p + 1] - expected) / std::abs(expected));
    EXPECT_NEAR(st[6 * p + 0], 0.6 * st[6 * p + 1], 1e-9 * std::abs(expected));
    EXPECT_NEAR(st[6 * p + 2], 0.6 * st[6 * p + 1], 1e-9 * std::abs(expected));
    for (std::size_t k = 3; k < 6; ++k) EXPECT_EQ(st[6 * p + k], 0.0);
  }
  std::printf("geostatic box: max relative error of sigma_yy vs -rho g d = %.2e\n", worst);
  EXPECT_LT(worst, 0.01);
}

TEST(InitialState, GeostaticBox3DUsesVerticalColumnsInXAndZ) {
  json j = base_scene("dry");
  j["dimension"] = 3;
  j["gravity"] = {0.0, -9.81, 0.0};
  j["grid"] = {{"cell_size", 0.1}, {"min", {0, 0, 0}}, {"max", {0.4, 1.0, 0.3}}};
  j["bodies"] = json::array({json{{"name", "block"}, {"solid", "soil"},
                                   {"geometry", {{"type", "box"}, {"min", {0, 0, 0}}, {"max", {0.4, 1.0, 0.3}}}},
                                   {"initial", {{"stress", "geostatic"}, {"k0", 0.5}}}}});
  const PointCloud c = swmpm::pre::seed_phases(parse(j)).solid;
  ASSERT_EQ(c.size(), 4u * 10u * 3u * 8u);
  const auto& st = values(c, "stress");
  double worst = 0.0;
  for (std::size_t p = 0; p < c.size(); ++p) {
    const double expected = -2000.0 * g * (1.0 - c.points[p][1]);
    worst = std::max(worst, std::abs(st[6 * p + 1] - expected) / std::abs(expected));
    EXPECT_NEAR(st[6 * p + 0], 0.5 * st[6 * p + 1], 1e-6);
    EXPECT_NEAR(st[6 * p + 2], 0.5 * st[6 * p + 1], 1e-6);
  }
  std::printf("geostatic 3D box: max relative error of sigma_yy = %.2e\n", worst);
  EXPECT_LT(worst, 0.01);
}

TEST(InitialState, GeostaticUnderASlopeFaceIsTheSlopeHeightAbove) {
  // Lower level y = 2 for x < 3, a 45 degree face up to the crest y = 5 at x = 6.
  json j = base_scene("dry");
  const json vertices = json::array({{0, 0}, {10, 0}, {10, 5}, {6, 5}, {3, 2}, {0, 2}});
  j["bodies"] = json::array({json{{"name", "slope"}, {"solid", "soil"},
                                   {"geometry", {{"type", "polygon"}, {"vertices", vertices}}},
                                   {"initial", {{"stress", "geostatic"}, {"k0", 0.5}}}}});
  auto surface = [](double x) { return x < 3 ? 2.0 : x < 6 ? 2.0 + (x - 3.0) : 5.0; };
  const PointCloud c = swmpm::pre::seed_phases(parse(j)).solid;
  const auto& st = values(c, "stress");
  const double spacing = 0.05;  // m, h / particles_per_cell
  double worst_depth = 0.0, worst_rel = 0.0;
  int under_face = 0;
  for (std::size_t p = 0; p < c.size(); ++p) {
    const double x = c.points[p][0], y = c.points[p][1];
    if (x < 3.0 || x > 6.0) continue;
    ++under_face;
    const double depth = surface(x) - y;             // m, slope surface above the point
    const double measured = -st[6 * p + 1] / (2000.0 * g);  // m, depth the stress implies
    worst_depth = std::max(worst_depth, std::abs(measured - depth));
    if (depth > 1.0) worst_rel = std::max(worst_rel, std::abs(measured - depth) / depth);
  }
  std::printf("slope: %d points under the face, max depth error %.4f m (lattice half-spacing %.3f m), "
              "max relative error below 1 m depth %.2e\n", under_face, worst_depth, spacing / 2, worst_rel);
  EXPECT_GT(under_face, 1000);
  EXPECT_LE(worst_depth, 0.5 * spacing + 1e-9);  // the lattice staircase of the face
  EXPECT_LT(worst_rel, 0.03);

  // The point under the middle of the face at y = 1: 2.5 m of slope above it.
  std::size_t nearest = 0;
  double best = 1e9;
  for (std::size_t p = 0; p < c.size(); ++p) {
    const double d = std::hypot(c.points[p][0] - 4.5, c.points[p][1] - 1.0);
    if (d < best) best = d, nearest = p;
  }
  const double depth = surface(c.points[nearest][0]) - c.points[nearest][1];
  EXPECT_NEAR(-st[6 * nearest + 1], 2000.0 * g * depth, 0.01 * 2000.0 * g * depth);
}

TEST(InitialState, StackedBodiesCarryTheWeightOfEveryBodyAbove) {
  // Soil 0..2.4 (2 per cell) under fill 2..3 (4 per cell, 1500 kg/m^3); the fill wins on 2..2.4.
  json j = base_scene("dry");
  j["bodies"] = json::array({box_body("ground", 0, 0, 2, 2.4), box_body("fill", 0, 2, 2, 3)});
  j["bodies"][0]["solid"] = "soil";
  j["bodies"][1]["solid"] = "fill";
  j["bodies"][1]["particles_per_cell"] = 4;
  for (auto& b : j["bodies"]) b["initial"] = {{"stress", "geostatic"}};
  const PointCloud c = swmpm::pre::seed_phases(parse(j)).solid;
  const auto& st = values(c, "stress");
  const auto& body = values(c, "body");
  double worst = 0.0;
  std::size_t in_fill = 0;
  for (std::size_t p = 0; p < c.size(); ++p) {
    const double y = c.points[p][1];
    const bool fill = body[p] == 1.0;
    EXPECT_EQ(fill, y > 2.0) << "later body wins at y = " << y;
    in_fill += fill;
    const double expected = fill ? -1500.0 * g * (3.0 - y) : -(1500.0 * 1.0 + 2000.0 * (2.0 - y)) * g;
    worst = std::max(worst, std::abs(st[6 * p + 1] - expected) / std::abs(expected));
  }
  std::printf("stacked bodies: max relative error of sigma_yy = %.2e\n", worst);
  EXPECT_EQ(in_fill, 80u * 40u);  // 2 m x 1 m of fill at 0.025 m spacing
  EXPECT_LT(worst, 1e-9);
}

// ---- pore pressure and effective stress ---------------------------------------------------------

json saturated_box(const std::string& formulation, const json& initial) {
  json j = base_scene(formulation);
  j["bodies"] = json::array({box_body("sand", 0, 0, 1, 2)});
  j["bodies"][0]["solid"] = "sand";
  j["bodies"][0]["fluid"] = "water";
  j["bodies"][0]["initial"] = initial;
  return j;
}

TEST(InitialState, HydrostaticPorePressureFromTheTopOrTheWaterTable) {
  for (const double table : {-1.0, 1.23}) {  // -1: default (top of the body, y = 2)
    json initial = {{"pore_pressure", "hydrostatic"}};
    if (table > 0) initial["water_table"] = table;
    const PointCloud c = swmpm::pre::seed_phases(parse(saturated_box("explicit-single-point", initial))).solid;
    const double y_wt = table > 0 ? table : 2.0;
    const auto& pp = values(c, "pore_pressure");
    double worst = 0.0;
    for (std::size_t p = 0; p < c.size(); ++p) {
      const double expected = rho_w * g * std::max(0.0, y_wt - c.points[p][1]);
      worst = std::max(worst, std::abs(pp[p] - expected));
    }
    std::printf("hydrostatic, water table %.2f m: max |p - rho_w g (y_wt - y)| = %.2e Pa\n", y_wt, worst);
    EXPECT_LT(worst, 1e-9 * rho_w * g * 2.0);
  }
}

TEST(InitialState, EffectiveStressIsTheBuoyantWeightBelowTheTable) {
  const double k0 = 0.5, rho_sat = (1 - n0) * rho_s + n0 * rho_w, rho_dry = (1 - n0) * rho_s;
  for (const double table : {-1.0, 1.23}) {  // a table inside the body cuts a lattice segment
    json initial = {{"stress", "geostatic"}, {"k0", k0}, {"pore_pressure", "hydrostatic"}};
    if (table > 0) initial["water_table"] = table;
    const PointCloud c = swmpm::pre::seed_phases(parse(saturated_box("explicit-single-point", initial))).solid;
    const double y_wt = table > 0 ? table : 2.0;
    // The points whose centre lies below the table are saturated, those above it dry: the
    // saturated segments reach y_s, the top of the segment (0.05 m) the table cuts (its centre
    // 1.225 m lies below 1.23 m).
    const double y_s = table > 0 ? 1.25 : 2.0;
    const auto& st = values(c, "stress");
    const auto& pp = values(c, "pore_pressure");
    const auto& mf = values(c, "fluid_mass");
    double worst = 0.0, worst_total = 0.0;
    for (std::size_t p = 0; p < c.size(); ++p) {
      const double y = c.points[p][1];
      EXPECT_EQ(mf[p] > 0.0, y < y_wt) << "saturated below the table, dry above it, at y = " << y;
      // The dry unit weight above y_s, the saturated one from there down to the table, the buoyant
      // (1 - n)(rho_s - rho_w) below the table; the total stress sigma' - p is the weight above.
      const double weight = g * (rho_dry * (2.0 - std::max(y, y_s)) + rho_sat * std::max(0.0, y_s - y));
      const double expected = -weight + rho_w * g * std::max(0.0, y_wt - y);
      const double scale = rho_sat * g * 2.0;
      worst = std::max(worst, std::abs(st[6 * p + 1] - expected) / scale);
      worst_total = std::max(worst_total, std::abs(st[6 * p + 1] - pp[p] + weight) / scale);
      EXPECT_NEAR(st[6 * p + 0], k0 * st[6 * p + 1], 1e-9 * scale);
    }
    std::printf("effective stress, water table %.2f m: max error %.2e, total stress sigma' - p vs -rho_sat g d "
                "max error %.2e (relative to rho_sat g H)\n", y_wt, worst, worst_total);
    EXPECT_LT(worst, 1e-9);
    EXPECT_LT(worst_total, 1e-9);
  }
}

TEST(InitialState, SubmergedSoilUnderFreeWaterKeepsTheBuoyantEffectiveStress) {
  // Sand 0..1 under free water 1..1.5 (double-point): the water's weight goes to the pore pressure.
  // explicit-double-point: semi-implicit-double-point refuses free water (issue 27, item 8).
  json j = base_scene("explicit-double-point");
  j["bodies"] = json::array({box_body("sand", 0, 0, 1, 1), box_body("lake", 0, 1, 1, 1.5)});
  j["bodies"][0]["solid"] = "sand";
  j["bodies"][0]["fluid"] = "water";
  j["bodies"][0]["initial"] = {{"stress", "geostatic"}, {"pore_pressure", "hydrostatic"}, {"water_table", 1.5}};
  j["bodies"][1]["fluid"] = "water";
  j["bodies"][1]["initial"] = {{"pore_pressure", "hydrostatic"}};
  const auto phases = swmpm::pre::seed_phases(parse(j));
  const auto& st = values(phases.solid, "stress");
  double worst = 0.0;
  for (std::size_t p = 0; p < phases.solid.size(); ++p) {
    const double expected = -(1 - n0) * (rho_s - rho_w) * g * (1.0 - phases.solid.points[p][1]);
    worst = std::max(worst, std::abs(st[6 * p + 1] - expected));
  }
  EXPECT_LT(worst, 1e-6);
  const auto& pf = values(phases.fluid, "pore_pressure");
  for (std::size_t p = 0; p < phases.fluid.size(); ++p)
    EXPECT_NEAR(pf[p], rho_w * g * (1.5 - phases.fluid.points[p][1]), 1e-6);
}

TEST(InitialState, ConstantPorePressureAndPorosityOverride) {
  const json initial = {{"pore_pressure", 1.0e4}, {"porosity", 0.25}};
  const PointCloud c = swmpm::pre::seed_phases(parse(saturated_box("explicit-single-point", initial))).solid;
  const double V = 0.05 * 0.05;  // m^2 per metre
  for (std::size_t p = 0; p < c.size(); ++p) {
    EXPECT_EQ(values(c, "pore_pressure")[p], 1.0e4);
    EXPECT_EQ(values(c, "porosity")[p], 0.25);
    EXPECT_NEAR(values(c, "mass")[p], 0.75 * rho_s * V, 1e-12);
    EXPECT_NEAR(values(c, "fluid_mass")[p], 0.25 * rho_w * V, 1e-12);
  }
}

// ---- particle files per formulation -------------------------------------------------------------

TEST(Seeding, SinglePointWritesThePoreFluidOnTheSolidSet) {
  const json initial = {{"pore_pressure", "hydrostatic"}};
  const fs::path run = preprocess_into(saturated_box("explicit-single-point", initial), "single");
  EXPECT_FALSE(fs::exists(run / "particles" / "fluid.vtu"));
  const PointCloud c = swmpm::scene::read_vtu((run / "particles" / "solid.vtu").string());
  ASSERT_EQ(c.size(), 10u * 20u * 4u);
  const double V = 0.05 * 0.05;
  for (std::size_t p = 0; p < c.size(); ++p) {
    EXPECT_NEAR(values(c, "mass")[p], (1 - n0) * rho_s * V, 1e-12);
    EXPECT_NEAR(values(c, "fluid_mass")[p], n0 * rho_w * V, 1e-12);
    EXPECT_EQ(values(c, "porosity")[p], n0);
    EXPECT_EQ(values(c, "fluid_material")[p], 3.0);
    EXPECT_NEAR(values(c, "pore_pressure")[p], rho_w * g * (2.0 - c.points[p][1]), 1e-9);
  }
  // The solver reads it as a two-phase set.
  const auto ps = swmpm::particles_from_cloud<2>(c, "solid.vtu");
  EXPECT_TRUE(ps.two_phase());
  EXPECT_NEAR(ps.p[0], rho_w * g * (2.0 - c.points[0][1]), 1e-9);
}

TEST(Seeding, DoublePointWritesCoincidentSolidAndFluidSets) {
  const fs::path run =
      preprocess_into(saturated_box("semi-implicit-double-point", {{"pore_pressure", "hydrostatic"}}), "double");
  const PointCloud s = swmpm::scene::read_vtu((run / "particles" / "solid.vtu").string());
  const PointCloud f = swmpm::scene::read_vtu((run / "particles" / "fluid.vtu").string());
  ASSERT_EQ(s.size(), 800u);
  ASSERT_EQ(f.size(), s.size());
  EXPECT_EQ(s.find("fluid_mass"), nullptr) << "the water of a double-point set is on its own points";
  ASSERT_NE(s.find("pore_pressure"), nullptr) << "the soil points carry the initial pore pressure (for output)";
  for (std::size_t p = 0; p < s.size(); ++p)
    EXPECT_EQ(s.get("pore_pressure", "s").values[p], f.get("pore_pressure", "f").values[p]);
  for (const char* name : {"id", "mass", "volume", "half_size", "velocity", "pore_pressure", "porosity", "material",
                           "body", "faces"})
    EXPECT_NE(f.find(name), nullptr) << name;
  const double V = 0.05 * 0.05;
  for (std::size_t p = 0; p < s.size(); ++p) {
    EXPECT_EQ(s.points[p], f.points[p]);
    EXPECT_NEAR(values(s, "mass")[p], (1 - n0) * rho_s * V, 1e-12);
    EXPECT_NEAR(values(f, "mass")[p], n0 * rho_w * V, 1e-12);
    EXPECT_EQ(values(s, "porosity")[p], n0);
    EXPECT_EQ(values(f, "porosity")[p], n0);
    EXPECT_EQ(values(f, "material")[p], 3.0);
    EXPECT_EQ(values(f, "faces")[p], values(s, "faces")[p]);
    EXPECT_EQ(values(f, "volume")[p], values(s, "volume")[p]);
    EXPECT_NEAR(values(f, "pore_pressure")[p], rho_w * g * (2.0 - f.points[p][1]), 1e-9);
  }
}

TEST(Seeding, FreeWaterIsFluidParticlesOnly) {
  // A run directory that held a saturated scene's solid.vtu before: it must not survive. In
  // explicit-double-point: semi-implicit-double-point refuses free water (issue 27, item 8).
  json sat = saturated_box("explicit-double-point", json::object());
  const fs::path first = preprocess_into(sat, "free-water");
  ASSERT_TRUE(fs::exists(first / "particles" / "solid.vtu"));

  json j = base_scene("explicit-double-point");
  j["bodies"] = json::array({box_body("lake", 0, 0, 2, 1)});
  j["bodies"][0]["fluid"] = "water";
  j["bodies"][0]["initial"] = {{"pore_pressure", "hydrostatic"}};
  std::ofstream(first.parent_path() / "scene.json") << j.dump(2);
  // The folder holds a run: preprocess replaces it only when asked to (--overwrite).
  EXPECT_THROW(swmpm::pre::preprocess((first.parent_path() / "scene.json").string(), first.string(), true),
               swmpm::files::RunDirectoryError);
  const fs::path run =
      swmpm::pre::preprocess((first.parent_path() / "scene.json").string(), first.string(), {true, true, false});
  EXPECT_FALSE(fs::exists(run / "particles" / "solid.vtu"));
  const PointCloud f = swmpm::scene::read_vtu((run / "particles" / "fluid.vtu").string());
  ASSERT_EQ(f.size(), 20u * 10u * 4u);
  for (std::size_t p = 0; p < f.size(); ++p) {
    EXPECT_EQ(values(f, "porosity")[p], 1.0);
    EXPECT_NEAR(values(f, "mass")[p], rho_w * 0.05 * 0.05, 1e-12);
    EXPECT_NEAR(values(f, "pore_pressure")[p], rho_w * g * (1.0 - f.points[p][1]), 1e-9);
  }
}

TEST(Seeding, SinglePointRefusesFreeWaterButMpmFemLeavesItToTheGrid) {
  json j = base_scene("explicit-single-point");
  j["bodies"] = json::array({box_body("sand", 0, 0, 1, 1), box_body("lake", 0, 1, 1, 1.5)});
  j["bodies"][0]["solid"] = "sand";
  j["bodies"][0]["fluid"] = "water";
  j["bodies"][1]["fluid"] = "water";
  const std::string e = seeding_error(j);
  EXPECT_NE(e.find("scene.json: /bodies/1: body \"lake\" is free water"), std::string::npos) << e;
  EXPECT_NE(e.find("explicit-double-point"), std::string::npos) << e;

  j["formulation"] = "mpm-fem";
  j["materials"][3].erase("bulk_modulus");  // incompressible water: mpm-fem refuses the key
  j["grid"]["shape_function"] = "bspline2";
  const auto phases = swmpm::pre::seed_phases(parse(j));
  EXPECT_EQ(phases.solid.size(), 10u * 10u * 4u);  // the sand only
  EXPECT_EQ(phases.fluid.size(), 0u);
  ASSERT_EQ(phases.notes.size(), 1u);
  EXPECT_NE(phases.notes[0].find("\"lake\" is free water: mpm-fem models it on the grid"), std::string::npos);
  EXPECT_NE(phases.solid.find("fluid_mass"), nullptr);
}

TEST(Seeding, DryOutputKeepsItsArrays) {
  const json scene = [] {
    std::ifstream in(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json");
    return json::parse(in);
  }();
  const fs::path run = preprocess_into(scene, "dry");
  EXPECT_FALSE(fs::exists(run / "particles" / "fluid.vtu"));
  const PointCloud c = swmpm::scene::read_vtu((run / "particles" / "solid.vtu").string());
  std::vector<std::string> names;
  for (const auto& a : c.arrays) names.push_back(a.name);
  EXPECT_EQ(names, (std::vector<std::string>{"id", "mass", "volume", "half_size", "velocity", "stress", "material",
                                             "body", "faces"}));
  ASSERT_EQ(c.size(), 2u * 20u * 4u);
  for (std::size_t p = 0; p < c.size(); ++p) {
    EXPECT_DOUBLE_EQ(values(c, "mass")[p], 1800.0 * 0.025 * 0.025);
    EXPECT_EQ(values(c, "stress")[6 * p + 1], 0.0);
  }
}

// ---- the solver starts at rest from it ----------------------------------------------------------

/// Largest |displacement| [m] and largest relative change of `field` over the run's last frame.
std::pair<double, double> drift(const fs::path& run, const std::string& field) {
  const auto entries = swmpm::scene::read_pvd((run / "output" / "results.pvd").string());
  const PointCloud first = swmpm::scene::read_vtu((run / "output" / entries.front().file).string());
  const PointCloud last = swmpm::scene::read_vtu((run / "output" / entries.back().file).string());
  double disp = 0.0, change = 0.0, scale = 0.0;
  for (double v : values(last, "displacement")) disp = std::max(disp, std::abs(v));
  for (std::size_t k = 0; k < values(first, field).size(); ++k) {
    change = std::max(change, std::abs(values(last, field)[k] - values(first, field)[k]));
    scale = std::max(scale, std::abs(values(first, field)[k]));
  }
  return {disp, change / scale};
}

TEST(InitialState, GeostaticAndHydrostaticColumnIsAtRestInTheSolver) {
  // A saturated column, rollers on the sides: with sigma'_h = k0 sigma'_v and k0 = nu / (1 - nu)
  // nothing should move; without the hydrostatic pressure it would (checked below).
  json j = saturated_box("explicit-single-point", {{"stress", "geostatic"}, {"k0", 0.3 / 0.7},
                                                   {"pore_pressure", "hydrostatic"}});
  j["grid"] = {{"cell_size", 0.1}, {"min", {0.0, 0.0}}, {"max", {0.2, 2.2}}};
  j["bodies"][0]["geometry"]["max"] = {0.2, 2.0};
  j["boundaries"] = json::array({json{{"on", "x_min"}, {"solid", "roller"}, {"fluid", "impermeable"}},
                                 json{{"on", "x_max"}, {"solid", "roller"}, {"fluid", "impermeable"}},
                                 json{{"on", "y_min"}, {"solid", "fixed"}, {"fluid", "impermeable"}}});
  j["time"] = {{"end", 0.01}, {"dt", 2e-5}};
  const fs::path run = preprocess_into(j, "at-rest");
  ASSERT_EQ(swmpm::solve(run.string(), {1, true}), 0);
  const auto [disp, dp] = drift(run, "pore_pressure");
  std::printf("geostatic + hydrostatic column after 500 steps: max |u| = %.2e m, max |dp|/p = %.2e\n", disp, dp);
  EXPECT_LT(disp, 1e-9);
  EXPECT_LT(dp, 1e-6);

  j["bodies"][0]["initial"]["pore_pressure"] = 0.0;  // the same column out of balance
  const fs::path unbalanced = preprocess_into(j, "not-at-rest");
  ASSERT_EQ(swmpm::solve(unbalanced.string(), {1, true}), 0);
  EXPECT_GT(drift(unbalanced, "pore_pressure").first, 1e-7);
}

// ---- errors -------------------------------------------------------------------------------------

TEST(InitialState, GeostaticNeedsVerticalGravity) {
  json j = base_scene("dry");
  j["bodies"] = json::array({box_body("ground", 0, 0, 1, 1)});
  j["bodies"][0]["solid"] = "soil";
  j["bodies"][0]["initial"] = {{"stress", "geostatic"}};
  j["gravity"] = {0.0, 0.0};
  std::string e = seeding_error(j);
  EXPECT_NE(e.find("scene.json: /bodies/0/initial/stress: got \"geostatic\" with zero gravity"), std::string::npos) << e;

  j["gravity"] = {1.0, -9.81};
  e = seeding_error(j);
  EXPECT_NE(e.find("scene.json: /gravity: got [1, -9.81], expected gravity along -y"), std::string::npos) << e;

  // Nothing is written when seeding fails.
  j["gravity"] = {0.0, 0.0};
  EXPECT_THROW(preprocess_into(j, "zero-gravity"), swmpm::scene::SceneError);
  EXPECT_FALSE(fs::exists(fs::path(::testing::TempDir()) / "swmpm-tests" / "initial-zero-gravity" / "run"));
}

TEST(InitialState, FreeWaterHasNoSkeletonStress) {
  json j = base_scene("explicit-double-point");
  j["bodies"] = json::array({box_body("lake", 0, 0, 1, 1)});
  j["bodies"][0]["fluid"] = "water";
  j["bodies"][0]["initial"] = {{"stress", "geostatic"}};
  const std::string e = seeding_error(j);
  EXPECT_NE(e.find("scene.json: /bodies/0/initial/stress: body \"lake\" is free water"), std::string::npos) << e;
}

}  // namespace
