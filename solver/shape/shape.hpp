// Shape functions as compile-time policies. Each policy evaluates, for one coordinate along one
// axis, the first node index `base` and the S one-dimensional weights w[s] and derivatives dw[s]
// (1/m) of nodes base .. base + S - 1. Tensor products give N_ip and grad N_ip:
//     N_ip = prod_a w_a[s_a],   d N_ip / d x_b = dw_b[s_b] prod_{a != b} w_a[s_a].
// Every policy satisfies partition of unity and sum dw = 0 everywhere in [min, max] of the grid,
// including the boundary cells (tests/unit/test_shape.cpp).
//
// - Linear: hat functions on cell corners.
// - Gimp: uGIMP, the hat function averaged over the particle domain [x - l_p, x + l_p]; where that
//   domain reaches past the grid boundary it is clipped to the grid, which keeps partition of unity
//   (linear reproduction then holds for the clipped domain's centre).
// - BSpline<p>: B-splines of degree p on the open (clamped) uniform knot vector
//   t = {0 (p+1 times), h, 2h, ..., L (p+1 times)}: interpolatory at the boundary, so the first and
//   last node carry Dirichlet conditions exactly, and they reproduce linear fields everywhere with
//   nodes at the Greville abscissae (Grid). Cox–de Boor recursion (Piegl & Tiller, The NURBS Book,
//   A2.2/A2.3), written out for the clamped uniform knots.
#pragma once

#include <algorithm>
#include <cmath>
#include <stdexcept>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "scene/scene.hpp"
#include "solver/common.hpp"
#include "solver/grid/grid.hpp"

namespace swmpm::shape {

/// Index of the cell holding xi (in cells), clamped to [0, cells - 1]. Truncation plus a
/// correction instead of std::floor, which without SSE4.1 is a library call on the hot path.
[[gnu::always_inline]] inline int cell_of(double xi, int cells) {
  int c = static_cast<int>(xi);
  c -= xi < static_cast<double>(c) ? 1 : 0;
  return std::clamp(c, 0, cells - 1);
}

struct Linear {
  static constexpr int support = 2;
  static constexpr int degree = 1;
  static constexpr bool bspline = false;
  static constexpr const char* name = "linear";
  [[gnu::always_inline]] static void eval(const Axis& ax, double x, double /*l_p*/, int& base, double* w, double* dw) {
    const double xi = (x - ax.origin) / ax.h;
    const int c = cell_of(xi, ax.cells);
    const double r = xi - c;
    base = c;
    w[0] = 1.0 - r;
    w[1] = r;
    dw[0] = -1.0 / ax.h;
    dw[1] = 1.0 / ax.h;
  }
};

struct Gimp {
  static constexpr int support = 3;
  static constexpr int degree = 1;
  static constexpr bool bspline = false;
  static constexpr const char* name = "gimp";
  /// Hat function of a node at r = 0 (r in cells) and its antiderivative.
  static double hat(double r) { return std::max(0.0, 1.0 - std::abs(r)); }
  static double hat_integral(double r) {
    if (r <= -1.0) return 0.0;
    if (r <= 0.0) return 0.5 * (r + 1.0) * (r + 1.0);
    if (r <= 1.0) return 1.0 - 0.5 * (1.0 - r) * (1.0 - r);
    return 1.0;
  }
  [[gnu::always_inline]] static void eval(const Axis& ax, double x, double l_p, int& base, double* w, double* dw) {
    const double xi = (x - ax.origin) / ax.h;
    const double l = l_p / ax.h;  // half-size in cells, <= 1/2
    const int c = cell_of(xi, ax.cells);
    base = std::clamp(xi - c < 0.5 ? c - 1 : c, 0, ax.nodes - 3);
    const double inv_h = 1.0 / ax.h;
    if (l <= 0.0) {  // a point (e.g. a traction's face point): the hat functions themselves
      for (int s = 0; s < 3; ++s) {
        const double r = xi - (base + s);
        w[s] = hat(r);
        dw[s] = std::abs(r) < 1.0 ? (r < 0.0 ? inv_h : -inv_h) : 0.0;
      }
      return;
    }
    if (xi - l >= 0.0 && xi + l <= ax.cells) {
      // Domain inside the grid: closed-form uGIMP (Bardenhagen & Kober 2004), r = (x - x_i)/h.
      // `base` makes node 1 the nearest (|r_1| < 1/2), so each node has only two cases, picked
      // without branches: near node |r| <= l: 1 - (r^2 + l^2)/2l, else 1 - |r|;
      // outer nodes |r| <= 1 - l: 1 - |r|, else (1 + l - |r|)^2 / 4l (0 beyond 1 + l).
      const double inv_2l = 0.5 / l;
      {
        const double r = xi - (base + 1), ar = std::abs(r), sg = r < 0.0 ? -1.0 : 1.0;
        const bool inner = ar <= l;
        w[1] = inner ? 1.0 - (r * r + l * l) * inv_2l : 1.0 - ar;
        dw[1] = (inner ? -r * 2.0 * inv_2l : -sg) * inv_h;
      }
      for (int s = 0; s < 3; s += 2) {
        const double r = xi - (base + s), ar = std::abs(r), sg = r < 0.0 ? -1.0 : 1.0;
        const double d = std::max(0.0, 1.0 + l - ar);
        const bool linear = ar <= 1.0 - l;
        w[s] = linear ? 1.0 - ar : d * d * 0.5 * inv_2l;
        dw[s] = -sg * (linear ? 1.0 : d * inv_2l) * inv_h;
      }
      return;
    }
    // Particle domain clipped to the grid [0, cells]: average of the hat function over [a, b].
    const double a = std::max(xi - l, 0.0), b = std::min(xi + l, static_cast<double>(ax.cells));
    const double inv = 1.0 / (b - a);
    for (int s = 0; s < 3; ++s) {
      const double i = base + s;
      w[s] = (hat_integral(b - i) - hat_integral(a - i)) * inv;
      dw[s] = (hat(b - i) - hat(a - i)) * inv * inv_h;
    }
  }
};

template <int P>
struct BSpline {
  static constexpr int support = P + 1;
  static constexpr int degree = P;
  static constexpr bool bspline = true;
  static constexpr const char* name = P == 2 ? "bspline2" : "bspline3";
  /// Away from the clamped ends (cells P .. n - P - 1 see only uniform knots) the closed forms of
  /// the uniform B-splines, with xi = u - c in [0, 1) (de Boor; the recursion below gives the same
  /// polynomials, tests/unit/test_shape.cpp):
  ///   P = 2: w = ((1 - xi)^2 / 2, 1/2 + xi - xi^2, xi^2 / 2)
  ///   P = 3: w = ((1 - xi)^3, 3 xi^3 - 6 xi^2 + 4, -3 xi^3 + 3 xi^2 + 3 xi + 1, xi^3) / 6
  ///   P = 2 with the clamped knots (0, 0, 0, 1, 2, ...): only the end cells 0 and n - 1 differ
  ///   from the uniform span (cell 1 is uniform):
  ///     cell 0:      w = ((1 - xi)^2, 2 xi - 3/2 xi^2, xi^2 / 2)
  ///     cell n - 1:  the mirror image, eta = 1 - xi: w = (eta^2 / 2, 2 eta - 3/2 eta^2, (1 - eta)^2)
  [[gnu::always_inline]] static void eval(const Axis& ax, double x, double l_p, int& base, double* w, double* dw) {
    const double u = (x - ax.origin) / ax.h;  // in cells
    const int c = cell_of(u, ax.cells);
    constexpr int kFirstUniform = P == 2 ? 1 : P;  // cells of the closed forms: kFirstUniform .. n - 1 - kFirstUniform
    if (c < kFirstUniform || c > ax.cells - kFirstUniform - 1) {
      if constexpr (P != 2) {
        return eval_clamped(ax, x, l_p, base, w, dw);
      } else {
        if (ax.cells < 3) return eval_clamped(ax, x, l_p, base, w, dw);
        base = c;
        const double inv_h = 1.0 / ax.h;
        if (c == 0) {
          const double xi = u, r = 1.0 - xi;
          w[0] = r * r;
          w[1] = xi * (2.0 - 1.5 * xi);
          w[2] = 0.5 * xi * xi;
          dw[0] = -2.0 * r * inv_h;
          dw[1] = (2.0 - 3.0 * xi) * inv_h;
          dw[2] = xi * inv_h;
        } else {
          const double eta = 1.0 - (u - c), r = 1.0 - eta;
          w[0] = 0.5 * eta * eta;
          w[1] = eta * (2.0 - 1.5 * eta);
          w[2] = r * r;
          dw[0] = -eta * inv_h;
          dw[1] = -(2.0 - 3.0 * eta) * inv_h;
          dw[2] = 2.0 * r * inv_h;
        }
        return;
      }
    }
    base = c;
    const double xi = u - c, inv_h = 1.0 / ax.h;
    if constexpr (P == 2) {
      const double r = 1.0 - xi;
      w[0] = 0.5 * r * r;
      w[1] = 0.5 + xi * r;
      w[2] = 0.5 * xi * xi;
      dw[0] = -r * inv_h;
      dw[1] = (r - xi) * inv_h;
      dw[2] = xi * inv_h;
    } else {
      const double r = 1.0 - xi, xi2 = xi * xi, xi3 = xi2 * xi;
      constexpr double sixth = 1.0 / 6.0;
      w[0] = sixth * r * r * r;
      w[1] = sixth * (3.0 * xi3 - 6.0 * xi2 + 4.0);
      w[2] = sixth * (-3.0 * xi3 + 3.0 * xi2 + 3.0 * xi + 1.0);
      w[3] = sixth * xi3;
      dw[0] = -0.5 * r * r * inv_h;
      dw[1] = (1.5 * xi2 - 2.0 * xi) * inv_h;
      dw[2] = (-1.5 * xi2 + xi + 0.5) * inv_h;
      dw[3] = 0.5 * xi2 * inv_h;
    }
  }
  /// Any cell, by the recursion (the path of the cubic's P cells next to each clamped end, and of
  /// axes of fewer than 3 cells).
  static void eval_clamped(const Axis& ax, double x, double /*l_p*/, int& base, double* w, double* dw) {
    const double u = (x - ax.origin) / ax.h;  // in cells
    const int n = ax.cells;
    const int c = cell_of(u, n);
    base = c;                       // nonzero bases: c .. c + P
    const int k = c + P;            // knot span index: t_k <= u < t_{k+1}
    auto t = [&](int i) { return static_cast<double>(std::clamp(i - P, 0, n)); };
    // N[d][i] = N_{k-d+i, d}(u), i = 0..d, built degree by degree.
    double N[P + 1][P + 1] = {};
    N[0][0] = 1.0;
    for (int d = 1; d <= P; ++d) {
      for (int i = 0; i <= d; ++i) {
        const int j = k - d + i;
        double val = 0.0;
        if (i >= 1) {  // N_{j, d-1} = N[d-1][i-1]
          const double den = t(j + d) - t(j);
          if (den > 0.0) val += (u - t(j)) / den * N[d - 1][i - 1];
        }
        if (i <= d - 1) {  // N_{j+1, d-1} = N[d-1][i]
          const double den = t(j + d + 1) - t(j + 1);
          if (den > 0.0) val += (t(j + d + 1) - u) / den * N[d - 1][i];
        }
        N[d][i] = val;
      }
    }
    for (int i = 0; i <= P; ++i) {
      const int j = k - P + i;
      w[i] = N[P][i];
      double der = 0.0;
      if (i >= 1) {
        const double den = t(j + P) - t(j);
        if (den > 0.0) der += P / den * N[P - 1][i - 1];
      }
      if (i <= P - 1) {
        const double den = t(j + P + 1) - t(j + 1);
        if (den > 0.0) der -= P / den * N[P - 1][i];
      }
      dw[i] = der / ax.h;
    }
  }
};

using BSpline2 = BSpline<2>;
using BSpline3 = BSpline<3>;

/// Calls fn.template operator()<Policy>() with the policy of a scene's shape function, for code
/// outside the formulations that evaluates the solver's basis functions (preprocess's initial
/// phase field); the formulations are dispatched once, when they are built, by dispatch_shape
/// (formulations/registry.hpp).
template <class Fn>
auto with_policy(scene::ShapeFunction f, Fn&& fn) {
  switch (f) {
    case scene::ShapeFunction::linear: return fn.template operator()<Linear>();
    case scene::ShapeFunction::gimp: return fn.template operator()<Gimp>();
    case scene::ShapeFunction::bspline2: return fn.template operator()<BSpline2>();
    case scene::ShapeFunction::bspline3: return fn.template operator()<BSpline3>();
  }
  throw std::logic_error("unknown shape function");
}

/// Per-particle shape data, computed once per step and reused by every transfer of that step.
/// kGradients = false: the weights only (points that never take a gradient, e.g. the water points
/// of the semi-implicit double-point with cell moments): 56 instead of 104 bytes per point in 2D,
/// which every pass over those points streams.
template <int Dim, int S, bool kGradients = true>
struct ShapeData {
  std::array<int, Dim> base;
  double w[Dim][S];
  double dw[Dim][S];
};
template <int Dim, int S>
struct ShapeData<Dim, S, false> {
  std::array<int, Dim> base;
  double w[Dim][S];
};

/// What the visitors below pass for the gradient of weights-only shape data: a callback that
/// uses it (as a Vec) does not compile.
struct NoGradient {};

/// Visits the S^Dim nodes of a particle: fn(flat node index, N_ip, grad N_ip).
/// Node order is fixed (x fastest), so every sum over nodes has one summation order.
/// Weights-only shape data pass NoGradient for grad N_ip.
template <int Dim, int S, bool G, class Fn>
inline void for_each_node(const Grid<Dim>& g, const ShapeData<Dim, S, G>& sd, Fn&& fn) {
  const auto& nn = g.nodes_per_axis();
  if constexpr (Dim == 2) {
    for (int b = 0; b < S; ++b) {
      const std::size_t row = static_cast<std::size_t>(sd.base[1] + b) * nn[0] + sd.base[0];
      for (int a = 0; a < S; ++a) {
        const double N = sd.w[0][a] * sd.w[1][b];
        if constexpr (G) {
          Vec<2> dN(sd.dw[0][a] * sd.w[1][b], sd.w[0][a] * sd.dw[1][b]);
          fn(row + a, N, dN);
        } else {
          fn(row + a, N, NoGradient{});
        }
      }
    }
  } else {
    for (int c = 0; c < S; ++c) {
      for (int b = 0; b < S; ++b) {
        const std::size_t row =
            (static_cast<std::size_t>(sd.base[2] + c) * nn[1] + (sd.base[1] + b)) * nn[0] + sd.base[0];
        const double wbc = sd.w[1][b] * sd.w[2][c];
        for (int a = 0; a < S; ++a) {
          const double N = sd.w[0][a] * wbc;
          if constexpr (G) {
            Vec<3> dN(sd.dw[0][a] * wbc, sd.w[0][a] * sd.dw[1][b] * sd.w[2][c],
                      sd.w[0][a] * sd.w[1][b] * sd.dw[2][c]);
            fn(row + a, N, dN);
          } else {
            fn(row + a, N, NoGradient{});
          }
        }
      }
    }
  }
}

/// Visits the S^(Dim-1) rows (runs of S nodes along x) of a particle's support:
/// fn(flat index of the row's first node, w_r, g_r) where, for node a of the row,
///     N_ip = wx[a] w_r,   grad N_ip = (dwx[a] w_r, wx[a] g_r[0] (, wx[a] g_r[1])),
/// with wx = sd.w[0], dwx = sd.dw[0]. Hot kernels use it to hoist the per-row products out of the
/// per-node work (the tensor-product structure of the shape functions); the visiting order is the
/// same as for_each_node's. Weights-only shape data pass NoGradient for g_r.
template <int Dim, int S, bool G, class Fn>
inline void for_each_row(const Grid<Dim>& g, const ShapeData<Dim, S, G>& sd, Fn&& fn) {
  const auto& nn = g.nodes_per_axis();
  if constexpr (Dim == 2) {
    for (int b = 0; b < S; ++b) {
      const std::size_t row = static_cast<std::size_t>(sd.base[1] + b) * nn[0] + sd.base[0];
      if constexpr (G) fn(row, sd.w[1][b], Vec<1>(sd.dw[1][b]));
      else fn(row, sd.w[1][b], NoGradient{});
    }
  } else {
    for (int c = 0; c < S; ++c)
      for (int b = 0; b < S; ++b) {
        const std::size_t row =
            (static_cast<std::size_t>(sd.base[2] + c) * nn[1] + (sd.base[1] + b)) * nn[0] + sd.base[0];
        if constexpr (G) fn(row, sd.w[1][b] * sd.w[2][c], Vec<2>(sd.dw[1][b] * sd.w[2][c], sd.w[1][b] * sd.dw[2][c]));
        else fn(row, sd.w[1][b] * sd.w[2][c], NoGradient{});
      }
  }
}

/// Axis a of a particle's shape data: the coordinate x_a with half-size l_a (weights-only data:
/// the weights only).
template <class Shape, int Dim, bool kGradients>
[[gnu::always_inline]] inline void evaluate_axis(const Grid<Dim>& g, int a, double x_a, double l_a,
                                                 ShapeData<Dim, Shape::support, kGradients>& sd) {
  if constexpr (kGradients) {
    Shape::eval(g.axis(a), x_a, l_a, sd.base[a], sd.w[a], sd.dw[a]);
  } else {
    double unused[Shape::support];  // dead stores once eval is inlined
    Shape::eval(g.axis(a), x_a, l_a, sd.base[a], sd.w[a], unused);
  }
}

/// Evaluates the shape data of a particle at x with half-sizes l_p (weights-only data: the
/// weights only).
template <class Shape, int Dim, bool kGradients>
inline void evaluate(const Grid<Dim>& g, const Vec<Dim>& x, const Vec<Dim>& l_p,
                     ShapeData<Dim, Shape::support, kGradients>& sd) {
#pragma GCC unroll 3
  for (int a = 0; a < Dim; ++a) evaluate_axis<Shape>(g, a, x[a], l_p[a], sd);
}

#if defined(__SSE2__)
/// Quadratic B-splines in 2D, both axes of a point at once in register pairs (SSE2), for the
/// points inside the grid whose cells are uniform on both axes (cells 1 .. n - 2, the closed form
/// of BSpline<2>::eval): the same operations in the same order as eval(), lane by lane, so the
/// same shape data bit for bit (tests/unit/test_shape.cpp), with one packed division where eval()
/// does one per axis (two with gradients). The grid's constants are packed once per pass.
/// cell_of's truncation and its correction are the packed cvttpd2dq and compare.
class BSpline2Pairs {
 public:
  explicit BSpline2Pairs(const Grid<2>& g)
      : origin_(_mm_set_pd(g.axis(1).origin, g.axis(0).origin)),
        h_(_mm_set_pd(g.axis(1).h, g.axis(0).h)),
        last_uniform_(_mm_set_pd(g.axis(1).cells - 2.0, g.axis(0).cells - 2.0)),
        gmin_(_mm_set_pd(g.min()[1], g.min()[0])),
        gmax_(_mm_set_pd(g.max()[1], g.max()[0])),
        inv_h_(1.0 / Pair(h_)) {}
  /// Writes sd (base and weights, and gradients if it has them) and the cells (base as doubles)
  /// of a point at x and returns true; false, with nothing written, for a point outside the grid
  /// (or not finite) or in a cell next to a clamped end.
  template <bool kGradients>
  [[gnu::always_inline]] bool operator()(const double* x, ShapeData<2, 3, kGradients>& sd, __m128d& cell) const {
    const __m128d xv = _mm_loadu_pd(x);
    if (_mm_movemask_pd(_mm_and_pd(_mm_cmpge_pd(xv, gmin_), _mm_cmple_pd(xv, gmax_))) != 3) return false;
    const __m128d u = _mm_div_pd(_mm_sub_pd(xv, origin_), h_);
    __m128d c = _mm_cvtepi32_pd(_mm_cvttpd_epi32(u));
    c = _mm_sub_pd(c, _mm_and_pd(_mm_cmplt_pd(u, c), _mm_set1_pd(1.0)));  // floor: c -= u < c
    if (_mm_movemask_pd(_mm_and_pd(_mm_cmpge_pd(c, _mm_set1_pd(1.0)), _mm_cmple_pd(c, last_uniform_))) != 3)
      return false;
    cell = c;
    sd.base[0] = static_cast<int>(c[0]);
    sd.base[1] = static_cast<int>(c[1]);
    const Pair xi = u - c, r = 1.0 - xi;
    const Pair w0 = 0.5 * r * r, w1 = 0.5 + xi * r, w2 = 0.5 * xi * xi;
    sd.w[0][0] = w0[0], sd.w[0][1] = w1[0], sd.w[0][2] = w2[0];
    sd.w[1][0] = w0[1], sd.w[1][1] = w1[1], sd.w[1][2] = w2[1];
    if constexpr (kGradients) {
      const Pair d0 = -r * inv_h_, d1 = (r - xi) * inv_h_, d2 = xi * inv_h_;
      sd.dw[0][0] = d0[0], sd.dw[0][1] = d1[0], sd.dw[0][2] = d2[0];
      sd.dw[1][0] = d0[1], sd.dw[1][1] = d1[1], sd.dw[1][2] = d2[1];
    }
    return true;
  }

 private:
  __m128d origin_, h_, last_uniform_, gmin_, gmax_;
  Pair inv_h_;  // 1/h per axis, as eval() computes it
};
#endif

}  // namespace swmpm::shape
