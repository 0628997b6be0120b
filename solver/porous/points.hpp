// Per-set G2P of the two-phase formulations and the soil skeleton's update, shared by every
// two-phase formulation (the dry formulation's row-factored fast path is transfer/transfer.hpp's
// gather_velocity_position_remap, with the same FLIP/PIC blend, transfer::flip_pic).
//
// Every kernel takes one particle set and the node fields of its phase(s); scatters run through
// the set's StripeSchedule (race-free, the same order for any --threads).
#pragma once

#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/particles/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::porous {

/// G2P of points that carry the soil skeleton (and, kPoreWater, their pore water: single-point),
/// then the MUSL remap (seed 001 step 8a, seed 000 sub-step 5):
///   v_p <- flip_pic(v_p, sum S v_I, sum S vL_I)  (soil; kPoreWater also v_f from the water nodes)
///   x_p <- x_p + dt sum S v_sI                    (the points move with the soil)
///   (M v)_I = sum S m v_p,  v_I = (M v)_I / M_I    (soil; kRemapWater: also the water, with m_f v_f)
/// The velocity boundary conditions of the remapped field are the caller's.
template <bool kPoreWater, bool kRemapWater, int Dim, int S, bool G>
void gather_soil_points(const Grid<Dim>& g, const NodeBox<Dim>& box, const StripeSchedule& schedule,
                        const std::vector<shape::ShapeData<Dim, S, G>>& sd, double flip, double dt,
                        ParticleSet<Dim>& ps, NodeFields<Dim>& soil, NodeFields<Dim>& water) {
  static_assert(kPoreWater || !kRemapWater);
  g.parallel_for_each_node(box, [&](std::size_t i, const auto&) {
    soil.acc[i].mv.setZero();
    if constexpr (kRemapWater) water.acc[i].mv.setZero();
  });
  auto remap = [&](int p) __attribute__((always_inline)) {
    Vec<Dim> vs = Vec<Dim>::Zero(), vs_old = Vec<Dim>::Zero(), vw = Vec<Dim>::Zero(), vw_old = Vec<Dim>::Zero();
    shape::for_each_node(g, sd[p], [&](std::size_t i, double N, const auto&) {
      vs += N * soil.v[i];
      vs_old += N * soil.vL[i];
      if constexpr (kPoreWater) {
        vw += N * water.v[i];
        vw_old += N * water.vL[i];
      }
    });
    ps.v[p] = transfer::flip_pic(ps.v[p], vs, vs_old, flip);
    if constexpr (kPoreWater) ps.v_f[p] = transfer::flip_pic(ps.v_f[p], vw, vw_old, flip);
    ps.x[p] += dt * vs;
    const Vec<Dim> mv = ps.m[p] * ps.v[p];
    if constexpr (kRemapWater) {
      const Vec<Dim> mvw = ps.m_f[p] * ps.v_f[p];
      shape::for_each_node(g, sd[p], [&](std::size_t i, double N, const auto&) {
        soil.acc[i].mv += N * mv;
        water.acc[i].mv += N * mvw;
      });
    } else {
      shape::for_each_node(g, sd[p], [&](std::size_t i, double N, const auto&) { soil.acc[i].mv += N * mv; });
    }
  };
  // Under mpirun the remapped momenta are exchanged at the cuts (StripeSchedule::run).
  if constexpr (kRemapWater) schedule.run(remap, soil.acc, water.acc);
  else schedule.run(remap, soil.acc);
  auto remapped = [](const typename NodeFields<Dim>::Accum& a) {
    return a.m > transfer::empty_node_mass ? Vec<Dim>(a.mv / a.m) : Vec<Dim>::Zero();
  };
  g.parallel_for_each_node(box, [&](std::size_t i, const auto&) {
    soil.v[i] = remapped(soil.acc[i]);
    if constexpr (kRemapWater) water.v[i] = remapped(water.acc[i]);
  });
}

/// G2P of points that move with their own phase's velocity and are not remapped (double-point
/// water points, seed 001 step 7): v_p <- flip_pic(v_p, sum S v_I, sum S vL_I), x_p += dt sum S v_I.
template <int Dim, int S, bool G>
void gather_free_points(const Grid<Dim>& g, const std::vector<shape::ShapeData<Dim, S, G>>& sd, double flip,
                        double dt, ParticleSet<Dim>& ps, const NodeFields<Dim>& nodes) {
  const long n = static_cast<long>(ps.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
  for (long p = 0; p < n; ++p) {
    Vec<Dim> v = Vec<Dim>::Zero(), v_old = Vec<Dim>::Zero();
    shape::for_each_node(g, sd[p], [&](std::size_t i, double N, const auto&) {
      v += N * nodes.v[i];
      v_old += N * nodes.vL[i];
    });
    ps.v[p] = transfer::flip_pic(ps.v[p], v, v_old, flip);
    ps.x[p] += dt * v;
  }
}

/// The soil skeleton of one point over a step with velocity gradient L (seed 000 sub-step 8, seed
/// 001 steps 8c-8f): F_{n+1} = dF F_n (transfer::deformation_increment), V = det F V0, and the
/// porosity from the solid's mass balance with incompressible grains, (1 - n) V = const.
/// Returns J = det F.
template <int Dim>
inline double update_skeleton(const MatD<Dim>& L, double dt, Mat3& F, double& V, double V0, double& n) {
  transfer::apply_increment<Dim>(transfer::deformation_increment<Dim>(L, dt), F);  // F_{n+1} = dF F_n
  const double V_old = V;
  const double J = F.determinant();
  V = J * V0;
  n = 1.0 - (1.0 - n) * V_old / V;
  return J;
}

}  // namespace swmpm::porous
