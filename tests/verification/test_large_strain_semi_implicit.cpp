// B2 (seed 001 §5.2): 1D large-strain consolidation with the semi-implicit formulations.
// examples/large-strain-consolidation-semi-implicit: column 0.1 x 1.0 m, cells 0.05 m, 2x2 points
// per cell, GIMP, E = 1 MPa, nu = 0, n0 = 0.3, k0 = 1e-3 m/s with k = k0 J^2 (`xie-leo`: the law
// of Xie & Leo's closed form), incompressible water, q = 200 kPa held from t = 0, dt = 5e-4 s,
// 20 s (T_v = 2).
//
// The paper compares a "small strain" and a "finite strain" constitutive model: the first
// overestimates the settlement by about 17 % at large strain and follows Xie & Leo's closed form.
// In 1D strain with nu = 0 swmpm's two elastic laws are exactly those two readings
// (examples/large-strain-consolidation-semi-implicit/README.md):
//   linear-elastic (Jaumann rate)  sigma'_yy = E ln J    -> S_inf = H (1 - e^{-q/E}) = 0.18127 m,
//                                                          history = Xie & Leo's series
//   hencky (finite strain)         tau'_yy = E ln J      -> E ln J = -q J: S_inf = 0.15542 m
// (ratio 1.166: the paper's 17 %). References: examples/large-strain-consolidation/reference.py
// (finite volumes, 200 cells, backward Euler; its self-test matches the series to 3e-5 m) for the
// settlement of the monitored point (initial height 0.9875 m: the top particle).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "postprocess/postprocess.hpp"
#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;

constexpr const char* kDir = SWMPM_SOURCE_DIR "/examples/large-strain-consolidation-semi-implicit/";

struct B2 {
  swmpm::post::Comparison history;
  double final = 0.0;  // m, settlement of the monitored point at 20 s (positive down)
};

B2 run_b2(const std::string& scene, const std::string& formulation, const std::string& reference,
          const std::string& name) {
  json s = swmpm::testing::load_json(std::string(kDir) + scene);
  s["formulation"] = formulation;
  const std::string run = swmpm::testing::run_scene(s, name);
  B2 r;
  r.history = swmpm::post::compare(run, "top.displacement_y", std::string(kDir) + reference);
  const auto t = swmpm::post::read_csv(run + "/monitors.csv");
  r.final = -t.column("top.displacement_y").back();
  std::printf("B2 %s, %s: settlement at 20 s %.5f m; history vs %s: relative L2 %.3f %%, max |error| %.2e m at %.2f s\n",
              formulation.c_str(), scene.c_str(), r.final, reference.c_str(), 100 * r.history.rel_l2,
              r.history.max_abs, r.history.max_abs_time);
  return r;
}

/// The reference's settlement at its last row (20 s).
double reference_final(const std::string& reference) {
  const auto c = swmpm::post::read_reference(std::string(kDir) + reference);
  return -c.v.back();
}

}  // namespace

// Measured (single-point, conservative continuity): hencky 0.15298 m at 20 s vs 0.15333 (-0.2 %),
// history 1.17 % relative L2 (max error 2.2 mm at 0.02 s, the first cell's sub-cell boundary
// layer); linear-elastic 0.17807 vs 0.17802 (+0.03 %), 1.03 %; ratio 1.164 vs 1.161.
TEST(LargeStrainSemiImplicit, B2FiniteAndSmallStrainSettlementsSinglePoint) {
  const B2 finite = run_b2("scene.json", "semi-implicit-single-point", "reference-monitor-settlement-hencky.csv",
                           "b2-sp-finite");
  const B2 small = run_b2("scene-small-strain.json", "semi-implicit-single-point",
                          "reference-monitor-settlement-small-strain.csv", "b2-sp-small");
  const double ref_finite = reference_final("reference-monitor-settlement-hencky.csv");
  const double ref_small = reference_final("reference-monitor-settlement-small-strain.csv");
  std::printf("references at 20 s: hencky %.5f m, linear-elastic (Xie & Leo) %.5f m; ratio run %.4f, reference %.4f\n",
              ref_finite, ref_small, small.final / finite.final, ref_small / ref_finite);
  EXPECT_NEAR(finite.final, ref_finite, 0.02 * ref_finite);  // issue 5: within 2 %
  EXPECT_NEAR(small.final, ref_small, 0.02 * ref_small);
  EXPECT_LT(finite.history.rel_l2, 0.03);
  EXPECT_LT(small.history.rel_l2, 0.03);
  // The paper's finding: the small-strain reading settles about 17 % more.
  EXPECT_NEAR(small.final / finite.final, ref_small / ref_finite, 0.02);
  EXPECT_GT(small.final / finite.final, 1.12);
}

// The mixture volume balance in the paper's non-conservative form (1 - n) div v_s + n div v_w
// drops (v_w - v_s) . grad n; at large strain the drained top compacts (n 0.30 -> 0.15) and the
// dropped term is as large as the rest, so the column consolidates faster than Darcy flow allows.
// Measured: relative L2 14 % over 0-3 s with cells 0.05, 0.025 and 0.0125 m alike (not a
// resolution effect); conservative 0.4 %.
TEST(LargeStrainSemiImplicit, B2NonConservativeContinuityConsolidatesTooFast) {
  json s = swmpm::testing::load_json(std::string(kDir) + "scene-small-strain.json");
  s["solver"]["continuity"] = "non-conservative";
  s["time"]["end"] = 3.0;
  const std::string run = swmpm::testing::run_scene(s, "b2-sp-nonconservative");
  const auto c = swmpm::post::compare(run, "top.displacement_y", std::string(kDir) + "reference-monitor-settlement-small-strain.csv");
  std::printf("B2 non-conservative continuity, 0-3 s: relative L2 %.2f %%\n", 100 * c.rel_l2);
  EXPECT_GT(c.rel_l2, 0.08);
}

// Double-point (seed 001's own variant) with `solver.escaped_water: remove` and 4x4 points per
// cell (examples/large-strain-consolidation-semi-implicit/scene-double-point.json). The water
// squeezed out of the drained top leaves the run instead of floating above the soil as a sheet
// thinner than a cell (which cut the soil off its drained top: the run diverged at 0.0985 s);
// with 2x2 points per cell the water points thin out and bunch under the large outflow (history
// 9.4 %). Measured 2026-12-02: hencky 0.15407 m (+0.5 %), history 1.40 %; linear-elastic 0.18000 m
// (+1.1 %), 1.99 %; ratio 1.168 (reference 1.161); removed water 15.75 / 17.63 kg per metre
// against rho_w x width x settlement of the top particle 15.41 / 18.00 kg.
TEST(LargeStrainSemiImplicit, B2DoublePointWithEscapedWaterRemoved) {
  auto run_dp = [](const std::string& material, const std::string& reference, const std::string& name) {
    json s = swmpm::testing::load_json(std::string(kDir) + "scene-double-point.json");
    s["materials"][0]["model"] = material;
    const std::string run = swmpm::testing::run_scene(s, name);
    const auto rj = swmpm::testing::load_json(run + "/run.json");
    EXPECT_EQ(rj["status"], "completed") << material;
    B2 r;
    r.history = swmpm::post::compare(run, "top.displacement_y", std::string(kDir) + reference);
    const auto t = swmpm::post::read_csv(run + "/monitors.csv");
    r.final = -t.column("top.displacement_y").back();
    // Mass balance of the mixture: with incompressible constituents the column loses exactly the
    // water that left, rho_w x width x settlement (the top particle stands for the surface here
    // to a quarter of a point spacing of strain: < 0.5 %).
    const double removed = rj["counters"]["escaped_water_mass"].get<double>();
    const double lost = 1000.0 * 0.1 * r.final;
    std::printf("B2 double-point %s: settlement %.5f m, history %.2f %%, removed water %.3f kg/m vs %.3f\n",
                material.c_str(), r.final, 100 * r.history.rel_l2, removed, lost);
    EXPECT_NEAR(removed, lost, 0.03 * lost) << material;
    return r;
  };
  const B2 finite = run_dp("hencky", "reference-monitor-settlement-hencky.csv", "b2-dp-finite");
  const B2 small = run_dp("linear-elastic", "reference-monitor-settlement-small-strain.csv", "b2-dp-small");
  const double ref_finite = reference_final("reference-monitor-settlement-hencky.csv");
  const double ref_small = reference_final("reference-monitor-settlement-small-strain.csv");
  EXPECT_NEAR(finite.final, ref_finite, 0.02 * ref_finite);
  EXPECT_NEAR(small.final, ref_small, 0.02 * ref_small);
  EXPECT_LT(finite.history.rel_l2, 0.03);
  EXPECT_LT(small.history.rel_l2, 0.03);
  EXPECT_NEAR(small.final / finite.final, ref_small / ref_finite, 0.02);
}
