// `box` and `polygon` shapes (the polygon inside test is CGAL's bounded_side_2), the dispatch from
// a scene geometry to its shape, and the checks that need the shapes built.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2_algorithms.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <new>

#include "preprocess/shape_types.hpp"

namespace swmpm::pre {
namespace {

class BoxShape final : public SurfacedShape {
 public:
  BoxShape(const Point& lo, const Point& hi, int dim, const std::vector<std::pair<std::string, int>>& faces)
      : lo_(lo), hi_(hi), dim_(dim) {
    for (const auto& [name, f] : faces) add_surface(name, face(f));
  }
  bool inside(const Point& x) const override {
    for (int a = 0; a < dim_; ++a)
      if (x[a] < lo_[a] || x[a] > hi_[a]) return false;
    return true;
  }
  std::array<Point, 2> bounds() const override { return {lo_, hi_}; }

 private:
  /// Face f = 2 axis + side: a segment in 2D, two triangles in 3D.
  SurfaceElements face(int f) const {
    const int axis = f / 2;
    const double at = f % 2 == 0 ? lo_[axis] : hi_[axis];
    if (dim_ == 2) {
      const int other = 1 - axis;
      Point a{}, b{};
      a[axis] = b[axis] = at;
      a[other] = lo_[other];
      b[other] = hi_[other];
      return SurfaceElements(2, {a, b}, {{0, 1, 0}});
    }
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    std::vector<Point> corners(4);
    for (int k = 0; k < 4; ++k) {
      corners[k][axis] = at;
      corners[k][u] = (k == 1 || k == 2) ? hi_[u] : lo_[u];
      corners[k][v] = k >= 2 ? hi_[v] : lo_[v];
    }
    return SurfaceElements(3, corners, {{0, 1, 2}, {0, 2, 3}});
  }

  Point lo_, hi_;
  int dim_;
};

class PolygonShape final : public SurfacedShape {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;

 public:
  PolygonShape(const Polyline2& v, const std::vector<std::pair<std::string, Polyline2>>& surfaces) {
    lo_ = {v[0][0], v[0][1], 0.0};
    hi_ = lo_;
    for (const auto& p : v) {
      pts_.emplace_back(p[0], p[1]);
      for (int a = 0; a < 2; ++a) {
        lo_[a] = std::min(lo_[a], p[a]);
        hi_[a] = std::max(hi_[a], p[a]);
      }
    }
    for (const auto& [name, line] : surfaces) add_surface(name, polyline(line));
  }
  bool inside(const Point& x) const override {
    return CGAL::bounded_side_2(pts_.begin(), pts_.end(), K::Point_2(x[0], x[1]), K()) != CGAL::ON_UNBOUNDED_SIDE;
  }
  std::array<Point, 2> bounds() const override { return {lo_, hi_}; }

 private:
  std::vector<K::Point_2> pts_;
  Point lo_, hi_;
};

std::string fmt_point(const Point& p, int dim) {
  std::string out = "[";
  for (int a = 0; a < dim; ++a) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.10g", p[a]);
    out += (a ? ", " : "") + std::string(buf);
  }
  return out + "]";
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "none" : out;
}

bool is_axis_face(const std::string& name) { return scene::grid_face_index(name) >= 0; }

bool has(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

}  // namespace

std::unique_ptr<Shape> make_box(const Point& lo, const Point& hi, int dim,
                                const std::vector<std::pair<std::string, int>>& faces) {
  return std::make_unique<BoxShape>(lo, hi, dim, faces);
}

std::unique_ptr<Shape> make_polygon(const Polyline2& vertices,
                                    const std::vector<std::pair<std::string, Polyline2>>& surfaces) {
  return std::make_unique<PolygonShape>(vertices, surfaces);
}

std::unique_ptr<Shape> make_shape(const scene::Geometry& g, int dimension, const std::string& scene_dir,
                                  bool trust_scripts, double lattice_spacing) {
  if (g.type == "box") return make_box(g.min, g.max, dimension);
  if (g.type == "polygon") return make_polygon(g.vertices);
  if (g.type == "slope") return make_slope(g);
  if (g.type == "footing") return make_footing(g, dimension);
  if (g.type == "gmsh") return make_gmsh(g, dimension, {scene_dir, trust_scripts, lattice_spacing});
  if (g.type == "surface-mesh") return make_surface_mesh(g);
  throw GeometryError("type", "got \"" + g.type + "\", expected a geometry type (box, polygon, slope, footing, gmsh, "
                              "surface-mesh)");
}

std::vector<std::unique_ptr<Shape>> make_shapes(const scene::Scene& s) {
  const int dim = s.dimension;
  std::vector<std::string> problems;
  auto problem = [&](const std::string& path, const std::string& what) {
    problems.push_back(s.source_file + ": " + path + ": " + what);
  };
  const std::string scene_dir = std::filesystem::path(s.source_file).parent_path().string();

  std::vector<std::unique_ptr<Shape>> shapes;
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const scene::Geometry& g = s.bodies[b].geometry;
    const std::string path = "/bodies/" + std::to_string(b) + "/geometry";
    try {
      shapes.push_back(make_shape(g, dim, scene_dir, s.trust_geometry,
                                  s.grid.cell_size / s.bodies[b].particles_per_cell));
    } catch (const GeometryError& e) {
      problem(path + "/" + e.key(), e.what());
      shapes.push_back(nullptr);
      continue;
    } catch (const std::bad_alloc&) {  // a file whose contents ask for more than the memory there is
      problem(path + "/file", g.file + ": reading it needs more memory than this process may have; expected a "
                                       "valid geometry file (is it corrupt?)");
      shapes.push_back(nullptr);
      continue;
    }
    // The parser checked the bounds it could compute; a file's bounds are known only now.
    if (g.file.empty()) continue;
    const auto [lo, hi] = shapes.back()->bounds();
    for (int a = 0; a < dim; ++a) {
      const double tol = 1e-9 * (s.grid.max[a] - s.grid.min[a]);
      if (lo[a] < s.grid.min[a] - tol || hi[a] > s.grid.max[a] + tol) {
        problem(path, "got bounds " + fmt_point(lo, dim) + ".." + fmt_point(hi, dim) + " from " + g.file +
                          ", expected a geometry inside the grid " + fmt_point(s.grid.min, dim) + ".." +
                          fmt_point(s.grid.max, dim) + " [m]");
        break;
      }
    }
  }

  // Named surfaces only a file can tell (gmsh physical groups); the parser checked the others.
  for (std::size_t i = 0; i < s.loads.size(); ++i) {
    const scene::Load& l = s.loads[i];
    if (is_axis_face(l.face)) continue;
    for (std::size_t b = 0; b < s.bodies.size(); ++b) {
      if (s.bodies[b].name != l.body || !shapes[b]) continue;
      const auto names = shapes[b]->surface_names();
      if (!has(names, l.face))
        problem("/loads/" + std::to_string(i) + "/face",
                "got \"" + l.face + "\", expected an axis face or a named surface of body \"" + l.body +
                    "\" (named surfaces of " + s.bodies[b].geometry.type +
                    (s.bodies[b].geometry.file.empty() ? "" : " file " + s.bodies[b].geometry.file) + ": " +
                    join(names) + ")");
    }
  }
  for (std::size_t i = 0; i < s.boundaries.size(); ++i) {
    const std::string& on = s.boundaries[i].on;
    if (is_axis_face(on)) continue;
    std::vector<std::string> all;
    for (const auto& shape : shapes) {
      if (!shape) continue;
      for (const auto& n : shape->surface_names())
        if (!has(all, n)) all.push_back(n);
    }
    if (!has(all, on))
      problem("/boundaries/" + std::to_string(i) + "/on",
              "got \"" + on + "\", expected an axis face or a named surface of a body (named surfaces: " +
                  join(all) + ")");
  }
  if (!problems.empty()) throw scene::SceneError(problems);
  return shapes;
}

std::uint32_t named_surface_bits(const std::vector<std::string>& bit_names, const Shape& shape, const Point& x,
                                 double tol) {
  std::uint32_t bits = 0;
  for (std::size_t k = 0; k < bit_names.size(); ++k)
    if (shape.on_surface(bit_names[k], x, tol)) bits |= 1u << (scene::kFirstSurfaceBit + static_cast<int>(k));
  return bits;
}

}  // namespace swmpm::pre
