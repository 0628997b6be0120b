// Exact assembly of the semi-implicit pressure operators from per-cell moments of the points
// (2D; shape functions that are one polynomial per cell: Linear and the B-splines).
//
// The operators of the pressure Poisson equation (seed 001 eqs. 61-63) are sums over points of
// products of shape functions:
//   L_IJ  = sum_p cl_p grad S_I(x_p) . grad S_J(x_p)
//   D^s_IK = sum_p cs_p S_I(x_p) grad S_K(x_p),   D^w_IK = sum_p cw_p S_I(x_p) grad S_K(x_p)
// Inside one cell every 1D factor of S_I = w_s(xi) w_t(eta) is a polynomial of degree P in the
// cell's local coordinates (xi, eta) in [0, 1)^2 (the B-splines' knots are the cell faces), so each
// product above is a polynomial of degree <= 2P per axis, and its sum over the cell's points is a
// fixed linear combination of the cell's weighted moments
//   M^c_mn = sum_{p in cell} c_p xi_p^m eta_p^n,   m, n = 0 .. 2P.
// A point then adds (2P + 1)^2 products per weight (25 for quadratic B-splines) instead of visiting
// the (P + 1)^4 node pairs of its support (81), and each cell turns its moments into its node pairs
// once, by sum factorisation (axis 1 first, then axis 0). The result equals the point-wise sums up
// to rounding (tests/unit/test_cell_moments.cpp).
//
// Determinism: points add to their own cell only, in StripeSchedule order (a cell lies in one
// stripe, so one thread, one order); cells are reduced stripe by stripe in two colours along axis
// 0 (a cell touches S node columns, so stripes of S cells two apart never share a node), in a fixed
// order inside a stripe. The sums do not depend on the number of threads.
#pragma once

#include <omp.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/shape/shape.hpp"

namespace swmpm::transfer {

template <class Shape>
class CellMoments {
 public:
  static constexpr int S = Shape::support;  // nodes per axis of a cell's support
  static constexpr int P = Shape::degree;
  static constexpr int Q = 2 * P + 1;       // moment orders per axis: 0 .. 2P
  static constexpr int QQ = Q * Q;
  static constexpr int NP = S * S;          // nodes of a cell's support (x fastest)
  static_assert(S == P + 1, "cell moments need shape functions that are one polynomial per cell");

  /// One cell's share of the operators, as matrices over the axis pairs: entry (p0, p1) with
  /// p0 = s0 S + t0 (axis 0: row node s0, column node t0) and p1 = s1 S + t1 (axis 1). The node
  /// pair (r, k) of the cell's support (x fastest: r = s0 + S s1, k = t0 + S t1) is read with the
  /// accessors. L holds every pair; the caller takes the ones it stores.
  using PairMatrix = Eigen::Matrix<double, S * S, S * S, Eigen::RowMajor>;
  struct CellOperators {
    PairMatrix L, Dsx, Dsy, Dwx, Dwy;
    static int p0(int r, int k) { return (r % S) * S + k % S; }
    static int p1(int r, int k) { return (r / S) * S + k / S; }
    double l(int r, int k) const { return L(p0(r, k), p1(r, k)); }
    Vec<2> ds(int r, int k) const { return Vec<2>(Dsx(p0(r, k), p1(r, k)), Dsy(p0(r, k), p1(r, k))); }
    Vec<2> dw(int r, int k) const { return Vec<2>(Dwx(p0(r, k), p1(r, k)), Dwy(p0(r, k), p1(r, k))); }
  };

  explicit CellMoments(const Grid<2>& g) : nn_(g.nodes_per_axis()) {
#if defined(__SSE2__)
    origin_ = _mm_set_pd(g.axis(1).origin, g.axis(0).origin);
    h_ = _mm_set_pd(g.axis(1).h, g.axis(0).h);
#endif
    for (int a = 0; a < 2; ++a) build_axis(g.axis(a), tables_[a]);
    moments_.resize(static_cast<std::size_t>(nn_[0]) * nn_[1] * 3 * QQ);  // zero (NodeArray)
  }

  /// When every point's L weight is cl = cs / rho_s + cw / rho_w with the same densities (one
  /// grain density, one water density: c = (1 - n)/rho_s + n/rho_w of seed 001 eq. 61), the L
  /// moments are that combination of the D^s and D^w moments. After this call add() takes no cl
  /// and reduce() forms the L moments per cell: one weight less per point (25 products for
  /// quadratic B-splines). The sums then differ from the point-wise ones by rounding only.
  void derive_laplace(double rho_s, double rho_w) {
    laplace_from_sets_ = true;
    inv_rho_s_ = 1.0 / rho_s;
    inv_rho_w_ = 1.0 / rho_w;
  }
  bool laplace_derived() const { return laplace_from_sets_; }

  /// Adds one point at x in the cell whose first node is `base` (ShapeData::base): the weights of
  /// D^s (cs, m^3 in 2D per metre), D^w (cw) and L (cl, ignored after derive_laplace()). Sets
  /// whose flag is off are skipped.
  template <bool kSoil, bool kWater>
  [[gnu::always_inline]] void add([[maybe_unused]] const Grid<2>& g, const std::array<int, 2>& base, const Vec<2>& x, double cs,
                                  double cw, double cl) {
    // Local coordinates in the cell, (x - origin) / h - base per axis. A point outside the grid
    // (or not finite) has shape data clamped to the grid (transfer::evaluate_shapes reports it):
    // clamp it the same way, so the operators stay what the clamped weights give and the run
    // stops with "left the grid". Per axis isfinite(u) ? clamp(u, 0, 1) : 0; with SSE2 both axes
    // in one register pair, lane by lane the same values (max(u, 0) is 0 for a NaN u, and the
    // finite mask zeroes +-inf).
    double xi, eta;
#if defined(__SSE2__)
    const __m128d u = _mm_sub_pd(_mm_div_pd(_mm_sub_pd(_mm_loadu_pd(x.data()), origin_), h_),
                                 _mm_cvtepi32_pd(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(base.data()))));
    const __m128d finite = _mm_cmpeq_pd(_mm_sub_pd(u, u), _mm_setzero_pd());
    const __m128d local =
        _mm_and_pd(_mm_min_pd(_mm_max_pd(u, _mm_setzero_pd()), _mm_set1_pd(1.0)), finite);
    xi = _mm_cvtsd_f64(local);
    eta = _mm_cvtsd_f64(_mm_unpackhi_pd(local, local));
#else
    auto clamp01 = [](double u) { return std::isfinite(u) ? std::clamp(u, 0.0, 1.0) : 0.0; };
    xi = clamp01((x[0] - g.axis(0).origin) / g.axis(0).h - base[0]);
    eta = clamp01((x[1] - g.axis(1).origin) / g.axis(1).h - base[1]);
#endif
    double* M = moments_.data() + cell_index(base) * 3 * QQ;
    if (laplace_from_sets_) add_products<kSoil, kWater, false>(M, xi, eta, cs, cw, cl);
    else add_products<kSoil, kWater, true>(M, xi, eta, cs, cw, cl);
  }

  /// Turns the moments of every cell with points into its node pairs, calls
  /// out(first node's flat index, const CellOperators&) once per such cell, and zeroes the moments
  /// for the next step. `box` is the step's node box (every point's support lies in it). The cells
  /// go in the scatter schedule's stripes along `axis` (S node columns from the grid's first, the
  /// cells of one colour in parallel), so a node gets its cells' pairs in an order that depends on
  /// the grid only; after_colour(colour) then lets the ranks exchange the rows of their shared
  /// columns (StripeSchedule::run's protocol; nothing at one rank).
  template <class AfterColour, class Out>
  void reduce(const NodeBox<2>& box, int axis, AfterColour&& after_colour, Out&& out) {
    const int other = 1 - axis;
    const int a_lo = box.lo[axis], a_hi = box.hi[axis] - (S - 1);  // cells' first nodes along the axis
    const int o_lo = box.lo[other], o_hi = box.hi[other] - (S - 1);
    const bool any = !box.empty() && a_hi >= a_lo && o_hi >= o_lo;
    const int s_lo = any ? a_lo / S : 0, s_hi = any ? a_hi / S : -1;
    for (int colour = 0; colour < 2; ++colour) {
      const int first = s_lo + ((s_lo % 2 == colour) ? 0 : 1);
#pragma omp parallel for schedule(dynamic, 1) if (s_hi - s_lo > 1)
      for (int s = first; s <= s_hi; s += 2) {
        CellOperators op;
        for (int bo = o_lo; bo <= o_hi; ++bo)
          for (int ba = std::max(a_lo, s * S); ba <= std::min(a_hi, s * S + S - 1); ++ba) {
            std::array<int, 2> base;
            base[axis] = ba, base[other] = bo;
            double* M = moments_.data() + cell_index(base) * 3 * QQ;
            const bool empty = M[kSoilSet * QQ] == 0.0 && M[kWaterSet * QQ] == 0.0 && M[kLaplaceSet * QQ] == 0.0;
            if (!empty && laplace_from_sets_)
              for (int i = 0; i < QQ; ++i)
                M[kLaplaceSet * QQ + i] = inv_rho_s_ * M[kSoilSet * QQ + i] + inv_rho_w_ * M[kWaterSet * QQ + i];
            if (!empty) cell_operators(tables_[0][base[0]], tables_[1][base[1]], M, op);
            std::fill_n(M, 3 * QQ, 0.0);  // every cell of the range: nothing carries into the next step
            if (!empty) out(cell_index(base), op);
          }
      }
      after_colour(colour);
    }
  }

 private:
  static constexpr int kSoilSet = 0, kWaterSet = 1, kLaplaceSet = 2;
  bool laplace_from_sets_ = false;
  double inv_rho_s_ = 0.0, inv_rho_w_ = 0.0;  // m^3/kg, derive_laplace()

  /// One axis and one cell: coefficients in xi of the products of the cell's S 1D functions,
  /// pair (s, t) = s * S + t: w_s w_t, w_s dw_t, dw_s dw_t (dw in 1/m).
  using PairPoly = Eigen::Matrix<double, S * S, Q, Eigen::RowMajor>;  // row: pair, column: power
  struct AxisCell {
    PairPoly ww, wd, dd;
  };

  /// M[set][m Q + n] += c_set (xi^m eta^n) for m, n < Q, the same products and sums as written
  /// out one by one (bitwise), in pairs of n: the powers of eta are built in registers, and xi^m
  /// times a pair of them is one packed product. (Built one double at a time in a stack array and
  /// read back in 16-byte packets, they stalled on store-to-load forwarding.)
  template <bool kSoil, bool kWater, bool kLaplace>
  [[gnu::always_inline]] static void add_products(double* M, double xi, double eta, double cs, double cw, double cl) {
    constexpr int H = Q / 2;  // full pairs per row; Q = 2P + 1 is odd: one power is left over
    double py[Q];
    py[0] = 1.0;
    for (int n = 1; n < Q; ++n) py[n] = py[n - 1] * eta;
    Pair pair[H];
    for (int h = 0; h < H; ++h) pair[h] = Pair{py[2 * h], py[2 * h + 1]};
    double px = 1.0;
    for (int m = 0; m < Q; ++m, px *= xi) {
      auto row = [&](int set, double c) __attribute__((always_inline)) {
        double* R = M + set * QQ + m * Q;
        for (int h = 0; h < H; ++h) {
          const Pair v = px * pair[h];
          *reinterpret_cast<PairU*>(R + 2 * h) += c * v;
        }
        R[Q - 1] += c * (px * py[Q - 1]);
      };
      if constexpr (kSoil) row(kSoilSet, cs);
      if constexpr (kWater) row(kWaterSet, cw);
      if constexpr (kLaplace) row(kLaplaceSet, cl);
    }
  }

  std::size_t cell_index(const std::array<int, 2>& base) const {
    return static_cast<std::size_t>(base[1]) * nn_[0] + base[0];
  }

  /// The S functions of each cell as polynomials in xi: sampled at S points and interpolated
  /// (exact: each is one polynomial of degree P on the cell), checked against the policy's own
  /// derivative.
  static void build_axis(const Axis& ax, std::vector<AxisCell>& cells) {
    cells.assign(ax.cells, AxisCell{PairPoly::Zero(), PairPoly::Zero(), PairPoly::Zero()});
    for (int c = 0; c < ax.cells; ++c) {
      Eigen::Matrix<double, S, S> V;
      Eigen::Matrix<double, S, S> W, dW;  // (j, s): w_s and dw_s at sample j
      std::array<double, S> xs;
      for (int j = 0; j < S; ++j) {
        xs[j] = (j + 0.5) / S;
        int base = 0;
        double w[S], dw[S];
        Shape::eval(ax, ax.origin + (c + xs[j]) * ax.h, 0.0, base, w, dw);
        if (base != c)
          throw std::logic_error("cell moments: shape function's first node " + std::to_string(base) + " is not cell " +
                                 std::to_string(c));
        for (int m = 0; m < S; ++m) V(j, m) = std::pow(xs[j], m);
        for (int s = 0; s < S; ++s) W(j, s) = w[s], dW(j, s) = dw[s];
      }
      const Eigen::Matrix<double, S, S> coef = V.fullPivLu().solve(W);  // coef(m, s): xi^m of w_s
      double wc[S][S] = {}, dc[S][S] = {};                           // [s][m]; dc in 1/m
      for (int s = 0; s < S; ++s)
        for (int m = 0; m < S; ++m) {
          wc[s][m] = coef(m, s);
          if (m + 1 < S) dc[s][m] = (m + 1) * coef(m + 1, s) / ax.h;
        }
      // The derivative of the interpolant must be the policy's derivative (same polynomial).
      for (int j = 0; j < S; ++j)
        for (int s = 0; s < S; ++s) {
          double d = 0.0;
          for (int m = S - 2; m >= 0; --m) d = d * xs[j] + dc[s][m];
          if (std::abs(d - dW(j, s)) > 1e-9 / ax.h)
            throw std::logic_error("cell moments: shape function is not one polynomial per cell");
        }
      AxisCell& out = cells[c];
      for (int s = 0; s < S; ++s)
        for (int t = 0; t < S; ++t) {
          const int pair = s * S + t;
          out.ww.row(pair).setZero();
          out.wd.row(pair).setZero();
          out.dd.row(pair).setZero();
          for (int m = 0; m < S; ++m)
            for (int n = 0; n < S; ++n) {
              out.ww(pair, m + n) += wc[s][m] * wc[t][n];
              out.wd(pair, m + n) += wc[s][m] * dc[t][n];
              out.dd(pair, m + n) += dc[s][m] * dc[t][n];
            }
        }
    }
  }

  /// Sum factorisation of one cell, with the moments M (m: power of xi, n: power of eta):
  ///   L   = sum_mn M^l_mn (dd0[p0]_m ww1[p1]_n + ww0[p0]_m dd1[p1]_n)
  ///   D_x = sum_mn M^c_mn wd0[p0]_m ww1[p1]_n,   D_y = sum_mn M^c_mn ww0[p0]_m wd1[p1]_n   (c = s, w)
  /// First over n (A = M Y^T: powers of xi by axis-1 pairs), then over m (X A): small fixed-size
  /// products, 3780 multiply-adds per cell for quadratic B-splines.
  static void cell_operators(const AxisCell& X, const AxisCell& Y, const double* M, CellOperators& op) {
    using Moment = Eigen::Matrix<double, Q, Q, Eigen::RowMajor>;
    using Half = Eigen::Matrix<double, Q, S * S>;
    const Eigen::Map<const Moment> Ms(M + kSoilSet * QQ), Mw(M + kWaterSet * QQ), Ml(M + kLaplaceSet * QQ);
    // lazyProduct: coefficient-wise loops the compiler unrolls (Eigen's GEMM kernel is slower at
    // these sizes).
    Half a, b;
    a.noalias() = Ml.lazyProduct(Y.ww.transpose());
    b.noalias() = Ml.lazyProduct(Y.dd.transpose());
    op.L.noalias() = X.dd.lazyProduct(a) + X.ww.lazyProduct(b);
    a.noalias() = Ms.lazyProduct(Y.ww.transpose());
    b.noalias() = Ms.lazyProduct(Y.wd.transpose());
    op.Dsx.noalias() = X.wd.lazyProduct(a);
    op.Dsy.noalias() = X.ww.lazyProduct(b);
    a.noalias() = Mw.lazyProduct(Y.ww.transpose());
    b.noalias() = Mw.lazyProduct(Y.wd.transpose());
    op.Dwx.noalias() = X.wd.lazyProduct(a);
    op.Dwy.noalias() = X.ww.lazyProduct(b);
  }

  std::array<int, 2> nn_;
#if defined(__SSE2__)
  __m128d origin_, h_;  // per axis (add)
#endif
  std::array<std::vector<AxisCell>, 2> tables_;
  NodeArray<double> moments_;  // per cell (indexed by its first node): soil, water, L sets of QQ
};

}  // namespace swmpm::transfer
