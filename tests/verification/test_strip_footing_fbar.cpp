// B6 (seed 001 App. A): the nearly incompressible (ν = 0.49) elastic strip footing of
// examples/strip-footing-fbar at h = 0.2 m (10 000 particles, 4680 steps to the static state at
// 1.6 s), against the Q2/P1 finite-element solution of the same static problem
// (support/strip_footing_fe.hpp: settlement 6.1098 mm at the first particle's centre). Measures:
// settlement error, RMS error of σ_yy along the centreline column and of the mean stress p over
// the whole layer (both / q), and the checkerboard indicator of p. The paper's findings: GIMP
// without stabilisation locks (here: the mean stress checkerboards, the settlement barely moves);
// patch-wise modified F-bar (h_patch = 1.5 h) works on GIMP and B-splines; cell-wise modified F-bar
// fails on B-splines — NOT reproduced here (cell-wise is as smooth as patch-wise on bspline2; see
// the example's README). Numbers in docs/verification.md, "B6".
#include <gtest/gtest.h>

#include "support/strip_footing.hpp"

using swmpm::testing::run_strip_footing;
using swmpm::testing::StripFootingRun;

namespace {

void expect_accurate(const StripFootingRun& r, double syy_tol, double p_tol, double checker_tol) {
  EXPECT_EQ(r.status, 0);
  EXPECT_LT(std::abs(r.settlement_error), 0.01);
  EXPECT_LT(r.syy_error, syy_tol);
  EXPECT_LT(r.p_error, p_tol);
  EXPECT_LT(r.checkerboard, checker_tol);
}

}  // namespace

// Measured: none: settlement -0.40 %, σ_yy 0.085 q, p 0.086 q, checkerboard 0.066;
// modified (cell-wise, the GIMP default): -0.05 %, 0.0032 q, 0.0058 q, 0.0084.
TEST(StripFootingFBar, B6GimpLocksWithoutFBarAndTheModifiedFBarRemovesIt) {
  const StripFootingRun none = run_strip_footing("gimp", "none", 0.0, 0.2, "b6-gimp-none");
  const StripFootingRun modified = run_strip_footing("gimp", "modified", 0.0, 0.2, "b6-gimp-modified");
  EXPECT_EQ(none.status, 0);
  EXPECT_LT(std::abs(none.settlement_error), 0.01);  // the displacement hardly locks ...
  EXPECT_GT(none.checkerboard, 0.04);                // ... the mean stress does
  EXPECT_GT(none.p_error, 0.05);
  EXPECT_GT(none.syy_error, 0.05);
  expect_accurate(modified, 0.01, 0.01, 0.015);
  EXPECT_GT(none.checkerboard, 5.0 * modified.checkerboard);
  EXPECT_LT(modified.checkerboard_fe, 0.002);  // the reference field itself is smooth at this radius
}

// Measured: cell-wise (h_patch = h) -0.01 %, σ_yy 0.0043 q, p 0.0065 q, checkerboard 0.0090;
// patch-wise (1.5 h, the B-spline default) +0.02 %, 0.0067 q, 0.0087 q, 0.0094.
TEST(StripFootingFBar, B6Bspline2ModifiedFBarCellWiseAndPatchWise) {
  const StripFootingRun cell = run_strip_footing("bspline2", "modified", 1.0, 0.2, "b6-bspline2-cell");
  const StripFootingRun patch = run_strip_footing("bspline2", "modified", 0.0, 0.2, "b6-bspline2-patch");
  expect_accurate(patch, 0.01, 0.012, 0.015);
  expect_accurate(cell, 0.01, 0.012, 0.015);
  // The paper's "cell-wise fails on B-splines" does not appear: cell-wise is within 25 % of patch-wise.
  EXPECT_LT(cell.checkerboard, 1.25 * patch.checkerboard);
}

// The other four variants of App. A's comparison, and the standard F-bar (measured: GIMP standard
// -0.07 %, σ_yy 0.0024 q, p 0.0031 q, checkerboard 0.0016; GIMP patch-wise -0.08 %, 0.0084 q,
// 0.0100 q, 0.0081; bspline2 none -0.00 %, 0.0005 q, 0.0120 q, 0.0116; bspline2 standard -0.00 %,
// 0.0004 q, 0.0019 q, 0.0011).
TEST(StripFootingFBar, B6OtherVariantsSlow) {
  const StripFootingRun gs = run_strip_footing("gimp", "standard", 0.0, 0.2, "b6-gimp-standard");
  const StripFootingRun gp = run_strip_footing("gimp", "modified", 1.5, 0.2, "b6-gimp-patch");
  const StripFootingRun bn = run_strip_footing("bspline2", "none", 0.0, 0.2, "b6-bspline2-none");
  const StripFootingRun bs = run_strip_footing("bspline2", "standard", 0.0, 0.2, "b6-bspline2-standard");
  expect_accurate(gs, 0.005, 0.005, 0.003);
  expect_accurate(gp, 0.012, 0.015, 0.015);
  expect_accurate(bs, 0.005, 0.005, 0.003);
  // B-splines without F-bar: accurate centreline stress, but the mean stress oscillates near the
  // load's edge (x = 3 m) — less than GIMP's, more than with any F-bar.
  EXPECT_EQ(bn.status, 0);
  EXPECT_LT(std::abs(bn.settlement_error), 0.01);
  EXPECT_GT(bn.checkerboard, 1.1 * gp.checkerboard);
  EXPECT_GT(bn.p_error, 3.0 * bs.p_error);
}

// h = 0.05 m (seed 001 Fig. 13: the patch-wise field's resolution improves with the mesh):
// 160 000 particles, ~18 700 steps; about 20 min per run on one core.
TEST(StripFootingFBar, B6FineMeshSlow) {
  const StripFootingRun patch = run_strip_footing("bspline2", "modified", 0.0, 0.05, "b6-fine-bspline2-patch");
  expect_accurate(patch, 0.005, 0.006, 0.01);
}

// Cubic B-splines (the paper: "the same patch size can be used"). At 2×2 ppc the cubic basis is
// under-integrated (docs/verification.md: 2.5-4.8 % stress noise in the column tests), so every
// variant has a few % of q in σ_yy. Measured: none -0.20 %, σ_yy 0.034 q, p 0.014 q, checkerboard
// 0.0092; cell-wise +0.21 %, 0.020 q, 0.0086 q, 0.0096; patch-wise +0.90 %, 0.028 q, 0.0091 q, 0.0088.
TEST(StripFootingFBar, B6Bspline3Slow) {
  const StripFootingRun none = run_strip_footing("bspline3", "none", 0.0, 0.2, "b6-bspline3-none");
  const StripFootingRun cell = run_strip_footing("bspline3", "modified", 1.0, 0.2, "b6-bspline3-cell");
  const StripFootingRun patch = run_strip_footing("bspline3", "modified", 0.0, 0.2, "b6-bspline3-patch");
  for (const StripFootingRun* r : {&none, &cell, &patch}) {
    EXPECT_EQ(r->status, 0);
    EXPECT_LT(std::abs(r->settlement_error), 0.015);
    EXPECT_LT(r->syy_error, 0.04);
    EXPECT_LT(r->checkerboard, 0.015);
  }
  EXPECT_LT(cell.p_error, 0.012);
  EXPECT_LT(patch.p_error, 0.012);
  EXPECT_GT(none.p_error, 1.2 * cell.p_error);
}
