// Geometry behind one interface: an inside test, bounds, and named surfaces. Seeding, face tagging
// and initial states only talk to Shape; box and polygon (shapes_basic.cpp), slope and footing
// (shape_parametric.cpp), gmsh meshes (shape_gmsh.cpp) and CGAL surface meshes
// (shape_surface_mesh.cpp) are its implementations.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
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
  /// Named surfaces besides the six axis faces: slope and footing surfaces, gmsh physical groups
  /// of dimension dim - 1. None for box, polygon and surface meshes.
  virtual std::vector<std::string> surface_names() const { return {}; }
  /// Whether x lies within `tol` of the named surface, measured perpendicular to it (the foot of
  /// the perpendicular on the surface, not past its ends); false for a name the shape lacks.
  virtual bool on_surface(const std::string& /*name*/, const Point& /*x*/, double /*tol*/) const { return false; }
  /// Unit normal of the named surface at the point nearest to x (within `tol`, as on_surface),
  /// pointing out of the body: the direction a `pressure` load on that surface pushes against.
  /// Zero when x is not within `tol` of the surface.
  virtual Point outward_normal(const std::string& /*name*/, const Point& /*x*/, double /*tol*/) const {
    return {0.0, 0.0, 0.0};
  }
  /// Quadrature samples of a named surface (empty for a name the shape lacks): points on it no
  /// further than about `max_size` apart, each with the length (2D) or area (3D) it stands for
  /// and the outward unit normal there. The solver shares loads among the particles by them and
  /// finds the grid nodes of boundary conditions on named surfaces (particles/surfaces.vtu).
  struct Samples {
    std::vector<Point> x, normal;
    std::vector<double> measure;  // m (2D, per metre of thickness) or m^2
  };
  virtual Samples surface_samples(const std::string& /*name*/, double /*max_size*/) const { return {}; }
};

/// A geometry that cannot be built from its file or keys. `key` is the geometry key at fault
/// ("file", "physical", "parameters/<name>"); make_shapes turns it into a scene error line.
class GeometryError : public std::runtime_error {
 public:
  GeometryError(std::string key, const std::string& what) : std::runtime_error(what), key_(std::move(key)) {}
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

/// How far a geometry file that is a program (a gmsh .geo script) is trusted: by default it is
/// read first and refused when it could run commands, write files or read files outside the
/// scene's folder and its own (preprocess/geo_script.hpp); `trust_scripts` (--trust-geometry)
/// meshes it as it is.
struct GeoAccess {
  std::string scene_dir;
  bool trust_scripts = false;
  double lattice_spacing = 0.0;  // m, the body's particle spacing: a .geo is meshed no finer than 1/8 of it
};

/// Builds the shape of a body's geometry (throws GeometryError). File paths in `g` are absolute
/// (the parser resolved them); `scene_dir` is the scene file's folder.
std::unique_ptr<Shape> make_shape(const scene::Geometry& g, int dimension, const std::string& scene_dir,
                                  bool trust_scripts = false, double lattice_spacing = 0.0);

/// Every body's shape, checked against the scene where only the files can tell: bounds from a
/// file inside the grid, named surfaces that loads and boundaries refer to present. Throws
/// scene::SceneError with one line per problem, "<scene>: /bodies/N/geometry/...: ...".
/// Geometry scripts are trusted only when s.trust_geometry is set.
std::vector<std::unique_ptr<Shape>> make_shapes(const scene::Scene& s);

/// Face bits of the named surfaces within `tol` of x: bit scene::kFirstSurfaceBit + k for the
/// k-th of `bit_names` (scene::surface_bit_names of the scene) when `shape` has that surface.
std::uint32_t named_surface_bits(const std::vector<std::string>& bit_names, const Shape& shape, const Point& x,
                                 double tol);

}  // namespace swmpm::pre
