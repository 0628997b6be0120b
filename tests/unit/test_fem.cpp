// solver/fem/: the grid's basis on cells, the Eulerian fluid of mpm-fem and its phase field, on
// their own (no soil): quadrature exactness, water at rest, phase-field profile and volume.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "solver/fem/cell_basis.hpp"
#include "solver/fem/fluid.hpp"
#include "solver/fem/phase_field.hpp"
#include "solver/porous/free_surface.hpp"
#include "solver/shape/shape.hpp"

namespace swmpm {
namespace {

using Shape = shape::BSpline2;

Grid<2> tank_grid(double w, double hgt, double h) { return Grid<2>(Vec<2>(0, 0), Vec<2>(w, hgt), h, 2, true); }

// Sum over cells of int N_k dOmega equals each node's basis integral, and int 1 the grid's area.
TEST(CellBasis, IntegratesTheBasisExactly) {
  const Grid<2> g = tank_grid(0.5, 0.3, 0.05);
  fem::CellBasis<2, Shape> basis;
  basis.build(g);
  std::vector<double> integral(g.num_nodes(), 0.0);
  double area = 0.0;
  fem::CellBasis<2, Shape>::Cell c;
  for (int j = 0; j < g.axis(1).cells; ++j)
    for (int i = 0; i < g.axis(0).cells; ++i) {
      basis.eval({i, j}, c);
      for (int gp = 0; gp < fem::CellBasis<2, Shape>::G; ++gp) {
        double sumN = 0.0;
        Vec<2> sumdN = Vec<2>::Zero();
        for (int k = 0; k < fem::CellBasis<2, Shape>::K; ++k) {
          integral[c.node[k]] += c.JxW[gp] * c.N[gp][k];
          sumN += c.N[gp][k];
          sumdN += c.dN[gp][k];
        }
        EXPECT_NEAR(sumN, 1.0, 1e-14);
        EXPECT_NEAR(sumdN.norm(), 0.0, 1e-11);
        area += c.JxW[gp];
      }
    }
  EXPECT_NEAR(area, 0.5 * 0.3, 1e-14);
  for (std::size_t i = 0; i < g.num_nodes(); ++i)
    EXPECT_NEAR(integral[i], porous::basis_integral<Shape>(g, i), 1e-15) << "node " << i;
}

/// Walls on the sides and the base (normal velocity 0), the top open (p = 0).
fem::Fluid<2, Shape>::Conditions tank_conditions(const Grid<2>& g) {
  fem::Fluid<2, Shape>::Conditions bc;
  bc.fixed.assign(g.num_nodes(), 0);
  bc.p_value.assign(g.num_nodes(), 0.0);
  bc.face_load.assign(g.num_nodes(), Vec<2>::Zero());
  const auto nn = g.nodes_per_axis();
  g.for_each_node(g.all_nodes(), [&](std::size_t i, const std::array<int, 2>& ijk) {
    if (ijk[0] == 0 || ijk[0] == nn[0] - 1) bc.fixed[i] |= 1;
    if (ijk[1] == 0) bc.fixed[i] |= 2;
    if (ijk[1] == nn[1] - 1) bc.fixed[i] |= 4;
  });
  return bc;
}

// Water 0.3 m deep at rest under air in a closed tank open at the top: p = rho g depth (+ the
// air's weight) within 0.5 %, spurious velocities below 1e-4 sqrt(g H), the surface flat.
TEST(EulerianFluid, WaterAtRestIsHydrostatic) {
  const double H = 0.3, h = 0.02, g = 9.81;
  const Grid<2> grid = tank_grid(0.4, 0.5, h);
  fem::Fluid<2, Shape> fluid;
  fluid.setup(grid, fem::FluidProperties{}, tank_conditions(grid));
  fluid.pspg_time_floor = std::sqrt(h / g) / 40.0;  // as mpm-fem sets it (1.1 ms: above dt = 1 ms)
  fem::PhaseFieldParameters prm;
  prm.width = 3.0 * h;
  prm.mobility = 100.0;
  fem::PhaseField<2, Shape> pf;
  pf.setup(grid, fluid.basis(), prm);
  grid.for_each_node(grid.all_nodes(), [&](std::size_t i, const std::array<int, 2>& ijk) {
    const double y = grid.node_position(ijk)[1];
    fluid.phi[i] = 0.5 * (1.0 + std::tanh((H - y) / prm.delta()));
  });
  fem::SoilOnGrid<2> soil;
  soil.resize(grid.num_nodes());
  const double dt = 1e-3;
  const double V0 = pf.volume(fluid.phi, soil.n);
  for (int s = 0; s < 1000; ++s) {  // 1 s
    ASSERT_TRUE(fluid.step(soil, Vec<2>(0, -g), dt));
    ASSERT_GE(pf.step(fluid.phi, fluid.v, soil.n, dt), 0);
  }
  double vmax = 0.0, vair = 0.0;
  for (std::size_t i = 0; i < fluid.v.size(); ++i)
    (fluid.phi[i] >= 0.5 ? vmax : vair) = std::max(fluid.phi[i] >= 0.5 ? vmax : vair, fluid.v[i].norm());
  std::printf("water |v|max %.3e, air %.3e m/s\n", vmax, vair);
  EXPECT_LT(vmax, 1e-4 * std::sqrt(g * H)) << vmax;
  // p at the base's mid-node against rho_w g H + rho_a g (top - H)
  const auto nn = grid.nodes_per_axis();
  const std::size_t base = grid.index({nn[0] / 2, 0});
  const double p_ref = 1000.0 * g * H + 1.2 * g * (0.5 - H);
  EXPECT_NEAR(fluid.p[base], p_ref, 0.005 * p_ref) << fluid.p[base];
  // The surface (phi = 1/2) stays at H within a tenth of a cell on the middle column.
  double level = NAN;
  for (int j = nn[1] - 1; j > 0; --j) {
    const double a = fluid.phi[grid.index({nn[0] / 2, j})], b = fluid.phi[grid.index({nn[0] / 2, j - 1})];
    if (a < 0.5 && b >= 0.5) {
      const double ya = grid.node_position({nn[0] / 2, j})[1], yb = grid.node_position({nn[0] / 2, j - 1})[1];
      level = yb + (b - 0.5) / (b - a) * (ya - yb);
      break;
    }
  }
  EXPECT_NEAR(level, H, 0.1 * h);
  EXPECT_NEAR(pf.volume(fluid.phi, soil.n), V0, 1e-6 * V0);
}

}  // namespace
}  // namespace swmpm
