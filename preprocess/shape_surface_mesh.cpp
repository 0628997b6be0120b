// `surface-mesh` geometries (3D): a closed surface read with CGAL (.off, .stl, .obj), checked
// closed and free of self-intersections, with CGAL::Side_of_triangle_mesh as the inside test
// (an AABB tree over the triangles, built once, on the first query).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "preprocess/shape_types.hpp"

namespace swmpm::pre {
namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;

/// What a surface file declares before its data: CGAL reserves memory for an OFF header's counts
/// and reads a binary STL's triangle count, so a small file that declares 1e9 vertices cost
/// gigabytes. A count the file's bytes cannot hold is refused before CGAL reads it. Returns "" or
/// why.
std::string surface_header_problem(const std::string& file) {
  const double bytes = static_cast<double>(std::filesystem::file_size(file));
  std::ifstream in(file, std::ios::binary);
  std::string ext = std::filesystem::path(file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  auto declares = [&](double items, const std::string& what, double each) {
    return "declares " + std::to_string(static_cast<long long>(std::min(items, 9e18))) + " " + what + " in " +
           std::to_string(static_cast<long long>(bytes)) + " bytes (each takes at least " +
           std::to_string(static_cast<int>(each)) + "): a truncated or corrupt surface file";
  };
  if (ext == ".off") {
    // "OFF" (possibly with the counts on the same line), comments, then "vertices faces edges".
    std::string token;
    in >> token;  // OFF, COFF, NOFF, STOFF, ...: anything else is CGAL's to refuse
    if (token.size() < 3 || token.compare(token.size() - 3, 3, "OFF") != 0) return "";
    double counts[2] = {0.0, 0.0};
    for (double& c : counts) {
      while (in >> token && token[0] == '#') std::getline(in, token);
      try {
        c = std::stod(token);
      } catch (const std::exception&) {
        return "";  // not a count: CGAL reports the format error
      }
    }
    // A vertex is at least "0 0 0\n" (6 bytes) or 12 binary bytes; a face at least "3 0 1 2\n".
    if (6.0 * counts[0] + 8.0 * counts[1] > bytes)
      return declares(counts[0] + counts[1], "vertices and faces", 6.0);
    // Each face's corner count: CGAL reserves it (a face of "1e12" corners cost std::bad_alloc).
    std::getline(in, token);  // the rest of the counts' line
    const long vertices = static_cast<long>(counts[0]);
    for (long v = 0; v < vertices && std::getline(in, token);)
      if (!token.empty() && token[0] != '#') ++v;
    for (long f = 0; f < static_cast<long>(counts[1]) && std::getline(in, token);) {
      std::istringstream face(token);
      double corners = 0.0;
      if (token.empty() || token[0] == '#' || !(face >> corners)) continue;
      if (!(corners >= 3.0 && corners <= counts[0]))
        return "face " + std::to_string(f) + " has " + token.substr(0, token.find_first_of(" \t")) + " corners, expected 3 to " +
               std::to_string(vertices) + " (the file's vertices): a corrupt surface file";
      ++f;
    }
  } else if (ext == ".stl") {
    char head[5] = {0, 0, 0, 0, 0};
    in.read(head, 5);
    if (std::string(head, 5) == "solid") return "";  // ASCII: read as it comes
    in.seekg(80);
    std::uint32_t triangles = 0;
    in.read(reinterpret_cast<char*>(&triangles), sizeof triangles);
    if (84.0 + 50.0 * triangles > bytes) return declares(triangles, "triangles", 50.0);
  }
  return "";
}

class SurfaceMeshShape final : public Shape {
 public:
  explicit SurfaceMeshShape(const std::string& file) : file_(file) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file_, ec)) fail("no such file");
    if (const std::string why = surface_header_problem(file_); !why.empty()) fail(why);
    // read_polygon_mesh merges duplicated vertices (STL stores each triangle's own corners) and
    // orients the faces consistently before building the mesh.
    if (!CGAL::IO::read_polygon_mesh(file_, mesh_) || mesh_.is_empty())
      fail("CGAL could not read it as a polygon mesh, expected a valid .off, .stl or .obj surface");
    if (!CGAL::is_triangle_mesh(mesh_)) PMP::triangulate_faces(mesh_);
    if (!CGAL::is_closed(mesh_)) fail("got an open surface (" + std::to_string(border_edges()) +
                                      " border edges), expected a closed surface around a volume");
    if (PMP::does_self_intersect(mesh_))
      fail("got a self-intersecting surface, expected a closed surface that does not cross itself");
    const CGAL::Bbox_3 b = PMP::bbox(mesh_);
    bounds_ = {Point{b.xmin(), b.ymin(), b.zmin()}, Point{b.xmax(), b.ymax(), b.zmax()}};
    side_ = std::make_unique<CGAL::Side_of_triangle_mesh<Mesh, K>>(mesh_);
  }
  bool inside(const Point& x) const override {
    return (*side_)(K::Point_3(x[0], x[1], x[2])) != CGAL::ON_UNBOUNDED_SIDE;
  }
  std::array<Point, 2> bounds() const override { return bounds_; }

 private:
  [[noreturn]] void fail(const std::string& why) const { throw GeometryError("file", file_ + ": " + why); }

  std::size_t border_edges() const {
    std::size_t n = 0;
    for (auto h : mesh_.halfedges())
      if (mesh_.is_border(h)) ++n;
    return n;
  }

  std::string file_;
  Mesh mesh_;  // side_ refers to it: the shape is neither copied nor moved
  std::unique_ptr<CGAL::Side_of_triangle_mesh<Mesh, K>> side_;
  std::array<Point, 2> bounds_{};
};

}  // namespace

std::unique_ptr<Shape> make_surface_mesh(const scene::Geometry& g) {
  return std::make_unique<SurfaceMeshShape>(g.file);
}

}  // namespace swmpm::pre
