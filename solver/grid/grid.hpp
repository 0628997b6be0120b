// Background grid: a structured box of square/cubic cells of size h, restricted at run time to the
// active box (the cells particles occupy plus the shape functions' support).
//
// Nodes are the basis functions' "control points": for linear and GIMP they sit at the cell corners
// (cells + 1 per axis); for the clamped B-splines of degree p they sit at the Greville abscissae of
// the open knot vector (cells + p per axis), so that the first and last node of each axis are
// interpolatory at the boundary and carry the boundary conditions (see solver/shape/shape.hpp).
//
//      y ^   node (i, j) -> flat index i + nodes[0] * j  (+ nodes[0] nodes[1] k in 3D)
//        |   o----o----o
//        |   |    |    |     cell (c0, c1) spans [min + c h, min + (c + 1) h] per axis
//        |   o----o----o
//        +------------> x
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "scene/scene.hpp"
#include "solver/common.hpp"
#include "solver/grid/node_array.hpp"

namespace swmpm {

/// One axis of the grid: what the shape functions need to evaluate a coordinate.
struct Axis {
  double origin = 0.0;  // m
  double h = 1.0;       // m, cell size
  int cells = 0;
  int nodes = 0;                 // basis functions along this axis
  std::vector<double> node_x;    // m, node (control point) coordinates
};

/// Nodal fields of one phase. What P2G accumulates (m, mv, f) sits together in one struct per
/// node, so a particle's scatter touches one cache line per node rather than three. NodeArrays:
/// memory only for the nodes the steps' boxes reach (grid/node_array.hpp).
template <int Dim>
struct NodeFields {
  struct Accum {
    Vec<Dim> mv;  // kg m/s, momentum
    Vec<Dim> f;   // N, total force (internal + external + body)
    double m;     // kg, lumped mass
  };
  NodeArray<Accum> acc;
  NodeArray<Vec<Dim>> v;    // m/s, velocity at the end of the step (after BCs)
  NodeArray<Vec<Dim>> vL;   // m/s, velocity at the start of the step ("Lagrangian" v^L)

  /// All zero; called once, at construction.
  void resize(std::size_t n) {
    acc = NodeArray<Accum>(n);
    v = NodeArray<Vec<Dim>>(n);
    vL = NodeArray<Vec<Dim>>(n);
  }
};

/// Index box [lo, hi] (inclusive) of nodes per axis.
template <int Dim>
struct NodeBox {
  std::array<int, Dim> lo{}, hi{};
  bool empty() const {
    for (int a = 0; a < Dim; ++a)
      if (hi[a] < lo[a]) return true;
    return false;
  }
};

template <int Dim>
class Grid {
 public:
  Grid() = default;
  /// Uniform grid on [min, max] (max rounded up to whole cells) with cell size h. Linear/GIMP
  /// (bspline = false): cells + 1 nodes per axis at the cell corners. B-splines of degree p
  /// (bspline = true, degree = p): cells + p nodes per axis at the Greville abscissae.
  Grid(const Vec<Dim>& min, const Vec<Dim>& max, double h, int degree, bool bspline);

  const Axis& axis(int a) const { return axis_[a]; }
  double h() const { return h_; }
  std::size_t num_nodes() const { return num_nodes_; }
  const std::array<int, Dim>& nodes_per_axis() const { return nodes_; }
  Vec<Dim> min() const { return min_; }
  Vec<Dim> max() const { return max_; }

  std::size_t index(const std::array<int, Dim>& ijk) const {
    std::size_t idx = static_cast<std::size_t>(ijk[Dim - 1]);
    for (int a = Dim - 2; a >= 0; --a) idx = idx * nodes_[a] + ijk[a];
    return idx;
  }
  Vec<Dim> node_position(const std::array<int, Dim>& ijk) const {
    Vec<Dim> x;
    for (int a = 0; a < Dim; ++a) x[a] = axis_[a].node_x[ijk[a]];
    return x;
  }
  /// Calls fn(flat_index, ijk) for every node of the box, x fastest.
  template <class Fn>
  void for_each_node(const NodeBox<Dim>& box, Fn&& fn) const {
    if (box.empty()) return;
    std::array<int, Dim> ijk = box.lo;
    while (true) {
      fn(index(ijk), ijk);
      int a = 0;
      while (a < Dim) {
        if (++ijk[a] <= box.hi[a]) break;
        ijk[a] = box.lo[a];
        ++a;
      }
      if (a == Dim) return;
    }
  }
  /// for_each_node split over threads along the last axis, for work that touches only the visited
  /// node (per-node solves, clearing): the result does not depend on the thread count.
  template <class Fn>
  void parallel_for_each_node(const NodeBox<Dim>& box, Fn&& fn) const {
    if (box.empty()) return;
    const int lo = box.lo[Dim - 1], hi = box.hi[Dim - 1];
    std::size_t per_slab = 1;
    for (int a = 0; a < Dim - 1; ++a) per_slab *= static_cast<std::size_t>(box.hi[a] - box.lo[a] + 1);
    const bool parallel = per_slab * static_cast<std::size_t>(hi - lo + 1) > 4096;
#pragma omp parallel for schedule(static) if (parallel)
    for (int k = lo; k <= hi; ++k) {
      NodeBox<Dim> slab = box;
      slab.lo[Dim - 1] = slab.hi[Dim - 1] = k;
      for_each_node(slab, fn);
    }
  }
  /// The node nearest to x along each axis (x clamped into the grid).
  std::array<int, Dim> nearest_node(const Vec<Dim>& x) const {
    std::array<int, Dim> ijk;
    for (int a = 0; a < Dim; ++a) {
      const auto& nx = axis_[a].node_x;
      const auto it = std::lower_bound(nx.begin(), nx.end(), x[a]);
      int i = static_cast<int>(it - nx.begin());
      if (i >= static_cast<int>(nx.size())) i = static_cast<int>(nx.size()) - 1;
      else if (i > 0 && x[a] - nx[i - 1] < nx[i] - x[a]) i -= 1;
      ijk[a] = i;
    }
    return ijk;
  }
  /// The whole node range.
  NodeBox<Dim> all_nodes() const {
    NodeBox<Dim> b;
    for (int a = 0; a < Dim; ++a) {
      b.lo[a] = 0;
      b.hi[a] = nodes_[a] - 1;
    }
    return b;
  }

 private:
  std::array<Axis, Dim> axis_;
  std::array<int, Dim> nodes_{};
  std::size_t num_nodes_ = 0;
  double h_ = 1.0;
  Vec<Dim> min_, max_;
};

template <int Dim>
Grid<Dim>::Grid(const Vec<Dim>& min, const Vec<Dim>& max, double h, int degree, bool bspline)
    : h_(h), min_(min) {
  num_nodes_ = 1;
  for (int a = 0; a < Dim; ++a) {
    Axis& ax = axis_[a];
    ax.origin = min[a];
    ax.h = h;
    // The grid covers [min, max] rounded up to whole cells.
    ax.cells = std::max(1, static_cast<int>(std::ceil((max[a] - min[a]) / h - 1e-9)));
    max_[a] = min[a] + ax.cells * h;
    ax.nodes = bspline ? ax.cells + degree : ax.cells + 1;
    ax.node_x.resize(ax.nodes);
    for (int i = 0; i < ax.nodes; ++i) {
      if (!bspline) {
        ax.node_x[i] = min[a] + i * h;
      } else {
        // Greville abscissa of basis i on the open knot vector t_k = clamp(k - p, 0, cells) h.
        double s = 0.0;
        for (int k = i + 1; k <= i + degree; ++k) s += std::clamp(k - degree, 0, ax.cells);
        ax.node_x[i] = min[a] + h * s / degree;
      }
    }
    nodes_[a] = ax.nodes;
    num_nodes_ *= static_cast<std::size_t>(ax.nodes);
  }
}

/// The grid of a scene's `grid` for basis functions of `degree` (bspline: the clamped B-splines,
/// nodes at the Greville abscissae; otherwise cell corners): the construction the solver's
/// formulations (formulations/registry.hpp, make_grid, which also refuses fewer than 2 cells per
/// axis) and preprocess (the initial phase field of mpm-fem, particles/phase_field.vtu) share,
/// so that preprocess's nodes are the solver's, in the same flat order. Header-only: preprocess
/// does not link the solver.
template <int Dim>
Grid<Dim> scene_grid(const scene::Grid& g, int degree, bool bspline) {
  Vec<Dim> lo, hi;
  for (int a = 0; a < Dim; ++a) {
    lo[a] = g.min[static_cast<std::size_t>(a)];
    hi[a] = g.max[static_cast<std::size_t>(a)];
  }
  return Grid<Dim>(lo, hi, g.cell_size, degree, bspline);
}

}  // namespace swmpm
