// Free-surface detection, shared by the two-phase formulations.
//
// Node test (SupportCut): a node with water is on the free surface when the water inside its
// basis function's support stops more than kSurfaceCut cells short of the support's end along
// some axis (a grid face is not a cut: the support is clipped to the grid). Kularathna & Soga
// 2017 (seed-notes, seed 001 item 7) took a support less than 60 % full, which misses the surface
// between the nodes of the B-splines (docs/formulations.md).
//
// Point test (volume_fraction_at_point): the volume fraction of a set of points interpolated at a
// point, phi(x) = sum_I S_I(x) min(1, sum_p S_Ip V_p / int S_I dx); the set's surface is where
// phi = 1/2 (semi-implicit double-point: water points outside the soil).
#pragma once

#include <algorithm>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/shape/shape.hpp"

namespace swmpm::porous {

/// A node whose support reaches more than this many cells beyond the water is on the free surface.
constexpr double kSurfaceCut = 0.25;

/// The water's extent in each node's support, and the support-cut node test.
template <int Dim, class Shape>
class SupportCut {
  static constexpr int S = Shape::support;

 public:
  /// kBaseExtent: every node of a point's support has S > 0 (off the cell faces), so the points
  /// are collected per first node of their support (base) and a node's extent is the union over
  /// the bases whose supports hold it (extent()): one update per point instead of one per node.
  /// Otherwise (GIMP: a far node's S may vanish) per node over its points with S > 0.
  static constexpr bool kBaseExtent = Shape::bspline || std::is_same_v<Shape, shape::Linear>;
  struct Extent {
    Vec<Dim> lo = Vec<Dim>::Constant(std::numeric_limits<double>::infinity());
    Vec<Dim> hi = Vec<Dim>::Constant(-std::numeric_limits<double>::infinity());
    void add(const Vec<Dim>& x_lo, const Vec<Dim>& x_hi) {
      lo = lo.cwiseMin(x_lo);
      hi = hi.cwiseMax(x_hi);
    }
  };

  explicit SupportCut(std::size_t nodes) : extent_(nodes) {}
  void clear(std::size_t i) { extent_[i] = Extent{}; }
  /// The per-node extents as a node array (what a scatter names and a ghost fill copies).
  std::vector<Extent>& extents() { return extent_; }
  /// A water point's domain [x_lo, x_hi] = [x - l, x + l] joins the extent (through the scatter
  /// schedule): kBaseExtent at its support's first node, here; otherwise at each node with S > 0,
  /// in the P2G's node loop (add_at_node).
  template <bool G>
  void add_at_base(const Grid<Dim>& g, const shape::ShapeData<Dim, S, G>& sd, const Vec<Dim>& x_lo,
                   const Vec<Dim>& x_hi) {
    if constexpr (kBaseExtent) extent_[g.index(sd.base)].add(x_lo, x_hi);
  }
  void add_at_node(std::size_t i, double N, const Vec<Dim>& x_lo, const Vec<Dim>& x_hi) {
    if constexpr (!kBaseExtent)
      if (N > 0.0) extent_[i].add(x_lo, x_hi);
  }

  /// The extent of the water inside node i's support (box: this step's active nodes).
  Extent extent(const Grid<Dim>& g, const NodeBox<Dim>& box, std::size_t i, const std::array<int, Dim>& ijk) const {
    if constexpr (!kBaseExtent) {
      return extent_[i];
    } else {
      // Bases b with b <= ijk <= b + S - 1 per axis, inside the box (cleared entries).
      std::array<int, Dim> lo, n;
      for (int a = 0; a < Dim; ++a) {
        lo[a] = std::max(ijk[a] - (S - 1), box.lo[a]);
        n[a] = ijk[a] - lo[a] + 1;
      }
      Extent e;
      std::array<int, Dim> b = lo;
      for (;;) {
        const Extent& c = extent_[g.index(b)];
        e.add(c.lo, c.hi);
        int a = 0;
        for (; a < Dim; ++a) {
          if (++b[a] < lo[a] + n[a]) break;
          b[a] = lo[a];
        }
        if (a == Dim) break;
      }
      return e;
    }
  }

  /// The largest cut of node i's support by the water's extent: its length [m], axis, side
  /// (hi_cut: the water stops short of the support's upper end) and the extent x_s there.
  double cut(const Grid<Dim>& g, const NodeBox<Dim>& box, std::size_t i, const std::array<int, Dim>& ijk, int& axis,
             bool& hi_cut, double& x_s) const {
    const Extent e = extent(g, box, i, ijk);
    double c = 0.0;
    axis = -1;
    for (int a = 0; a < Dim; ++a) {
      const auto [s_lo, s_hi] = support_range(g, a, ijk[a]);
      if (s_hi - e.hi[a] > c) c = s_hi - e.hi[a], x_s = e.hi[a], axis = a, hi_cut = true;
      if (e.lo[a] - s_lo > c) c = e.lo[a] - s_lo, x_s = e.lo[a], axis = a, hi_cut = false;
    }
    return c;
  }
  /// The node test: node i is on the free surface.
  bool on_surface(double cut_length, const Grid<Dim>& g) const { return cut_length > kSurfaceCut * g.h(); }

  /// Support of basis j along axis a, clipped to the grid [m]: B-splines [t_j, t_{j+q+1}] on the
  /// clamped knot vector; linear and GIMP the hat's [x_j - h, x_j + h] (GIMP's wider reach of l_p
  /// belongs to the points' domains, which the water extent already includes).
  static std::pair<double, double> support_range(const Grid<Dim>& g, int a, int j) {
    const auto& ax = g.axis(a);
    if constexpr (Shape::bspline) {
      const int q = Shape::degree;
      auto knot = [&](int t) { return ax.origin + std::clamp(t - q, 0, ax.cells) * ax.h; };
      return {knot(j), knot(j + q + 1)};
    } else {
      return {std::max(ax.node_x[j] - ax.h, ax.origin), std::min(ax.node_x[j] + ax.h, ax.origin + ax.cells * ax.h)};
    }
  }

 private:
  std::vector<Extent> extent_;  // per node (kBaseExtent: of the points whose support starts there)
};

/// Integral of node i's basis function over the grid [m^Dim]: linear/GIMP h (h/2 on a grid
/// face) per axis; clamped B-splines of degree q (t_{i+q+1} - t_i) / (q + 1) from the open knot
/// vector. except_axis >= 0: over the grid face normal to that axis [m^(Dim-1)] (the other axes'
/// factors).
template <class Shape, int Dim>
double basis_integral(const Grid<Dim>& g, std::size_t i, int except_axis = -1) {
  double v = 1.0;
  for (int a = 0; a < Dim; ++a) {
    const auto& ax = g.axis(a);
    const int j = static_cast<int>(i % static_cast<std::size_t>(ax.nodes));
    i /= static_cast<std::size_t>(ax.nodes);
    if (a == except_axis) continue;
    if constexpr (Shape::bspline) {
      const int q = Shape::degree;
      auto knot = [&](int t) { return std::clamp(t - q, 0, ax.cells) * ax.h; };
      v *= (knot(j + q + 1) - knot(j)) / (q + 1);
    } else {
      v *= (j == 0 || j == ax.nodes - 1) ? 0.5 * ax.h : ax.h;
    }
  }
  return v;
}

/// The point test: phi(x) = sum_I S_I(x) min(1, volume_I / support_I) with volume_I(i) the set's
/// sum S V at node i and support_I(i) the integral of node i's basis function [m^Dim].
template <int Dim, int S, bool G, class NodeVolume, class NodeSupport>
double volume_fraction_at_point(const Grid<Dim>& g, const shape::ShapeData<Dim, S, G>& sd, NodeVolume&& volume,
                                NodeSupport&& support) {
  double phi = 0.0;
  shape::for_each_node(g, sd, [&](std::size_t i, double N, const auto&) { phi += N * std::min(1.0, volume(i) / support(i)); });
  return phi;
}

}  // namespace swmpm::porous
