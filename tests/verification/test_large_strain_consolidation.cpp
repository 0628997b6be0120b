// A2 (seed 000 §4.1.2): 1D large-strain consolidation (Xie & Leo) with explicit-single-point.
// Column 0.1 x 1.0 m as A1 (cells 0.05 m, 2x2 particles per cell, GIMP, strain smoothing; the
// seed's mfvp-constant pressure step with eq. 9, or the consistent scheme of the example: the
// cell-constant pressure with the conservative continuity), E = 1 MPa, nu = 0, n0 = 0.3, rho_s = 2650, rho_w = 1000; initial p0 = q = 200 kPa,
// sigma' = 0, a 200 kPa traction on top, no gravity; sides roller + impermeable, base fixed +
// impermeable, top drained.
//
// Final settlement (derivation: examples/large-strain-consolidation/README.md): with the Cauchy
// effective stress linear in the logarithmic strain, sigma'_yy = E ln J — what `linear-elastic`
// (Jaumann rate) integrates to in 1D strain — the end state sigma'_yy = -q gives
// J = exp(-q/E) and S_inf = H (1 - exp(-q/E)) = 0.18127 m (Xie & Leo; the paper's numerical value
// 0.1815). The `hencky` model is linear in log strain for the Kirchhoff stress (sigma = tau / J),
// so its end state solves E ln J = -q J: J = 0.84459, S_inf = 0.15541 m.
//
// The settlement is measured at the top surface: the top particle's displacement plus the
// compression of the half particle above it, u + (1 - J) l_y (l_y its initial half-size).
//
// What these runs change from the paper, to fit the default suite: K_f softened to 2.2e7 Pa
// (c_v = k / (gamma_w (m_v + n/K_f)) drops by 1.35 %, the CFL step rises 10x) and k = 1e-3 m/s
// instead of 1e-4 (ten times faster consolidation); the final settlement depends on neither. The
// paper's own parameters (K_f = 2.2 GPa, k = 1e-4, dt = 1e-5) run with the consistent scheme in
// the slow test below; with the seed's they diverge at t = 4.25 s
// (examples/large-strain-consolidation/README.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "scene/scene.hpp"
#include "support/consolidation_reference.hpp"
#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;

constexpr double H = 1.0, E = 1.0e6, q = 2.0e5;

/// The column's stabilisation: the seed's (mfvp-constant pressure step + strain smoothing, eq. 9)
/// or the consistent one (cell-constant pressure, conservative continuity with the interaction
/// force p grad n; docs/formulations.md, "Cell-constant pressure and conservative continuity").
enum class Scheme { seed, consistent, consistent_eq9 };

json scene_a2(const std::string& model, double K_f, double k, double end, double interval, double dt,
              Scheme scheme = Scheme::seed) {
  json s = json::parse(R"json({
    "name": "large-strain-consolidation", "dimension": 2, "formulation": "explicit-single-point",
    "grid": { "cell_size": 0.05, "min": [0.0, 0.0], "max": [0.1, 1.1], "shape_function": "gimp" },
    "materials": [
      { "name": "soil", "model": "linear-elastic", "grain_density": 2650.0, "porosity": 0.3,
        "youngs_modulus": 1.0e6, "poisson_ratio": 0.0, "hydraulic_conductivity": 1.0e-4 },
      { "name": "water", "model": "fluid", "density": 1000.0, "bulk_modulus": 2.2e9 } ],
    "bodies": [ { "name": "column", "geometry": { "type": "box", "min": [0.0, 0.0], "max": [0.1, 1.0] },
                  "solid": "soil", "fluid": "water", "particles_per_cell": 2, "initial": { "pore_pressure": 2.0e5 } } ],
    "boundaries": [ { "on": "x_min", "solid": "roller", "fluid": "impermeable" },
                    { "on": "x_max", "solid": "roller", "fluid": "impermeable" },
                    { "on": "y_min", "solid": "fixed", "fluid": "impermeable" } ],
    "loads": [ { "type": "traction", "body": "column", "face": "y_max", "value": [0.0, -2.0e5] } ],
    "time": { "end": 1.0, "dt": "auto", "cfl": 0.5 },
    "output": { "interval": 1.0, "monitors": [
      { "name": "top", "at": [0.05, 1.0], "phase": "solid", "quantities": ["displacement_y"] } ] },
    "solver": { "stabilisation": { "pressure": "mfvp-constant", "strain_smoothing": true } }
  })json");
  s["materials"][0]["model"] = model;
  s["materials"][0]["hydraulic_conductivity"] = k;
  s["materials"][1]["bulk_modulus"] = K_f;
  s["time"]["end"] = end;
  if (dt > 0.0) s["time"] = {{"end", end}, {"dt", dt}};
  s["output"]["interval"] = interval;
  if (scheme != Scheme::seed) s["solver"]["stabilisation"]["pressure"] = "cell-constant";
  if (scheme == Scheme::consistent) s["solver"]["continuity"] = "conservative";
  return s;
}

/// Top-surface settlement of a frame (mean over the top row of particles) and that row's initial height.
struct Top {
  double settlement, a;
};
Top top_surface(const swmpm::scene::PointCloud& f, const std::string& where) {
  const auto& d = f.get("displacement", where).values;
  const auto& J = f.get("volume_ratio", where).values;
  const auto& l = f.get("half_size", where).values;
  double a_top = -1.0;
  for (std::size_t p = 0; p < f.size(); ++p) a_top = std::max(a_top, f.points[p][1] - d[3 * p + 1]);
  double sum = 0.0;
  int count = 0;
  for (std::size_t p = 0; p < f.size(); ++p) {
    if (f.points[p][1] - d[3 * p + 1] < a_top - 1e-9) continue;
    sum += -d[3 * p + 1] + (1.0 - J[p]) * l[3 * p + 1];
    ++count;
  }
  return {sum / count, a_top};
}

double final_settlement(const std::string& run) {
  return top_surface(swmpm::testing::last_frame(run), "last frame").settlement;
}

/// Settlement of the top surface and RMS of (p - p_ref)/q of every frame after t = 0 against the
/// constant-k reference (the same continuum model solved by finite volumes,
/// tests/support/consolidation_reference.hpp). Returns the worst of each.
struct HistoryError {
  double settlement = 0.0, rms = 0.0;
};
HistoryError history_error(const std::string& run, double K_f, const char* label, double k0 = 1.0e-4,
                           bool xie_leo_k = false) {
  const auto entries = swmpm::scene::read_pvd(run + "/output/results.pvd");
  std::vector<double> times;
  for (const auto& e : entries)
    if (e.time > 0.0) times.push_back(e.time);
  swmpm::testing::LargeStrainColumn ref;
  ref.K_f = K_f;
  ref.k0 = k0;
  ref.xie_leo_k = xie_leo_k;
  const auto profiles = ref.solve(times);
  HistoryError worst;
  std::size_t k = 0;
  for (const auto& e : entries) {
    if (e.time <= 0.0) continue;
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    const auto& prof = profiles[k++];
    const Top top = top_surface(f, e.file);
    const double S_ref = ref.settlement(prof, H);
    const auto& pp = f.get("pore_pressure", e.file).values;
    const auto& d = f.get("displacement", e.file).values;
    double err2 = 0.0;
    for (std::size_t p = 0; p < f.size(); ++p)
      err2 += std::pow((pp[p] - ref.pressure(prof, f.points[p][1] - d[3 * p + 1])) / q, 2);
    const double rms = std::sqrt(err2 / static_cast<double>(f.size()));
    std::printf("A2 %s t = %6.2f s: settlement %.5f m vs %.5f m (%+.2f %%), RMS of (p - p_ref)/q = %.4f\n", label,
                e.time, top.settlement, S_ref, 100.0 * (top.settlement / S_ref - 1.0), rms);
    worst.settlement = std::max(worst.settlement, std::abs(top.settlement / S_ref - 1.0));
    worst.rms = std::max(worst.rms, rms);
  }
  return worst;
}

}  // namespace

// The seed's scheme (mfvp-constant + smoothing, eq. 9) on A2 (softened K_f, k = 1e-3, 16 s) used to
// "complete" with the settlement -0.26 % off but the pore pressures frozen at -1.12 ... +1.29 MPa
// (+-5.6 q, where 0 is right) and J 0.772 ... 0.864 (measured 2026-11-22 and again 2026-12-05). The
// pore-pressure bound now stops it (issue 27, item 7): status diverged, the remedy named.
TEST(LargeStrainConsolidation, A2SeedSchemeIsStoppedByThePorePressureBound) {
  int rc = 0;
  const std::string run =
      swmpm::testing::run_scene(scene_a2("linear-elastic", 2.2e7, 1.0e-3, 16.0, 2.0, 0.0), "a2-final", 0, &rc);
  const auto rj = swmpm::testing::load_json(run + "/run.json");
  const std::string diagnosis = rj.value("diagnosis", "");
  std::printf("A2 seed scheme: exit %d, %s at t = %.4f s: %s\n", rc, rj["status"].get<std::string>().c_str(),
              rj["end_time"].get<double>(), diagnosis.c_str());
  EXPECT_EQ(rc, 3);
  EXPECT_EQ(rj["status"], "diverged");
  EXPECT_NE(diagnosis.find("below -400000 Pa"), std::string::npos) << diagnosis;  // 2 q
  EXPECT_NE(diagnosis.find(R"("continuity": "conservative", "stabilisation": {"pressure": "cell-constant"})"),
            std::string::npos)
      << diagnosis;
  EXPECT_LT(rj["end_time"].get<double>(), 3.0);  // measured 2026-12-05: t = 1.108 s, particle 16 at y = 0.11 m, -407 kPa
}

// The same end state with the example's scheme (examples/large-strain-consolidation/scene-fast.json).
TEST(LargeStrainConsolidation, A2ConsistentSchemeFinalSettlementMatchesLogStrainClosedForm) {
  const std::string run = swmpm::testing::run_scene(
      scene_a2("linear-elastic", 2.2e7, 1.0e-3, 16.0, 16.0, 0.0, Scheme::consistent), "a2-final-consistent");
  const double S_inf = H * (1.0 - std::exp(-q / E));
  const double S = final_settlement(run);
  std::printf("A2 consistent scheme: final settlement %.5f m vs %.5f m: %+.2f %%\n", S, S_inf, 100.0 * (S / S_inf - 1.0));
  EXPECT_NEAR(S / S_inf, 1.0, 0.02);  // measured 2026-12-02: 0.18259 m, +0.73 %
}

TEST(LargeStrainConsolidation, HenckyKirchhoffLawSettlesToItsOwnClosedForm) {
  // `hencky`: Kirchhoff stress tau = E ln J, sigma = tau / J. End state E ln J = -q J (Newton).
  double J = 0.85;
  for (int i = 0; i < 50; ++i) J -= (E * std::log(J) + q * J) / (E / J + q);
  const double S_hencky = H * (1.0 - J);  // 0.15541 m
  // The consistent scheme: the seed's ended at -525 ... +553 kPa (+-2.7 q) and stops on the
  // pore-pressure bound now (issue 27, item 7).
  const std::string run =
      swmpm::testing::run_scene(scene_a2("hencky", 2.2e7, 1.0e-3, 16.0, 16.0, 0.0, Scheme::consistent), "a2-hencky");
  const double S = final_settlement(run);
  std::printf("A2 with hencky: final settlement %.5f m vs H(1 - J), E ln J = -q J: %.5f m (%+.2f %%); "
              "log-strain Cauchy law %.5f m\n",
              S, S_hencky, 100.0 * (S / S_hencky - 1.0), H * (1.0 - std::exp(-q / E)));
  // Measured 2026-12-05 (consistent scheme): 0.15595 m, +0.34 %, 12 s wall. The seed's scheme: 0.15538 m, -0.03 %.
  EXPECT_NEAR(S / S_hencky, 1.0, 0.02);
}


// The history with the consistent scheme: K_f = 2.2e7 (softened), k = 1e-4 m/s as in the paper,
// 10 s (U = 53 %), frames every second.
TEST(LargeStrainConsolidation, A2SettlementHistoryAndPorePressureMatchConstantK) {
  const std::string run = swmpm::testing::run_scene(
      scene_a2("linear-elastic", 2.2e7, 1.0e-4, 10.0, 1.0, 0.0, Scheme::consistent), "a2-history");
  const HistoryError e = history_error(run, 2.2e7, "consistent");
  // Measured 2026-12-02: settlement +0.60 ... +2.79 % (worst at 3 s), RMS of (p - p_ref)/q 0.019-0.035
  // (the piecewise-constant pressure against a continuous profile).
  EXPECT_LT(e.settlement, 0.03);
  EXPECT_LT(e.rms, 0.05);
}

// The permeability law k = k0 J^2 (`xie-leo`, porous/permeability.hpp) in explicit-single-point:
// the history test's column and scheme (K_f 2.2e7, k0 = 1e-4 m/s, 10 s) against the reference
// with the same law. As the column compacts (J -> 0.83) k drops to 0.69 k0, so the constant-k
// reference runs ahead of it: the run must follow its own law, not the constant one.
TEST(LargeStrainConsolidation, A2XieLeoPermeabilityFollowsItsReference) {
  json s = scene_a2("linear-elastic", 2.2e7, 1.0e-4, 10.0, 1.0, 0.0, Scheme::consistent);
  s["materials"][0]["permeability_law"] = "xie-leo";
  const std::string run = swmpm::testing::run_scene(s, "a2-xie-leo");
  const HistoryError own = history_error(run, 2.2e7, "xie-leo vs k0 J^2", 1.0e-4, true);
  const HistoryError constant = history_error(run, 2.2e7, "xie-leo vs constant k", 1.0e-4, false);
  // Measured 2026-12-04: settlement +1.1 ... +3.7 % of its own reference (worst at 4 s; the
  // constant-k history test's is +0.6 ... +2.8 %), RMS 0.019-0.037; against constant k -8.6 ...
  // -10.9 %. 4 s wall.
  EXPECT_LT(own.settlement, 0.045);
  EXPECT_LT(own.rms, 0.05);
  EXPECT_GT(constant.settlement, 2.0 * own.settlement);
}

// The consistent scheme in 3D: the same column 0.1 x 1 x 0.1 m (roller impermeable z faces too,
// 640 points), K_f 2.2e7, k = 1e-3 m/s, 2 s (U = 57 %).
TEST(LargeStrainConsolidation, A2ConsistentSchemeIn3D) {
  json s = scene_a2("linear-elastic", 2.2e7, 1.0e-3, 2.0, 1.0, 0.0, Scheme::consistent);
  s["dimension"] = 3;
  s["grid"]["min"] = {0.0, 0.0, 0.0};
  s["grid"]["max"] = {0.1, 1.1, 0.1};
  s["bodies"][0]["geometry"] = {{"type", "box"}, {"min", {0.0, 0.0, 0.0}}, {"max", {0.1, 1.0, 0.1}}};
  s["boundaries"].push_back({{"on", "z_min"}, {"solid", "roller"}, {"fluid", "impermeable"}});
  s["boundaries"].push_back({{"on", "z_max"}, {"solid", "roller"}, {"fluid", "impermeable"}});
  s["loads"][0]["value"] = {0.0, -q, 0.0};
  s["output"]["monitors"][0]["at"] = {0.05, 1.0, 0.05};
  const std::string run = swmpm::testing::run_scene(s, "a2-3d");
  const HistoryError e = history_error(run, 2.2e7, "3D", 1.0e-3);
  EXPECT_LT(e.settlement, 0.02);  // measured 2026-12-02: +0.63 %, +0.38 % at 1, 2 s (RMS 0.019, 0.016)
}

// What each ingredient does, 0-3 s of the same column: the cell-constant pressure with the seed's
// eq. 9 (no porosity-gradient terms) runs stably but consolidates too fast, by as much as the seed's
// scheme; the porosity-gradient terms alone (conservative continuity with the mfvp step) are accurate
// at first but let the row-pair pressure mode grow (examples/large-strain-consolidation/README.md).
TEST(LargeStrainConsolidation, A2WithoutThePorosityGradientTermsConsolidatesTooFast) {
  const std::string run = swmpm::testing::run_scene(
      scene_a2("linear-elastic", 2.2e7, 1.0e-4, 3.0, 1.0, 0.0, Scheme::consistent_eq9), "a2-eq9");
  const HistoryError e = history_error(run, 2.2e7, "cell-constant, eq. 9");
  EXPECT_GT(e.settlement, 0.15);  // measured 2026-12-02: +26.5 / +31.3 / +30.2 % at 1 / 2 / 3 s
}

// Issue 27, item 7, "wrong but finite": a 1 m column at about 14 % strain with the solver block left
// out (the seed's defaults: mfvp-linear, eq. 9, strain smoothing). E = 2 MPa, q = p0 = 300 kPa
// (S_inf = H (1 - e^(-q/E)) = 0.13929 m, J = 0.861), water's K_f = 2.2 GPa, k = 1e-2 m/s
// (c_v = k E / gamma_w = 2.0 m^2/s: consolidated within 1 s), dt auto (cfl 0.5).
// Before the bound the defaults "completed" 2 s with the settlement -0.10 % off but the pore
// pressures frozen at -1.21 ... +1.58 MPa (0 is right); the consistent scheme ends at 0 ... 0.1 kPa.
json column_14_percent(double end, double interval, bool consistent) {
  json s = scene_a2("linear-elastic", 2.2e9, 1.0e-2, end, interval, 0.0, consistent ? Scheme::consistent : Scheme::seed);
  s["materials"][0]["youngs_modulus"] = 2.0e6;
  s["bodies"][0]["initial"]["pore_pressure"] = 3.0e5;
  s["loads"][0]["value"] = {0.0, -3.0e5};
  s["time"] = {{"end", end}};
  if (consistent) s["solver"] = {{"continuity", "conservative"}, {"stabilisation", {{"pressure", "cell-constant"}}}};
  else s.erase("solver");
  return s;
}

// The defaults stop on the pore-pressure bound (p < -2 max(100 kPa, q) = -600 kPa for 100 steps in a
// row), exit 3, with the particle, the value, the time and the remedy on stderr and in run.json.
TEST(LargeStrainConsolidation, DefaultsAt14PercentStrainStopNamingTheRemedy) {
  namespace fs = std::filesystem;
  const fs::path dir = swmpm::testing::scratch("a2-14-percent-defaults");
  std::ofstream(dir / "scene.json") << column_14_percent(2.0, 0.01, false).dump(2);
  const auto r = swmpm::testing::swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + (dir / "run").string() + " -q", dir);
  const std::string remedy = R"("solver": {"continuity": "conservative", "stabilisation": {"pressure": "cell-constant"}})";
  std::printf("14 %% strain, defaults: exit %d, stderr: %s", r.status, r.err.c_str());
  EXPECT_EQ(r.status, 3);
  EXPECT_NE(r.err.find(remedy), std::string::npos) << r.err;
  const auto rj = swmpm::testing::load_json((dir / "run" / "run.json").string());
  EXPECT_EQ(rj["status"], "diverged");
  const std::string diagnosis = rj.value("diagnosis", "");
  for (const char* part : {"solid particle ", "(body \"column\") has pore pressure -", "below -600000 Pa", "steps in a row",
                           "in the step from t = ", "no desaturation"})
    EXPECT_NE(diagnosis.find(part), std::string::npos) << part << " in: " << diagnosis;
  EXPECT_NE(diagnosis.find(remedy), std::string::npos) << diagnosis;
  const double t_stop = rj["end_time"].get<double>();
  EXPECT_LT(t_stop, 0.3);  // measured 2026-12-05: t = 0.0099 s (-881 kPa at y = 0.90 m, 100 steps beyond the bound); 0.2 s wall
  // The last frame is the loop's last snapshot (solver.checkpoint_every), which may lie within the
  // 100 steps the suction had to persist.
  EXPECT_LE(rj["last_good_frame_time"].get<double>(), t_stop);
  EXPECT_GT(rj["last_good_frame_time"].get<double>(), 0.0);
}

// The same column with "solver": {"continuity": "conservative", "stabilisation": {"pressure":
// "cell-constant"}} completes and settles to the closed form, the pore pressure gone.
TEST(LargeStrainConsolidation, ConsistentSchemeAt14PercentStrainSettlesToTheClosedForm) {
  const std::string run = swmpm::testing::run_scene(column_14_percent(1.5, 0.5, true), "a2-14-percent-consistent");
  const double S_inf = H * (1.0 - std::exp(-3.0e5 / 2.0e6));  // 0.139292 m
  const double S = final_settlement(run);
  const auto f = swmpm::testing::last_frame(run);
  const auto& p = f.get("pore_pressure", "last frame").values;
  const auto [lo, hi] = std::minmax_element(p.begin(), p.end());
  std::printf("14 %% strain, consistent scheme: settlement %.5f m vs %.5f m (%+.2f %%), p in [%.1f, %.1f] Pa\n", S, S_inf,
              100.0 * (S / S_inf - 1.0), *lo, *hi);
  EXPECT_NEAR(S / S_inf, 1.0, 0.01);  // measured 2026-12-05: 0.14003 m, +0.53 %; p in [1.2, 16] Pa; 6.5 s wall
  EXPECT_GT(*lo, -0.01 * 3.0e5);
  EXPECT_LT(*hi, 0.01 * 3.0e5);
}

// The paper's parameters (K_f = 2.2 GPa, k = 1e-4 m/s, dt = 1e-5 s, 300 s: 3e7 steps, 40-55 min
// on one core) with the consistent scheme (the example's scene.json): the settlement history
// every 10 s against the constant-k reference with the paper's K_f, and the final settlement
// against Xie & Leo's H (1 - exp(-q/E)). The seed's scheme diverges at t = 4.25 s.
TEST(LargeStrainConsolidationSlow, A2PaperParametersHistoryAndFinalSettlement) {
  const std::string run = swmpm::testing::run_scene(
      scene_a2("linear-elastic", 2.2e9, 1.0e-4, 300.0, 10.0, 1.0e-5, Scheme::consistent), "a2-paper", 1);
  const HistoryError e = history_error(run, 2.2e9, "paper parameters");
  const double S_inf = H * (1.0 - std::exp(-q / E));
  const double S = final_settlement(run);
  std::printf("A2 (paper parameters): final settlement %.5f m vs %.5f m: %+.2f %%\n", S, S_inf, 100.0 * (S / S_inf - 1.0));
  // Measured 2026-12-02 on the example's scene.json (the same run): final 0.18308 m (+1.00 %),
  // the monitor within 0.82 % of the reference from 1 s, RMS of (p - p_ref)/q <= 0.019.
  EXPECT_NEAR(S / S_inf, 1.0, 0.02);
  EXPECT_LT(e.settlement, 0.03);
  EXPECT_LT(e.rms, 0.05);
}
