// The decomposition's calls in a formulation's step (solver/parallel/domain.hpp): one line each,
// so that a step reads the same at one rank, where they cost nothing.
#pragma once

#include <vector>

#include "solver/formulation.hpp"
#include "solver/grid/grid.hpp"
#include "solver/parallel/domain.hpp"
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

/// A run's start under mpirun: every rank read all particles (a fresh run's, or a checkpoint's
/// with the schedule order restored for the whole set); each keeps its own and the part of the
/// order that indexes them, and the schedule learns the exchange. Nothing at one rank.
template <class Shape, int Dim>
void distribute(Domain<Dim>& d, const Grid<Dim>& g, State<Dim>& st, StripeSchedule& schedule) {
  if (ranks() == 1) return;
  const int axis = transfer::stripe_axis(g);
  const std::size_t whole = st.solid.size();
  d.distribute(g, Shape::support, axis, {&st.solid}, [&](std::size_t, std::size_t p) {
    return first_node<Shape>(g, st.solid.x[p], st.solid.l[p], axis);
  });
  if (schedule.built() && schedule.order().size() == whole) schedule.restore_order(local_order(schedule.order(), st.solid.key));
  schedule.set_exchange(d.exchange());
  st.index_ids();
}

/// Step (1) under mpirun, after the shapes are evaluated: every kRebalanceInterval steps the cuts
/// move to even out the particle counts; particles whose stripe another rank owns move there
/// (their shapes, the box and `bad` are evaluated again); then the rank's node box. Returns
/// whether this rank's particles changed (the caller regroups what indexes them).
template <class Shape, int Dim, int S>
bool own_particles(Domain<Dim>& d, const Grid<Dim>& g, State<Dim>& st, StripeSchedule& schedule,
                   std::vector<shape::ShapeData<Dim, S>>& sd, NodeBox<Dim>& box, long& bad) {
  if (!d.active()) return false;
  ParticleSet<Dim>& ps = st.solid;
  const int axis = d.axis();
  if (st.step % kRebalanceInterval == 0 && st.step > 0) {
    std::vector<long> per_stripe(static_cast<std::size_t>(d.stripes()), 0);
    for (std::size_t p = 0; p < ps.size(); ++p) ++per_stripe[static_cast<std::size_t>(std::min(d.stripes() - 1, sd[p].base[axis] / d.width()))];
    if (d.rebalance(per_stripe, kRebalanceTolerance)) schedule.set_exchange(d.exchange());
  }
  const bool changed = d.migrate(0, ps, [&](std::size_t p) { return sd[p].base[axis]; });
  if (changed) {
    st.index_ids();
    box = transfer::evaluate_shapes<Shape>(g, ps, sd, bad);
  }
  box = d.node_box(box);
  return changed;
}

}  // namespace swmpm::parallel
