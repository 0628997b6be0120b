// mpm-fem's two grid systems over the ranks (fem::RankShare, parallel::SparseSolve), under
// `mpirun -n 2` and 3: each rank assembles its share of the cells and PETSc solves the sum. The
// ranks' partial systems, added up, are the whole system (assembly is linear), so every rank can
// solve that sum itself with Eigen's SparseLU and compare: the solution the ranks computed
// together must satisfy it to the solver's tolerance.
#include <gtest/gtest.h>

#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <span>
#include <vector>

#include "solver/fem/fluid.hpp"
#include "solver/fem/phase_field.hpp"
#include "solver/grid/grid.hpp"
#include "solver/parallel/comm.hpp"
#include "solver/shape/shape.hpp"

namespace swmpm::parallel {
namespace {

/// The sum over the ranks of this rank's part of a system (its A's values and right-hand side).
struct Whole {
  linear::CscMatrix A;
  Eigen::VectorXd rhs;
};
Whole summed(const linear::CscMatrix& A, const Eigen::VectorXd& rhs) {
  Whole w{A, rhs};
  sum(std::span<double>(w.A.valuePtr(), static_cast<std::size_t>(w.A.nonZeros())));
  sum(std::span<double>(w.rhs.data(), static_cast<std::size_t>(w.rhs.size())));
  return w;
}
/// |b - A x| / |b| and the largest |x - x_ref| relative to max |x_ref|, x_ref = A^-1 b by SparseLU.
struct Check {
  double residual, difference;
};
Check check(const Whole& w, const Eigen::VectorXd& x) {
  Eigen::SparseLU<linear::CscMatrix> lu;
  lu.compute(w.A);
  EXPECT_EQ(lu.info(), Eigen::Success);
  const Eigen::VectorXd ref = lu.solve(w.rhs);
  return {(w.rhs - w.A * x).norm() / w.rhs.norm(), (x - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff()};
}

using Shape = shape::BSpline<2>;
using Fluid = fem::Fluid<2, Shape>;

/// A 2D tank 0.6 m x 0.3 m (h = 0.02 m): water to 0.18 m, air above, a saturated soil block
/// (n = 0.4, k = 1e-9 m^2) on the floor in its middle third; walls on the sides and floor, the
/// top open (p = 0).
struct Tank {
  Grid<2> g{Vec<2>(0.0, 0.0), Vec<2>(0.6, 0.3), 0.02, Shape::degree, true};
  Fluid fluid;
  fem::SoilOnGrid<2> soil;
  Tank() {
    const std::size_t nn = g.num_nodes();
    const auto& n_axis = g.nodes_per_axis();
    Fluid::Conditions bc;
    bc.fixed.assign(nn, 0);
    bc.p_value.assign(nn, 0.0);
    bc.face_load.assign(nn, Vec<2>::Zero());
    g.for_each_node(g.all_nodes(), [&](std::size_t i, const std::array<int, 2>& ijk) {
      for (int a = 0; a < 2; ++a) {
        if (a == 1 && ijk[a] == n_axis[a] - 1) bc.fixed[i] |= 1u << 2;                   // the open top
        else if (ijk[a] == 0 || ijk[a] == n_axis[a] - 1) bc.fixed[i] |= 1u << a;         // walls
      }
    });
    fluid.setup(g, fem::FluidProperties{}, bc);
    soil.resize(nn);
    g.for_each_node(g.all_nodes(), [&](std::size_t i, const std::array<int, 2>& ijk) {
      const Vec<2> x = g.node_position(ijk);
      fluid.phi[i] = x[1] < 0.18 ? 1.0 : 0.0;
      if (x[0] > 0.2 && x[0] < 0.4 && x[1] < 0.06) soil.n[i] = 0.4, soil.theta[i] = 0.6, soil.k[i] = 1e-9, soil.rho_p[i] = 0.6 * 2650.0;
    });
  }
  Eigen::VectorXd solution() const {
    Eigen::VectorXd x(static_cast<long>(fluid.v.size()) * 3);
    for (std::size_t i = 0; i < fluid.v.size(); ++i)
      x[static_cast<long>(i) * 3] = fluid.v[i][0], x[static_cast<long>(i) * 3 + 1] = fluid.v[i][1], x[static_cast<long>(i) * 3 + 2] = fluid.p[i];
    return x;
  }
};

TEST(FemSystems, FluidOverTheRanksSolvesTheWholeSystem) {
  // Step 1 factorises (MUMPS) and solves directly; the later steps reuse the factor in BiCGSTAB
  // (|b - A x| <= 1e-8 |b|) as one rank reuses UMFPACK's.
  Tank t;
  const Vec<2> b(0.0, -9.81);
  for (int step = 1; step <= 6; ++step) {
    ASSERT_TRUE(t.fluid.step(t.soil, b, 1e-3)) << "step " << step;
    const Whole w = summed(t.fluid.system().A, t.fluid.system().rhs);
    // A prescribed unknown's row is the identity once over the ranks (its owner's), its value 0.
    long fixed = 0, wrong = 0;
    for (long r = 0; r < w.A.rows(); ++r)
      if (t.fluid.system().is_fixed(r)) ++fixed, wrong += w.A.coeff(r, r) != 1.0 || w.rhs[r] != 0.0;
    EXPECT_GT(fixed, 0);
    EXPECT_EQ(wrong, 0) << "step " << step;
    const Check c = check(w, t.solution());
    EXPECT_LE(c.residual, step == 1 ? 1e-12 : 1.1e-8) << "step " << step;
    EXPECT_LE(c.difference, step == 1 ? 1e-10 : 1e-5) << "step " << step;  // 1.3e-11, then up to 1.0e-9 (2026-12-06)
    if (rank() == 0) std::printf("fluid step %d on %d ranks: residual %.2e, difference %.2e\n", step, ranks(), c.residual, c.difference);
  }
  EXPECT_GE(t.fluid.factorisations(), 1);
  EXPECT_LT(t.fluid.factorisations(), 6);   // the factor was reused
  EXPECT_GT(t.fluid.krylov_iterations, 0);  // by BiCGSTAB
  // Every rank holds the same whole solution.
  const Eigen::VectorXd x = t.solution();
  std::vector<double> lo(x.data(), x.data() + x.size()), hi = lo;
  min(std::span<double>(lo)), max(std::span<double>(hi));
  EXPECT_EQ(lo, hi);
}

TEST(FemSystems, PhaseFieldOverTheRanksSolvesTheWholeSystem) {
  // The interface advected by a swirl; BiCGSTAB with the diagonal to 1e-10 over the ranks.
  Tank t;
  fem::PhaseFieldParameters prm;
  prm.width = 0.06;
  prm.mobility = 1.0;
  prm.volume_correction = false;
  fem::PhaseField<2, Shape> phase;
  phase.setup(t.g, t.fluid.basis(), prm);
  std::vector<Vec<2>> v(t.g.num_nodes());
  t.g.for_each_node(t.g.all_nodes(), [&](std::size_t i, const std::array<int, 2>& ijk) {
    const Vec<2> x = t.g.node_position(ijk) - Vec<2>(0.3, 0.15);
    v[i] = Vec<2>(-x[1], x[0]) * 2.0;
  });
  std::vector<double> phi = t.fluid.phi;
  for (int step = 1; step <= 3; ++step) {
    const std::vector<double> before = phi;
    ASSERT_GE(phase.step(phi, v, t.soil.n, 1e-3), 0) << "step " << step;
    const Check c = check(summed(phase.system().A, phase.system().rhs), Eigen::Map<const Eigen::VectorXd>(phi.data(), static_cast<long>(phi.size())));
    EXPECT_LE(c.residual, 1.1e-10) << "step " << step;
    EXPECT_LE(c.difference, 1e-7) << "step " << step;  // 1.4e-8 on 2 and 3 ranks (2026-12-06)
    double moved = 0.0;
    for (std::size_t i = 0; i < phi.size(); ++i) moved = std::max(moved, std::abs(phi[i] - before[i]));
    EXPECT_GT(moved, 1e-3) << "step " << step;  // the interface did move
  }
}

}  // namespace
}  // namespace swmpm::parallel
