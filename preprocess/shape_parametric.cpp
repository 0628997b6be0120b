// Parametric geometries: `slope` (2D) and `footing` (2D and 3D), built from a few lengths into the
// polygon and box shapes, with named surfaces for loads and boundaries. The drawing of the slope
// and the names are in docs/scene-format.md; scene::named_surfaces lists the same names.
#include <cmath>
#include <numbers>

#include "preprocess/shape_types.hpp"

namespace swmpm::pre {

std::unique_ptr<Shape> make_slope(const scene::Geometry& g) {
  const double x0 = g.origin[0], y0 = g.origin[1];
  const double D = g.foundation_depth, H = g.height;
  // Horizontal run of the slope face [m]: H times the gradient, or H / tan(angle).
  const double run = g.ratio > 0.0 ? H * g.ratio : H / std::tan(g.angle * std::numbers::pi / 180.0);
  const double L = g.toe_length + run + g.crest_length;
  const std::array<double, 2> base_left{x0, y0}, base_right{x0 + L, y0}, crest_right{x0 + L, y0 + D + H},
      crest_left{x0 + g.toe_length + run, y0 + D + H}, toe{x0 + g.toe_length, y0 + D}, ground_left{x0, y0 + D};
  const Polyline2 outline{base_left, base_right, crest_right, crest_left, toe, ground_left};  // counter-clockwise
  return make_polygon(outline, {{"surface", {ground_left, toe, crest_left, crest_right}},
                                {"base", {base_left, base_right}},
                                {"left", {base_left, ground_left}},
                                {"right", {base_right, crest_right}},
                                {"toe", {ground_left, toe}},
                                {"slope_face", {toe, crest_left}},
                                {"crest", {crest_left, crest_right}}});
}

std::unique_ptr<Shape> make_footing(const scene::Geometry& g, int dim) {
  const bool is3d = dim == 3;
  const Point lo{g.center_x - g.width / 2, g.base_y, is3d ? g.center_z - g.length / 2 : 0.0};
  const Point hi{g.center_x + g.width / 2, g.base_y + g.height, is3d ? g.center_z + g.length / 2 : 0.0};
  // Names by face index 2 axis + side; z_min is the back, z_max the front (z towards the viewer).
  std::vector<std::pair<std::string, int>> faces{{"bottom", 2}, {"top", 3}, {"left", 0}, {"right", 1}};
  if (is3d) faces.insert(faces.end(), {{"back", 4}, {"front", 5}});
  return make_box(lo, hi, dim, faces);
}

}  // namespace swmpm::pre
