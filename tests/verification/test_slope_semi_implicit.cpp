// B3 (seed 001 §5.3): the Mohr-Coulomb slope (examples/slope-stability-mohr-coulomb) with the
// semi-implicit formulations, at the reduced resolution of the cost study B4 (cells 1 m, 2x2
// points per cell; the example runs the paper's 0.5 m and 4x4), quadratic B-splines and the
// paper's modified F-bar, dt 0.003 s for both permeabilities, a 1 s initialisation (elastic,
// gravity over 0.5 s, k = 1 m/s, damping 0.5), then SRF 2 to 6 s. What the paper reports and
// these tests hold:
//  - the time step does not depend on k (the same dt runs k = 1e-3 and 1e-7 m/s);
//  - the slope fails at SRF 2 and the low-permeability slope develops its shear band deeper and
//    settles more (its Fig. 6);
//  - without stabilisation the mean effective stress of the sliding mass checkerboards; the
//    modified F-bar removes it (its Fig. 7; standard F-bar in between).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "postprocess/postprocess.hpp"
#include "support/indicators.hpp"
#include "support/run_helpers.hpp"
#include "support/slope_scene.hpp"

namespace {

using nlohmann::json;

json slope(const std::string& formulation, double k, const std::string& fbar) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/slope-stability-mohr-coulomb/scene.json");
  s["formulation"] = formulation;
  s["grid"]["cell_size"] = 1.0;
  s["bodies"][0]["particles_per_cell"] = 2;
  s["materials"][0]["hydraulic_conductivity"] = k;
  s["solver"]["stabilisation"]["fbar"] = fbar;
  s["time"]["dt"] = 0.003;
  s["output"]["interval"] = 3.0;
  return s;
}

struct Slope {
  double dt = 0.0;            // s, run.json
  double crest_dx = 0.0, crest_dy = 0.0;  // m, the crest monitor at 6 s
  double band_depth = 0.0;    // m, mean initial height of the points with plastic strain > 0.5 under the face
  double mean_stress_checker = 0.0, p_checker = 0.0;  // at 6 s
  double p_min = 0.0, p_max = 0.0;                    // Pa, at 6 s
};

Slope run(const std::string& formulation, double k, const std::string& fbar, const std::string& name) {
  const std::string dir = swmpm::testing::run_scene(slope(formulation, k, fbar), name);
  Slope r;
  r.dt = swmpm::testing::load_json(dir + "/run.json")["dt"].get<double>();
  const auto t = swmpm::post::read_csv(dir + "/monitors.csv");
  r.crest_dx = t.column("crest.displacement_x").back();
  r.crest_dy = t.column("crest.displacement_y").back();
  const auto f = swmpm::testing::last_frame(dir);
  const auto& ep = f.get("plastic_strain", "f").values;
  const auto& u = f.get("displacement", "f").values;
  const auto& sm = f.get("mean_effective_stress", "f").values;
  const auto& p = f.get("pore_pressure", "f").values;
  double sum = 0.0;
  int n = 0;
  for (std::size_t q = 0; q < f.size(); ++q) {
    const double x0 = f.points[q][0] - u[3 * q], y0 = f.points[q][1] - u[3 * q + 1];
    if (ep[q] > 0.5 && x0 > 25.0 && x0 < 35.0) sum += y0, ++n;
  }
  r.band_depth = n ? 20.0 - sum / n : 0.0;
  r.mean_stress_checker = swmpm::testing::checkerboard_indicator(f, sm, 1.5);
  r.p_checker = swmpm::testing::checkerboard_indicator(f, p, 1.5);
  r.p_min = *std::min_element(p.begin(), p.end());
  r.p_max = *std::max_element(p.begin(), p.end());
  std::printf("B3 %s k = %g, F-bar %s: dt %g s, crest (%.3f, %.3f) m, plastic band (eps_p > 0.5 under the face) "
              "%.2f m below the crest, checkerboard of p' %.4f, of p %.4f, p in [%.0f, %.0f] Pa\n",
              formulation.c_str(), k, fbar.c_str(), r.dt, r.crest_dx, r.crest_dy, r.band_depth,
              r.mean_stress_checker, r.p_checker, r.p_min, r.p_max);
  return r;
}

}  // namespace

// Measured (GIMP would show a suction below the toe, docs/verification.md; bspline2 here), with
// the well-posed free-surface fits (docs/formulations.md, "Free-surface nodes with an ill-posed fit"):
//   k = 1e-3, modified: crest (-3.96, -3.88) m, band 10.7 m below the crest
//   k = 1e-7, modified: crest (-3.35, -3.72) m, band 11.3 m below the crest
//   k = 1e-3, none:     crest (-2.88, -3.18) m (locked: slides least)
TEST(SlopeSemiImplicit, B3PermeabilityAndFbar) {
  const Slope high = run("semi-implicit-single-point", 1e-3, "modified", "b3-sp-high-k");
  const Slope low = run("semi-implicit-single-point", 1e-7, "modified", "b3-sp-low-k");
  EXPECT_EQ(high.dt, low.dt);
  EXPECT_LT(high.crest_dx, -0.5);  // SRF 2: the slope slides
  EXPECT_LT(low.crest_dx, -0.5);
  // The paper's finding: a deeper shear band with low k. At this resolution the difference is
  // 0.6 m (at the example's 0.5 m cells 0.4 m, and the crest settles 0.74 m more with low k, which
  // the 1 m cells do not resolve: 0.16 m less here).
  EXPECT_GT(low.band_depth, high.band_depth + 0.3);
  const double total = swmpm::testing::kB3SlopeBaseOverburden;  // rho_sat g H at the base
  for (const Slope* s : {&high, &low}) {
    EXPECT_LT(s->p_max, total);
    EXPECT_GT(s->p_min, -0.1 * total);
    EXPECT_LT(s->p_checker, 0.02);
    EXPECT_LT(s->mean_stress_checker, 0.06);
  }
  // F-bar: without it (and with the standard one) the sliding mass's mean effective stress
  // checkerboards; locking also stiffens the slope (it slides least without stabilisation).
  const Slope none = run("semi-implicit-single-point", 1e-3, "none", "b3-sp-fbar-none");
  const Slope standard = run("semi-implicit-single-point", 1e-3, "standard", "b3-sp-fbar-standard");
  EXPECT_GT(none.mean_stress_checker, 2.0 * high.mean_stress_checker);
  EXPECT_GT(standard.mean_stress_checker, 2.0 * high.mean_stress_checker);
  EXPECT_GT(none.crest_dx, high.crest_dx + 0.5);
}
