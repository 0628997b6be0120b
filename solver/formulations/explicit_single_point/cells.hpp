// The per-cell stages of explicit-single-point (seed 000): the strain smoothing of eqs. 26-27 and
// the cell-constant pore pressure (docs/formulations.md, "Cell-constant pressure and conservative
// continuity"). A point belongs to the grid cell that holds its centre.
#pragma once

#include <array>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/particles/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::explicit_single_point {

/// Flat index of the grid cell holding x (x fastest).
template <int Dim>
std::size_t cell_of(const Grid<Dim>& g, const Vec<Dim>& x) {
  std::size_t idx = 0;
  for (int a = Dim - 1; a >= 0; --a) {
    const auto& ax = g.axis(a);
    idx = idx * ax.cells + shape::cell_of((x[a] - ax.origin) / ax.h, ax.cells);
  }
  return idx;
}

template <int Dim>
std::size_t cell_count(const Grid<Dim>& g) {
  std::size_t cells = 1;
  for (int a = 0; a < Dim; ++a) cells *= static_cast<std::size_t>(g.axis(a).cells);
  return cells;
}

/// (6) eqs. 26-27: in each cell, the solid-mass-weighted mean of div v_s and the fluid-mass-
/// weighted mean of div v_f replace the particles' own; the deviatoric part of L_s is kept.
/// In plane strain the volumetric rate is spread over the Dim in-plane axes (no out-of-plane
/// strain rate appears).
template <int Dim>
class StrainSmoothing {
 public:
  explicit StrainSmoothing(const Grid<Dim>& g) : sum_(cell_count(g)) {}  // zero (NodeArray)

  void apply(const Grid<Dim>& g, ParticleSet<Dim>& ps, std::vector<double>& div_f) {
    const std::size_t n = ps.size();
    cell_.resize(n);
    const long N = static_cast<long>(n);
#pragma omp parallel for schedule(static) if (N > parallel_threshold)
    for (long p = 0; p < N; ++p) cell_[p] = cell_of(g, ps.x[p]);
    for (std::size_t p = 0; p < n; ++p) sum_[cell_[p]] = {0.0, 0.0, 0.0, 0.0};
    for (std::size_t p = 0; p < n; ++p) {  // serial: cells are shared; fixed summation order
      auto& cs = sum_[cell_[p]];
      cs[0] += ps.m[p] * ps.L[p].trace();
      cs[1] += ps.m[p];
      cs[2] += ps.m_f[p] * div_f[p];
      cs[3] += ps.m_f[p];
    }
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
  void project(const Grid<Dim>& g, const StripeSchedule& schedule, const ParticleSet<Dim>& ps, BulkModulus&& K_f) {
    if (cell_.size() != cell_count(g)) cell_.assign(cell_count(g), Cell{});
    const std::size_t n = ps.size();
    pcell_.resize(n);
    const long N = static_cast<long>(n);
#pragma omp parallel for schedule(static) if (N > parallel_threshold)
    for (long p = 0; p < N; ++p) pcell_[p] = cell_of(g, ps.x[p]);
    schedule.run([&](int p) { cell_[pcell_[p]] = Cell{}; });
    schedule.run([&](int p) {
      if (ps.fluid_material[p] < 0) return;
      auto& c = cell_[pcell_[p]];
      const double storage = ps.n[p] * ps.V[p] / K_f(p);  // m^3/Pa (m^2/Pa in 2D)
      c.S += storage;
      c.Sp += storage * ps.p[p];
    });
  }

  /// p_c of point p's cell (Pa): the pressure the forces of (2) see.
  double at_point(int p) const { return cell_[pcell_[p]].pressure(); }

  /// (7) dp_c = -dt sum r_p / S_c, then every saturated point of the cell takes p_c + dp_c; S_c,
  /// p_c and the cells are those of the start of the step (project). Returns the first point
  /// whose pressure is not finite, or -1.
  long update(const StripeSchedule& schedule, ParticleSet<Dim>& ps, const std::vector<double>& vol_rate, double dt) {
    schedule.run([&](int p) { cell_[pcell_[p]].r += vol_rate[p]; });  // r was cleared in project
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
  std::vector<Cell> cell_;            // per cell
  std::vector<std::size_t> pcell_;    // per particle: its cell at the start of the step
};

}  // namespace swmpm::explicit_single_point
