// A3 (seed 000 §4.2): 2D consolidation under a strip load, half model, explicit-single-point.
// examples/strip-load-consolidation: E = 10 MPa, nu = 0.3, rho_s = 2700, n = 0.3, K_f = 2.2 GPa,
// k = 1e-4 m/s; sides and base roller + impermeable, top free and drained; 20 kPa on the strip
// 0 <= x <= B of the top from t = 0; no gravity; zero initial stress and p; stabilised (strain
// smoothing + mfvp-linear); GIMP, 2x2 particles per cell; to t = 0.1 s.
//   scene.json        main reading: 10 x 10 m, cells 0.5 m (1600 points), B = 3.0 m, dt = 2e-4 s
//   scene-small.json  variant:      1 x 1 m, cells 0.05 m (1600 points), B = 0.3 m, dt auto (1.36e-5 s)
// The paper reports a maximum displacement of 6.737 mm at the top-left corner at t = 0.1 s. At
// 0.1 s the main model is undrained (T_v = c_v t / B^2 = 0.0015) and still in its dynamic
// transient: the shear wave (c_s = 41.9 m/s) has crossed 4.2 of the 10 m. Independent plane-strain
// FE of the same half model (examples/strip-load-consolidation/fe_check.cpp, Q1 with selective
// reduced integration) at the monitor particle's initial position (0.125, 9.875):
//   static drained 11.59 mm, static undrained 5.21 mm, dynamic undrained at t = 0.1 s 6.57-6.61 mm
//   (80x80 cells dt 5e-5 s / 40x40 dt 1e-4 s; 6.59-6.68 mm at the corner node itself).
// So 6.737 mm is the undrained dynamic settlement at 0.1 s, not a consolidation or static value.
#include <gtest/gtest.h>

#include "support/strip_load.hpp"

namespace {

constexpr double paper = 6.737e-3;      // m, seed 000 §4.2, Fig. 11
constexpr double fe_dynamic = 6.59e-3;  // m, FE dynamic undrained at (0.125, 9.875), t = 0.1 s (mean of 6.57, 6.61)
constexpr double fe_undrained = 5.21e-3, fe_drained = 11.59e-3;  // m, FE static at (0.125, 9.875)

}  // namespace

TEST(StripLoad, A3CornerSettlementMatchesThePaper) {
  const auto r = swmpm::testing::run_strip_load("scene.json", "mfvp-linear", true, 0.4, "a3-main");
  ASSERT_EQ(r.status, 0);
  const double u = -r.corner_uy;
  std::printf("A3 main: corner settlement %.4f mm, paper %.3f mm (%+.2f %%), FE dynamic %.2f mm (%+.2f %%)\n", 1e3 * u,
              1e3 * paper, 100 * (u / paper - 1), 1e3 * fe_dynamic, 100 * (u / fe_dynamic - 1));
  // Measured 6.358 mm: -5.6 % against the paper, -3.5 % against the FE. What moves it (measured):
  // FLIP 1.0 instead of 0.99 6.482 mm (the PIC share damps the transient), dt 1e-4 s 6.235 mm (twice
  // the PIC steps), mfvp-constant 6.361, bspline2 6.362; the FE itself sits 2.2 % under the paper.
  // At 0.1 s the corner moves at 0.053 m/s (0.8 % of u per ms), so the number is a point on a
  // steep transient. Tolerance 8 % against the paper (5 % against the FE): the measured gap plus
  // the FLIP/PIC and time-step spread above, and still tight enough to catch a lost or doubled
  // load, a wrong drainage condition (drained static 11.6 mm), or a stiffer response (no
  // stabilisation gives 4.50 mm).
  EXPECT_NEAR(u / paper, 1.0, 0.08);
  EXPECT_NEAR(u / fe_dynamic, 1.0, 0.05);
  EXPECT_GT(u, fe_undrained);  // past the static undrained settlement: the dynamic overshoot
  EXPECT_LT(u, fe_drained);
}

// The 1 x 1 m reading is the main model scaled by 1/10 in length with the same material: static
// displacements are 1/10 (FE at (0.0125, 0.9875): drained 1.159 mm, undrained 0.521 mm) and the
// dynamics 10 times faster, so at 0.1 s it rings about its static state (FE dynamic undrained
// swings between 0.23 and 0.91 mm over 0.05-0.1 s) while consolidation has begun
// (c_v t / B^2 = 0.15; p below the load centre at 0.1 m depth falls from 16.7 kPa at 0.02 s to 5.8 kPa at 0.1 s).
// It cannot give the paper's 6.737 mm, which is why the main reading is the 10 x 10 m one.
TEST(StripLoad, A3SmallReadingSettlesAnOrderOfMagnitudeLess) {
  const auto r = swmpm::testing::run_strip_load("scene-small.json", "mfvp-linear", true, 0.04, "a3-small");
  ASSERT_EQ(r.status, 0);
  EXPECT_LT(r.corner_max, 0.2 * paper);  // measured 0.980 mm (0.588 mm at 0.1 s)
  // Mean over 0.05-0.1 s between the undrained and the drained static settlement: measured 0.638 mm.
  EXPECT_GT(-r.corner_late, 0.521e-3);
  EXPECT_LT(-r.corner_late, 1.159e-3);
}
