// mpm-fem's initial phase field (preprocess/phase_field.cpp, written to particles/phase_field.vtu):
// the solver's grid nodes with phi_I = min(1, sum_p integral_{Omega_p} N_I / integral N_I) over the
// points that carry water at t = 0. Checked here: the nodes are those of the solver's grid (make_grid)
// for every shape function; a box of water gives phi = 1 at the nodes whose support lies in it,
// 0 at those whose support misses it, and sum_I phi_I integral N_I = its volume; a saturated bed
// under a pond is water throughout; a dry body above the water is air, one below it is water.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "preprocess/preprocess.hpp"
#include "scene/scene.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/porous/free_surface.hpp"
#include "support/mpm_fem_scene.hpp"

namespace {

using nlohmann::json;
using PhaseField = swmpm::pre::InitialPhaseField;
using swmpm::scene::Scene;
using swmpm::scene::parse_scene;
using swmpm::scene::ShapeFunction;

/// A pond of free water alone: the box [lo, hi] in the grid [0, 0.8]^dim of 0.05 m cells, as
/// parsed. mpm-fem itself refuses linear and GIMP (its fluid is integrated on the B-splines); the
/// phase field is defined for every basis, so the shape function is set after the parse.
Scene water_box(int dim, const std::string& shape, std::array<double, 3> lo, std::array<double, 3> hi) {
  json j = swmpm::testing::mpm_fem_scene();
  j["dimension"] = dim;
  j["gravity"] = dim == 2 ? json({0, -9.81}) : json({0, -9.81, 0});
  j["grid"] = {{"cell_size", 0.05}, {"min", json::array()}, {"max", json::array()}, {"shape_function", "bspline2"}};
  json bmin = json::array(), bmax = json::array();
  for (int a = 0; a < dim; ++a) {
    j["grid"]["min"].push_back(0.0);
    j["grid"]["max"].push_back(0.8);
    bmin.push_back(lo[a]);
    bmax.push_back(hi[a]);
  }
  j["materials"].erase(0);  // water only
  j["bodies"] = {{{"name", "pond"}, {"geometry", {{"type", "box"}, {"min", bmin}, {"max", bmax}}}, {"fluid", "water"}}};
  j["boundaries"] = json::array();
  Scene s = parse_scene(j, "t.json");
  s.grid.shape_function = shape == "linear" ? ShapeFunction::linear
                          : shape == "gimp" ? ShapeFunction::gimp
                          : shape == "bspline3" ? ShapeFunction::bspline3
                                                : ShapeFunction::bspline2;
  return s;
}

PhaseField phase_field_of(const Scene& s) { return swmpm::pre::seed_phases(s).phase_field; }
PhaseField phase_field_of(const json& j) { return phase_field_of(parse_scene(j, "t.json")); }

/// Half the support of a basis function [m]: a node's phi reads the points within this distance
/// (per axis) of it. Linear 1 cell, GIMP 1.5 (the hat's cell plus a point's half-size h/4 — use
/// 1.5 to be safe), quadratic B-splines 1.5, cubic 2.
double reach(const std::string& shape) {
  const double h = 0.05;
  if (shape == "linear") return h;
  if (shape == "bspline3") return 2 * h;
  return 1.5 * h;
}

/// The box's volume [m^dim] and sum_I phi_I integral N_I, for the scene's shape function.
template <int Dim>
double phase_volume(const Scene& s, const PhaseField& pf) {
  return swmpm::dispatch_shape<Dim>(s.grid.shape_function, [&]<class Shape>() {
    const auto g = swmpm::make_grid<Dim>(s, Shape::degree, Shape::bspline);
    const auto& phi = pf.nodes.get("phi", "phase field").values;
    double v = 0.0;
    for (std::size_t i = 0; i < g.num_nodes(); ++i) v += phi[i] * swmpm::porous::basis_integral<Shape>(g, i);
    return v;
  });
}

/// The phase field's nodes are the solver's grid nodes (make_grid, formulations/registry.hpp),
/// in the same flat order, with the lattice's counts.
template <int Dim>
void expect_solver_nodes(const Scene& s, const PhaseField& pf) {
  swmpm::dispatch_shape<Dim>(s.grid.shape_function, [&]<class Shape>() {
    const auto g = swmpm::make_grid<Dim>(s, Shape::degree, Shape::bspline);
    ASSERT_EQ(pf.nodes.size(), g.num_nodes());
    for (int a = 0; a < Dim; ++a) EXPECT_EQ(pf.lattice[a], g.nodes_per_axis()[a]);
    g.for_each_node(g.all_nodes(), [&](std::size_t i, const std::array<int, Dim>& ijk) {
      for (int a = 0; a < Dim; ++a) ASSERT_EQ(pf.nodes.points[i][a], g.node_position(ijk)[a]) << i;
    });
  });
}

}  // namespace

// Measured (2D, 0.05 m cells, the box [0.15, 0.65] x [0.15, 0.55] inside the grid): sum phi_I
// int N_I equals the box's volume to round-off for all four shape functions (partition of unity;
// the points' domains are integrated exactly, so no node passes 1 and the cap cuts nothing);
// phi = 1 (to 1e-12) wherever a node's support lies in the water, 0 where it misses it.
TEST(PhaseField, BoxOfWaterIsOneInsideZeroOutsideAndKeepsItsVolume) {
  for (const std::string shape : {"linear", "gimp", "bspline2", "bspline3"}) {
    const Scene s = water_box(2, shape, {0.15, 0.15, 0}, {0.65, 0.55, 0});
    const PhaseField pf = phase_field_of(s);
    expect_solver_nodes<2>(s, pf);
    const auto& phi = pf.nodes.get("phi", "phase field").values;
    const double r = reach(shape) + 1e-9;
    int inside = 0, outside = 0;
    for (std::size_t i = 0; i < pf.nodes.size(); ++i) {
      const auto& x = pf.nodes.points[i];
      const bool in = x[0] - r >= 0.15 && x[0] + r <= 0.65 && x[1] - r >= 0.15 && x[1] + r <= 0.55;
      const bool out = x[0] + r <= 0.15 || x[0] - r >= 0.65 || x[1] + r <= 0.15 || x[1] - r >= 0.55;
      EXPECT_GE(phi[i], 0.0);
      EXPECT_LE(phi[i], 1.0);
      if (in) {
        EXPECT_NEAR(phi[i], 1.0, 1e-12) << shape << " node " << i;
        ++inside;
      }
      if (out) {
        EXPECT_EQ(phi[i], 0.0) << shape << " node " << i;
        ++outside;
      }
    }
    EXPECT_GT(inside, 10) << shape;
    EXPECT_GT(outside, 50) << shape;
    const double V = 0.5 * 0.4, v = phase_volume<2>(s, pf);
    std::printf("%s: sum phi int N = %.15g m^2 for a box of %.15g m^2 (relative %.2e)\n", shape.c_str(), v, V,
                v / V - 1.0);
    EXPECT_NEAR(v / V, 1.0, 1e-12) << shape;
  }
}

// Measured: against the grid faces (the box [0, 0.4] x [0, 0.3] in a corner, where the B-splines
// are clamped) the sum is the volume to round-off as well, and phi = 1 at the wall and corner
// nodes of a full support (point values N_I(x_p) V_p would give 0.9375 and 0.88 with bspline2);
// in 3D (bspline2) too.
TEST(PhaseField, WaterAgainstTheGridFacesAndIn3D) {
  for (const std::string shape : {"linear", "gimp", "bspline2", "bspline3"}) {
    const Scene s = water_box(2, shape, {0.0, 0.0, 0}, {0.4, 0.3, 0});
    const PhaseField pf = phase_field_of(s);
    const double v = phase_volume<2>(s, pf);
    std::printf("%s, box in the corner: sum phi int N / V - 1 = %.2e, phi at the corner node %.15g\n", shape.c_str(),
                v / (0.4 * 0.3) - 1.0, pf.nodes.get("phi", "phase field").values[0]);
    EXPECT_NEAR(v / (0.4 * 0.3), 1.0, 1e-12) << shape;
    EXPECT_NEAR(pf.nodes.get("phi", "phase field").values[0], 1.0, 1e-12) << shape;  // the node at (0, 0)
  }
  const Scene s = water_box(3, "bspline2", {0.2, 0.1, 0.25}, {0.5, 0.4, 0.55});
  const PhaseField pf = phase_field_of(s);
  expect_solver_nodes<3>(s, pf);
  EXPECT_EQ(pf.lattice[2], 18);  // 16 cells + 2
  const double V = 0.3 * 0.3 * 0.3, v = phase_volume<3>(s, pf);
  std::printf("3D bspline2: sum phi int N / V - 1 = %.2e\n", v / V - 1.0);
  EXPECT_NEAR(v / V, 1.0, 1e-12);
}

TEST(PhaseField, SaturatedBedUnderAPondIsWaterThroughout) {
  const json j = swmpm::testing::mpm_fem_scene();  // bed [0, 0.4] x [0, 0.1], pond up to 0.3
  const PhaseField pf = phase_field_of(j);
  const auto& phi = pf.nodes.get("phi", "phase field").values;
  int wet = 0;
  for (std::size_t i = 0; i < pf.nodes.size(); ++i) {
    const auto& x = pf.nodes.points[i];
    if (x[1] + 0.075 <= 0.3) {  // the support in the bed and the pond
      EXPECT_NEAR(phi[i], 1.0, 1e-12) << "node " << i << " at y = " << x[1];
      ++wet;
    }
    if (x[1] - 0.075 >= 0.3) {  // the support in the air
      EXPECT_EQ(phi[i], 0.0) << "node " << i;
    }
  }
  EXPECT_GT(wet, 40);
}

TEST(PhaseField, DryBodiesAreAirAboveTheWaterAndWaterBelowIt) {
  // A dry bed [0, 1] x [0, 0.2] under a pond [0, 0.6] x [0.2, 0.5], and a dry block [0.1, 0.4] x
  // [0.6, 0.8] above the pond: the bed's pores under the pond are full of water, the rest of the
  // bed (x > 0.6) and the block are dry.
  json j = swmpm::testing::mpm_fem_scene();
  j["grid"]["max"] = {1.0, 1.0};
  j["materials"][0] = {{"name", "gravel"}, {"model", "linear-elastic"}, {"density", 1800}, {"youngs_modulus", 1e7},
                       {"poisson_ratio", 0.3}};
  j["bodies"] = {
      {{"name", "bed"}, {"geometry", {{"type", "box"}, {"min", {0, 0}}, {"max", {1.0, 0.2}}}}, {"solid", "gravel"}},
      {{"name", "pond"}, {"geometry", {{"type", "box"}, {"min", {0, 0.2}}, {"max", {0.6, 0.5}}}}, {"fluid", "water"}},
      {{"name", "block"}, {"geometry", {{"type", "box"}, {"min", {0.1, 0.6}}, {"max", {0.4, 0.8}}}}, {"solid", "gravel"}}};
  const PhaseField pf = phase_field_of(j);
  const auto& phi = pf.nodes.get("phi", "phase field").values;
  auto phi_at = [&](double x, double y) {  // the node at (x, y) (a Greville abscissa of bspline2)
    for (std::size_t i = 0; i < pf.nodes.size(); ++i)
      if (std::abs(pf.nodes.points[i][0] - x) < 1e-12 && std::abs(pf.nodes.points[i][1] - y) < 1e-12) return phi[i];
    ADD_FAILURE() << "no node at (" << x << ", " << y << ")";
    return -1.0;
  };
  EXPECT_NEAR(phi_at(0.275, 0.075), 1.0, 1e-12);  // the bed under the pond: saturated
  EXPECT_NEAR(phi_at(0.275, 0.325), 1.0, 1e-12);  // the pond
  EXPECT_EQ(phi_at(0.875, 0.075), 0.0);           // the bed beyond the pond: dry
  EXPECT_EQ(phi_at(0.275, 0.725), 0.0);           // the block above the pond: dry
  EXPECT_EQ(phi_at(0.875, 0.875), 0.0);           // air
  // Where the bed's pores stop being wet: half a cell beyond the pond's side (x = 0.6 + 0.025),
  // so the node at x = 0.675 (support from 0.6) still sees a little.
  std::printf("phi along y = 0.075 from x = 0.525: %.3f %.3f %.3f %.3f\n", phi_at(0.525, 0.075), phi_at(0.575, 0.075),
              phi_at(0.625, 0.075), phi_at(0.675, 0.075));
}
