// The decomposition's calls in a formulation's step (solver/parallel/domain.hpp): one line each,
// so that a step reads the same at one rank, where they cost nothing.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "solver/formulation.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/grid/grid.hpp"
#include "solver/loads.hpp"
#include "solver/parallel/domain.hpp"
#include "solver/porous/tie.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::parallel {

constexpr long kRebalanceInterval = 100;  // steps between checks of the particle count per rank
constexpr double kRebalanceTolerance = 0.05;  // re-cut when the largest rank holds 5 % above the mean

/// The first node along `axis` of the shape functions at x (clamped into the grid).
template <class Shape, int Dim>
int first_node(const Grid<Dim>& g, const Vec<Dim>& x, const Vec<Dim>& l, int axis) {
  shape::ShapeData<Dim, Shape::support, false> sd;
  transfer::evaluate_point<Shape>(g, g.min(), g.max(), x, l, sd);
  return sd.base[axis];
}

/// The indices of `place` in increasing place (a schedule order from the places its particles had).
inline std::vector<int> order_by(const std::vector<std::int64_t>& place) {
  std::vector<int> order(place.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return place[static_cast<std::size_t>(a)] < place[static_cast<std::size_t>(b)]; });
  return order;
}

/// A run's start under mpirun: each rank holds a slice of the particles (a fresh run's, dealt out
/// by parallel::scatter_slices, or the pieces of a checkpoint it read: State::shares) and sends
/// every particle to its owner, each carrying its place in the schedule order; or every rank read
/// a whole checkpoint (one rank's) and keeps its own and the part of the order that indexes them.
/// The schedule then learns the exchange. With `water_schedule` (the
/// double-point formulations) the water points too (set 1 of the domain), the cuts balanced on
/// both sets' particles. Nothing at one rank.
template <class Shape, int Dim>
void distribute(Domain<Dim>& d, const Grid<Dim>& g, State<Dim>& st, StripeSchedule& schedule,
                StripeSchedule* water_schedule = nullptr) {
  if (ranks() == 1) return;
  const int axis = transfer::stripe_axis(g);
  std::vector<ParticleSet<Dim>*> sets{&st.solid};
  std::vector<StripeSchedule*> schedules{&schedule};
  if (water_schedule) sets.push_back(&st.fluid), schedules.push_back(water_schedule);
  std::vector<std::size_t> whole;
  for (const auto* ps : sets) whole.push_back(ps->size());
  // Shares (State::shares): each schedule order's place in the whole order (each rank's order
  // after those of the ranks before it, as the pieces were written) travels with its particle.
  std::vector<std::vector<std::int64_t>> place(sets.size());
  if (st.shares)
    for (std::size_t k = 0; k < sets.size(); ++k) {
      place[k].assign(sets[k]->size(), -1);
      const std::vector<long> counts = all_gather(static_cast<long>(sets[k]->size()));  // every rank calls it
      const StripeSchedule& sc = *schedules[k];
      if (!sc.built() || sc.order().size() != sets[k]->size()) continue;
      std::int64_t first = 0;
      for (int r = 0; r < rank(); ++r) first += counts[static_cast<std::size_t>(r)];
      for (std::size_t j = 0; j < sc.order().size(); ++j) place[k][static_cast<std::size_t>(sc.order()[j])] = first + static_cast<std::int64_t>(j);
    }
  d.distribute(
      g, Shape::support, axis, sets,
      [&](std::size_t k, std::size_t p) { return first_node<Shape>(g, sets[k]->x[p], sets[k]->l[p], axis); },
      st.shares ? &place : nullptr);
  for (std::size_t k = 0; k < sets.size(); ++k) {
    StripeSchedule& sc = *schedules[k];
    if (st.shares) {
      const auto placed = [](std::int64_t q) { return q >= 0; };
      if (any(std::any_of(place[k].begin(), place[k].end(), placed))) {
        if (!std::all_of(place[k].begin(), place[k].end(), placed))
          throw std::logic_error("distribute: a schedule order without some of its particles");
        sc.restore_order(order_by(place[k]));
      }
    } else if (sc.built() && sc.order().size() == whole[k]) {
      sc.restore_order(local_order(sc.order(), sets[k]->key));
    }
    sc.set_exchange(d.exchange());
  }
  st.shares = false;
  st.index_ids();
}

/// distribute() for a formulation that groups its particles by material (regrouped after).
template <class Shape, int Dim>
void distribute(Domain<Dim>& d, const Grid<Dim>& g, State<Dim>& st, StripeSchedule& schedule,
                std::vector<std::vector<int>>& material_particles) {
  distribute<Shape>(d, g, st, schedule);
  regroup_by_material(st.solid, material_particles);
}

/// porous::coincident_points over the whole run: under mpirun each rank holds a share of the
/// points (its slice before distribute, its own after), so rank 0 builds the table from the
/// gathered sets and sends it to every rank (the same table on every rank, as one rank builds it).
/// Collective then.
template <int Dim>
std::vector<std::int64_t> coincident_points(const Domain<Dim>& d, const ParticleSet<Dim>& soil,
                                            const ParticleSet<Dim>& water) {
  if (!d.active()) return porous::coincident_points(soil, water);
  const ParticleSet<Dim> whole_soil = gather_set(soil), whole_water = gather_set(water);
  return broadcast(rank() == 0 ? porous::coincident_points(whole_soil, whole_water) : std::vector<std::int64_t>{});
}

/// The decomposition's counters (Domain::add_counters) as a formulation reports them.
template <class Counter, int Dim>
std::vector<Counter> counters(const Domain<Dim>& d) {
  std::vector<Counter> c;
  d.add_counters(c);
  return c;
}

/// One particle set of a step under mpirun (set k of the Domain, k its place in the argument
/// list): its schedule, its shape data, its node box and its first bad particle as
/// evaluate_shapes left them.
template <int Dim, class ShapeData>
struct StepSet {
  ParticleSet<Dim>& ps;
  StripeSchedule& schedule;
  std::vector<ShapeData>& sd;
  NodeBox<Dim>& box;
  long& bad;
};
template <int Dim, class ShapeData>
StepSet(ParticleSet<Dim>&, StripeSchedule&, std::vector<ShapeData>&, NodeBox<Dim>&, long&) -> StepSet<Dim, ShapeData>;

/// Step (1) under mpirun, after the shapes of every set are evaluated: every kRebalanceInterval
/// steps the cuts move to even out the particle counts (of all sets together); particles whose
/// stripe another rank owns move there (their set's shapes, box and `bad` are evaluated again).
/// Returns, per set, whether this rank's particles changed (the caller regroups what indexes them
/// and takes the node box). Collective.
template <class Shape, int Dim, class... ShapeData>
std::array<bool, sizeof...(ShapeData)> migrate_sets(Domain<Dim>& d, const Grid<Dim>& g, long step,
                                                    const StepSet<Dim, ShapeData>&... sets) {
  std::array<bool, sizeof...(ShapeData)> changed{};
  if (!d.active()) return changed;
  const int axis = d.axis();
  if (step % kRebalanceInterval == 0 && step > 0) {
    std::vector<long> per_stripe(static_cast<std::size_t>(d.stripes()), 0);
    auto count = [&](const auto& set) {
      for (std::size_t p = 0; p < set.ps.size(); ++p)
        ++per_stripe[static_cast<std::size_t>(std::min(d.stripes() - 1, set.sd[p].base[axis] / d.width()))];
    };
    (count(sets), ...);
    if (d.rebalance(per_stripe, kRebalanceTolerance)) (sets.schedule.set_exchange(d.exchange()), ...);
  }
  std::size_t k = 0;
  auto migrate = [&](const auto& set) {
    changed[k] = d.migrate(k, set.ps, [&](std::size_t p) { return set.sd[p].base[axis]; });
    if (changed[k]) set.box = transfer::evaluate_shapes<Shape>(g, set.ps, set.sd, set.bad);
    ++k;
  };
  (migrate(sets), ...);
  return changed;
}

/// migrate_sets of the double-point formulations' two sets (the soil points set 0, the water
/// points set 1); the id table and the soil's material groups follow its points. Collective.
template <class Shape, int Dim, class SoilShapes, class WaterShapes>
void own_both_sets(Domain<Dim>& d, const Grid<Dim>& g, State<Dim>& st, std::vector<std::vector<int>>& material_particles,
                   const StepSet<Dim, SoilShapes>& soil, const StepSet<Dim, WaterShapes>& water) {
  if (migrate_sets<Shape>(d, g, st.step, soil, water)[0]) {
    st.index_ids();
    regroup_by_material(st.solid, material_particles);
  }
}

/// migrate_sets for the soil points alone (the single-point formulations and dry), then the
/// rank's node box. Returns whether this rank's particles changed.
template <class Shape, int Dim, class ShapeData>
bool own_particles(Domain<Dim>& d, const Grid<Dim>& g, State<Dim>& st, StripeSchedule& schedule,
                   std::vector<ShapeData>& sd, NodeBox<Dim>& box, long& bad) {
  if (!d.active()) return false;
  const bool changed = migrate_sets<Shape>(d, g, st.step, StepSet{st.solid, schedule, sd, box, bad})[0];
  if (changed) st.index_ids();
  box = d.node_box(box);
  return changed;
}

/// Loads on particles under mpirun, step (1): the face forces of every rank (collect_face_forces
/// gives a rank those of its own particles), on every rank in the one-rank order (ordinal), with
/// their shape data; the node box grows on the other axes to hold all their nodes, as the one-rank
/// box does, and keeps the rank's columns along the cut axis. Collective; nothing at one rank.
template <class Shape, int Dim, int S>
void share_face_forces(const Domain<Dim>& d, const Grid<Dim>& g, std::vector<FaceForce<Dim, S>>& ffs,
                       NodeBox<Dim>& box) {
  if (!d.active() || !any(!ffs.empty())) return;
  struct Record {
    std::int64_t ordinal;
    double f[3], x[3], n;
    std::int64_t split;
  };
  std::vector<char> mine(ffs.size() * sizeof(Record));
  std::vector<std::pair<std::int64_t, int>> own;  // ordinal -> this rank's particle
  for (std::size_t k = 0; k < ffs.size(); ++k) {
    Record r{ffs[k].ordinal, {0, 0, 0}, {0, 0, 0}, ffs[k].n, ffs[k].split ? 1 : 0};
    for (int a = 0; a < Dim; ++a) r.f[a] = ffs[k].f[a], r.x[a] = ffs[k].x[a];
    std::memcpy(mine.data() + k * sizeof r, &r, sizeof r);
    own.emplace_back(ffs[k].ordinal, ffs[k].p);
  }
  std::vector<Record> all;
  for (const auto& part : all_gather(mine))
    for (std::size_t k = 0; k < part.size() / sizeof(Record); ++k) {
      Record r;
      std::memcpy(&r, part.data() + k * sizeof r, sizeof r);
      all.push_back(r);
    }
  std::sort(all.begin(), all.end(), [](const Record& a, const Record& b) { return a.ordinal < b.ordinal; });
  ffs.clear();
  for (const Record& r : all) {
    FaceForce<Dim, S> ff{{}, Vec<Dim>::Zero(), -1, r.split != 0};
    for (int a = 0; a < Dim; ++a) ff.f[a] = r.f[a], ff.x[a] = r.x[a];
    ff.n = r.n;
    ff.ordinal = r.ordinal;
    const auto it = std::lower_bound(own.begin(), own.end(), std::make_pair(r.ordinal, -1));
    if (it != own.end() && it->first == r.ordinal) ff.p = it->second;
    shape::evaluate<Shape>(g, ff.x, Vec<Dim>::Zero().eval(), ff.sd);
    for (int a = 0; a < Dim; ++a) {
      box.lo[a] = std::min(box.lo[a], ff.sd.base[a]);
      box.hi[a] = std::max(box.hi[a], ff.sd.base[a] + S - 1);
    }
    ffs.push_back(ff);
  }
  std::tie(box.lo[d.axis()], box.hi[d.axis()]) = d.box_columns();
}

/// Step (3) under mpirun: the weights of the face forces' nodes (weigh_face_forces). The rank that
/// owns a face point's first node column holds all of its nodes (its box reaches S - 1 columns
/// past its own) with their finished masses: it weighs the face force, and a sum over the ranks
/// gives every rank its scale. At one rank, weigh_face_forces.
template <int Dim, int S, class HasMass>
void weigh_face_forces(const Domain<Dim>& d, const Grid<Dim>& g, std::vector<FaceForce<Dim, S>>& ffs,
                       HasMass&& has_mass) {
  if (!d.active()) return swmpm::weigh_face_forces(g, ffs, has_mass);
  if (ffs.empty()) return;  // every rank holds the same list (share_face_forces)
  std::vector<double> scale(ffs.size(), 0.0);
  for (std::size_t k = 0; k < ffs.size(); ++k)
    if (d.owner(d.stripe_of_node(ffs[k].sd.base[d.axis()])) == rank()) scale[k] = face_force_scale(g, ffs[k], has_mass);
  sum(std::span<double>(scale));
  for (std::size_t k = 0; k < ffs.size(); ++k) ffs[k].scale = scale[k];
}

}  // namespace swmpm::parallel
