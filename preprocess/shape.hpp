// Geometry behind one interface: an inside test, bounds, and named surfaces. Seeding, face tagging
// and (next) initial states only talk to Shape, so gmsh volumes, CGAL surface meshes and the
// parametric slope and footing plug in as further implementations.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace swmpm::pre {

using Point = std::array<double, 3>;

class Shape {
 public:
  virtual ~Shape() = default;
  /// True for points inside or on the boundary.
  virtual bool inside(const Point& x) const = 0;
  /// Axis-aligned bounds [lo, hi] (unused components 0 in 2D).
  virtual std::array<Point, 2> bounds() const = 0;
  /// Named surfaces besides the six axis faces (e.g. gmsh physical groups); none for box/polygon.
  virtual std::vector<std::string> surface_names() const { return {}; }
  /// Whether x lies within `tol` of the named surface.
  virtual bool on_surface(const std::string& /*name*/, const Point& /*x*/, double /*tol*/) const { return false; }
};

/// Builds the shape of a body's geometry; `scene_dir` resolves relative file paths.
std::unique_ptr<Shape> make_shape(const scene::Geometry& g, int dimension, const std::string& scene_dir);

}  // namespace swmpm::pre
