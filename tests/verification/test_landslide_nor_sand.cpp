// B5 (seed 001 §5.4): the Nor-Sand landslides of examples/landslide-nor-sand at reduced
// resolution (cells 0.05 m instead of 0.025, 2x2 points per cell instead of 3x3, dt doubled to
// 2.4e-4 s), the example's 1 s elastic initialisation (k = 1 m/s, water tied to the soil), then
// 1 s of Nor-Sand with k0 = 5e-3 m/s: single- against double-point, loose (v0 = 1.70) and dense
// (v0 = 1.55), the CSL with p in kPa as shipped.
//
// What the paper reports: loose, similar run-out in both variants; dense, double-point's run-out
// clearly longer (single-point "cannot fully generate" the slide). What this test holds is what
// swmpm does (docs/verification.md, B5): the loose half of the finding, and that the loose slope
// moves more than the dense one. The dense half is NOT reproduced: neither dense slope slides and
// the variants agree to 1 %; the dense checks below pin that measured behaviour (a change to the
// model that lets the dense slope slide will show up here), they do not claim the paper's result.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "postprocess/postprocess.hpp"
#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;

constexpr double kToe = 1.25;         // m, x of the slope's toe (geometry in the scene)
constexpr double kFoundation = 0.5;   // m, y of the foundation's surface

struct Landslide {
  double crest_dy = 0.0;  // m, the crest monitor at the end
  double run_out = 0.0;   // m, how far the slope's own points (above the foundation at t = 0) pass the toe
  double v_max = 0.0;     // m/s, fastest soil point at the end
};

Landslide run(const std::string& sand, const std::string& formulation) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/landslide-nor-sand/scene-" + sand + ".json");
  s["formulation"] = formulation;
  s["grid"]["cell_size"] = 0.05;
  s["bodies"][0]["particles_per_cell"] = 2;
  s["time"]["dt"] = 2.4e-4;
  s["time"]["end"] = 1.0;
  s["output"]["interval"] = 1.0;
  const std::string name = "b5r-" + sand + "-" + formulation;
  // One thread: 2,410 points per phase gain little from two, and ctest runs this beside another test.
  const std::string dir = swmpm::testing::run_scene(s, name, 1);
  Landslide r;
  r.crest_dy = swmpm::post::read_csv(dir + "/monitors.csv").column("crest.displacement_y").back();
  const auto f = swmpm::testing::last_frame(dir);
  const auto& u = f.get("displacement", "f").values;
  const auto& v = f.get("velocity", "f").values;
  double x_min = kToe;
  for (std::size_t q = 0; q < f.size(); ++q) {
    if (f.points[q][1] - u[3 * q + 1] > kFoundation) x_min = std::min(x_min, f.points[q][0]);
    r.v_max = std::max(r.v_max, std::hypot(v[3 * q], v[3 * q + 1]));
  }
  r.run_out = kToe - x_min;
  std::printf("B5 reduced, %s, %s: crest settlement %.4f m, run-out past the toe %.4f m, max |v| %.2e m/s at 1 s\n",
              sand.c_str(), formulation.c_str(), r.crest_dy, r.run_out, r.v_max);
  return r;
}

}  // namespace

// Measured 2026-12-02 (1 + 3 s; by 1 s the crest is within 0.1 mm of these):
//   loose: crest -0.0446 (SP) / -0.0445 m (DP), run-out 0.031 m both
//   dense: crest -0.0211 / -0.0210 m, run-out 0.007 m both
TEST(LandslideNorSand, B5ReducedSingleAgainstDoublePoint) {
  const Landslide loose_sp = run("loose", "semi-implicit-single-point");
  const Landslide loose_dp = run("loose", "semi-implicit-double-point");
  const Landslide dense_sp = run("dense", "semi-implicit-single-point");
  const Landslide dense_dp = run("dense", "semi-implicit-double-point");
  for (const Landslide* r : {&loose_sp, &loose_dp, &dense_sp, &dense_dp}) {
    EXPECT_LT(r->crest_dy, -0.005);   // every slope yields when plasticity starts
    EXPECT_LT(r->v_max, 0.01);        // and is nearly static by 1 s (measured <= 1.7e-3 m/s; paper: 6 s loose, 12 s dense)
  }
  // The paper's loose finding: similar run-out and crest settlement in both variants.
  EXPECT_NEAR(loose_dp.crest_dy, loose_sp.crest_dy, 0.03 * std::abs(loose_sp.crest_dy));
  EXPECT_NEAR(loose_dp.run_out, loose_sp.run_out, 0.005);
  // Loose moves more than dense (measured 2.1x at the crest).
  EXPECT_GT(std::abs(loose_sp.crest_dy), 1.5 * std::abs(dense_sp.crest_dy));
  EXPECT_GT(std::abs(loose_dp.crest_dy), 1.5 * std::abs(dense_dp.crest_dy));
  // Dense: swmpm's behaviour, not the paper's (see the header): the variants agree.
  EXPECT_NEAR(dense_dp.crest_dy, dense_sp.crest_dy, 0.03 * std::abs(dense_sp.crest_dy));
  EXPECT_NEAR(dense_dp.run_out, dense_sp.run_out, 0.005);
}

// The elastic initialisation without the example's damping (seed 001 has none). Nor-Sand's
// elasticity gives p_ref = 2 kPa at zero elastic strain, so the unloaded body first expands:
// stored energy goes negative and turns into motion while gravity has done almost no work. The
// energy check once read that as "creating energy" and stopped the run at step 10 (kinetic +
// stored 2.6e-4 J against an allowance of 1e-9 J). It now allows the stored energy released
// below its initial value (solver/run.cpp); this scene must run through the 1 s phase.
TEST(LandslideNorSand, UndampedElasticInitialisationIsNotStoppedByTheEnergyCheck) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/landslide-nor-sand/scene-dense.json");
  s["grid"]["cell_size"] = 0.05;
  s["bodies"][0]["particles_per_cell"] = 2;
  s["time"]["dt"] = 2.4e-4;
  s["time"]["end"] = 0.001;
  s["initialisation"]["damping"] = 0.0;
  s["output"]["interval"] = 0.0;
  s["output"]["monitor_interval"] = 2.4e-4;
  s["output"]["monitors"] = json::array({{{"name", "energy"}, {"quantities", {"kinetic_energy", "strain_energy"}}}});
  const std::string dir = swmpm::testing::run_scene(s, "b5-undamped-initialisation", 1);
  const json run = swmpm::testing::load_json(dir + "/run.json");
  ASSERT_EQ(run["status"], "completed") << run.value("diagnosis", "");
  const auto m = swmpm::post::read_csv(dir + "/monitors.csv");
  const auto& stored = m.column("energy.strain_energy");
  const auto& kinetic = m.column("energy.kinetic_energy");
  // The situation the check must tolerate did occur: in the first steps stored energy fell below
  // its initial 0 while the body gained kinetic energy.
  ASSERT_GT(stored.size(), 10u);
  EXPECT_LT(stored[10], -1e-3);
  EXPECT_GT(kinetic[10], 1e-3);
}
