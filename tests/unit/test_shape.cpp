// Shape functions: partition of unity, zero gradient sum, linear reproduction (where it holds),
// derivative consistency and boundary interpolation, in 2D and 3D.
#include <gtest/gtest.h>

#include <random>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "solver/loads.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/transfer.hpp"

using namespace swmpm;

namespace {

template <int Dim, class Shape>
struct Case {
  static Grid<Dim> grid() {
    Vec<Dim> lo, hi;
    for (int a = 0; a < Dim; ++a) {
      lo[a] = -0.3 + 0.1 * a;
      hi[a] = lo[a] + 0.25 * (5 + a);  // 5, 6, 7 cells of 0.25
    }
    return Grid<Dim>(lo, hi, 0.25, Shape::degree, Shape::bspline);
  }
};

/// Checks sum N = 1, sum grad N = 0 and, where `linear`, sum N x_i = x and sum x_i grad N^T = I.
template <int Dim, class Shape>
void check_point(const Grid<Dim>& g, const Vec<Dim>& x, double l_p, bool linear) {
  shape::ShapeData<Dim, Shape::support> sd;
  Vec<Dim> l = Vec<Dim>::Constant(l_p);
  shape::evaluate<Shape>(g, x, l, sd);
  double sum = 0.0;
  Vec<Dim> grad_sum = Vec<Dim>::Zero(), x_rep = Vec<Dim>::Zero();
  MatD<Dim> grad_rep = MatD<Dim>::Zero();
  // Decode flat node indices back to positions.
  shape::for_each_node(g, sd, [&](std::size_t i, double N, const Vec<Dim>& dN) {
    std::array<int, Dim> ijk;
    std::size_t r = i;
    for (int a = 0; a < Dim; ++a) {
      ijk[a] = static_cast<int>(r % g.nodes_per_axis()[a]);
      r /= g.nodes_per_axis()[a];
    }
    ASSERT_GE(N, -1e-14);
    const Vec<Dim> xi = g.node_position(ijk);
    sum += N;
    grad_sum += dN;
    x_rep += N * xi;
    grad_rep += xi * dN.transpose();
  });
  EXPECT_NEAR(sum, 1.0, 1e-13) << Shape::name << " at " << x.transpose();
  EXPECT_NEAR(grad_sum.norm(), 0.0, 1e-11) << Shape::name << " at " << x.transpose();
  if (linear) {
    EXPECT_NEAR((x_rep - x).norm(), 0.0, 1e-13) << Shape::name << " at " << x.transpose();
    EXPECT_NEAR((grad_rep - MatD<Dim>::Identity()).norm(), 0.0, 1e-11) << Shape::name << " at " << x.transpose();
  }
}

template <int Dim, class Shape>
void check_shape(bool linear_everywhere) {
  const Grid<Dim> g = Case<Dim, Shape>::grid();
  std::mt19937 rng(42);
  const double h = g.h();
  const double l_p = 0.25 * h;  // 2 particles per cell
  for (int k = 0; k < 400; ++k) {
    Vec<Dim> x;
    for (int a = 0; a < Dim; ++a) x[a] = std::uniform_real_distribution<double>(g.min()[a], g.max()[a])(rng);
    // GIMP reproduces linear fields where the particle domain lies inside the grid.
    bool interior = true;
    for (int a = 0; a < Dim; ++a) interior = interior && x[a] - l_p >= g.min()[a] && x[a] + l_p <= g.max()[a];
    check_point<Dim, Shape>(g, x, l_p, linear_everywhere || interior);
  }
  // Exactly on the boundary and on nodes.
  check_point<Dim, Shape>(g, g.min(), l_p, linear_everywhere);
  check_point<Dim, Shape>(g, g.max(), l_p, linear_everywhere);
}

}  // namespace

TEST(ShapeFunctions, Linear2D) { check_shape<2, shape::Linear>(true); }
TEST(ShapeFunctions, Linear3D) { check_shape<3, shape::Linear>(true); }
TEST(ShapeFunctions, Gimp2D) { check_shape<2, shape::Gimp>(false); }
TEST(ShapeFunctions, Gimp3D) { check_shape<3, shape::Gimp>(false); }
TEST(ShapeFunctions, BSpline2_2D) { check_shape<2, shape::BSpline2>(true); }
TEST(ShapeFunctions, BSpline2_3D) { check_shape<3, shape::BSpline2>(true); }
TEST(ShapeFunctions, BSpline3_2D) { check_shape<2, shape::BSpline3>(true); }
TEST(ShapeFunctions, BSpline3_3D) { check_shape<3, shape::BSpline3>(true); }

/// One-dimensional derivatives agree with central differences of the weights (inside a cell).
template <class Shape>
void check_derivative() {
  Axis ax;
  ax.origin = 0.0;
  ax.h = 0.5;
  ax.cells = 6;
  ax.nodes = Shape::bspline ? ax.cells + Shape::degree : ax.cells + 1;
  const double eps = 1e-6;
  for (double x = 0.013; x < 3.0; x += 0.0371) {
    int b0, bp, bm;
    double w[Shape::support], dw[Shape::support], wp[Shape::support], wm[Shape::support], tmp[Shape::support];
    Shape::eval(ax, x, 0.125, b0, w, dw);
    Shape::eval(ax, x + eps, 0.125, bp, wp, tmp);
    Shape::eval(ax, x - eps, 0.125, bm, wm, tmp);
    if (bp != b0 || bm != b0) continue;  // crossed a span: skip
    // Clipped GIMP domains (within l_p of the boundary) use the domain-average gradient instead.
    if (!Shape::bspline && Shape::support == 3 && (x < 0.125 + eps || x > 3.0 - 0.125 - eps)) continue;
    for (int s = 0; s < Shape::support; ++s)
      EXPECT_NEAR(dw[s], (wp[s] - wm[s]) / (2 * eps), 1e-6) << Shape::name << " x=" << x << " s=" << s;
  }
}

TEST(ShapeFunctions, DerivativesMatchFiniteDifferences) {
  check_derivative<shape::Linear>();
  check_derivative<shape::Gimp>();
  check_derivative<shape::BSpline2>();
  check_derivative<shape::BSpline3>();
}

/// Clamped B-splines are interpolatory at the boundary: only the first/last node is non-zero there,
/// so a Dirichlet condition on that node holds exactly on the boundary.
TEST(ShapeFunctions, BSplinesInterpolateAtBoundary) {
  for (int p : {2, 3}) {
    Axis ax;
    ax.origin = 1.0;
    ax.h = 0.1;
    ax.cells = 8;
    ax.nodes = ax.cells + p;
    int base;
    double w[4], dw[4];
    auto eval = [&](double x) {
      if (p == 2) shape::BSpline2::eval(ax, x, 0.0, base, w, dw);
      else shape::BSpline3::eval(ax, x, 0.0, base, w, dw);
    };
    eval(1.0);
    EXPECT_EQ(base, 0);
    EXPECT_NEAR(w[0], 1.0, 1e-15);
    for (int s = 1; s <= p; ++s) EXPECT_NEAR(w[s], 0.0, 1e-15);
    eval(1.8);
    EXPECT_EQ(base + p, ax.nodes - 1);
    EXPECT_NEAR(w[p], 1.0, 1e-15);
  }
}

/// Uniform interior B-spline values: quadratic at a node 1/8, 3/4, 1/8; cubic 1/6, 2/3, 1/6.
TEST(ShapeFunctions, BSplineInteriorValues) {
  Axis ax;
  ax.origin = 0.0;
  ax.h = 1.0;
  ax.cells = 10;
  int base;
  double w[4], dw[4];
  ax.nodes = ax.cells + 2;
  shape::BSpline2::eval(ax, 5.5, 0.0, base, w, dw);  // quadratic nodes sit at cell centres inside
  EXPECT_NEAR(w[0], 0.125, 1e-14);
  EXPECT_NEAR(w[1], 0.75, 1e-14);
  EXPECT_NEAR(w[2], 0.125, 1e-14);
  ax.nodes = ax.cells + 3;
  shape::BSpline3::eval(ax, 5.0, 0.0, base, w, dw);
  EXPECT_NEAR(w[0], 1.0 / 6.0, 1e-14);
  EXPECT_NEAR(w[1], 2.0 / 3.0, 1e-14);
  EXPECT_NEAR(w[2], 1.0 / 6.0, 1e-14);
  EXPECT_NEAR(w[3], 0.0, 1e-14);
}

/// The closed forms agree with the clamped-knot recursion: the uniform interior spans, and for
/// quadratic B-splines the end cells too (every cell of the axis; cubic: interior only).
TEST(ShapeFunctions, BSplineClosedFormsMatchTheRecursion) {
  auto compare = [](auto policy, int P) {
    using Shape = decltype(policy);
    Axis ax;
    ax.origin = -1.0;
    ax.h = 0.3;
    ax.cells = 12;
    ax.nodes = ax.cells + P;
    int tested = 0;
    const double u_lo = P == 2 ? 0.0 : P, u_hi = P == 2 ? ax.cells : ax.cells - P;
    for (double u = u_lo; u < u_hi; u += 0.0137) {
      const double x = ax.origin + u * ax.h;
      int b1, b2;
      double w1[4], dw1[4], w2[4], dw2[4];
      Shape::eval(ax, x, 0.0, b1, w1, dw1);
      Shape::eval_clamped(ax, x, 0.0, b2, w2, dw2);
      ASSERT_EQ(b1, b2);
      for (int i = 0; i <= P; ++i) {
        EXPECT_NEAR(w1[i], w2[i], 1e-14) << "u = " << u;
        EXPECT_NEAR(dw1[i], dw2[i], 1e-13) << "u = " << u;
      }
      ++tested;
    }
    EXPECT_GT(tested, P == 2 ? 800 : 300);
  };
  compare(shape::BSpline2{}, 2);
  compare(shape::BSpline3{}, 3);
}

/// Short axes: with 3 and 4 cells both clamped ends are one cell apart (cell 1 borders both), and
/// below 3 cells eval takes the recursion. Every cell of every such axis agrees with it.
TEST(ShapeFunctions, QuadraticBSplineOnShortAxesMatchesTheRecursion) {
  for (int cells = 1; cells <= 4; ++cells) {
    Axis ax;
    ax.origin = 0.5;
    ax.h = 0.2;
    ax.cells = cells;
    ax.nodes = cells + 2;
    int tested = 0;
    for (double u = 0.0; u < cells; u += 0.0113) {
      const double x = ax.origin + u * ax.h;
      int b1, b2;
      double w1[3], dw1[3], w2[3], dw2[3];
      shape::BSpline2::eval(ax, x, 0.0, b1, w1, dw1);
      shape::BSpline2::eval_clamped(ax, x, 0.0, b2, w2, dw2);
      ASSERT_EQ(b1, b2) << cells << " cells, u = " << u;
      double sum = 0.0;
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(w1[i], w2[i], 1e-14) << cells << " cells, u = " << u;
        EXPECT_NEAR(dw1[i], dw2[i], 1e-12) << cells << " cells, u = " << u;
        sum += w1[i];
      }
      EXPECT_NEAR(sum, 1.0, 1e-14);  // partition of unity
      ++tested;
    }
    EXPECT_GT(tested, 80 * cells);
  }
}

/// transfer::evaluate_shapes takes quadratic B-splines in 2D through shape::BSpline2Pairs (both
/// axes in register pairs) where it can: its shape data must be the per-axis evaluation's bit for
/// bit, and its node box and first point off the grid the same, for points in every cell (the
/// clamped end cells take the per-axis path), on cell faces, on the grid's faces and corners, and
/// outside it (also not finite).
template <bool kGradients>
void check_packed_bspline2() {
  const Grid<2> g(Vec<2>(-1.3, 0.7), Vec<2>(4.2, 3.1), 0.25, 2, true);  // 22 x 10 cells
  ParticleSet<2> ps;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-1.3, 4.2), uy(0.7, 3.1);
  std::vector<Vec<2>> xs;
  for (int k = 0; k < 4000; ++k) xs.emplace_back(ux(rng), uy(rng));
  for (int i = 0; i <= 22; ++i)  // cell faces and grid faces, corners included
    for (int j = 0; j <= 10; ++j) xs.emplace_back(-1.3 + 0.25 * i, 0.7 + 0.25 * j);
  const int first_out = static_cast<int>(xs.size());
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const Vec<2>& x : {Vec<2>(-1.4, 1.0), Vec<2>(1.0, 3.2), Vec<2>(nan, 1.0), Vec<2>(inf, 1.0), Vec<2>(1.0, -inf)})
    xs.push_back(x);
  ps.resize(xs.size());
  for (std::size_t p = 0; p < xs.size(); ++p) ps.x[p] = xs[p], ps.l[p] = Vec<2>::Constant(0.0625);
  std::vector<shape::ShapeData<2, 3, kGradients>> sd;
  long bad = -2;
  const NodeBox<2> box = transfer::evaluate_shapes<shape::BSpline2>(g, ps, sd, bad);
  EXPECT_EQ(bad, first_out);
  std::array<int, 2> lo{1 << 30, 1 << 30}, hi{-1, -1};
  int interior = 0;
  const Vec<2> gmin = g.min(), gmax = g.max();
  for (std::size_t p = 0; p < xs.size(); ++p) {
    Vec<2> x = xs[p];
    for (int a = 0; a < 2; ++a) x[a] = std::isfinite(x[a]) ? std::clamp(x[a], gmin[a], gmax[a]) : gmin[a];
    shape::ShapeData<2, 3, kGradients> ref;
    for (int a = 0; a < 2; ++a) shape::evaluate_axis<shape::BSpline2>(g, a, x[a], 0.0625, ref);
    ASSERT_EQ(std::memcmp(&ref, &sd[p], sizeof ref), 0) << "point " << p << " at " << xs[p].transpose();
    for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], ref.base[a]), hi[a] = std::max(hi[a], ref.base[a] + 2);
    interior += ref.base[0] >= 1 && ref.base[0] <= 20 && ref.base[1] >= 1 && ref.base[1] <= 8;
  }
  EXPECT_EQ(box.lo, lo);
  EXPECT_EQ(box.hi, hi);
  EXPECT_GT(interior, 2500);  // the packed path was taken
}
TEST(ShapeFunctions, PackedQuadraticBSplinesAreThePerAxisOnesBitForBit) {
  check_packed_bspline2<true>();
  check_packed_bspline2<false>();
}

/// A face force goes to the face point's nodes that carry mass, scaled so that the shares still
/// sum to the force (solver/loads.hpp, face_force_scale and for_each_loaded_node): the case of linear shape functions
/// with a particle on a node row, whose next row up has no mass but a weight of 1/2 at the face point.
TEST(FaceForces, MasslessNodesGetNoShareAndTheResultantIsKept) {
  const Grid<2> g(Vec<2>(0.0, 0.0), Vec<2>(1.0, 1.0), 0.1, 1, false);
  FaceForce<2, 2> ff{};
  ff.f = Vec<2>(0.0, -3.0);
  shape::evaluate<shape::Linear>(g, Vec<2>(0.45, 0.85), Vec<2>::Zero().eval(), ff.sd);  // face point mid-cell in y
  const auto& nn = g.nodes_per_axis();
  const std::size_t top_row = 9;  // y = 0.9: no mass
  auto has_mass = [&](std::size_t i) { return i / static_cast<std::size_t>(nn[0]) != top_row; };
  Vec<2> total = Vec<2>::Zero();
  double weight = 0.0;
  ff.scale = face_force_scale(g, ff, has_mass);  // weigh_face_forces, once the masses are scattered
  for_each_loaded_node(g, ff, has_mass, [&](std::size_t i, double N) {
    EXPECT_NE(i / static_cast<std::size_t>(nn[0]), top_row);
    total += N * ff.f;
    weight += N;
  });
  EXPECT_NEAR(weight, 1.0, 1e-14);
  EXPECT_NEAR((total - ff.f).norm(), 0.0, 1e-14);
  // Every node loaded: the face point's own weights.
  double all = 0.0;
  ff.scale = face_force_scale(g, ff, [](std::size_t) { return true; });
  for_each_loaded_node(g, ff, [](std::size_t) { return true; }, [&](std::size_t, double N) { all += N; });
  EXPECT_NEAR(all, 1.0, 1e-14);
}
