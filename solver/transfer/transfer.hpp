// Particle <-> grid transfers shared by every formulation (the "vocabulary" of the MPM step).
// Scatters go through StripeSchedule (race-free, thread-count independent); gathers are plain
// parallel loops over particles. Nothing here allocates per particle.
#pragma once

#include <algorithm>
#include <limits>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/particles/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"

namespace swmpm::transfer {

constexpr double empty_node_mass = 1e-14;  // kg; nodes lighter than this carry no velocity
constexpr long no_particle = std::numeric_limits<long>::max();

/// Evaluates every particle's shape data and returns the active node box (the nodes any particle
/// touches). Particles outside [grid.min, grid.max] or with non-finite positions are reported
/// through `bad` (smallest index) and get clamped shape data so the step can finish.
template <class Shape, int Dim>
NodeBox<Dim> evaluate_shapes(const Grid<Dim>& g, const ParticleSet<Dim>& ps,
                             std::vector<shape::ShapeData<Dim, Shape::support>>& sd, long& bad) {
  constexpr int S = Shape::support;
  const long n = static_cast<long>(ps.size());
  sd.resize(ps.size());
  std::array<int, Dim> lo, hi;
  lo.fill(std::numeric_limits<int>::max());
  hi.fill(std::numeric_limits<int>::min());
  const Vec<Dim> gmin = g.min(), gmax = g.max();
  long first_bad = no_particle;
#pragma omp parallel if (n > parallel_threshold)
  {
    std::array<int, Dim> tlo = lo, thi = hi;
    long tbad = no_particle;
#pragma omp for schedule(static) nowait
    for (long p = 0; p < n; ++p) {
      Vec<Dim> x = ps.x[p];
      const bool inside = ((x - gmin).array() >= 0.0).all() && ((gmax - x).array() >= 0.0).all();
      if (!inside) {  // includes NaN
        tbad = std::min(tbad, p);
        for (int a = 0; a < Dim; ++a) x[a] = std::isfinite(x[a]) ? std::clamp(x[a], gmin[a], gmax[a]) : gmin[a];
      }
      shape::evaluate<Shape>(g, x, ps.l[p], sd[p]);
      for (int a = 0; a < Dim; ++a) {
        tlo[a] = std::min(tlo[a], sd[p].base[a]);
        thi[a] = std::max(thi[a], sd[p].base[a] + S - 1);
      }
    }
#pragma omp critical
    {
      for (int a = 0; a < Dim; ++a) {
        lo[a] = std::min(lo[a], tlo[a]);
        hi[a] = std::max(hi[a], thi[a]);
      }
      first_bad = std::min(first_bad, tbad);
    }
  }
  bad = first_bad == no_particle ? -1 : first_bad;
  NodeBox<Dim> box;
  box.lo = lo;
  box.hi = hi;
  return box;
}

/// The axis with the most nodes: the stripes of the scatter schedule run across it.
template <int Dim>
int stripe_axis(const Grid<Dim>& g) {
  int best = 0;
  for (int a = 1; a < Dim; ++a)
    if (g.nodes_per_axis()[a] > g.nodes_per_axis()[best]) best = a;
  return best;
}

template <int Dim, int S>
void build_schedule(const Grid<Dim>& g, const std::vector<shape::ShapeData<Dim, S>>& sd,
                    StripeSchedule& schedule) {
  const int axis = stripe_axis(g);
  schedule.build(sd.size(), g.nodes_per_axis()[axis], S, [&](std::size_t p) { return sd[p].base[axis]; });
}

/// Zeroes the nodal fields in the box.
template <int Dim>
void clear_nodes(const Grid<Dim>& g, const NodeBox<Dim>& box, NodeFields<Dim>& nf) {
  g.for_each_node(box, [&](std::size_t i, const auto&) {
    nf.m[i] = 0.0;
    nf.mv[i].setZero();
    nf.f[i].setZero();
  });
}

/// P2G of mass, momentum and force:
///   m_i = sum_p N_ip m_p,  (mv)_i = sum_p N_ip m_p v_p,
///   f_i = sum_p [ -V_p sigma_p . grad N_ip + N_ip m_p b ]     (internal + body force)
template <int Dim, int S>
void scatter_mass_momentum_force(const Grid<Dim>& g, const StripeSchedule& schedule,
                                 const ParticleSet<Dim>& ps,
                                 const std::vector<shape::ShapeData<Dim, S>>& sd, const Vec<Dim>& b,
                                 NodeFields<Dim>& nf) {
  schedule.run([&](int p) {
    const double m_p = ps.m[p];
    const Vec<Dim> mv_p = m_p * ps.v[p];
    const Vec<Dim> mb_p = m_p * b;
    const Mat3 s = to_matrix(ps.sigma[p]);
    const MatD<Dim> Vs = ps.V[p] * s.template topLeftCorner<Dim, Dim>();
    shape::for_each_node(g, sd[p], [&](std::size_t i, double N, const Vec<Dim>& dN) {
      nf.m[i] += N * m_p;
      nf.mv[i] += N * mv_p;
      nf.f[i] += N * mb_p - Vs * dN;
    });
  });
}

/// G2P and MUSL remap in one pass over the particles (Sulsky et al. 1995):
///   v_p <- flip (v_p + sum_i N_ip (v_i - vL_i)) + (1 - flip) sum_i N_ip v_i      (FLIP/PIC blend)
///   x_p <- x_p + dt sum_i N_ip v_i
///   (mv)_i = sum_p N_ip m_p v_p,  v_i = (mv)_i / m_i                           (remap, then BCs)
/// Fusing is valid because the gather reads v_i, vL_i and the scatter writes only (mv)_i; running
/// it through the stripe schedule keeps the scatter race-free and its order fixed.
template <int Dim, int S>
void gather_velocity_position_remap(const Grid<Dim>& g, const StripeSchedule& schedule, const NodeBox<Dim>& box,
                                    const std::vector<shape::ShapeData<Dim, S>>& sd, double dt, double flip,
                                    ParticleSet<Dim>& ps, NodeFields<Dim>& nf) {
  g.for_each_node(box, [&](std::size_t i, const auto&) { nf.mv[i].setZero(); });
  schedule.run([&](int p) {
    Vec<Dim> v_new = Vec<Dim>::Zero(), dv = Vec<Dim>::Zero();
    shape::for_each_node(g, sd[p], [&](std::size_t i, double N, const Vec<Dim>&) {
      v_new += N * nf.v[i];
      dv += N * (nf.v[i] - nf.vL[i]);
    });
    const Vec<Dim> v_p = flip * (ps.v[p] + dv) + (1.0 - flip) * v_new;
    ps.v[p] = v_p;
    ps.x[p] += dt * v_new;
    const Vec<Dim> mv_p = ps.m[p] * v_p;
    shape::for_each_node(g, sd[p], [&](std::size_t i, double N, const Vec<Dim>&) { nf.mv[i] += N * mv_p; });
  });
  g.for_each_node(box, [&](std::size_t i, const auto&) {
    nf.v[i] = nf.m[i] > empty_node_mass ? Vec<Dim>(nf.mv[i] / nf.m[i]) : Vec<Dim>::Zero();
  });
}

/// Velocity gradient L_p = sum_i v_i (x) grad N_ip, then F_{n+1} = (I + dt L) F_n and V = det F V0.
/// Returns the smallest particle index with det F <= 0 or a non-finite L, or -1.
template <int Dim, int S>
long gather_velocity_gradient(const Grid<Dim>& g, const NodeFields<Dim>& nf,
                              const std::vector<shape::ShapeData<Dim, S>>& sd, double dt,
                              ParticleSet<Dim>& ps) {
  const long n = static_cast<long>(ps.size());
  long bad = no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
  for (long p = 0; p < n; ++p) {
    MatD<Dim> L = MatD<Dim>::Zero();
    shape::for_each_node(g, sd[p], [&](std::size_t i, double, const Vec<Dim>& dN) {
      L.noalias() += nf.v[i] * dN.transpose();
    });
    ps.L[p] = L;
    Mat3 dF = Mat3::Identity();
    dF.template topLeftCorner<Dim, Dim>() += dt * L;
    ps.F[p] = dF * ps.F[p];
    const double J = ps.F[p].determinant();
    ps.V[p] = J * ps.V0[p];
    if (!(J > 0.0) || !L.allFinite()) bad = std::min(bad, p);
  }
  return bad == no_particle ? -1 : bad;
}

}  // namespace swmpm::transfer
