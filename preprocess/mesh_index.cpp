#include "preprocess/mesh_index.hpp"

#include <algorithm>
#include <cmath>

namespace swmpm::pre {
namespace {

Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Point axpy(double s, const Point& a, const Point& b) { return {b[0] + s * a[0], b[1] + s * a[1], b[2] + s * a[2]}; }

Box box_of(const Point* p, int n) {
  Box b{p[0], p[0]};
  for (int k = 1; k < n; ++k)
    for (int d = 0; d < 3; ++d) {
      b[0][d] = std::min(b[0][d], p[k][d]);
      b[1][d] = std::max(b[1][d], p[k][d]);
    }
  return b;
}

/// Grows every box by a round-off margin of the whole set's size, so that a point on an element's
/// face is found in the buckets of that element.
void pad(std::vector<Box>& boxes) {
  double size = 0.0;
  for (const Box& b : boxes)
    for (int d = 0; d < 3; ++d) size = std::max({size, std::abs(b[0][d]), std::abs(b[1][d])});
  const double margin = 1e-9 * std::max(size, 1e-30);
  for (Box& b : boxes)
    for (int d = 0; d < 3; ++d) b[0][d] -= margin, b[1][d] += margin;
}

/// Distance from p to segment ab along a perpendicular, or -1 when the foot of the perpendicular
/// falls outside the segment (beyond its ends).
double perpendicular_to_segment(const Point& p, const Point& a, const Point& b) {
  constexpr double eps = 1e-9;
  const Point ab = sub(b, a);
  const double len2 = dot(ab, ab);
  if (!(len2 > 0.0)) return -1.0;
  const double t = dot(sub(p, a), ab) / len2;
  if (t < -eps || t > 1.0 + eps) return -1.0;
  const Point d = sub(p, axpy(t, ab, a));
  return std::sqrt(dot(d, d));
}

/// Distance from p to the plane of triangle abc, or -1 when the foot of the perpendicular falls
/// outside the triangle.
double perpendicular_to_triangle(const Point& p, const Point& a, const Point& b, const Point& c) {
  constexpr double eps = 1e-9;
  const Point ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const Point n = cross(ab, ac);
  const double n2 = dot(n, n);
  if (!(n2 > 0.0)) return -1.0;
  // Barycentric coordinates of the foot: the sub-triangles' signed areas over the whole.
  const double v = dot(cross(ap, ac), n) / n2, w = dot(cross(ab, ap), n) / n2;
  if (v < -eps || w < -eps || v + w > 1.0 + eps) return -1.0;
  return std::abs(dot(ap, n)) / std::sqrt(n2);
}

}  // namespace

// ------------------------------------------------------------------------------------------------

BucketGrid::BucketGrid(const std::vector<Box>& boxes, int dim) : dim_(dim) {
  if (boxes.empty()) return;
  lo_ = boxes[0][0];
  hi_ = boxes[0][1];
  for (const Box& b : boxes)
    for (int d = 0; d < 3; ++d) lo_[d] = std::min(lo_[d], b[0][d]), hi_[d] = std::max(hi_[d], b[1][d]);
  // Bucket edge: the box's measure shared out evenly, over the axes with extent (a flat surface
  // in 3D has none along its normal).
  double longest = 0.0;
  for (int d = 0; d < dim_; ++d) longest = std::max(longest, hi_[d] - lo_[d]);
  double measure = 1.0;
  int axes = 0;
  for (int d = 0; d < dim_; ++d)
    if (hi_[d] - lo_[d] > 1e-6 * longest) measure *= hi_[d] - lo_[d], ++axes;
  const double h = axes == 0 ? 1.0 : std::pow(measure / static_cast<double>(boxes.size()), 1.0 / axes);
  for (int d = 0; d < dim_; ++d) {
    const double extent = hi_[d] - lo_[d];
    n_[d] = extent > 1e-6 * longest ? std::clamp(static_cast<int>(std::ceil(extent / h)), 1, 1024) : 1;
  }
  // At most a few buckets per element, whatever the shape of the box.
  const double limit = 8.0 * static_cast<double>(boxes.size()) + 64.0;
  while (static_cast<double>(n_[0]) * n_[1] * n_[2] > limit) {
    int* largest = std::max_element(n_.begin(), n_.end());
    *largest = std::max(1, *largest / 2);
  }
  for (int d = 0; d < dim_; ++d) {
    const double extent = hi_[d] - lo_[d];
    inv_h_[d] = extent > 0.0 ? n_[d] / extent : 0.0;
  }

  const std::size_t buckets = static_cast<std::size_t>(n_[0]) * n_[1] * n_[2];
  start_.assign(buckets + 1, 0);
  auto visit = [&](const Box& b, auto&& fn) {
    std::array<int, 3> a{0, 0, 0}, z{0, 0, 0};
    for (int d = 0; d < dim_; ++d) a[d] = cell(d, b[0][d]), z[d] = cell(d, b[1][d]);
    for (int k = a[2]; k <= z[2]; ++k)
      for (int j = a[1]; j <= z[1]; ++j)
        for (int i = a[0]; i <= z[0]; ++i) fn(static_cast<std::size_t>(i + n_[0] * (j + n_[1] * k)));
  };
  for (const Box& b : boxes) visit(b, [&](std::size_t q) { ++start_[q + 1]; });
  for (std::size_t q = 0; q < buckets; ++q) start_[q + 1] += start_[q];
  items_.resize(start_[buckets]);
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (std::size_t e = 0; e < boxes.size(); ++e)
    visit(boxes[e], [&](std::size_t q) { items_[fill[q]++] = static_cast<std::uint32_t>(e); });
}

int BucketGrid::cell(int d, double x) const {
  return std::clamp(static_cast<int>((x - lo_[d]) * inv_h_[d]), 0, n_[d] - 1);
}

// ------------------------------------------------------------------------------------------------

SimplexMesh::SimplexMesh(int dim, const std::vector<Point>& nodes,
                         const std::vector<std::array<std::uint32_t, 4>>& cells)
    : dim_(dim) {
  std::vector<Box> boxes;
  for (const auto& c : cells) {
    std::array<Point, 4> p{};
    for (int k = 0; k <= dim; ++k) p[k] = nodes[c[k]];
    if (dim == 2)
      for (auto& q : p) q[2] = 0.0;
    const Point e1 = sub(p[1], p[0]), e2 = sub(p[2], p[0]), e3 = sub(p[3], p[0]);
    Cell cell{p[0], {}};
    double det = 0.0, scale = 0.0;
    if (dim == 2) {
      det = e1[0] * e2[1] - e2[0] * e1[1];
      scale = std::sqrt(dot(e1, e1) * dot(e2, e2));
      cell.inv = {e2[1] / det, -e2[0] / det, -e1[1] / det, e1[0] / det, 0, 0, 0, 0, 0};
    } else {
      // The rows of T^-1 for T = [e1 e2 e3] are the cross products of the other two columns / det.
      const Point r0 = cross(e2, e3), r1 = cross(e3, e1), r2 = cross(e1, e2);
      det = dot(e1, r0);
      scale = std::sqrt(dot(e1, e1) * dot(e2, e2) * dot(e3, e3));
      for (int d = 0; d < 3; ++d) {
        cell.inv[d] = r0[d] / det;
        cell.inv[3 + d] = r1[d] / det;
        cell.inv[6 + d] = r2[d] / det;
      }
    }
    if (!(std::abs(det) > 1e-12 * scale)) continue;  // degenerate: no interior to find points in
    measure_ += std::abs(det) / (dim == 2 ? 2.0 : 6.0);
    cells_.push_back(cell);
    boxes.push_back(box_of(p.data(), dim + 1));
  }
  if (!boxes.empty()) {
    bounds_ = boxes[0];
    for (const Box& b : boxes)
      for (int d = 0; d < 3; ++d) {
        bounds_[0][d] = std::min(bounds_[0][d], b[0][d]);
        bounds_[1][d] = std::max(bounds_[1][d], b[1][d]);
      }
  }
  pad(boxes);
  index_ = BucketGrid(boxes, dim);
}

bool SimplexMesh::contains(const Point& x) const {
  constexpr double eps = 1e-10;  // barycentric: points on a shared face count as inside
  return index_.any(x, x, [&](std::uint32_t i) {
    const Cell& c = cells_[i];
    const Point r = sub(x, c.a);
    double rest = 1.0;
    for (int k = 0; k < dim_; ++k) {
      double lambda = 0.0;
      for (int d = 0; d < dim_; ++d) lambda += c.inv[dim_ * k + d] * r[d];
      if (lambda < -eps) return false;
      rest -= lambda;
    }
    return rest >= -eps;
  });
}

// ------------------------------------------------------------------------------------------------

SurfaceElements::SurfaceElements(int dim, const std::vector<Point>& nodes,
                                 const std::vector<std::array<std::uint32_t, 3>>& facets)
    : dim_(dim) {
  std::vector<Box> boxes;
  for (const auto& f : facets) {
    std::array<Point, 3> p{nodes[f[0]], nodes[f[1]], dim == 3 ? nodes[f[2]] : nodes[f[1]]};
    if (dim == 2)
      for (auto& q : p) q[2] = 0.0;
    facets_.push_back(p);
    boxes.push_back(box_of(p.data(), 3));
  }
  pad(boxes);
  index_ = BucketGrid(boxes, dim);
}

double SurfaceElements::perpendicular(const std::array<Point, 3>& f, const Point& y) const {
  return dim_ == 2 ? perpendicular_to_segment(y, f[0], f[1]) : perpendicular_to_triangle(y, f[0], f[1], f[2]);
}

bool SurfaceElements::within(const Point& x, double tol) const {
  Point y = x;
  if (dim_ == 2) y[2] = 0.0;
  const Point lo{y[0] - tol, y[1] - tol, y[2] - tol}, hi{y[0] + tol, y[1] + tol, y[2] + tol};
  return index_.any(lo, hi, [&](std::uint32_t i) {
    const auto& f = facets_[i];
    const double d = perpendicular(f, y);
    return d >= 0.0 && d <= tol;
  });
}

bool SurfaceElements::nearest(const Point& x, double tol, Point& normal, Point& foot) const {
  Point y = x;
  if (dim_ == 2) y[2] = 0.0;
  const Point lo{y[0] - tol, y[1] - tol, y[2] - tol}, hi{y[0] + tol, y[1] + tol, y[2] + tol};
  double best = -1.0;
  index_.any(lo, hi, [&](std::uint32_t i) {
    const auto& f = facets_[i];
    const double d = perpendicular(f, y);
    if (d < 0.0 || d > tol || (best >= 0.0 && d >= best)) return false;
    best = d;
    const Point e = sub(f[1], f[0]);
    const Point n = dim_ == 2 ? Point{-e[1], e[0], 0.0} : cross(e, sub(f[2], f[0]));
    const double len = std::sqrt(dot(n, n));
    normal = {n[0] / len, n[1] / len, n[2] / len};
    foot = axpy(-dot(sub(y, f[0]), normal), normal, y);
    return false;  // keep looking for a nearer facet
  });
  return best >= 0.0;
}

double SurfaceElements::measure() const {
  double m = 0.0;
  for (const auto& f : facets_) {
    const Point a = sub(f[1], f[0]);
    m += dim_ == 2 ? std::sqrt(dot(a, a)) : 0.5 * std::sqrt(dot(cross(a, sub(f[2], f[0])), cross(a, sub(f[2], f[0]))));
  }
  return m;
}

void SurfaceElements::samples(double max_size, std::vector<Point>& x, std::vector<Point>& normal,
                               std::vector<double>& measure) const {
  for (const auto& f : facets_) {
    const Point e1 = sub(f[1], f[0]);
    if (dim_ == 2) {
      const double len = std::sqrt(dot(e1, e1));
      if (len <= 0.0) continue;
      const int m = std::max(1, static_cast<int>(std::ceil(len / max_size)));
      const Point n{-e1[1] / len, e1[0] / len, 0.0};
      for (int i = 0; i < m; ++i) {
        x.push_back(axpy((i + 0.5) / m, e1, f[0]));
        normal.push_back(n);
        measure.push_back(len / m);
      }
      continue;
    }
    const Point e2 = sub(f[2], f[0]), c = cross(e1, e2);
    const double twice_area = std::sqrt(dot(c, c));
    if (twice_area <= 0.0) continue;
    const Point e3 = sub(f[2], f[1]);
    const double longest = std::sqrt(std::max({dot(e1, e1), dot(e2, e2), dot(e3, e3)}));
    const int m = std::max(1, static_cast<int>(std::ceil(longest / max_size)));
    const Point n{c[0] / twice_area, c[1] / twice_area, c[2] / twice_area};
    const double piece = 0.5 * twice_area / (m * m);
    auto at = [&](double u, double v) { return axpy(v, e2, axpy(u, e1, f[0])); };
    for (int i = 0; i < m; ++i)
      for (int j = 0; i + j < m; ++j) {
        // m^2 congruent sub-triangles: "up" (i, j), (i+1, j), (i, j+1) and, where it fits,
        // "down" (i+1, j), (i, j+1), (i+1, j+1); samples at their centroids.
        x.push_back(at((i + 1.0 / 3.0) / m, (j + 1.0 / 3.0) / m));
        normal.push_back(n);
        measure.push_back(piece);
        if (i + j + 2 <= m) {
          x.push_back(at((i + 2.0 / 3.0) / m, (j + 2.0 / 3.0) / m));
          normal.push_back(n);
          measure.push_back(piece);
        }
      }
  }
}

SurfaceElements polyline(const std::vector<std::array<double, 2>>& points) {
  std::vector<Point> nodes;
  std::vector<std::array<std::uint32_t, 3>> segments;
  for (std::size_t i = 0; i < points.size(); ++i) {
    nodes.push_back({points[i][0], points[i][1], 0.0});
    if (i > 0) segments.push_back({static_cast<std::uint32_t>(i - 1), static_cast<std::uint32_t>(i), 0});
  }
  return SurfaceElements(2, nodes, segments);
}

}  // namespace swmpm::pre
