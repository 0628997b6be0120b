// The grid's basis on its cells, for finite-element integrals (mpm-fem, seed 004 §"Spatial
// discretization"): the Eulerian fluid and the phase field use the same B-spline basis N_alpha
// as the MPM soil, integrated cell by cell ("element" = grid cell) with Gauss–Legendre rules of
// Q = p + 1 points per axis (p the basis degree), exact for the mass matrix int N_a N_b (degree 2p
// per axis, exact up to 2Q - 1 = 2p + 1).
//
// A cell (c_0, .., c_{Dim-1}) is covered by the S^Dim functions of nodes c_a .. c_a + S - 1 per
// axis (S = p + 1 for the clamped B-splines; solver/shape/shape.hpp): local function
// k = s_0 + S s_1 (+ S^2 s_2), x fastest, as shape::for_each_node visits them. The 1D values of
// each axis at each cell's Gauss points are tabulated once (build); a cell's tensor products are
// formed on demand (eval), so nothing per cell is stored.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <utility>
#include <vector>

#include "solver/common.hpp"
#include "solver/grid/grid.hpp"

namespace swmpm::fem {

constexpr int ipow(int b, int e) { return e == 0 ? 1 : b * ipow(b, e - 1); }

/// Gauss–Legendre points on [0, 1] and their weights (sum 1), Q = 2, 3, 4.
template <int Q>
struct Gauss01;
template <>
struct Gauss01<2> {
  static constexpr double x[2] = {0.5 - 0.28867513459481287, 0.5 + 0.28867513459481287};
  static constexpr double w[2] = {0.5, 0.5};
};
template <>
struct Gauss01<3> {
  static constexpr double x[3] = {0.5 - 0.38729833462074170, 0.5, 0.5 + 0.38729833462074170};
  static constexpr double w[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
};
template <>
struct Gauss01<4> {
  static constexpr double x[4] = {0.5 - 0.43056815579702629, 0.5 - 0.16999052179242813,
                                  0.5 + 0.16999052179242813, 0.5 + 0.43056815579702629};
  static constexpr double w[4] = {0.17392742256872693, 0.32607257743127307, 0.32607257743127307,
                                  0.17392742256872693};
};

template <int Dim, class Shape>
class CellBasis {
 public:
  static constexpr int S = Shape::support;       // functions per axis on a cell
  static constexpr int Q = Shape::degree + 1;    // Gauss points per axis
  static constexpr int K = ipow(S, Dim);         // functions on a cell
  static constexpr int G = ipow(Q, Dim);         // Gauss points on a cell

  /// One cell's data: its nodes (flat indices, local order), and at each Gauss point g the weight
  /// |J| w_g (m^Dim), N_k and grad N_k (1/m).
  struct Cell {
    std::array<std::size_t, K> node;
    double JxW[G];
    double N[G][K];
    Vec<Dim> dN[G][K];
  };

  void build(const Grid<Dim>& g) {
    for (int a = 0; a < Dim; ++a) {
      const Axis& ax = g.axis(a);
      auto& t = axis_[a];
      t.w.assign(static_cast<std::size_t>(ax.cells) * Q * S, 0.0);
      t.dw.assign(t.w.size(), 0.0);
      for (int c = 0; c < ax.cells; ++c)
        for (int q = 0; q < Q; ++q) {
          int base = 0;
          const double x = ax.origin + (c + Gauss01<Q>::x[q]) * ax.h;
          Shape::eval(ax, x, 0.0, base, &t.w[(static_cast<std::size_t>(c) * Q + q) * S],
                      &t.dw[(static_cast<std::size_t>(c) * Q + q) * S]);
          if (base != c) throw std::logic_error("CellBasis: a cell's functions must start at its own index");
        }
    }
    double h = g.h(), vol = 1.0;
    for (int a = 0; a < Dim; ++a) vol *= h;
    for (int gp = 0; gp < G; ++gp) {
      double w = vol;
      int r = gp;
      for (int a = 0; a < Dim; ++a) {
        w *= Gauss01<Q>::w[r % Q];
        r /= Q;
      }
      weight_[gp] = w;
    }
    nodes_ = g.nodes_per_axis();
  }

  /// Fills `out` for cell c (per-axis cell indices).
  void eval(const std::array<int, Dim>& c, Cell& out) const {
    for (int k = 0; k < K; ++k) {
      std::size_t idx = 0, stride = 1;
      int r = k;
      for (int a = 0; a < Dim; ++a) {
        idx += static_cast<std::size_t>(c[a] + r % S) * stride;
        stride *= static_cast<std::size_t>(nodes_[a]);
        r /= S;
      }
      out.node[k] = idx;
    }
    for (int gp = 0; gp < G; ++gp) {
      out.JxW[gp] = weight_[gp];
      const double* w[Dim];
      const double* dw[Dim];
      int r = gp;
      for (int a = 0; a < Dim; ++a) {
        const std::size_t off = (static_cast<std::size_t>(c[a]) * Q + r % Q) * S;
        w[a] = &axis_[a].w[off];
        dw[a] = &axis_[a].dw[off];
        r /= Q;
      }
      for (int k = 0; k < K; ++k) {
        int s[Dim];
        int rk = k;
        for (int a = 0; a < Dim; ++a) {
          s[a] = rk % S;
          rk /= S;
        }
        double N = 1.0;
        for (int a = 0; a < Dim; ++a) N *= w[a][s[a]];
        out.N[gp][k] = N;
        for (int b = 0; b < Dim; ++b) {
          double d = dw[b][s[b]];
          for (int a = 0; a < Dim; ++a)
            if (a != b) d *= w[a][s[a]];
          out.dN[gp][k][b] = d;
        }
      }
    }
  }

 private:
  struct AxisTable {
    std::vector<double> w, dw;  // [cell][q][s]
  };
  std::array<AxisTable, Dim> axis_;
  double weight_[G] = {};
  std::array<int, Dim> nodes_{};
};

/// The cells lo ... hi (inclusive, per axis) in S^Dim colours (c_a mod S per axis): two cells of
/// one colour share no node, so a colour's cells assemble in parallel without races, and every
/// sum over cells at a node has one order (colour by colour, one cell per colour) whatever the
/// thread count. A colour is a cell's index mod S, so a sub-box's loop sums each node in the
/// order the whole grid's loop does.
template <int Dim, int S, class Fn>
void for_each_cell_coloured(const std::array<int, Dim>& lo, const std::array<int, Dim>& hi, Fn&& fn) {
  constexpr int colours = ipow(S, Dim);
  for (int colour = 0; colour < colours; ++colour) {
    std::array<int, Dim> first{}, count{};
    long total = 1;
    int r = colour;
    for (int a = 0; a < Dim; ++a) {
      const int k = r % S;
      r /= S;
      first[a] = lo[a] + ((k - lo[a]) % S + S) % S;
      count[a] = first[a] <= hi[a] ? (hi[a] - first[a]) / S + 1 : 0;
      total *= count[a];
    }
#pragma omp parallel for schedule(static) if (total > 256)
    for (long t = 0; t < total; ++t) {
      std::array<int, Dim> c;
      long q = t;
      for (int a = 0; a < Dim; ++a) {
        c[a] = first[a] + static_cast<int>(q % count[a]) * S;
        q /= count[a];
      }
      fn(c);
    }
  }
}

/// for_each_cell_coloured over all `cells` (per axis) of a grid.
template <int Dim, int S, class Fn>
void for_each_cell_coloured(const std::array<int, Dim>& cells, Fn&& fn) {
  std::array<int, Dim> lo{}, hi{};
  for (int a = 0; a < Dim; ++a) hi[a] = cells[a] - 1;
  for_each_cell_coloured<Dim, S>(lo, hi, std::forward<Fn>(fn));
}

}  // namespace swmpm::fem
