// The per-cell stages of explicit-single-point (seed 000): the strain smoothing of eqs. 26-27 and
// the cell-constant pore pressure (docs/formulations.md, "Cell-constant pressure and conservative
// continuity"). A point belongs to the grid cell that holds its centre.
#pragma once

#include <algorithm>
#include <array>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/particles/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::explicit_single_point {

/// The grid cell holding x, by the flat index of its lowest node (Grid::index): cell arrays are
/// laid out as node arrays, so that the exchange of node columns at the cuts between ranks
/// (StripeSchedule::run) carries them too. A point's cell lies in the node columns its shape
/// functions reach, [base, base + S - 2] along each axis.
template <int Dim>
std::size_t cell_of(const Grid<Dim>& g, const Vec<Dim>& x) {
  std::array<int, Dim> c;
  for (int a = 0; a < Dim; ++a) {
    const auto& ax = g.axis(a);
    c[a] = shape::cell_of((x[a] - ax.origin) / ax.h, ax.cells);
  }
  return g.index(c);
}

/// The boxes of the cells that hold the points after the step's move: the node box (the points'
/// supports at the start of the step) and one column below on every axis (a point moves less
/// than a cell per step).
template <int Dim>
NodeBox<Dim> moved_cell_box(NodeBox<Dim> box) {
  for (int a = 0; a < Dim; ++a) box.lo[a] = std::max(0, box.lo[a] - 1);
  return box;
}

/// (6) eqs. 26-27: in each cell, the solid-mass-weighted mean of div v_s and the fluid-mass-
/// weighted mean of div v_f replace the particles' own; the deviatoric part of L_s is kept.
/// In plane strain the volumetric rate is spread over the Dim in-plane axes (no out-of-plane
/// strain rate appears). A point belongs to the cell that holds it after the step's move (with
/// the cell at the start of the step, A5 at cfl 0.9 builds a suction of 10 rho_sat g H and stops:
/// HardCases.SelfWeightConsolidationAtNinetyPercentOfTheCriticalStep). The cell sums go through
/// the scatter schedule (StripeSchedule::run_after_move): one fixed order for any --threads and
/// any number of ranks.
template <int Dim>
class StrainSmoothing {
 public:
  explicit StrainSmoothing(const Grid<Dim>& g) : sum_(g.num_nodes()) {}  // zero (NodeArray)

  /// `box`: the step's node box (the points' supports at the start of the step).
  void apply(const Grid<Dim>& g, const NodeBox<Dim>& box, const StripeSchedule& schedule, ParticleSet<Dim>& ps,
             std::vector<double>& div_f) {
    const long N = static_cast<long>(ps.size());
    cell_.resize(ps.size());
#pragma omp parallel for schedule(static) if (N > parallel_threshold)
    for (long p = 0; p < N; ++p) cell_[p] = cell_of(g, ps.x[p]);
    g.parallel_for_each_node(moved_cell_box(box), [&](std::size_t i, const auto&) { sum_[i] = {0.0, 0.0, 0.0, 0.0}; });
    schedule.run_after_move([&](int p) {
      auto& cs = sum_[cell_[p]];
      cs[0] += ps.m[p] * ps.L[p].trace();
      cs[1] += ps.m[p];
      cs[2] += ps.m_f[p] * div_f[p];
      cs[3] += ps.m_f[p];
    }, sum_);
#pragma omp parallel for schedule(static) if (N > parallel_threshold)
    for (long p = 0; p < N; ++p) {
      const auto& cs = sum_[cell_[p]];
      const double div_s = cs[0] / cs[1];
      ps.L[p] += (div_s - ps.L[p].trace()) / Dim * MatD<Dim>::Identity();
      if (cs[3] > 0.0) div_f[p] = cs[2] / cs[3];
    }
  }

 private:
  std::vector<std::size_t> cell_;             // per particle
  NodeArray<std::array<double, 4>> sum_;      // per cell: sum m div v_s, sum m_s, sum m_f div v_f, sum m_f
};

/// The cell-constant pore pressure: one pressure per grid cell, p_c = sum S_p p_p / sum S_p over
/// the saturated points whose centre lies in cell c at the start of the step, with the storage
/// S_p = n_p V_p / K_f of eq. 9; its rate S_c dp_c/dt = -sum_{p in c} r_p, with r_p the point's rate
/// of change of pore-water volume, the exact transpose of the pressure forces.
template <int Dim>
class CellPressure {
 public:
  /// (1b) The projection (applied twice it changes nothing): the points of a cell carry one
  /// pressure, and only a point that moves into another cell is averaged anew. The cell sums go
  /// through the scatter schedule: a cell's points have their first node in one stripe or two
  /// neighbouring ones (of different colours), so every cell is summed in one fixed order for any
  /// --threads. K_f(p): the bulk modulus of point p's pore water [Pa].
  template <class BulkModulus>
  void project(const Grid<Dim>& g, const NodeBox<Dim>& box, const StripeSchedule& schedule, const ParticleSet<Dim>& ps,
               BulkModulus&& K_f) {
    if (cell_.size() != g.num_nodes()) cell_ = NodeArray<Cell>(g.num_nodes());
    const std::size_t n = ps.size();
    pcell_.resize(n);
    const long N = static_cast<long>(n);
#pragma omp parallel for schedule(static) if (N > parallel_threshold)
    for (long p = 0; p < N; ++p) pcell_[p] = cell_of(g, ps.x[p]);
    g.parallel_for_each_node(box, [&](std::size_t i, const auto&) { cell_[i] = Cell{}; });
    schedule.run([&](int p) {
      if (ps.fluid_material[p] < 0) return;
      auto& c = cell_[pcell_[p]];
      const double storage = ps.n[p] * ps.V[p] / K_f(p);  // m^3/Pa (m^2/Pa in 2D)
      c.S += storage;
      c.Sp += storage * ps.p[p];
    }, cell_);
  }

  /// p_c of point p's cell (Pa): the pressure the forces of (2) see.
  double at_point(int p) const { return cell_[pcell_[p]].pressure(); }

  /// (7) dp_c = -dt sum r_p / S_c, then every saturated point of the cell takes p_c + dp_c; S_c,
  /// p_c and the cells are those of the start of the step (project). Returns the first point
  /// whose pressure is not finite, or -1.
  long update(const StripeSchedule& schedule, ParticleSet<Dim>& ps, const std::vector<double>& vol_rate, double dt) {
    schedule.run([&](int p) { cell_[pcell_[p]].r += vol_rate[p]; }, cell_);  // r was cleared in project
    const long N = static_cast<long>(ps.size());
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (N > parallel_threshold)
    for (long p = 0; p < N; ++p) {
      if (ps.fluid_material[p] < 0) continue;
      const auto& c = cell_[pcell_[p]];
      ps.p[p] = (c.Sp - dt * c.r) / c.S;
      if (!std::isfinite(ps.p[p])) bad = std::min(bad, p);
    }
    return bad == transfer::no_particle ? -1 : bad;
  }

 private:
  /// Per cell: storage S_c = sum S_p, sum S_p p_p, sum of the points' r_p.
  struct Cell {
    double S = 0.0, Sp = 0.0, r = 0.0;
    double pressure() const { return Sp / S; }  // p_c (Pa)
  };
  NodeArray<Cell> cell_;              // per cell (laid out as the nodes: cell_of)
  std::vector<std::size_t> pcell_;    // per particle: its cell at the start of the step
};

}  // namespace swmpm::explicit_single_point
