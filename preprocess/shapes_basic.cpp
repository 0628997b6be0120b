// `box` and `polygon` shapes. The polygon inside test is CGAL's bounded_side_2.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2_algorithms.h>

#include <stdexcept>

#include "preprocess/shape.hpp"

namespace swmpm::pre {
namespace {

class Box final : public Shape {
 public:
  Box(const Point& lo, const Point& hi, int dim) : lo_(lo), hi_(hi), dim_(dim) {}
  bool inside(const Point& x) const override {
    for (int a = 0; a < dim_; ++a)
      if (x[a] < lo_[a] || x[a] > hi_[a]) return false;
    return true;
  }
  std::array<Point, 2> bounds() const override { return {lo_, hi_}; }

 private:
  Point lo_, hi_;
  int dim_;
};

class Polygon final : public Shape {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;

 public:
  explicit Polygon(const std::vector<std::array<double, 2>>& v) {
    lo_ = {v[0][0], v[0][1], 0.0};
    hi_ = lo_;
    for (const auto& p : v) {
      pts_.emplace_back(p[0], p[1]);
      for (int a = 0; a < 2; ++a) {
        lo_[a] = std::min(lo_[a], p[a]);
        hi_[a] = std::max(hi_[a], p[a]);
      }
    }
  }
  bool inside(const Point& x) const override {
    return CGAL::bounded_side_2(pts_.begin(), pts_.end(), K::Point_2(x[0], x[1]), K()) != CGAL::ON_UNBOUNDED_SIDE;
  }
  std::array<Point, 2> bounds() const override { return {lo_, hi_}; }

 private:
  std::vector<K::Point_2> pts_;
  Point lo_, hi_;
};

}  // namespace

std::unique_ptr<Shape> make_shape(const scene::Geometry& g, int dimension, const std::string&) {
  if (g.type == "box") return std::make_unique<Box>(g.min, g.max, dimension);
  if (g.type == "polygon") return std::make_unique<Polygon>(g.vertices);
  throw std::runtime_error("geometry type \"" + g.type + "\" is not implemented yet in this version");
}

}  // namespace swmpm::pre
