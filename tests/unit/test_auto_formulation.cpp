// `"formulation": "auto"` (scene/auto_formulation.hpp, issue 26 item 1): each branch of the rule on a
// scene built for it, the single-point estimates against hand values of the step limits, the choice
// flipping with the numbers that decide it, and a key the chosen formulation does not read.
// Parsing only: no files but the examples read.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "scene/auto_formulation.hpp"
#include "scene/budget.hpp"
#include "scene/formulations.hpp"
#include "scene/scene.hpp"

namespace {

using nlohmann::json;
using namespace swmpm::scene;

json example(const std::string& name) {
  std::ifstream in(SWMPM_SOURCE_DIR "/examples/" + name + "/scene.json");
  return json::parse(in);
}

/// examples/terzaghi with "auto", dt "auto" and no formulation-specific switches: a 1 m column of
/// sand (E 10 MPa, nu 0, n 0.3, grains 2650 kg/m^3) with water (K_f 2.2 GPa), cells 0.05 m, 1 s.
json terzaghi_auto() {
  json s = example("terzaghi");
  s["formulation"] = "auto";
  s["time"] = {{"end", 1.0}};
  s.erase("solver");
  return s;
}

const FormulationEstimate& estimate_of(const FormulationChoice& c, Formulation f) {
  for (const auto& e : c.estimates)
    if (e.formulation == f) return e;
  throw std::logic_error("no estimate of " + to_string(f));
}

/// The choice as the parser made it, recomputed from the parsed scene (the same function).
FormulationChoice choice(const json& j) { return choose_formulation(parse_scene(j, "t.json")); }

}  // namespace

TEST(AutoFormulation, NoFluidIsDry) {
  json s = example("elastic-column");
  s["formulation"] = "auto";
  const Scene sc = parse_scene(s, "t.json");
  EXPECT_EQ(sc.formulation, Formulation::dry);
  EXPECT_EQ(sc.formulation_choice["rule"], "dry");
  EXPECT_TRUE(sc.formulation_choice["automatic"].get<bool>());
  EXPECT_FALSE(sc.formulation_choice.contains("estimates"));
  EXPECT_NE(sc.formulation_reason.find("no body has a fluid"), std::string::npos);
}

// The Terzaghi column: the undrained wave (K_f/n = 7.3 GPa against the skeleton's 10 MPa) is 27
// times the skeleton's, a semi-implicit step costs 1.2 / 0.35 = 3.4 explicit ones: semi-implicit
// reaches 1 s about 8 times sooner. Both estimates against the step limits by hand.
TEST(AutoFormulation, TerzaghiColumnTakesTheCheaperSinglePoint) {
  const Scene s = parse_scene(terzaghi_auto(), "t.json");
  const FormulationChoice c = choose_formulation(s);
  ASSERT_EQ(c.estimates.size(), 2u);
  const double n = 0.3, rho_sat = (1.0 - n) * 2650.0 + n * 1000.0, M = 1e7, Kf = 2.2e9, h = 0.05, cfl = 0.5;
  const FormulationEstimate& e = estimate_of(c, Formulation::explicit_single_point);
  const FormulationEstimate& i = estimate_of(c, Formulation::semi_implicit_single_point);
  EXPECT_NEAR(e.wave_speed, std::sqrt((M + Kf / n) / rho_sat), 1e-9 * e.wave_speed);
  EXPECT_NEAR(i.wave_speed, std::sqrt(M / rho_sat), 1e-9 * i.wave_speed);
  EXPECT_NEAR(e.dt, cfl * h / e.wave_speed, 1e-12);
  EXPECT_NEAR(i.dt, cfl * h / i.wave_speed, 1e-12);
  EXPECT_DOUBLE_EQ(e.steps, std::ceil(1.0 / e.dt));
  EXPECT_DOUBLE_EQ(e.us_per_point_step, row_of(Formulation::explicit_single_point).cost.us_per_point_step);
  EXPECT_DOUBLE_EQ(i.us_per_point_step, row_of(Formulation::semi_implicit_single_point).cost.us_per_point_step);
  // 0.1 x 1.0 m at 2 x 2 per 0.05 m cell: 160 particles, one set in both.
  EXPECT_NEAR(c.points, 160.0, 1e-9);
  EXPECT_NEAR(e.points, 160.0, 1e-9);
  EXPECT_NEAR(i.points, 160.0, 1e-9);
  EXPECT_LT(i.wall_seconds, e.wall_seconds / 5.0);
  EXPECT_EQ(s.formulation, Formulation::semi_implicit_single_point);
  EXPECT_EQ(c.chosen, s.formulation);
  EXPECT_EQ(s.formulation_choice["rule"], "pore water");
  EXPECT_EQ(s.formulation_choice["estimates"].size(), 2u);
  // The reason names both and the ratio of the wave speeds.
  EXPECT_NE(s.formulation_reason.find("\"explicit-single-point\""), std::string::npos) << s.formulation_reason;
  EXPECT_NE(s.formulation_reason.find("27.1 times faster"), std::string::npos) << s.formulation_reason;
  // The switches take the chosen formulation's defaults.
  EXPECT_EQ(s.solver.continuity, "conservative");
}

// The choice flips where the numbers say it should: the step ratio sqrt(1 + K_f / (n M)) against the
// cost ratio of a step. Gassy pore water (K_f 10 MPa) or a stiff skeleton (E 2 GPa) make the
// undrained wave barely faster than the skeleton's: explicit is cheaper. A fixed dt below both
// limits gives both the same steps: the cheaper step wins.
TEST(AutoFormulation, TheSinglePointChoiceFlipsWithTheNumbers) {
  const auto chosen_by_cost = [](const FormulationChoice& c) {
    const auto& e = estimate_of(c, Formulation::explicit_single_point);
    const auto& i = estimate_of(c, Formulation::semi_implicit_single_point);
    return e.wall_seconds <= i.wall_seconds ? e.formulation : i.formulation;
  };
  json gassy = terzaghi_auto();
  gassy["materials"][1]["bulk_modulus"] = 1e7;
  json stiff = terzaghi_auto();
  stiff["materials"][0]["youngs_modulus"] = 2e9;
  json fixed = terzaghi_auto();
  fixed["time"]["dt"] = 1e-5;
  for (const json& j : {gassy, stiff, fixed}) {
    const FormulationChoice c = choice(j);
    EXPECT_EQ(c.chosen, Formulation::explicit_single_point) << c.reason;
    EXPECT_EQ(c.chosen, chosen_by_cost(c));
    EXPECT_EQ(parse_scene(j, "t.json").formulation, Formulation::explicit_single_point);
  }
  EXPECT_DOUBLE_EQ(estimate_of(choice(fixed), Formulation::explicit_single_point).dt, 1e-5);
  EXPECT_DOUBLE_EQ(estimate_of(choice(fixed), Formulation::semi_implicit_single_point).dt, 1e-5);
  // Sweep the skeleton's stiffness: one switch from semi-implicit (soft) to explicit (stiff), where
  // the estimates cross.
  int switches = 0;
  Formulation last = Formulation::semi_implicit_single_point;
  for (double E = 1e6; E <= 1e11; E *= 2.0) {
    json j = terzaghi_auto();
    j["materials"][0]["youngs_modulus"] = E;
    const FormulationChoice c = choice(j);
    EXPECT_EQ(c.chosen, chosen_by_cost(c)) << "E " << E;
    if (c.chosen != last) ++switches;
    last = c.chosen;
  }
  EXPECT_EQ(switches, 1);
  EXPECT_EQ(last, Formulation::explicit_single_point);
}

// A candidate the scene's own checks refuse is not chosen, however cheap: one point per cell with
// B-splines diverges in the semi-implicit formulations, so the column goes explicit and says why.
TEST(AutoFormulation, ACandidateTheSceneCannotRunIsLeftOut) {
  json j = terzaghi_auto();
  j["grid"]["shape_function"] = "bspline2";
  j["bodies"][0]["particles_per_cell"] = 1;
  const FormulationChoice c = choice(j);
  ASSERT_EQ(c.estimates.size(), 2u);
  EXPECT_LT(estimate_of(c, Formulation::semi_implicit_single_point).wall_seconds,
            estimate_of(c, Formulation::explicit_single_point).wall_seconds);
  EXPECT_EQ(c.chosen, Formulation::explicit_single_point);
  EXPECT_NE(c.reason.find("\"semi-implicit-single-point\" is left out"), std::string::npos) << c.reason;
  j["bodies"][0]["particles_per_cell"] = 2;
  EXPECT_EQ(choice(j).chosen, Formulation::semi_implicit_single_point);
}

// Free water: a water column on a thin bed is mostly water, under gravity: mpm-fem on B-splines,
// explicit-double-point on GIMP (mpm-fem needs B-splines) and when the water is the smaller part.
TEST(AutoFormulation, FreeWaterTakesADoublePointOrMpmFem) {
  json s = example("dam-break-double-point");
  s["formulation"] = "auto";
  s.erase("solver");
  ASSERT_EQ(s["grid"]["shape_function"], "gimp");
  // The example is free water alone (0.057 x 0.114 m): explicit-double-point on GIMP.
  Scene sc = parse_scene(s, "t.json");
  EXPECT_EQ(sc.formulation, Formulation::explicit_double_point);
  EXPECT_EQ(sc.formulation_choice["rule"], "free water");
  EXPECT_NE(sc.formulation_reason.find("\"bspline2\""), std::string::npos) << sc.formulation_reason;
  s["grid"]["shape_function"] = "bspline2";
  for (auto& m : s["materials"]) m.erase("bulk_modulus");  // mpm-fem's water is incompressible
  s["output"].erase("monitors");                           // they follow water points
  sc = parse_scene(s, "t.json");
  EXPECT_EQ(sc.formulation, Formulation::mpm_fem) << sc.formulation_reason;
  // A saturated bed 0.4 x 0.1 m under the 0.0065 m^2 column: mostly soil, explicit-double-point.
  json bed = example("dam-break-double-point");
  bed["formulation"] = "auto";
  bed.erase("solver");
  bed["grid"]["max"] = {0.4, 0.3};
  bed["materials"].push_back({{"name", "sand"}, {"model", "linear-elastic"}, {"grain_density", 2650.0},
                              {"porosity", 0.4}, {"youngs_modulus", 1e7}, {"poisson_ratio", 0.3},
                              {"hydraulic_conductivity", 1e-3}});
  bed["bodies"][0]["geometry"] = {{"type", "box"}, {"min", {0.0, 0.1}}, {"max", {0.05715, 0.2143}}};
  bed["bodies"].push_back({{"name", "bed"}, {"geometry", {{"type", "box"}, {"min", {0.0, 0.0}}, {"max", {0.4, 0.1}}}},
                           {"solid", "sand"}, {"fluid", bed["bodies"][0]["fluid"]}});
  sc = parse_scene(bed, "t.json");
  EXPECT_EQ(sc.formulation, Formulation::explicit_double_point) << sc.formulation_reason;
  EXPECT_NE(sc.formulation_reason.find("mostly free water"), std::string::npos) << sc.formulation_reason;
}

// Saturated Nor-Sand can liquefy: a double-point formulation, the cheaper of the two. The loose
// landslide (seed 001's B5, which runs semi-implicit-double-point): water of K_f 2.2 GPa over a soft
// skeleton makes the explicit step far smaller than the skeleton's.
TEST(AutoFormulation, SoilThatCanLiquefyTakesTheCheaperDoublePoint) {
  json s = json::parse(std::ifstream(SWMPM_SOURCE_DIR "/examples/landslide-nor-sand/scene-loose.json"));
  s["formulation"] = "auto";
  const Scene sc = parse_scene(s, "t.json");
  EXPECT_EQ(sc.formulation_choice["rule"], "liquefiable");
  const FormulationChoice c = choose_formulation(sc);
  ASSERT_EQ(c.estimates.size(), 2u);
  const auto& e = estimate_of(c, Formulation::explicit_double_point);
  const auto& i = estimate_of(c, Formulation::semi_implicit_double_point);
  EXPECT_GT(e.wave_speed, 5.0 * i.wave_speed);
  EXPECT_EQ(sc.formulation, Formulation::semi_implicit_double_point) << sc.formulation_reason;
  EXPECT_LT(i.wall_seconds, e.wall_seconds);
  EXPECT_NE(sc.formulation_reason.find("can liquefy"), std::string::npos) << sc.formulation_reason;
}

// A body with a water table carries water points below the table only (issue 26 item 3): the
// double-point candidates' estimates count them so. A box 2 x 1 m with the table at 0.25 m carries
// 1.25 points per particle, not 2; a right triangle with legs 2 and 1 m (the right angle at the
// origin) clipped at y = 0.5 keeps 3/4 of its area below, so 1.75.
TEST(AutoFormulation, WaterPointsOnlyBelowTheWaterTable) {
  json s = json::parse(std::ifstream(SWMPM_SOURCE_DIR "/examples/landslide-nor-sand/scene-loose.json"));
  s["formulation"] = "auto";
  s["grid"]["min"] = {0.0, 0.0};
  s["grid"]["max"] = {2.5, 1.5};
  s["boundaries"] = json::array();
  auto& body = s["bodies"][0];
  body["geometry"] = {{"type", "box"}, {"min", {0.0, 0.0}}, {"max", {2.0, 1.0}}};
  body["initial"]["pore_pressure"] = "hydrostatic";
  auto points_of = [&](const json& j, Formulation f) {
    const FormulationChoice c = choose_formulation(parse_scene(j, "t.json"));
    EXPECT_EQ(c.rule, "liquefiable");
    return estimate_of(c, f).points / c.points;
  };
  EXPECT_NEAR(points_of(s, Formulation::explicit_double_point), 2.0, 1e-12);  // saturated to the top
  body["initial"]["water_table"] = 0.25;
  EXPECT_NEAR(points_of(s, Formulation::explicit_double_point), 1.25, 1e-12);
  EXPECT_NEAR(points_of(s, Formulation::semi_implicit_double_point), 1.25, 1e-12);
  body["initial"]["water_table"] = -1.0;  // below the body: refused by preprocess, counted dry here
  EXPECT_NEAR(points_of(s, Formulation::explicit_double_point), 1.0, 1e-12);
  body["geometry"] = {{"type", "polygon"}, {"vertices", {{0.0, 0.0}, {2.0, 0.0}, {0.0, 1.0}}}};
  body["initial"]["water_table"] = 0.5;
  EXPECT_NEAR(points_of(s, Formulation::explicit_double_point), 1.75, 1e-12);
}

// A key only the formulation auto did not choose reads: an error naming the key's path, the
// chosen formulation, and that auto chose it.
TEST(AutoFormulation, AKeyTheChosenFormulationDoesNotReadIsAnError) {
  json s = terzaghi_auto();
  s["solver"] = {{"stabilisation", {{"strain_smoothing", true}}}};
  try {
    (void)parse_scene(s, "t.json");
    FAIL() << "expected a SceneError";
  } catch (const SceneError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("t.json: /solver/stabilisation/strain_smoothing: got true, but semi-implicit-single-point does "
                     "not read this switch"),
              std::string::npos) << m;
    EXPECT_NE(m.find("was chosen automatically by \"auto\""), std::string::npos) << m;
  }
  // Named, the same key is fine.
  s["formulation"] = "explicit-single-point";
  EXPECT_NO_THROW((void)parse_scene(s, "t.json"));
}

// The resolved scene (preprocess's RUN_DIR/scene.json) names the chosen formulation and keeps how
// auto chose; it parses back to the same.
TEST(AutoFormulation, TheResolvedSceneKeepsTheChoice) {
  const Scene s = parse_scene(terzaghi_auto(), "t.json");
  const json resolved = to_json(s);
  EXPECT_EQ(resolved["formulation"], "semi-implicit-single-point");
  EXPECT_EQ(resolved["formulation_choice"]["chosen"], "semi-implicit-single-point");
  EXPECT_TRUE(resolved["formulation_choice"]["automatic"].get<bool>());
  const Scene r = parse_scene(resolved, "scene.json");
  EXPECT_EQ(r.formulation, Formulation::semi_implicit_single_point);
  EXPECT_EQ(r.formulation_choice, s.formulation_choice);
  EXPECT_EQ(to_json(r), resolved);
  const auto lines = explain_lines(choice_of(r));
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_NE(lines[1].find("estimate explicit-single-point: dt "), std::string::npos) << lines[1];
  EXPECT_NE(lines[2].find("estimate semi-implicit-single-point: dt "), std::string::npos) << lines[2];
}

// mpm-fem's grid work runs once per fluid step: with solver.soil_substeps k the estimate's
// per-node part is divided by k, its per-point part is not (the D4 run at 4 mm with k = 3 was
// estimated as if k were 1: 5.86 h).
TEST(RunEstimate, MpmFemCountsTheGridOncePerFluidStep) {
  json j = example("terzaghi-mpm-fem");
  const Scene one = parse_scene(j, "t.json");
  j["solver"]["soil_substeps"] = 3;
  const Scene three = parse_scene(j, "t.json");
  const double points = 1000.0;
  const double us1 = step_microseconds(one, Formulation::mpm_fem, points);
  const double us3 = step_microseconds(three, Formulation::mpm_fem, points);
  const double fixed = step_microseconds(one, Formulation::mpm_fem, 0.0) - 20.0;  // the grid's part at k = 1
  EXPECT_GT(fixed, 0.0);
  EXPECT_NEAR(us1 - us3, fixed * (1.0 - 1.0 / 3.0), 1e-9 * us1);
  // Other formulations do not read the key: their estimate is unchanged by it.
  EXPECT_DOUBLE_EQ(step_microseconds(three, Formulation::explicit_double_point, points),
                   step_microseconds(one, Formulation::explicit_double_point, points));
}

// preprocess's memory check counts a double-point body's water points below its water table
// only (BodyCount::wet, sampled with the body's particles): a million particles of which none are
// wet fit where a fully saturated million would not.
TEST(RunEstimate, MemoryCheckCountsWaterPointsBelowTheWaterTableOnly) {
  json s = json::parse(std::ifstream(SWMPM_SOURCE_DIR "/examples/landslide-nor-sand/scene-loose.json"));
  s["formulation"] = "explicit-double-point";
  const Scene sc = parse_scene(s, "t.json");
  const double particles = 1e6;
  const MemoryLimit limit{run_memory(sc, 1.5 * particles), "the test's limit"};
  EXPECT_NO_THROW(check_memory(sc, "t.json", {BodyCount{particles, particles, 0.0}}, limit));
  EXPECT_NO_THROW(check_memory(sc, "t.json", {BodyCount{particles, particles, 0.4 * particles}}, limit));
  EXPECT_THROW(check_memory(sc, "t.json", {BodyCount{particles, particles, -1.0}}, limit), SceneError);
  EXPECT_THROW(check_memory(sc, "t.json", {BodyCount{particles, particles, 0.6 * particles}}, limit), SceneError);
}
