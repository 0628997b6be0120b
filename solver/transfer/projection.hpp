// Node-wise least-squares projection of a particle field (the node-based map/remap of seed 001
// eq. 77, and its linear-basis generalisation):
//
//   per node I:  H_I = sum_p w_p N_Ip Q_p Q_p^T,   a_I = H_I^-1 sum_p w_p N_Ip Q_p f_p
//   at a point:  f(x) = sum_I N_I(x) Q(x)^T a_I
//
// with Q = [1] (Order 0: a_I is the w-weighted nodal average of eq. 77), Q = [1, d] (Order 1) or
// Q = [1, d, d_a d_b (a <= b)] (Order 2: seed 000's quadratic multi-field variational basis),
// d = (x - x_I) / h centred at the node, so that a_I[0] is the fitted value AT the node and a
// linear field is reproduced exactly (also at nodes on a free surface, where a plain average is
// biased towards the interior). A node whose H_I is near-singular (pivot ratio < 1e-8: too few
// particles for the basis) falls back to Order 0.
//
// Well-posedness (Order 1). The fitted value at the node, a_I0, is the least-squares prediction
// at d = 0 from points whose weighted centroid is mean(d) and covariance C (units h^2): its
// sensitivity to the data is the leverage lambda = W (H_I^-1)_00 = 1 + mean(d)^T C^-1 mean(d)
// (W = sum w N): a data error e becomes ~ e sqrt(lambda) at the node. A full support has
// lambda ~ 1, the clamped boundary node of a bspline3 support ~ 9; a node whose points lie in a
// thin strip at the edge of its support (the water at a free surface covering one row of points
// of a B-spline support) 1e3 - 1e4: its own gradient is noise and its a_I0 an amplified
// extrapolation (docs/formulations.md, "Free-surface nodes with an ill-posed fit"). Above
// kMaxLeverage = 100 (node value error at most 10 x the data's) the node falls back to Order 0,
// unless the caller imposes a gradient (impose_gradient), with which only the value is fitted,
// a_I0 = mean_w(f - grad . (x - x_I)): a linear field with that gradient is still reproduced.
// Leverage is a choice of the projection (LeverageLimit): seed 000's multi-field variational
// pressure step (explicit-single-point) has none, only the pivot test.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Dense>

#include "solver/grid/grid.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"

namespace swmpm {

/// Whether a node whose fit has a leverage above kMaxLeverage falls back to Order 0.
enum class LeverageLimit { on, off };

template <int Dim, int S, int Order, LeverageLimit kLeverage = LeverageLimit::on>
class NodeProjection {
 public:
  static_assert(Order >= 0 && Order <= 2);
  static constexpr int NQ = Order == 0 ? 1 : (Order == 1 ? 1 + Dim : (Dim + 1) * (Dim + 2) / 2);
  static constexpr int NH = NQ * (NQ + 1) / 2, NB = NH + NQ;
  using VecQ = Eigen::Matrix<double, NQ, 1>;
  using MatQ = Eigen::Matrix<double, NQ, NQ>;

  /// Fits the nodes of `box` to the points' values: weight(p) and value(p) per point, shape data
  /// sd[p] and position x[p] (the points the shape data were evaluated at).
  template <bool G, class Weight, class Value>
  void fit(const Grid<Dim>& g, const NodeBox<Dim>& box, const StripeSchedule& schedule,
           const std::vector<shape::ShapeData<Dim, S, G>>& sd, const std::vector<Vec<Dim>>& x, Weight&& weight,
           Value&& value) {
    if (well_posed_.size() != g.num_nodes()) {  // first fit (or another grid): zero, memory only where used
      blocks_ = NodeArray<Block>(g.num_nodes());
      well_posed_ = NodeArray<std::uint8_t>(g.num_nodes());
    }
    g.parallel_for_each_node(box, [&](std::size_t i, const auto&) {
      std::fill_n(block(i), NB, 0.0);
      well_posed_[i] = 0;
    });
    schedule.run([&](int p) {
      const double w = weight(p), f = value(p);
      if (w == 0.0) return;
      for_each_node_offset(g, sd[p], x[p], [&](std::size_t i, double N, double d0, double d1, double d2) {
        if (N <= 0.0) return;
        double* h = block(i);
        const double wN = w * N, wf = wN * f;
        // H += wN Q Q^T (packed upper triangle, row by row), rhs += wN f Q; Q = (1, d), written
        // out in scalars (see for_each_node_offset).
        if constexpr (Order == 0) {
          h[0] += wN;
          h[1] += wf;
        } else if constexpr (Order == 2) {
          const VecQ q = basis(d0, d1, d2);
          for (int r = 0, k = 0; r < NQ; ++r) {
            const double s_r = wN * q[r];
            for (int c = r; c < NQ; ++c) h[k++] += s_r * q[c];
          }
          for (int r = 0; r < NQ; ++r) h[NH + r] += wf * q[r];
        } else if constexpr (Dim == 2) {
          const double s1 = wN * d0, s2 = wN * d1;
          h[0] += wN, h[1] += s1, h[2] += s2;
          h[3] += s1 * d0, h[4] += s1 * d1;
          h[5] += s2 * d1;
          h[6] += wf, h[7] += wf * d0, h[8] += wf * d1;
        } else {
          const double s1 = wN * d0, s2 = wN * d1, s3 = wN * d2;
          h[0] += wN, h[1] += s1, h[2] += s2, h[3] += s3;
          h[4] += s1 * d0, h[5] += s1 * d1, h[6] += s1 * d2;
          h[7] += s2 * d1, h[8] += s2 * d2;
          h[9] += s3 * d2;
          h[10] += wf, h[11] += wf * d0, h[12] += wf * d1, h[13] += wf * d2;
        }
      });
    }, blocks_);
    g.parallel_for_each_node(box, [&](std::size_t i, const auto&) {
      double* blk = block(i);
      if (!(blk[0] > 0.0)) {  // no weight (or not finite): a_I = 0, which at_point relies on
        std::fill_n(blk + NH, NQ, 0.0);
        return;
      }
      Eigen::Map<VecQ> rhs(blk + NH);
      if constexpr (NQ > 1) {
        MatQ H;
        for (int r = 0, k = 0; r < NQ; ++r)
          for (int c = r; c < NQ; ++c) H(r, c) = H(c, r) = blk[k++];
        Eigen::LDLT<MatQ> ldlt(H);
        const double cond = ldlt.vectorD().cwiseAbs().minCoeff() / ldlt.vectorD().cwiseAbs().maxCoeff();
        VecQ a = VecQ::Zero();
        bool ok = ldlt.info() == Eigen::Success && cond > 1e-8;
        if (kLeverage == LeverageLimit::on && ok) {
          // Leverage of the node: lambda = W (H^-1)_00 = 1 + mean(d)^T C^-1 mean(d) (C the points'
          // weighted covariance of d): a data error e becomes ~ e sqrt(lambda) in a_I0.
          VecQ e0 = VecQ::Zero();
          e0[0] = 1.0;
          const double lambda = blk[0] * ldlt.solve(e0)[0];
          ok = lambda <= kMaxLeverage;
        }
        if (ok) a = ldlt.solve(rhs);
        else a[0] = rhs[0] / blk[0];
        well_posed_[i] = ok;
        rhs = a;
      } else {
        rhs[0] /= blk[0];
      }
    });
  }

  /// Q(d) = [1, d, d_a d_b (a <= b)] of Order 2 (d in cells; d2 unused in 2D).
  static VecQ basis(double d0, double d1, double d2) {
    const double d[3] = {d0, d1, d2};
    VecQ q;
    q[0] = 1.0;
    for (int a = 0; a < Dim; ++a) q[1 + a] = d[a];
    if constexpr (Order == 2) {
      int k = 1 + Dim;
      for (int a = 0; a < Dim; ++a)
        for (int b = a; b < Dim; ++b) q[k++] = d[a] * d[b];
    }
    return q;
  }

  /// fn(array) for each of the fit's node arrays (the ranks' ghost fill of fitted nodes).
  template <class Fn>
  void for_each_node_array(Fn&& fn) {
    fn(blocks_);
    fn(well_posed_);
  }
  /// Whether node i received any weight in the last fit.
  bool has(std::size_t i) const { return blocks_[i][0] > 0.0; }
  /// The fitted value at node i (a_I[0]: the basis is centred at the node).
  double at_node(std::size_t i) const { return has(i) ? blocks_[i][NH] : 0.0; }
  /// The fitted gradient at node i [unit of f per m]: a_I[1..Dim] / h (Order 1; zero for Order 0, for a
  /// node that fell back to Order 0, and for a node without weight).
  Vec<Dim> gradient_at_node(const Grid<Dim>& g, std::size_t i) const {
    Vec<Dim> grad = Vec<Dim>::Zero();
    if constexpr (Order == 1)
      if (has(i))
        for (int a = 0; a < Dim; ++a) grad[a] = blocks_[i][NH + 1 + a] / g.h();
    return grad;
  }
  /// Whether node i's points determine its linear fit (Order 1: leverage <= kMaxLeverage; Order 0:
  /// any weight).
  bool well_posed(std::size_t i) const {
    if constexpr (Order == 0) return has(i);
    return well_posed_[i] != 0;
  }
  /// For a node whose fit is not well posed (fell back to Order 0): imposes the gradient `grad`
  /// [unit of f per m] and refits only the value, a_I0 = sum_p w N (f_p - grad . (x_p - x_I)) /
  /// sum_p w N (the first row of H_I holds sum w N and sum w N d). A linear field with that
  /// gradient is reproduced exactly. Call once per node after fit(), before the values are read.
  void impose_gradient(const Grid<Dim>& g, std::size_t i, const Vec<Dim>& grad) {
    if constexpr (Order == 1) {
      double* blk = block(i);
      if (!has(i) || well_posed_[i]) return;
      double shift = 0.0;
      for (int a = 0; a < Dim; ++a) {
        shift += grad[a] * g.h() * blk[1 + a] / blk[0];  // grad . mean_w(x - x_I)
        blk[NH + 1 + a] = grad[a] * g.h();
      }
      blk[NH] -= shift;
    }
  }
  /// The projected field at a point with shape data sd at x, a point of the last fit's box. Only
  /// nodes with weight count: fit() leaves every node of its box without (finite, positive)
  /// weight at a_I = 0, so no test per node is needed.
  template <bool G>
  double at_point(const Grid<Dim>& g, const shape::ShapeData<Dim, S, G>& sd, const Vec<Dim>& x) const {
    double value = 0.0;
    for_each_node_value(g, sd, x, [&](std::size_t, double N, double qa) { value += N * qa; });
    return value;
  }
  /// The terms of at_point, fn(node, N_Ip, Q(x_p - x_I) . a_I), over a point's nodes in
  /// for_each_node's order (and with its N_Ip): a pass that gathers other nodal fields at the
  /// point too visits its nodes once.
  template <bool G, class Fn>
  [[gnu::always_inline]] void for_each_node_value(const Grid<Dim>& g, const shape::ShapeData<Dim, S, G>& sd,
                                                  const Vec<Dim>& x, Fn&& fn) const {
    for_each_node_offset(g, sd, x, [&](std::size_t i, double N, double d0, double d1, double d2) {
      const double* a = blocks_[i].data() + NH;  // Q . a_I, Q = (1, d)
      double qa = a[0];
      if constexpr (Order == 1) {
        qa += d0 * a[1];
        qa += d1 * a[2];
        if constexpr (Dim == 3) qa += d2 * a[3];
      } else if constexpr (Order == 2) {
        qa = basis(d0, d1, d2).dot(Eigen::Map<const VecQ>(a));
      }
      fn(i, N, qa);
    });
  }

 private:
  double* block(std::size_t i) { return blocks_[i].data(); }

  /// fn(node, N_Ip, d_x, d_y, d_z) (d_z = 0 in 2D) over a point's nodes in for_each_node's order
  /// (and with its N_Ip: wx[a] times the row's weight). Row by row (shape::for_each_row): the row's offsets along
  /// y (and z) are set once per row, x's once per node, with no index arithmetic per node.
  template <bool G, class Fn>
  static void for_each_node_offset(const Grid<Dim>& g, const shape::ShapeData<Dim, S, G>& sd, const Vec<Dim>& x,
                                   Fn&& fn) {
    const double inv_h = 1.0 / g.h();
    double off[Dim][S];
    for (int a = 0; a < Dim; ++a)
      for (int k = 0; k < S; ++k) off[a][k] = (x[a] - g.axis(a).node_x[sd.base[a] + k]) * inv_h;
    // The offsets go to fn as scalars, and fn writes its sums out in scalars. With Q(d) in an
    // Eigen vector or an array rewritten per node, GCC stored the offsets and reloaded them as one
    // 16-byte packet: a store-to-load forwarding stall at every node (update_pressure 13 %, the
    // fit 14 % of B4's step).
    int b = 0, c = 0;  // the row's node along y (and z)
    shape::for_each_row(g, sd, [&](std::size_t row, double w_r, const auto&) {
      const double dy = off[1][b], dz = Dim == 3 ? off[Dim - 1][c] : 0.0;
#pragma GCC unroll 4
      for (int a = 0; a < S; ++a) fn(row + a, sd.w[0][a] * w_r, off[0][a], dy, dz);
      if (++b == S) b = 0, ++c;
    });
  }

  static constexpr double kMaxLeverage = 100.0;  // largest leverage W (H^-1)_00 of an own linear fit

  using Block = std::array<double, NB>;  // packed upper triangle of H_I, then rhs -> a_I
  NodeArray<Block> blocks_;  // per node
  NodeArray<std::uint8_t> well_posed_;  // per node: 1 when the last fit was well posed (Order 1)
};

}  // namespace swmpm
