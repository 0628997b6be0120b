// The concrete shapes' factories, one source file each, for make_shape (shapes_basic.cpp). Not
// for users of Shape: they take the scene's Geometry through make_shape / make_shapes.
#pragma once

#include <cmath>
#include <map>
#include <utility>

#include "preprocess/mesh_index.hpp"
#include "preprocess/shape.hpp"

namespace swmpm::pre {

/// A shape whose named surfaces are boundary elements (segments in 2D, triangles in 3D), kept in
/// the order they were added.
class SurfacedShape : public Shape {
 public:
  std::vector<std::string> surface_names() const override { return names_; }
  bool on_surface(const std::string& name, const Point& x, double tol) const override {
    const auto it = surfaces_.find(name);
    return it != surfaces_.end() && it->second.within(x, tol);
  }
  /// The nearest facet's normal, turned to point away from the inside: from x towards the
  /// surface, or, for x on the surface, to where the shape is not.
  Point outward_normal(const std::string& name, const Point& x, double tol) const override {
    const auto it = surfaces_.find(name);
    Point n{0.0, 0.0, 0.0}, foot{0.0, 0.0, 0.0};
    if (it == surfaces_.end() || !it->second.nearest(x, tol, n, foot)) return {0.0, 0.0, 0.0};
    double towards = 0.0;
    for (int a = 0; a < 3; ++a) towards += n[a] * (foot[a] - x[a]);
    if (std::abs(towards) <= 1e-9 * tol) {
      const Point probe{foot[0] + tol * n[0], foot[1] + tol * n[1], foot[2] + tol * n[2]};
      towards = inside(probe) ? -1.0 : 1.0;
    }
    if (towards < 0.0)
      for (double& c : n) c = -c;
    return n;
  }
  /// The facets' samples, each normal turned outward as outward_normal turns it.
  Samples surface_samples(const std::string& name, double max_size) const override {
    Samples out;
    const auto it = surfaces_.find(name);
    if (it == surfaces_.end()) return out;
    it->second.samples(max_size, out.x, out.normal, out.measure);
    for (std::size_t k = 0; k < out.x.size(); ++k) {
      const Point& x = out.x[k];
      Point& n = out.normal[k];
      const Point probe{x[0] + max_size * n[0], x[1] + max_size * n[1], x[2] + max_size * n[2]};
      if (inside(probe))
        for (double& c : n) c = -c;
    }
    return out;
  }

 protected:
  void add_surface(const std::string& name, SurfaceElements elements) {
    if (surfaces_.emplace(name, std::move(elements)).second) names_.push_back(name);
  }

 private:
  std::vector<std::string> names_;
  std::map<std::string, SurfaceElements> surfaces_;
};

using Polyline2 = std::vector<std::array<double, 2>>;

/// Axis-aligned box; `faces` names some of its faces (face index 2 axis + side, as the face bits).
std::unique_ptr<Shape> make_box(const Point& lo, const Point& hi, int dim,
                                const std::vector<std::pair<std::string, int>>& faces = {});
/// 2D polygon (either orientation), with named polylines as its named surfaces.
std::unique_ptr<Shape> make_polygon(const Polyline2& vertices,
                                    const std::vector<std::pair<std::string, Polyline2>>& surfaces = {});
/// shape_parametric.cpp
std::unique_ptr<Shape> make_slope(const scene::Geometry& g);
std::unique_ptr<Shape> make_footing(const scene::Geometry& g, int dim);
/// shape_gmsh.cpp
std::unique_ptr<Shape> make_gmsh(const scene::Geometry& g, int dim, const GeoAccess& access);
/// shape_surface_mesh.cpp
std::unique_ptr<Shape> make_surface_mesh(const scene::Geometry& g);

}  // namespace swmpm::pre
