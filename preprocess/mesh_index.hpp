// Point location and distance queries on simplex meshes, for the mesh-based shapes (gmsh) and the
// named surfaces of every shape. Each set is indexed once by a uniform grid of buckets over its
// bounding box, so a query tests only the few elements that share its bucket: seeding N lattice
// points costs O(N), not O(N x elements).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "preprocess/shape.hpp"

namespace swmpm::pre {

using Box = std::array<Point, 2>;  // lower, upper corner [m]

/// Uniform buckets over the union of element boxes; an element is listed in every bucket its box
/// touches (compressed rows: `start_` offsets into `items_`).
class BucketGrid {
 public:
  BucketGrid() = default;
  /// `dim` axes are bucketed (2 or 3); about one element per bucket for an even mesh.
  BucketGrid(const std::vector<Box>& boxes, int dim);
  /// Whether fn(i) is true for an element listed in a bucket that [lo, hi] touches (elements may
  /// come more than once).
  template <class Fn>
  bool any(const Point& lo, const Point& hi, Fn&& fn) const {
    if (items_.empty()) return false;
    std::array<int, 3> a{0, 0, 0}, b{0, 0, 0};
    for (int d = 0; d < dim_; ++d) {
      if (hi[d] < lo_[d] || lo[d] > hi_[d]) return false;
      a[d] = cell(d, lo[d]);
      b[d] = cell(d, hi[d]);
    }
    for (int k = a[2]; k <= b[2]; ++k)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int i = a[0]; i <= b[0]; ++i) {
          const std::size_t bucket = static_cast<std::size_t>(i + n_[0] * (j + n_[1] * k));
          for (std::uint32_t q = start_[bucket]; q < start_[bucket + 1]; ++q)
            if (fn(items_[q])) return true;
        }
    return false;
  }

 private:
  int cell(int d, double x) const;
  int dim_ = 2;
  Point lo_{0, 0, 0}, hi_{0, 0, 0}, inv_h_{0, 0, 0};
  std::array<int, 3> n_{1, 1, 1};
  std::vector<std::uint32_t> start_, items_;
};

/// Triangles (2D, z ignored) or tetrahedra (3D): is a point inside their union?
class SimplexMesh {
 public:
  SimplexMesh() = default;
  /// `cells` index `nodes`: 3 per triangle, 4 per tetrahedron (the 4th unused in 2D).
  /// Degenerate cells (zero measure) are dropped.
  SimplexMesh(int dim, const std::vector<Point>& nodes, const std::vector<std::array<std::uint32_t, 4>>& cells);
  bool contains(const Point& x) const;
  std::size_t size() const { return cells_.size(); }
  const Box& bounds() const { return bounds_; }
  /// Total area (2D) or volume (3D) [m^2, m^3].
  double measure() const { return measure_; }

 private:
  /// x = a + T lambda; `inv` = T^-1 (row-major, dim x dim), so lambda = inv (x - a).
  struct Cell {
    Point a;
    std::array<double, 9> inv;
  };
  int dim_ = 2;
  std::vector<Cell> cells_;
  BucketGrid index_;
  Box bounds_{};
  double measure_ = 0.0;
};

/// Segments (2D) or triangles (3D) of a surface: is a point within a distance of it?
class SurfaceElements {
 public:
  SurfaceElements() = default;
  /// `facets` index `nodes`: 2 per segment, 3 per triangle (the 3rd unused in 2D).
  SurfaceElements(int dim, const std::vector<Point>& nodes, const std::vector<std::array<std::uint32_t, 3>>& facets);
  /// Whether x is within `tol` of a facet, measured along the perpendicular from x to it: the
  /// foot must fall on the facet, so a surface does not reach past its ends and edges (a strip
  /// load on 0..3 m tags no particle at x = 3.1 m).
  bool within(const Point& x, double tol) const;
  /// The facet nearest to x among those `within` reaches: its unit normal (either orientation)
  /// and the foot of the perpendicular from x. False when there is none.
  bool nearest(const Point& x, double tol, Point& normal, Point& foot) const;
  std::size_t size() const { return facets_.size(); }
  /// Total length (2D) or area (3D) [m, m^2].
  double measure() const;
  /// Quadrature points of the surface: each facet cut into pieces no wider than `max_size` (m
  /// segments of a segment, m^2 sub-triangles of a triangle), one sample at each piece's centroid
  /// with the piece's length or area and the facet's unit normal (either orientation).
  void samples(double max_size, std::vector<Point>& x, std::vector<Point>& normal, std::vector<double>& measure) const;

 private:
  /// Distance from y to facet f along a perpendicular, or -1 when its foot is off the facet.
  double perpendicular(const std::array<Point, 3>& f, const Point& y) const;
  int dim_ = 2;
  std::vector<std::array<Point, 3>> facets_;
  BucketGrid index_;
};

/// Segments of a polyline through `points` (2D), as SurfaceElements.
SurfaceElements polyline(const std::vector<std::array<double, 2>>& points);

}  // namespace swmpm::pre
