// A3 (seed 000 §4.2, Fig. 10) as a stability case: the strip load on the saturated layer
// (examples/strip-load-consolidation, main reading: 10 x 10 m, 0.5 m cells, dt = 2e-4 s, to 0.1 s).
// With strain smoothing and the linear multi-field variational pressure step the pore pressure
// stays smooth; with neither it forms the checkerboard of the paper's Fig. 10b. Indicators: the
// checkerboard indicator of the final p field (support/indicators.hpp) and the largest |p| of
// any frame against the load q = 20 kPa.
#include <gtest/gtest.h>

#include "support/strip_load.hpp"

namespace {
constexpr double q = 2.0e4;  // Pa
}

TEST(Stability, StripLoadStabilisedPressureIsSmoothUnstabilisedCheckerboards) {
  const auto on = swmpm::testing::run_strip_load("scene.json", "mfvp-linear", true, 0.4, "a3-on");
  const auto off = swmpm::testing::run_strip_load("scene.json", "none", false, 0.4, "a3-off");
  EXPECT_EQ(on.status, 0);
  EXPECT_EQ(off.status, 0);
  EXPECT_TRUE(on.finite);
  EXPECT_TRUE(off.finite);
  EXPECT_LT(on.max_abs_p, 2.0 * q);  // measured 23.6 kPa (dynamic overshoot of the undrained response)
  EXPECT_LT(on.checkerboard, 0.02);  // measured 0.0041
  EXPECT_GT(off.checkerboard, 0.1);  // measured 0.373
  EXPECT_GT(off.checkerboard, 10.0 * on.checkerboard);
  EXPECT_GT(off.max_abs_p, 5.0 * q);   // measured 192 kPa: spurious, nearly 10 q
  EXPECT_LT(off.max_abs_p, 25.0 * q);  // but bounded over the 0.1 s
}

// The cell-constant pressure with the conservative continuity (docs/formulations.md, "Cell-constant
// pressure and conservative continuity"): one pressure per 0.5 m cell, so the indicator is taken
// over 0.8 m (1.6 cells, as 0.4 m is 1.6 particle spacings above) — a smooth field in steps of
// one cell stays low there, a cell checkerboard (the Q1-P0 mode) does not.
TEST(Stability, StripLoadCellConstantPressureHasNoCheckerboard) {
  const auto cc = swmpm::testing::run_strip_load("scene.json", "cell-constant", true, 0.8, "a3-cc", "conservative");
  const auto off = swmpm::testing::run_strip_load("scene.json", "none", false, 0.8, "a3-off-wide");
  EXPECT_EQ(cc.status, 0);
  EXPECT_TRUE(cc.finite);
  EXPECT_LT(cc.max_abs_p, 2.0 * q);                        // measured 2026-12-02: 22.3 kPa
  EXPECT_LT(cc.checkerboard, 0.05);                        // measured 0.0194
  EXPECT_GT(off.checkerboard, 5.0 * cc.checkerboard);      // measured 0.270 without stabilisation
  EXPECT_NEAR(cc.corner_uy, -6.358e-3, 0.05 * 6.358e-3);  // measured 6.363 mm; mfvp-linear 6.358 mm
}

// The 1 x 1 m / 0.05 m reading (dt auto 1.36e-5 s, 7335 steps): the same contrast.
TEST(Stability, StripLoadSmallReadingSlow) {
  const auto on = swmpm::testing::run_strip_load("scene-small.json", "mfvp-linear", true, 0.04, "a3s-on");
  const auto off = swmpm::testing::run_strip_load("scene-small.json", "none", false, 0.04, "a3s-off");
  EXPECT_EQ(on.status, 0);
  EXPECT_EQ(off.status, 0);
  EXPECT_TRUE(on.finite);
  EXPECT_TRUE(off.finite);
  EXPECT_LT(on.max_abs_p, 2.0 * q);  // measured 16.2 kPa
  EXPECT_LT(on.checkerboard, 0.02);  // measured 0.0036
  EXPECT_GT(off.checkerboard, 0.1);  // measured 0.309
  EXPECT_GT(off.checkerboard, 10.0 * on.checkerboard);
  EXPECT_GT(off.max_abs_p, 5.0 * q);  // measured 190 kPa
  EXPECT_LT(off.max_abs_p, 25.0 * q);
}
