// Nodal porosity and its interpolation to points, shared by every two-phase formulation.
//
//   mass-weighted   n_I = sum_p S_Ip m_p n_p / sum_p S_Ip m_p    (seed 001 eq. 46, seed 000 with the soil's mass)
//   volume-weighted n_I = sum_p S_Ip V_p n_p / sum_p S_Ip V_p    (seed 004 eq. 81: keeps grad n smooth)
// A node without soil takes `empty` (1 where the grid holds only water, seed 001 step 8h erratum).
#pragma once

#include <array>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/particles/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::porous {

/// n_I = sum S w n / sum S w at a node from its two sums; `empty` where the weight is (almost) zero.
inline double porosity_at_node(double wn, double w, double empty) {
  return w > transfer::empty_node_mass ? wn / w : empty;
}

enum class PorosityWeight { mass, volume };

/// Nodal porosity of a set of soil points: sums[i] = {sum S w n, sum S w} over the points through
/// the schedule, then sums[i][0] = n_I (porosity_at_node, `empty` where no soil) for the nodes of
/// the box. `sums` must be zero in the box on entry.
template <int Dim, int S, bool G>
void nodal_porosity(const Grid<Dim>& g, const NodeBox<Dim>& box, const StripeSchedule& schedule,
                    const std::vector<shape::ShapeData<Dim, S, G>>& sd, const ParticleSet<Dim>& ps,
                    PorosityWeight weight, double empty, NodeArray<std::array<double, 2>>& sums) {
  schedule.run([&](int p) {
    const double w = weight == PorosityWeight::mass ? ps.m[p] : ps.V[p], wn = w * ps.n[p];
    shape::for_each_node(g, sd[p], [&](std::size_t i, double N, const auto&) {
      sums[i][0] += N * wn;
      sums[i][1] += N * w;
    });
  }, sums);
  g.parallel_for_each_node(box, [&](std::size_t i, const auto&) {
    auto& s = sums[i];
    s[0] = porosity_at_node(s[0], s[1], empty);
  });
}

/// Porosity and its gradient at a point from nodal porosities (sums[i] = {n_I, weight} as
/// nodal_porosity leaves them): n = sum S n_I / sum S and grad n = sum grad S n_I over the nodes
/// that hold soil (the division restores the partition of unity where the point's support reaches
/// past the soil).
template <int Dim, int S>
struct PorosityAtPoint {
  double n;
  Vec<Dim> grad;
};
template <int Dim, int S>
PorosityAtPoint<Dim, S> porosity_at_point(const Grid<Dim>& g, const shape::ShapeData<Dim, S>& sd,
                                          const NodeArray<std::array<double, 2>>& sums) {
  double nh = 0.0, wsum = 0.0;
  Vec<Dim> grad = Vec<Dim>::Zero();
  shape::for_each_node(g, sd, [&](std::size_t i, double N, const Vec<Dim>& dN) {
    if (!(sums[i][1] > transfer::empty_node_mass)) return;
    nh += N * sums[i][0];
    grad += sums[i][0] * dN;
    wsum += N;
  });
  return {nh / wsum, grad};
}

}  // namespace swmpm::porous
