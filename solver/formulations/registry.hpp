// Helpers every formulation uses at construction, and the shape-function dispatch (done once).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <vector>

#include "scene/scene.hpp"
#include "solver/formulation.hpp"
#include "solver/grid/grid.hpp"
#include "solver/materials/material.hpp"
#include "solver/parallel/domain.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"

namespace swmpm {

template <int Dim>
Grid<Dim> make_grid(const scene::Scene& s, int degree, bool bspline) {
  Vec<Dim> lo, hi;
  for (int a = 0; a < Dim; ++a) {
    lo[a] = s.grid.min[a];
    hi[a] = s.grid.max[a];
  }
  Grid<Dim> g(lo, hi, s.grid.cell_size, degree, bspline);
  for (int a = 0; a < Dim; ++a)
    if (g.axis(a).cells < 2)
      throw std::runtime_error("grid: the grid needs at least 2 cells along every axis (axis " +
                               std::to_string(a) + " has " + std::to_string(g.axis(a).cells) + ")");
  return g;
}

template <int Dim>
std::vector<std::unique_ptr<MaterialModel<Dim>>> make_materials(const scene::Scene& s) {
  std::vector<std::unique_ptr<MaterialModel<Dim>>> out;
  for (const auto& m : s.materials)
    out.push_back(m.model == scene::MaterialModel::fluid ? nullptr : make_material<Dim>(m, s));
  return out;
}

/// Plastic flow on or off in every material model (the initialisation phase).
template <int Dim>
void set_plastic(std::vector<std::unique_ptr<MaterialModel<Dim>>>& materials, bool on) {
  for (auto& m : materials)
    if (m) m->set_plastic(on);
}

/// The damping of a step: the initialisation phase's while it runs (if it sets one), else the scene's.
inline double phase_damping(const scene::Initialisation* phase, double scene_damping) {
  return phase && phase->damping ? *phase->damping : scene_damping;
}

/// Particle indices of each material, in increasing index; regroup reuses the vectors' capacity.
template <int Dim>
void regroup_by_material(const ParticleSet<Dim>& ps, std::vector<std::vector<int>>& groups) {
  for (auto& g : groups) g.clear();
  for (std::size_t p = 0; p < ps.size(); ++p) groups.at(ps.material[p]).push_back(static_cast<int>(p));
}
template <int Dim>
std::vector<std::vector<int>> group_by_material(const ParticleSet<Dim>& ps, std::size_t materials) {
  std::vector<std::vector<int>> groups(materials);
  regroup_by_material(ps, groups);
  return groups;
}

/// Stores the particles of `ps` in the schedule's order every `interval` steps (memory locality
/// for the transfers; results stay thread-independent). True if it moved them: the caller then
/// refreshes what indexes them. Under mpirun (`domain` active) every rank takes the same steps,
/// and the keys follow the new order (parallel::Domain::renumber), as the one-rank run's storage
/// order does.
template <int Dim>
bool reorder_set(ParticleSet<Dim>& ps, long step, const StripeSchedule& schedule, Reorder<Dim>& reorder, long interval,
                 parallel::Domain<Dim>* domain = nullptr) {
  if (domain && domain->active()) {
    if (step % interval != 0 || !schedule.built()) return false;
    // As one rank: no reordering with an order older than the set (points removed since it was built).
    if (parallel::any(schedule.order().size() != ps.size())) return false;
    const bool moved = !schedule.in_order();
    if (moved) reorder.apply(ps, schedule.order());
    domain->renumber(ps);
    return moved;
  }
  if (step % interval != 0 || schedule.order().size() != ps.size() || schedule.in_order()) return false;
  reorder.apply(ps, schedule.order());
  return true;
}

/// reorder_set of the soil points, with the id table and the material groups refreshed.
template <int Dim>
bool reorder_for_locality(State<Dim>& st, const StripeSchedule& schedule, Reorder<Dim>& reorder,
                          std::vector<std::vector<int>>& material_particles, long interval,
                          parallel::Domain<Dim>* domain = nullptr) {
  if (!reorder_set(st.solid, st.step, schedule, reorder, interval, domain)) return false;
  st.index_ids();
  regroup_by_material(st.solid, material_particles);
  return true;
}

/// Restart: the schedule order the next step's reordering reads (reorder_for_locality), saved and
/// restored under `name`; `set` names the particle set it orders ("solid" or "fluid").
inline void save_order(Checkpoint& c, const std::string& name, const StripeSchedule& schedule,
                       const std::string& set = "solid") {
  c.put_order(name, set, schedule.order());
}
inline void restore_order(const Checkpoint& c, const std::string& name, StripeSchedule& schedule) {
  std::vector<int> order;
  c.get(name, order);
  schedule.restore_order(std::move(order));
}

/// Per material, the largest P-wave modulus K + 4G/3 of its points over all ranks (0 without
/// points): what a time step's CFL combines with each point's own density and porosity, the same
/// value on every rank as at one rank (a model's modulus may grow with its points' pressure, as
/// Nor-Sand's does). Collective.
template <int Dim, class Materials>
std::vector<double> max_p_wave_moduli(const Materials& materials, const ParticleSet<Dim>& ps,
                                      const std::vector<std::vector<int>>& groups) {
  std::vector<double> modulus(materials.size(), 0.0);
  for (std::size_t k = 0; k < materials.size(); ++k)
    if (!groups[k].empty() && materials[k]) modulus[k] = materials[k]->max_p_wave_modulus(ps, groups[k]);
  parallel::max(std::span<double>(modulus));
  return modulus;
}

/// Per material, whether any rank holds points of it (groups: the rank's points per material).
/// What a setup step asks of the whole run, whichever slice of it the rank holds (a fresh start
/// under mpirun builds the formulation from each rank's slice, State::shares). Collective.
inline std::vector<char> materials_present(const std::vector<std::vector<int>>& groups) {
  std::vector<long> any(groups.size(), 0);
  for (std::size_t k = 0; k < groups.size(); ++k) any[k] = !groups[k].empty();
  parallel::max(std::span<long>(any));
  std::vector<char> present(groups.size());
  for (std::size_t k = 0; k < groups.size(); ++k) present[k] = any[k] != 0;
  return present;
}

/// Per material k (of `materials`), of(p) at the first point p of material k (`last`: the last
/// one) in the one-rank storage order for which of(p) >= 0, over every rank's points; -1 where
/// no point has one (the one-rank order: ParticleSet::place). Collective.
template <int Dim, class Of>
std::vector<int> material_value_over_ranks(const ParticleSet<Dim>& ps, std::size_t materials, bool last, Of&& of) {
  constexpr long none_first = std::numeric_limits<long>::max(), none_last = -1;
  const long none = last ? none_last : none_first;
  std::vector<long> at(materials, none), value(materials, -1);
  for (std::size_t p = 0; p < ps.size(); ++p) {
    const int v = of(static_cast<int>(p));
    if (v < 0) continue;
    const std::size_t k = static_cast<std::size_t>(ps.material[p]);
    const long place = static_cast<long>(ps.place(p));
    if (last ? place > at[k] : place < at[k]) at[k] = place, value[k] = v;
  }
  std::vector<long> chosen = at;
  if (last) parallel::max(std::span<long>(chosen));
  else parallel::min(std::span<long>(chosen));
  for (std::size_t k = 0; k < materials; ++k)
    if (at[k] != chosen[k]) value[k] = -1;  // another rank holds the chosen point
  parallel::max(std::span<long>(value));
  std::vector<int> out(materials);
  for (std::size_t k = 0; k < materials; ++k) out[k] = static_cast<int>(value[k]);
  return out;
}

/// Cundall's local damping of a nodal force: f_a <- f_a - alpha |f_a| sign(v_a), per component.
template <int Dim>
inline Vec<Dim> local_damping(Vec<Dim> f, const Vec<Dim>& v, double alpha) {
  if (alpha > 0.0)
    for (int a = 0; a < Dim; ++a) f[a] -= alpha * std::abs(f[a]) * (v[a] > 0 ? 1.0 : (v[a] < 0 ? -1.0 : 0.0));
  return f;
}

/// Sum of f(p) over p < n in fixed-size chunks, chunks added in order: the same bits for any
/// thread count.
template <class F>
double fixed_order_sum(std::size_t n, F&& f) {
  constexpr std::size_t chunk = 4096;
  const long chunks = static_cast<long>((n + chunk - 1) / chunk);
  std::vector<double> partial(chunks, 0.0);
#pragma omp parallel for schedule(static) if (chunks > 1)
  for (long c = 0; c < chunks; ++c) {
    double sum = 0.0;
    for (std::size_t p = c * chunk; p < std::min(n, (c + 1) * chunk); ++p) sum += f(p);
    partial[c] = sum;
  }
  double total = 0.0;
  for (double v : partial) total += v;
  return total;
}

/// Number of distinct cells that hold a particle (sorted cell indices: the cost follows the
/// particles, not the grid).
template <int Dim>
std::size_t count_active_cells(const Grid<Dim>& g, const ParticleSet<Dim>& ps) {
  std::vector<std::size_t> cells;
  cells.reserve(ps.size());
  for (const auto& x : ps.x) {
    std::size_t idx = 0;
    for (int a = Dim - 1; a >= 0; --a) {
      const double xi = (x[a] - g.axis(a).origin) / g.h();
      const int c = std::isfinite(xi) ? std::clamp(static_cast<int>(std::floor(xi)), 0, g.axis(a).cells - 1) : 0;
      idx = idx * g.axis(a).cells + c;
    }
    cells.push_back(idx);
  }
  std::sort(cells.begin(), cells.end());
  return static_cast<std::size_t>(std::unique(cells.begin(), cells.end()) - cells.begin());
}

/// Calls fn.template operator()<Shape>() with the shape-function policy the scene names.
template <int Dim, class Fn>
auto dispatch_shape(scene::ShapeFunction f, Fn&& fn) {
  switch (f) {
    case scene::ShapeFunction::linear: return fn.template operator()<shape::Linear>();
    case scene::ShapeFunction::gimp: return fn.template operator()<shape::Gimp>();
    case scene::ShapeFunction::bspline2: return fn.template operator()<shape::BSpline2>();
    case scene::ShapeFunction::bspline3: return fn.template operator()<shape::BSpline3>();
  }
  throw std::logic_error("unknown shape function");
}

/// A formulation class template F<Dim, Shape> built for the scene's shape function.
template <template <int, class> class F, int Dim>
std::unique_ptr<Formulation<Dim>> make_for_shape(const scene::Scene& s, const State<Dim>& state) {
  return dispatch_shape<Dim>(s.grid.shape_function, [&]<class Shape>() -> std::unique_ptr<Formulation<Dim>> {
    return std::make_unique<F<Dim, Shape>>(s, state);
  });
}

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_dry(const scene::Scene& s, const State<Dim>& state);
template <int Dim>
std::unique_ptr<Formulation<Dim>> make_explicit_single_point(const scene::Scene& s, const State<Dim>& state);
template <int Dim>
std::unique_ptr<Formulation<Dim>> make_semi_implicit_single_point(const scene::Scene& s, const State<Dim>& state);
template <int Dim>
std::unique_ptr<Formulation<Dim>> make_semi_implicit_double_point(const scene::Scene& s, const State<Dim>& state);
template <int Dim>
std::unique_ptr<Formulation<Dim>> make_explicit_double_point(const scene::Scene& s, const State<Dim>& state);
template <int Dim>
std::unique_ptr<Formulation<Dim>> make_mpm_fem(const scene::Scene& s, const State<Dim>& state);

}  // namespace swmpm
