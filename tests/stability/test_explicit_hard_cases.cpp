// Hard cases for explicit-single-point (seed 000), each asserting boundedness and an indicator:
//   (a) sudden loading: the Terzaghi column (examples/terzaghi) with p = 0 at t = 0 and the 10 kPa
//       traction applied as a step: the undrained wave, its reflection at the rigid base, and then
//       Terzaghi's series;
//   (b) low permeability k = 1e-7 m/s: the response stays undrained and dt "auto" is the same as
//       with k = 1e-3 (the drag is implicit per node and sets no step limit);
//   (c) dt at 0.9 of the critical step on the Terzaghi column and on A5; a fixed dt of twice the
//       critical step stops with status 3;
//   (d) a soft (E = 100 kPa) saturated block under a gravity ramp.
// Indicators: the peak pore pressure against its physical bound, the RMS error against Terzaghi's
// series, the checkerboard indicator of the p field (support/indicators.hpp), the energy balance
// (kinetic + strain energy cannot exceed the external work plus what was stored at t = 0), and
// the mirror symmetry of a symmetric problem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "support/indicators.hpp"
#include "support/run_helpers.hpp"
#include "support/soft_block.hpp"

namespace {

using nlohmann::json;

// The Terzaghi column (A1): E = 10 MPa, nu = 0, n = 0.3, K_f = 2.2 GPa, rho_s = 2650, q = 10 kPa.
constexpr double H = 1.0, q = 1.0e4, E = 1.0e7, n0 = 0.3, rho_s = 2650.0, rho_w = 1000.0, K_f = 2.2e9, g = 9.81;
const double rho_sat = (1 - n0) * rho_s + n0 * rho_w;        // 2155 kg/m^3
const double M_u = E + K_f / n0;                             // undrained constrained modulus (nu = 0)
const double c_u = std::sqrt(M_u / rho_sat);                 // 1846 m/s, undrained P wave
const double B = (K_f / n0) / (K_f / n0 + E);                // 0.99864: p = B q under a sudden load
double c_v(double k) { return k / (rho_w * g * (1.0 / E + n0 / K_f)); }  // 1.018 m^2/s at k = 1e-3

double terzaghi(double z, double Tv) {  // p / p0 at depth z, drained top, impermeable base
  double sum = 0.0;
  for (int m = 0; m < 200; ++m) {
    const double M = (2 * m + 1) * M_PI / 2;
    sum += 2.0 / M * std::sin(M * z / H) * std::exp(-M * M * Tv);
  }
  return sum;
}

/// examples/terzaghi/scene.json with permeability k, initial pore pressure (p0 = q, or none for
/// the sudden-load case), end time and time step; monitors at the base, the middle and the top
/// particle of the column and the energies.
json terzaghi_scene(double k, bool initial_p, double end, const json& dt, double cfl = 0.5) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi/scene.json");
  s["materials"][0]["hydraulic_conductivity"] = k;
  if (!initial_p) s["bodies"][0].erase("initial");
  s["time"] = {{"end", end}, {"dt", dt}};
  if (dt.is_string()) s["time"]["cfl"] = cfl;
  s["output"]["interval"] = 0.01;
  s["output"]["monitor_interval"] = 1.0e-4;
  s["output"]["monitors"] = json::parse(R"([
    { "name": "base", "at": [0.0375, 0.0125], "quantities": ["pore_pressure"] },
    { "name": "mid", "at": [0.0375, 0.5125], "quantities": ["pore_pressure"] },
    { "name": "top", "at": [0.0375, 0.9875], "quantities": ["pore_pressure", "displacement_y"] },
    { "name": "energy", "quantities": ["kinetic_energy", "strain_energy", "external_work"] } ])");
  return s;
}

/// A5 (examples/self-weight-consolidation) with an energy monitor.
json a5_scene(double end, const json& dt, double cfl) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/self-weight-consolidation/scene.json");
  s["time"] = {{"end", end}, {"dt", dt}};
  if (dt.is_string()) s["time"]["cfl"] = cfl;
  s["output"]["interval"] = 0.1;
  s["output"]["monitors"].push_back(
      {{"name", "energy"}, {"quantities", {"kinetic_energy", "strain_energy", "external_work"}}});
  return s;
}

struct Column {
  double max, min, mean;  // over the rows in the window
};
Column column_stats(const swmpm::post::Table& tab, const std::string& name, double from, double to) {
  const auto& t = tab.column("time");
  const auto& v = tab.column(name);
  Column c{-1e300, 1e300, 0.0};
  int count = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (t[k] < from || t[k] > to) continue;
    c.max = std::max(c.max, v[k]);
    c.min = std::min(c.min, v[k]);
    c.mean += v[k];
    ++count;
  }
  c.mean /= std::max(count, 1);
  return c;
}

/// Largest (kinetic + strain energy - external work) over the run after t = 0, relative to the
/// external work at the end: > 0 is energy the scheme created, < 0 what drag, PIC and smoothing
/// dissipated at the worst moment. Skeleton strain energy only: the pore fluid's compression energy
/// n p^2 / (2 K_f) V is left out (about 0.1 % of the skeleton's in these cases); every case here
/// starts with no stored energy (sigma' = 0) or with a little fluid compression only.
double energy_excess(const swmpm::post::Table& tab) {
  const auto& ke = tab.column("energy.kinetic_energy");
  const auto& se = tab.column("energy.strain_energy");
  const auto& w = tab.column("energy.external_work");
  double worst = -1e300;
  for (std::size_t k = 1; k < ke.size(); ++k) worst = std::max(worst, ke[k] + se[k] - w[k]);
  return worst / std::max(std::abs(w.back()), 1e-300);
}

struct Field {
  double checkerboard = 0.0;  // largest over the frames in the window
  double max = -1e300, min = 1e300;
};
Field field_stats(const std::string& run, double from, double to, double radius) {
  Field out;
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd")) {
    if (e.time < from - 1e-9 || e.time > to + 1e-9) continue;
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    const auto& p = f.get("pore_pressure", e.file).values;
    out.checkerboard = std::max(out.checkerboard, swmpm::testing::checkerboard_indicator(f, p, radius));
    for (double v : p) {
      out.max = std::max(out.max, v);
      out.min = std::min(out.min, v);
    }
  }
  return out;
}

/// Largest RMS of p / p0 - series over the column, over the frames with t >= from.
double worst_terzaghi_rms(const std::string& run, double p0, double k, double from) {
  double worst = 0.0;
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd")) {
    if (e.time < from - 1e-9) continue;
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    const auto& pp = f.get("pore_pressure", e.file).values;
    const auto& d = f.get("displacement", e.file).values;
    const double Tv = c_v(k) * e.time / (H * H);
    double err2 = 0.0;
    for (std::size_t p = 0; p < f.size(); ++p) {
      const double z = H - (f.points[p][1] - d[3 * p + 1]);
      err2 += std::pow(pp[p] / p0 - terzaghi(z, Tv), 2);
    }
    worst = std::max(worst, std::sqrt(err2 / static_cast<double>(f.size())));
  }
  return worst;
}

}  // namespace

// (a) Sudden loading. At t = 0 the column carries nothing (p = 0, sigma' = 0) and the 10 kPa
// traction appears at once. An undrained P wave (c_u = 1846 m/s) carries p = B q = 0.9986 q down;
// the rigid base reflects it and doubles it (2 B q) until the relief from the top arrives, so the
// physical peak is 2 B q at the base, between H / c_u = 0.54 ms and 3 H / c_u = 1.6 ms. Biot's drag
// damps the ringing (the column's first mode, c_u / 4H = 461 Hz, is near Biot's characteristic frequency
// n g / (2 pi k) = 470 Hz at k = 1e-3), and then the column consolidates as Terzaghi says.
TEST(HardCases, SuddenLoadTerzaghiColumnPeaksBelowTwiceTheLoadThenFollowsTheSeries) {
  const std::string run = swmpm::testing::run_scene(terzaghi_scene(1.0e-3, false, 0.3, 1.0e-5), "hard-sudden", 1);
  const auto tab = swmpm::post::read_csv(run + "/monitors.csv");
  const auto& t = tab.column("time");
  const auto& base = tab.column("base.pore_pressure");
  std::size_t kmax = 0;
  for (std::size_t k = 0; k < base.size(); ++k)
    if (base[k] > base[kmax]) kmax = k;
  const auto late = column_stats(tab, "base.pore_pressure", 0.04, 0.05);
  const Field f = field_stats(run, 0.0, 0.3, 0.1);
  const double rms = worst_terzaghi_rms(run, B * q, 1.0e-3, 0.05);
  const double excess = energy_excess(tab);
  std::printf("sudden load: peak base p %.0f Pa = %.3f q at t = %.2f ms (window %.2f-%.2f ms); base p in "
              "[0.04, 0.05] s %.0f..%.0f Pa; field p %.0f..%.0f Pa; checkerboard %.4f; worst RMS of p/(B q) - series "
              "from 0.05 s %.4f; energy excess %.2e of W\n",
              base[kmax], base[kmax] / q, 1e3 * t[kmax], 1e3 * H / c_u, 3e3 * H / c_u, late.min, late.max, f.min,
              f.max, f.checkerboard, rms, excess);
  EXPECT_LT(base[kmax], 2.0 * B * q);          // measured 1.910 q: the reflection, slightly dispersed
  EXPECT_GT(base[kmax], 1.6 * q);              // the reflection is there (a scheme that smears it is too dissipative)
  EXPECT_GT(t[kmax], H / c_u);                 // measured 1.30 ms
  EXPECT_LT(t[kmax], 3.0 * H / c_u);
  EXPECT_LT(f.max, 2.0 * B * q);               // nowhere above the reflection bound
  EXPECT_LT(late.max - late.min, 0.01 * q);    // rung down within 0.04 s: measured 51 Pa
  EXPECT_LT(f.checkerboard, 0.05);             // measured 0.021
  EXPECT_LT(rms, 0.03);                        // the A1 tolerance; measured 0.0015
  EXPECT_LT(excess, 0.01);                     // no energy created; measured -3.2e-4
}

// (b) Low permeability. c_v = 1.0e-4 m^2/s: over 0.3 s the drained layer at the top is
// sqrt(c_v t) = 5.5 mm, less than half a particle spacing, so the column stays undrained: p = q
// (the example's initial state) and the settlement is a tiny fraction of the drained q H / E.
// Explicit drag would need dt < 2 / lambda, lambda = (n g / k)(1 + n rho_w / ((1 - n) rho_s)),
// = 5.8e-8 s here; the implicit nodal drag runs at the undrained CFL step, as with k = 1e-3.
TEST(HardCases, LowPermeabilityStaysUndrainedAtTheSameAutoTimeStep) {
  const double k_low = 1.0e-7;
  const std::string run = swmpm::testing::run_scene(terzaghi_scene(k_low, true, 0.3, "auto"), "hard-lowk", 1);
  const std::string ref = swmpm::testing::run_scene(terzaghi_scene(1.0e-3, true, 0.01, "auto"), "hard-lowk-ref", 1);
  const auto rj = swmpm::testing::load_json(run + "/run.json");
  const auto rj_ref = swmpm::testing::load_json(ref + "/run.json");
  const double lambda = n0 * g / k_low * (1 + n0 * rho_w / ((1 - n0) * rho_s));
  const auto tab = swmpm::post::read_csv(run + "/monitors.csv");
  const auto base = column_stats(tab, "base.pore_pressure", 0.0, 0.3);
  const auto mid = column_stats(tab, "mid.pore_pressure", 0.0, 0.3);
  const double settlement = -tab.column("top.displacement_y").back();
  const Field f = field_stats(run, 0.0, 0.3, 0.1);
  std::printf("k = 1e-7: dt (first step) %.6e s vs %.6e s at k = 1e-3; mean dt %.6e s over %d steps; explicit drag "
              "limit 2/lambda = %.2e s (auto dt is %.0f x that); base p %.1f..%.1f Pa, mid %.1f..%.1f Pa; "
              "settlement %.3e m = %.5f of q H / E; field p %.1f..%.1f Pa, checkerboard %.4f\n",
              rj["dt_max"].get<double>(), rj_ref["dt_max"].get<double>(), rj["dt"].get<double>(),
              rj["steps"].get<int>(), 2.0 / lambda, rj["dt_max"].get<double>() * lambda / 2.0, base.min, base.max,
              mid.min, mid.max, settlement, settlement / (q * H / E), f.min, f.max, f.checkerboard);
  EXPECT_EQ(rj["status"], "completed");
  EXPECT_NEAR(rj["dt_max"].get<double>(), rj_ref["dt_max"].get<double>(), 1e-9 * rj_ref["dt_max"].get<double>());
  // The mean dt does not shrink over the run: measured -2e-5 relative.
  EXPECT_NEAR(rj["dt"].get<double>(), rj["dt_max"].get<double>(), 1e-3 * rj["dt_max"].get<double>());
  EXPECT_GT(rj["dt_max"].get<double>(), 100.0 * 2.0 / lambda);  // measured 232 x
  EXPECT_LT(std::max(base.max - q, q - base.min), 0.002 * q);  // measured 0.06 %
  EXPECT_LT(std::max(mid.max - q, q - mid.min), 0.002 * q);   // measured 0.05 %
  EXPECT_LT(settlement, 0.01 * q * H / E);                      // measured 0.0009
  EXPECT_LT(f.max, 1.002 * q);
  EXPECT_GT(f.min, 0.9 * q);  // the top particle: 0.966 q
  // The indicator is relative to the field's range, here only 350 Pa (the top row); in units of q
  // the roughness is 0.084 x 350 Pa = 0.003 q.
  EXPECT_LT(f.checkerboard * (f.max - f.min), 0.01 * q);
}

// (b') Low permeability and a sudden load: nothing damps the undrained ringing any more (Biot's
// characteristic frequency is now 4.7 MHz), so p at the base swings between about 0 and 2 q for
// the whole run. Bounded: the swing does not grow, and its mean is the undrained B q.
TEST(HardCases, LowPermeabilitySuddenLoadRingsBoundedAroundTheUndrainedPressure) {
  const std::string run = swmpm::testing::run_scene(terzaghi_scene(1.0e-7, false, 0.2, 1.0e-5), "hard-lowk-sudden", 1);
  const auto tab = swmpm::post::read_csv(run + "/monitors.csv");
  const auto first = column_stats(tab, "base.pore_pressure", 0.0, 0.1);
  const auto last = column_stats(tab, "base.pore_pressure", 0.1, 0.2);
  const Field f = field_stats(run, 0.0, 0.2, 0.1);
  const double excess = energy_excess(tab);
  std::printf("k = 1e-7, sudden load: base p in [0, 0.1] s %.0f..%.0f (mean %.0f) Pa, in [0.1, 0.2] s %.0f..%.0f "
              "(mean %.0f) Pa; field p %.0f..%.0f Pa; checkerboard %.4f; energy excess %.2e of W\n",
              first.min, first.max, first.mean, last.min, last.max, last.mean, f.min, f.max, f.checkerboard, excess);
  EXPECT_LT(first.max, 3.0 * q);  // measured 2.67 q: 2 B q plus the dispersion overshoot of a sharp front
  EXPECT_LT(last.max - last.min, first.max - first.min);  // not growing: 33.8 -> 26.6 kPa
  EXPECT_NEAR(last.mean, B * q, 0.01 * q);  // measured 9967 Pa vs 9986 Pa
  EXPECT_LT(excess, 0.01);
}

// (c) dt at 0.9 of the critical step (time.dt "auto", cfl 0.9) on the Terzaghi column: the same
// answer as at the usual cfl 0.5 run (A1 verification), bounded and smooth.
TEST(HardCases, TerzaghiAtNinetyPercentOfTheCriticalStep) {
  const std::string run = swmpm::testing::run_scene(terzaghi_scene(1.0e-3, true, 0.5, "auto", 0.9), "hard-cfl09-a1", 1);
  const auto rj = swmpm::testing::load_json(run + "/run.json");
  const auto tab = swmpm::post::read_csv(run + "/monitors.csv");
  const auto base = column_stats(tab, "base.pore_pressure", 0.0, 0.5);
  const Field f = field_stats(run, 0.0, 0.5, 0.1);
  const double rms = worst_terzaghi_rms(run, q, 1.0e-3, 0.05);
  const double excess = energy_excess(tab);
  std::printf("A1 at cfl 0.9: dt %.4e s, %d steps; base p max %.0f Pa = %.3f q, end %.0f Pa; field p %.0f..%.0f Pa; "
              "checkerboard %.4f; worst RMS from 0.05 s %.4f; energy excess %.2e of W\n",
              rj["dt_max"].get<double>(), rj["steps"].get<int>(), base.max, base.max / q,
              tab.column("base.pore_pressure").back(), f.min, f.max, f.checkerboard, rms, excess);
  EXPECT_EQ(rj["status"], "completed");
  // The suddenly drained top sends a wave down: measured 1.35 q at the base at 1.6 ms (also at cfl 0.5).
  EXPECT_LT(base.max, 1.5 * q);
  EXPECT_LT(f.max, 1.5 * q);          // frames every 0.01 s: measured 1.065 q
  EXPECT_LT(f.checkerboard, 0.05);    // measured 0.019
  EXPECT_LT(rms, 0.03);               // measured 0.0015
  EXPECT_NEAR(tab.column("base.pore_pressure").back(), 3626.0, 0.01 * q);  // series at 0.5 s; measured 3620
  EXPECT_LT(excess, 0.01);
}

// (c) A5 (soft slumping block, mfvp-linear + smoothing, FLIP 0.99) at cfl 0.9. It runs through
// without creating energy, but the pressure field is rougher than at the example's cfl 0.5: over
// 0.4 s P1 peaks at 39.2 kPa (29.9 kPa at cfl 0.5), and 48 of 1024 particles exceed rho_sat g H at
// 0.4 s, 35 of them inside the block (0 at cfl 0.3 and 0.5, 3 at 0.7, 15 at 0.8). The bounds
// below are what holds at 0.9; use cfl <= 0.5 for soft, large-deformation cases.
TEST(HardCases, SelfWeightConsolidationAtNinetyPercentOfTheCriticalStep) {
  const std::string run = swmpm::testing::run_scene(a5_scene(0.4, "auto", 0.9), "hard-cfl09-a5", 1);
  const auto rj = swmpm::testing::load_json(run + "/run.json");
  const auto tab = swmpm::post::read_csv(run + "/monitors.csv");
  const auto p1 = column_stats(tab, "P1.pore_pressure", 0.0, 0.4);
  const double bound = ((1 - 0.4) * 2650.0 + 0.4 * 1000.0) * g * 2.0;  // rho_sat g H = 39.0 kPa
  const double excess = energy_excess(tab);
  double checker = 0.0, fmax = 0.0, share = 0.0;
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd")) {
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    const auto& p = f.get("pore_pressure", e.file).values;
    checker = std::max(checker, swmpm::testing::checkerboard_indicator(f, p, 0.2));
    std::size_t above = 0;
    for (double v : p) {
      fmax = std::max(fmax, std::abs(v));
      if (std::abs(v) > bound) ++above;
    }
    share = std::max(share, static_cast<double>(above) / static_cast<double>(p.size()));
  }
  std::printf("A5 at cfl 0.9: dt %.4e s, %d steps; P1 max %.0f Pa = %.3f rho_sat g H (%.0f Pa); field max |p| %.0f Pa "
              "= %.2f rho_sat g H; largest share of particles beyond it %.4f; checkerboard %.4f; energy excess %.2e "
              "of W\n",
              rj["dt_max"].get<double>(), rj["steps"].get<int>(), p1.max, p1.max / bound, bound, fmax, fmax / bound,
              share, checker, excess);
  EXPECT_EQ(rj["status"], "completed");
  EXPECT_LT(p1.max, 1.1 * bound);  // measured 1.005
  EXPECT_LT(fmax, 4.0 * bound);    // measured 3.51 (1.62 at cfl 0.5: one toe particle)
  EXPECT_LT(share, 0.1);           // measured 0.047
  EXPECT_LT(checker, 0.1);         // measured 0.082 (0.071 at cfl 0.5, same radius)
  EXPECT_LT(excess, 0.01);
}

// (c) Well above the limit: a fixed dt of twice the critical step (time.cfl may not exceed 1, so
// a fixed dt is the only way past the limit) stops with exit status 3 within a few steps, and the
// last frame is the last good state (finite, near the initial state).
TEST(HardCases, TwiceTheCriticalStepStopsWithStatusThree) {
  struct Case {
    const char* name;
    json scene;
    double dt_crit;  // s, from the log line of the cfl runs above
  };
  std::vector<Case> cases = {{"A1", terzaghi_scene(1.0e-3, true, 0.1, 1.0), 2.70861e-5},
                             {"A5", a5_scene(0.1, 1.0, 0.5), 7.51882e-5}};
  for (auto& c : cases) {
    c.scene["time"]["dt"] = 2.0 * c.dt_crit;
    int status = 0;
    const std::string run = swmpm::testing::run_scene(c.scene, std::string("hard-dt2-") + c.name, 1, &status);
    const auto rj = swmpm::testing::load_json(run + "/run.json");
    const auto last = swmpm::testing::last_frame(run);
    double pmax = 0.0;
    bool finite = true;
    for (double v : last.get("pore_pressure", "last frame").values) {
      finite = finite && std::isfinite(v);
      pmax = std::max(pmax, std::abs(v));
    }
    std::printf("%s at 2 x dt_crit: status %d, %s after %d steps (t = %.3e s); last good frame t = %.3e s, max |p| "
                "%.0f Pa\n",
                c.name, status, rj["status"].get<std::string>().c_str(), rj["steps"].get<int>(),
                rj["end_time"].get<double>(), rj.value("last_good_frame_time", -1.0), pmax);
    EXPECT_EQ(status, 3) << c.name;
    EXPECT_EQ(rj["status"], "diverged") << c.name;
    EXPECT_LT(rj["steps"].get<int>(), 500) << c.name;  // measured 28 (A1), 24 (A5)
    EXPECT_TRUE(finite) << c.name;
    EXPECT_LT(pmax, 2.0 * 39.0e3) << c.name;  // the last good state is not the blown-up one
  }
}

// At 1.9 x the critical step the Terzaghi column blows up within ~3 ms (kinetic energy 7000 J/m
// against 0.005 J/m at cfl 0.9, p up to 6 MPa at the base and -120 MPa at the top), then the drag
// damps the motion: J stays > 0 and the porosity in (0, 1), so only finiteness checks would let it
// finish with status 0 and a garbage state (top p -17.8 MPa). The time loop's energy check
// (kinetic + stored energy > 10 x (initial energy + external work)) stops it: measured at step 20,
// 0.38 J against an allowance of 0.24 J. Asserts status 3, or a physical answer.
TEST(HardCases, JustBelowTwiceTheCriticalStepIsStoppedOrStaysPhysical) {
  json s = terzaghi_scene(1.0e-3, true, 0.05, 1.9 * 2.70861e-5);
  int status = 0;
  const std::string run = swmpm::testing::run_scene(s, "hard-dt19", 1, &status);
  const auto tab = swmpm::post::read_csv(run + "/monitors.csv");
  const auto base = column_stats(tab, "base.pore_pressure", 0.0, 0.05);
  const double excess = energy_excess(tab);
  std::printf("A1 at 1.9 x dt_crit: status %d, base p max %.3g Pa, energy excess %.3g of W\n", status, base.max,
              excess);
  if (status != 3) {
    EXPECT_EQ(status, 0);
    EXPECT_LT(base.max, 2.0 * q);
    EXPECT_LT(excess, 0.01);
  }
}

// (d) A soft (E = 100 kPa) saturated block, 2 m wide and 1 m high, standing free on a roller,
// impermeable base (both sides and the top free and drained), under a 0.1 s gravity ramp; the
// full symmetric block (A5 models half of it with a symmetry wall). mfvp-linear + smoothing.
TEST(HardCases, SoftSaturatedBlockUnderGravityStaysBoundedSmoothAndSymmetric) {
  json s = swmpm::testing::soft_block_scene("explicit-single-point", 1.0e5);
  s["solver"] = json::parse(R"json({ "stabilisation": { "pressure": "mfvp-linear", "strain_smoothing": true } })json");
  s["output"] = json::parse(R"json({ "interval": 0.05, "monitor_interval": 0.001, "monitors": [
      { "name": "base", "at": [1.525, 0.025], "quantities": ["pore_pressure"] },
      { "name": "energy", "quantities": ["kinetic_energy", "strain_energy", "external_work"] } ] })json");
  const std::string run = swmpm::testing::run_scene(s, "hard-soft-block", 1);
  const auto tab = swmpm::post::read_csv(run + "/monitors.csv");
  const double bound = ((1 - 0.4) * 2650.0 + 0.4 * 1000.0) * g * 1.0;  // rho_sat g H = 19.5 kPa
  const auto base = column_stats(tab, "base.pore_pressure", 0.0, 0.3);
  const double excess = energy_excess(tab);
  // Field indicators on every frame: checkerboard, extremes, share of particles above the bound,
  // and the mirror asymmetry about x = 1.5 m (max |p(x) - p(3 - x)| over the range of p).
  double checker = 0.0, asym = 0.0, above = 0.0, fmax = -1e300;
  std::size_t inside_above = 0;  // particles beyond the bound that were not on the surface at t = 0
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd")) {
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    const auto& p = f.get("pore_pressure", e.file).values;
    const auto& d = f.get("displacement", e.file).values;
    const auto& faces = f.get("faces", e.file).values;  // surface-layer bits from preprocess
    checker = std::max(checker, swmpm::testing::checkerboard_indicator(f, p, 0.15));
    const auto [lo, hi] = std::minmax_element(p.begin(), p.end());
    const double range = std::max(*hi - *lo, 1e-300);
    std::size_t n_above = 0;
    for (std::size_t a = 0; a < f.size(); ++a) {
      fmax = std::max(fmax, p[a]);
      if (std::abs(p[a]) > bound) {
        ++n_above;
        if (faces[a] == 0.0) ++inside_above;
      }
      const double xa = f.points[a][0] - d[3 * a], ya = f.points[a][1] - d[3 * a + 1];  // reference position
      for (std::size_t b = 0; b < f.size(); ++b) {
        const double xb = f.points[b][0] - d[3 * b], yb = f.points[b][1] - d[3 * b + 1];
        if (std::abs(xa + xb - 3.0) < 1e-6 && std::abs(ya - yb) < 1e-6)
          asym = std::max(asym, std::abs(p[a] - p[b]) / range);
      }
    }
    above = std::max(above, static_cast<double>(n_above) / static_cast<double>(f.size()));
  }
  std::printf("soft block: base p max %.0f Pa (bound rho_sat g H %.0f), field max %.0f Pa, largest share of particles "
              "with |p| > bound %.4f, of them inside the block at t = 0: %zu; checkerboard %.4f; mirror asymmetry "
              "%.2e; energy excess %.2e of W\n",
              base.max, bound, fmax, above, inside_above, checker, asym, excess);
  EXPECT_LT(base.max, bound);   // measured 14.8 kPa
  EXPECT_EQ(inside_above, 0u);  // every particle beyond the bound starts in the surface layer
  // The toes misbehave: a few surface particles next to the base corners, where the block spreads
  // along the base, alternate in sign (+62 / -49 kPa one above the other at 0.15 s): 14 of 800.
  EXPECT_LT(above, 0.025);      // measured 0.0175
  EXPECT_LT(checker, 0.08);     // measured 0.0675
  EXPECT_LT(asym, 1e-6);        // measured 3-5e-9: the scheme keeps the mirror symmetry
  EXPECT_LT(excess, 0.01);
}
