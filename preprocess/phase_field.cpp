// mpm-fem's initial phase field (preprocess.hpp, InitialPhaseField): which seeded points carry water at
// t = 0, and their volume fraction at the solver's grid nodes.
#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

#include "preprocess/initial_state.hpp"
#include "scene/expression.hpp"
#include "preprocess/preprocess.hpp"
#include "solver/grid/grid.hpp"
#include "solver/porous/free_surface.hpp"
#include "solver/shape/shape.hpp"

namespace swmpm::pre {
namespace {

/// Per point: it carries water at t = 0. The points of bodies with a fluid do; a point of a dry
/// body does when it lies below the top y_q + l_q of the highest such point q within `reach`
/// of its vertical line (|x_q - x| <= reach, and |z_q - z| <= reach in 3D).
std::vector<char> water_bearing(const scene::Scene& s, const std::vector<SeedPoint>& points) {
  const int dim = s.dimension;
  std::vector<BodyContent> content;
  for (std::size_t b = 0; b < s.bodies.size(); ++b) content.push_back(body_content(s, b));
  std::vector<char> wet(points.size(), 0);
  for (std::size_t p = 0; p < points.size(); ++p) wet[p] = content_of(content, points[p]).has_fluid();

  // Columns of width h/2 in x (and z): the wet points' tops in each, highest first, so that a dry
  // point's query looks at the columns its reach touches and stops at the first top in reach.
  const double h = s.grid.cell_size, w = 0.5 * h, reach = 0.5 * h * (1.0 + 1e-9);  // m
  const int axis_z = dim == 3 ? 2 : 0;
  auto columns_of = [&](int a) { return static_cast<int>(std::ceil((s.grid.max[a] - s.grid.min[a]) / w)) + 1; };
  const int nx = columns_of(0), nz = dim == 3 ? columns_of(2) : 1;
  auto column = [&](double x, int a, int n) { return std::clamp(static_cast<int>(std::floor((x - s.grid.min[a]) / w)), 0, n - 1); };
  struct Top {
    double x, z, top;  // m
  };
  std::vector<std::vector<Top>> columns(static_cast<std::size_t>(nx) * nz);
  for (std::size_t p = 0; p < points.size(); ++p) {
    if (!wet[p]) continue;
    const Point& x = points[p].x;
    const int cz = dim == 3 ? column(x[2], 2, nz) : 0;
    columns[static_cast<std::size_t>(column(x[0], 0, nx) + nx * cz)].push_back({x[0], x[axis_z], x[1] + 0.5 * points[p].spacing});
  }
  for (auto& c : columns) std::sort(c.begin(), c.end(), [](const Top& a, const Top& b) { return a.top > b.top; });

  for (std::size_t p = 0; p < points.size(); ++p) {
    if (wet[p]) continue;
    const Point& x = points[p].x;
    double top = -std::numeric_limits<double>::infinity();  // m
    const int z_lo = dim == 3 ? column(x[2] - reach, 2, nz) : 0, z_hi = dim == 3 ? column(x[2] + reach, 2, nz) : 0;
    for (int cz = z_lo; cz <= z_hi; ++cz)
      for (int cx = column(x[0] - reach, 0, nx); cx <= column(x[0] + reach, 0, nx); ++cx)
        for (const Top& t : columns[static_cast<std::size_t>(cx + nx * cz)]) {
          if (t.top <= top) break;  // highest first: nothing further down this column is higher
          if (std::abs(t.x - x[0]) <= reach && (dim == 2 || std::abs(t.z - x[2]) <= reach)) {
            top = t.top;
            break;
          }
        }
    wet[p] = x[1] < top;
  }
  return wet;
}

template <int Dim, class Shape>
InitialPhaseField phase_field(const scene::Scene& s, const std::vector<SeedPoint>& points, const std::vector<char>& wet) {
  const Grid<Dim> g = scene_grid<Dim>(s.grid, Shape::degree, Shape::bspline);
  // sum_p integral over Omega_p of N_I [m^Dim, m^2 per metre in 2D], in the points' order. A
  // point's domain Omega_p, the box of side `spacing` around x_p (V_p = spacing^Dim), lies within
  // one knot span: the lattice's boxes start at grid.min + k h / particles_per_cell. There a hat or
  // a B-spline is a polynomial of degree <= 3 per axis, which the 2-point Gauss rule integrates
  // exactly; GIMP's weight at x_p with the half-size l_p is the box's average of the hat already.
  // The point value N_I(x_p) V_p instead is off where the basis is not a shifted copy of one
  // function: at a wall node of the clamped quadratic B-splines the water's sum is 0.9375 of
  // integral N_I, so a full support would read phi = 0.94 (0.88 in a corner).
  constexpr bool kGimp = std::is_same_v<Shape, shape::Gimp>;
  constexpr int kGauss = kGimp ? 1 : 2;  // points per axis
  const double gauss = 0.5 / std::sqrt(3.0);  // offset of the 2-point rule, in units of the box's side
  std::vector<double> volume(g.num_nodes(), 0.0);
  std::vector<Vec<Dim>> momentum(g.num_nodes(), Vec<Dim>::Zero());  // m^(Dim+1)/s: sum of N v over the water
  shape::ShapeData<Dim, Shape::support, false> sd;
  for (std::size_t p = 0; p < points.size(); ++p) {
    if (!wet[p]) continue;
    // The water's initial velocity: its body's `initial.velocity` (the pore water of a saturated
    // body moves with its skeleton; a dry body's submerged pores hold water at rest).
    Vec<Dim> v = Vec<Dim>::Zero();
    const auto& body = s.bodies[static_cast<std::size_t>(points[p].body)];
    if (!body.fluid.empty())
      for (int a = 0; a < Dim; ++a)
        v[a] = scene::initial_velocity(s, static_cast<std::size_t>(points[p].body), static_cast<std::size_t>(a), points[p].x);
    const double side = points[p].spacing, w = std::pow(side, Dim) / std::pow(kGauss, Dim);  // m, m^Dim
    for (int q = 0; q < (kGimp ? 1 : 1 << Dim); ++q) {  // the Gauss points, bit a: the side along axis a
      Vec<Dim> x, l;
      for (int a = 0; a < Dim; ++a) {
        x[a] = points[p].x[static_cast<std::size_t>(a)] + (kGimp ? 0.0 : ((q >> a) & 1 ? gauss : -gauss) * side);
        l[a] = kGimp ? 0.5 * side : 0.0;  // GIMP: the domain's half-size, as the solver reads it
      }
      shape::evaluate<Shape>(g, x, l, sd);
      shape::for_each_node(g, sd, [&](std::size_t i, double N, const auto&) {
        volume[i] += N * w;
        momentum[i] += N * w * v;
      });
    }
  }
  InitialPhaseField out;
  for (int a = 0; a < Dim; ++a) out.lattice[static_cast<std::size_t>(a)] = g.nodes_per_axis()[static_cast<std::size_t>(a)];
  out.nodes.points.resize(g.num_nodes());
  auto& phi = out.nodes.add("phi", 1);
  auto& velocity = out.nodes.add("velocity", 3);
  velocity.values.assign(3 * g.num_nodes(), 0.0);
  g.for_each_node(g.all_nodes(), [&](std::size_t i, const std::array<int, Dim>& ijk) {
    const Vec<Dim> xi = g.node_position(ijk);
    for (int a = 0; a < Dim; ++a) out.nodes.points[i][static_cast<std::size_t>(a)] = xi[a];
    phi.values[i] = std::min(1.0, volume[i] / porous::basis_integral<Shape>(g, i));
    if (volume[i] > 0.0)
      for (int a = 0; a < Dim; ++a) velocity.values[3 * i + static_cast<std::size_t>(a)] = momentum[i][a] / volume[i];
  });
  return out;
}

}  // namespace

InitialPhaseField initial_phase_field(const scene::Scene& s, const std::vector<SeedPoint>& points) {
  const std::vector<char> wet = water_bearing(s, points);
  return shape::with_policy(s.grid.shape_function, [&]<class Shape>() {
    return s.dimension == 3 ? phase_field<3, Shape>(s, points, wet) : phase_field<2, Shape>(s, points, wet);
  });
}

}  // namespace swmpm::pre
