// Cell-moment assembly of the semi-implicit operators (solver/transfer/cell_moments.hpp) against
// the point-wise sums it replaces, for every shape function it serves, with points in the clamped
// boundary cells of the B-splines as well as inside.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "solver/transfer/cell_moments.hpp"

using namespace swmpm;

namespace {

/// Dense node-pair matrices of one assembly.
struct Dense {
  std::size_t n = 0;
  std::vector<double> L, Dsx, Dsy, Dwx, Dwy;
  explicit Dense(std::size_t nodes) : n(nodes), L(n * n), Dsx(n * n), Dsy(n * n), Dwx(n * n), Dwy(n * n) {}
  double max_abs() const {
    double m = 0.0;
    for (const auto* v : {&L, &Dsx, &Dsy, &Dwx, &Dwy})
      for (double x : *v) m = std::max(m, std::abs(x));
    return m;
  }
};

/// Points in cells [cx0, cx1] x [cy0, cy1] of a 7 x 5 grid. Single-point adds every weight from
/// each point; double-point alternates soil points (D^s and L) and water points (D^w and L), as
/// semi_implicit/pressure.hpp does. The box is the points' supports only (a partial box when the range is).
template <class Shape>
void check_against_pointwise(int points_per_cell, int cx0 = 0, int cx1 = 6, int cy0 = 0, int cy1 = 4,
                             bool double_point = false, bool derived_laplace = false) {
  constexpr int S = Shape::support;
  // 7 x 5 cells of 0.4 m, off the origin: every B-spline cell class (clamped ends and interior).
  const Grid<2> g(Vec<2>(-1.1, 0.3), Vec<2>(-1.1 + 7 * 0.4, 0.3 + 5 * 0.4), 0.4, Shape::degree, Shape::bspline);
  const auto& nn = g.nodes_per_axis();
  const std::size_t nodes = static_cast<std::size_t>(nn[0]) * nn[1];
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Dense direct(nodes), moments(nodes);
  transfer::CellMoments<Shape> cm(g);
  // derive_laplace: every point's L weight is cs / rho_s + cw / rho_w (one grain, one water
  // density), and the moments form L from the D^s and D^w sets.
  const double rho_s = 2650.0, rho_w = 1000.0;
  if (derived_laplace) cm.derive_laplace(rho_s, rho_w);
  NodeBox<2> box;
  box.lo = {nn[0], nn[1]};
  box.hi = {-1, -1};
  for (int cy = cy0; cy <= cy1; ++cy)
    for (int cx = cx0; cx <= cx1; ++cx)
      for (int k = 0; k < points_per_cell; ++k) {
        const Vec<2> x(-1.1 + (cx + u01(rng)) * 0.4, 0.3 + (cy + u01(rng)) * 0.4);
        double cs = 0.5 + u01(rng), cw = 0.5 + u01(rng);
        double cl = 0.5 + u01(rng);
        const bool soil = k % 2 == 0;
        if (double_point) (soil ? cw : cs) = 0.0;
        if (derived_laplace) cl = cs / rho_s + cw / rho_w;
        shape::ShapeData<2, S> sd;
        shape::evaluate<Shape>(g, x, Vec<2>(Vec<2>::Zero()), sd);
        for (int a = 0; a < 2; ++a) {
          box.lo[a] = std::min(box.lo[a], sd.base[a]);
          box.hi[a] = std::max(box.hi[a], sd.base[a] + S - 1);
        }
        std::array<std::size_t, S * S> node;
        std::array<double, S * S> N;
        std::array<Vec<2>, S * S> grad;
        int a = 0;
        shape::for_each_node(g, sd, [&](std::size_t i, double w, const Vec<2>& dN) {
          node[a] = i;
          N[a] = w;
          grad[a++] = dN;
        });
        for (int r = 0; r < S * S; ++r)
          for (int c = 0; c < S * S; ++c) {
            const std::size_t e = node[r] * nodes + node[c];
            direct.L[e] += cl * grad[r].dot(grad[c]);
            direct.Dsx[e] += cs * N[r] * grad[c][0];
            direct.Dsy[e] += cs * N[r] * grad[c][1];
            direct.Dwx[e] += cw * N[r] * grad[c][0];
            direct.Dwy[e] += cw * N[r] * grad[c][1];
          }
        if (!double_point) cm.template add<true, true>(g, sd.base, x, cs, cw, cl);
        else if (soil) cm.template add<true, false>(g, sd.base, x, cs, 0.0, cl);
        else cm.template add<false, true>(g, sd.base, x, 0.0, cw, cl);
      }
  int cells = 0;
  // reduce() calls back from several threads (cells of one colour in parallel): the dense
  // matrices here are shared, so the callback is serialised.
  // Stripes along axis 0 here, along axis 1 below: the sums do not depend on it but through rounding.
  cm.reduce(box, 0, [](int) {}, [&](std::size_t first, const typename transfer::CellMoments<Shape>::CellOperators& op) {
#pragma omp critical
    {
    ++cells;
    for (int r = 0; r < S * S; ++r)
      for (int c = 0; c < S * S; ++c) {
        const std::size_t nr = first + (r / S) * nn[0] + r % S, nc = first + (c / S) * nn[0] + c % S;
        const std::size_t e = nr * nodes + nc;
        // L comes for the pairs c >= r only (symmetric): fill both triangles.
        if (c >= r) {
          moments.L[e] += op.l(r, c);
          if (c != r) moments.L[nc * nodes + nr] += op.l(r, c);
        }
        moments.Dsx[e] += op.ds(r, c)[0];
        moments.Dsy[e] += op.ds(r, c)[1];
        moments.Dwx[e] += op.dw(r, c)[0];
        moments.Dwy[e] += op.dw(r, c)[1];
      }
    }
  });
  EXPECT_EQ(cells, (cx1 - cx0 + 1) * (cy1 - cy0 + 1)) << Shape::name;
  const double scale = direct.max_abs();
  ASSERT_GT(scale, 0.0);
  double err = 0.0;
  for (std::size_t e = 0; e < nodes * nodes; ++e) {
    err = std::max(err, std::abs(direct.L[e] - moments.L[e]));
    err = std::max(err, std::abs(direct.Dsx[e] - moments.Dsx[e]));
    err = std::max(err, std::abs(direct.Dsy[e] - moments.Dsy[e]));
    err = std::max(err, std::abs(direct.Dwx[e] - moments.Dwx[e]));
    err = std::max(err, std::abs(direct.Dwy[e] - moments.Dwy[e]));
  }
  // Same integrals in exact arithmetic; the monomial basis on [0, 1) loses a few digits only.
  EXPECT_LT(err, 1e-12 * scale) << Shape::name << ": max |moments - pointwise| = " << err << " of " << scale;
  // The moments are zeroed by reduce(): a second reduction, over the whole grid, finds no cell.
  box.lo = {0, 0};
  box.hi = {nn[0] - 1, nn[1] - 1};
  cells = 0;
  cm.reduce(box, 1, [](int) {}, [&](std::size_t, const auto&) {
#pragma omp atomic
    ++cells;
  });
  EXPECT_EQ(cells, 0);
}

}  // namespace

TEST(CellMoments, LinearMatchesPointwiseSums) { check_against_pointwise<shape::Linear>(9); }
TEST(CellMoments, QuadraticBSplineMatchesPointwiseSumsInClampedAndInteriorCells) {
  check_against_pointwise<shape::BSpline2>(9);
}
TEST(CellMoments, CubicBSplineMatchesPointwiseSumsInClampedAndInteriorCells) {
  check_against_pointwise<shape::BSpline3>(16);
}
TEST(CellMoments, DoublePointSetsInAPartialBoxMatchPointwiseSums) {
  check_against_pointwise<shape::BSpline2>(8, 2, 5, 1, 3, true);
  check_against_pointwise<shape::BSpline3>(8, 0, 3, 2, 4, true);
  check_against_pointwise<shape::Linear>(4, 3, 6, 0, 1, true);
}
TEST(CellMoments, LaplaceDerivedFromTheDensitiesMatchesPointwiseSums) {
  check_against_pointwise<shape::BSpline2>(9, 0, 6, 0, 4, false, true);
  check_against_pointwise<shape::BSpline2>(8, 2, 5, 1, 3, true, true);
  check_against_pointwise<shape::Linear>(9, 0, 6, 0, 4, true, true);
}
