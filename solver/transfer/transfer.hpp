// Particle <-> grid transfers shared by every formulation (the "vocabulary" of the MPM step).
// Scatters (and the G2P fused with the MUSL scatter) go through StripeSchedule (race-free,
// thread-count independent); pure gathers are parallel loops over particles. Kernels use the
// row-factored visitor shape::for_each_row. Nothing here allocates per particle.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/particles/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"

namespace swmpm::transfer {

constexpr double empty_node_mass = 1e-14;  // kg; nodes lighter than this carry no velocity
constexpr long no_particle = std::numeric_limits<long>::max();

/// One point's shape data at x with half-sizes l: a point outside [gmin, gmax] (the grid) or with
/// a non-finite coordinate gets the shape data of x clamped to the grid (a non-finite coordinate
/// to gmin, as CellMoments::add takes it), and false.
template <class Shape, int Dim, bool kGradients>
[[gnu::always_inline]] inline bool evaluate_point(const Grid<Dim>& g, const Vec<Dim>& gmin, const Vec<Dim>& gmax,
                                                  const Vec<Dim>& x, const Vec<Dim>& l,
                                                  shape::ShapeData<Dim, Shape::support, kGradients>& sd) {
  bool inside = true;
#pragma GCC unroll 3
  for (int a = 0; a < Dim; ++a) inside &= x[a] >= gmin[a] && x[a] <= gmax[a];  // false for NaN
  if (inside) [[likely]] {
    shape::evaluate<Shape>(g, x, l, sd);
    return true;
  }
  Vec<Dim> xc;
  for (int a = 0; a < Dim; ++a) xc[a] = std::isfinite(x[a]) ? std::clamp(x[a], gmin[a], gmax[a]) : gmin[a];
  shape::evaluate<Shape>(g, xc, l, sd);
  return false;
}

#if defined(__SSE2__)
/// evaluate_shapes for quadratic B-splines in 2D: both axes of a point at once
/// (shape::BSpline2Pairs), the same data bit for bit; the cells' range as doubles, one packed min
/// and max per point. Points next to a clamped end or outside the grid take evaluate_point.
template <bool kGradients>
NodeBox<2> evaluate_bspline2_pairs(const Grid<2>& g, const ParticleSet<2>& ps,
                                   std::vector<shape::ShapeData<2, 3, kGradients>>& sd, long& bad) {
  const long n = static_cast<long>(ps.size());
  sd.resize(ps.size());
  NodeBox<2> box;
  box.lo.fill(std::numeric_limits<int>::max());
  box.hi.fill(std::numeric_limits<int>::min());
  const Vec<2> gmin = g.min(), gmax = g.max();
  const shape::BSpline2Pairs pairs(g);
  long first_bad = no_particle;
#pragma omp parallel if (n > parallel_threshold)
  {
    __m128d clo = _mm_set1_pd(std::numeric_limits<double>::infinity()), chi = -clo;
    long tbad = no_particle;
#pragma omp for schedule(static) nowait
    for (long p = 0; p < n; ++p) {
      __m128d c;
      if (!pairs(ps.x[p].data(), sd[p], c)) [[unlikely]] {
        if (!evaluate_point<shape::BSpline<2>>(g, gmin, gmax, ps.x[p], ps.l[p], sd[p])) tbad = std::min(tbad, p);
        c = _mm_set_pd(sd[p].base[1], sd[p].base[0]);
      }
      clo = _mm_min_pd(clo, c);
      chi = _mm_max_pd(chi, c);
    }
#pragma omp critical
    {
      if (_mm_movemask_pd(_mm_cmple_pd(clo, chi)) == 3)  // this thread had points
        for (int a = 0; a < 2; ++a) {
          box.lo[a] = std::min(box.lo[a], static_cast<int>(clo[a]));
          box.hi[a] = std::max(box.hi[a], static_cast<int>(chi[a]) + 2);
        }
      first_bad = std::min(first_bad, tbad);
    }
  }
  bad = first_bad == no_particle ? -1 : first_bad;
  return box;
}
#endif

/// The FLIP/PIC blend of a point's velocity (Brackbill's FLIP with a PIC share, every
/// formulation): v_p <- flip (v_p + v - vL) + (1 - flip) v, with v and vL the end- and
/// start-of-step nodal velocities interpolated at the point.
template <class V>
[[gnu::always_inline]] inline V flip_pic(const V& v_p, const V& v, const V& vL, double flip) {
  return flip * (v_p + v - vL) + (1.0 - flip) * v;
}

/// Evaluates every particle's shape data and returns the active node box (the nodes any particle
/// touches). Particles outside [grid.min, grid.max] or with non-finite positions are reported
/// through `bad` (smallest index) and get clamped shape data so the step can finish.
/// Weights-only shape data (kGradients = false) get the weights only.
template <class Shape, int Dim, bool kGradients>
NodeBox<Dim> evaluate_shapes(const Grid<Dim>& g, const ParticleSet<Dim>& ps,
                             std::vector<shape::ShapeData<Dim, Shape::support, kGradients>>& sd, long& bad) {
#if defined(__SSE2__)
  if constexpr (Dim == 2 && std::is_same_v<Shape, shape::BSpline<2>>) return evaluate_bspline2_pairs(g, ps, sd, bad);
#endif
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
      if (!evaluate_point<Shape>(g, gmin, gmax, ps.x[p], ps.l[p], sd[p])) [[unlikely]]
        tbad = std::min(tbad, p);
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

template <int Dim, int S, bool G>
void build_schedule(const Grid<Dim>& g, const std::vector<shape::ShapeData<Dim, S, G>>& sd,
                    StripeSchedule& schedule) {
  const int axis = stripe_axis(g);
  schedule.build(sd.size(), g.nodes_per_axis()[axis], S, [&](std::size_t p) { return sd[p].base[axis]; });
}

/// Zeroes the nodal fields in the box.
template <int Dim>
void clear_nodes(const Grid<Dim>& g, const NodeBox<Dim>& box, NodeFields<Dim>& nf) {
  g.for_each_node(box, [&](std::size_t i, const auto&) {
    auto& a = nf.acc[i];
    a.m = 0.0;
    a.mv.setZero();
    a.f.setZero();
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
    const auto& sp = sd[p];
    const double m_p = ps.m[p];
    const Vec<Dim> mv_p = m_p * ps.v[p];
    const Vec<Dim> mb_p = m_p * b;
    const Mat3 s = to_matrix(ps.sigma[p]);
    const MatD<Dim> Vs = ps.V[p] * s.template topLeftCorner<Dim, Dim>();
    // Per row: f_i = wx[a] (w_r m_p b - Vs[:, 1:] g_r) + dwx[a] (-w_r Vs[:, 0])   (= N m_p b - Vs grad N)
    shape::for_each_row(g, sp, [&](std::size_t row, double w_r, const Vec<Dim - 1>& g_r) {
      const double m_r = w_r * m_p;
      const Vec<Dim> mv_r = w_r * mv_p;
      const Vec<Dim> f_w = w_r * mb_p - Vs.template rightCols<Dim - 1>() * g_r;
      const Vec<Dim> f_dw = -w_r * Vs.col(0);
      for (int a = 0; a < S; ++a) {
        auto& nd = nf.acc[row + a];
        const double wx = sp.w[0][a], dwx = sp.dw[0][a];
        nd.m += wx * m_r;
        nd.mv += wx * mv_r;
        nd.f += wx * f_w + dwx * f_dw;
      }
    });
  }, nf.acc);
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
  g.for_each_node(box, [&](std::size_t i, const auto&) { nf.acc[i].mv.setZero(); });
  schedule.run([&](int p) {
    const auto& sp = sd[p];
    Vec<Dim> v_new = Vec<Dim>::Zero(), v_old = Vec<Dim>::Zero();
    shape::for_each_row(g, sp, [&](std::size_t row, double w_r, const Vec<Dim - 1>&) {
      Vec<Dim> sv = Vec<Dim>::Zero(), svL = Vec<Dim>::Zero();
      for (int a = 0; a < S; ++a) {
        sv += sp.w[0][a] * nf.v[row + a];
        svL += sp.w[0][a] * nf.vL[row + a];
      }
      v_new += w_r * sv;
      v_old += w_r * svL;
    });
    const Vec<Dim> v_p = flip_pic(ps.v[p], v_new, v_old, flip);
    ps.v[p] = v_p;
    ps.x[p] += dt * v_new;
    const Vec<Dim> mv_p = ps.m[p] * v_p;
    shape::for_each_row(g, sp, [&](std::size_t row, double w_r, const Vec<Dim - 1>&) {
      const Vec<Dim> mv_r = w_r * mv_p;
      for (int a = 0; a < S; ++a) nf.acc[row + a].mv += sp.w[0][a] * mv_r;
    });
  }, nf.acc);
  g.for_each_node(box, [&](std::size_t i, const auto&) {
    const auto& a = nf.acc[i];
    nf.v[i] = a.m > empty_node_mass ? Vec<Dim>(a.mv / a.m) : Vec<Dim>::Zero();
  });
}

/// Increment of the deformation gradient over a step with constant L (F_{n+1} = dF F_n), by the
/// midpoint (Hughes–Winget) rule dF = (I - dt L / 2)^-1 (I + dt L / 2): second order, and exactly
/// orthogonal for a pure spin, so a rigid rotation leaves J = 1 and a hyperelastic model stress
/// free (forward Euler, I + dt L, grows det F by (dt w)^2 per step).
template <int Dim>
inline MatD<Dim> deformation_increment(const MatD<Dim>& L, double dt) {
  const MatD<Dim> half = 0.5 * dt * L;
  return (MatD<Dim>::Identity() - half).inverse() * (MatD<Dim>::Identity() + half);
}

/// F <- [d 0; 0 1] F in place (plane strain and 3D: the first Dim rows change), entry by entry:
/// the Eigen product into a 3x3 temporary, copied back in 16-byte packets, stalled on
/// store-to-load forwarding (perf, semi-implicit update_soil: a fifth of the loop). Same sums, same
/// order as the product (a zero term adds nothing), so the result is bitwise the same.
template <int Dim>
inline void apply_increment(const MatD<Dim>& d, Mat3& F) {
  for (int c = 0; c < 3; ++c) {
    double row[Dim];
    for (int a = 0; a < Dim; ++a) {
      double sum = 0.0;
      for (int b = 0; b < Dim; ++b) sum += d(a, b) * F(b, c);
      row[a] = sum;
    }
    for (int a = 0; a < Dim; ++a) F(a, c) = row[a];
  }
}

/// det of deformation_increment(L, dt) without forming it: det(I + dt L/2) / det(I - dt L/2).
template <int Dim>
inline double deformation_jacobian(const MatD<Dim>& L, double dt) {
  const MatD<Dim> half = 0.5 * dt * L;
  return (MatD<Dim>::Identity() + half).determinant() / (MatD<Dim>::Identity() - half).determinant();
}

/// Velocity gradient L_p = sum_i v_i (x) grad N_ip, then F_{n+1} = dF F_n (deformation_increment) and V = det F V0.
/// Returns the smallest particle index with det F <= 0 or a non-finite L, or -1.
template <int Dim, int S>
long gather_velocity_gradient(const Grid<Dim>& g, const NodeFields<Dim>& nf,
                              const std::vector<shape::ShapeData<Dim, S>>& sd, double dt,
                              ParticleSet<Dim>& ps) {
  const long n = static_cast<long>(ps.size());
  long bad = no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
  for (long p = 0; p < n; ++p) {
    // L = sum_i v_i grad N_i^T; per row: column 0 gets w_r sum_a dwx[a] v_i, the others g_r sum_a wx[a] v_i.
    const auto& sp = sd[p];
    MatD<Dim> L = MatD<Dim>::Zero();
    shape::for_each_row(g, sp, [&](std::size_t row, double w_r, const Vec<Dim - 1>& g_r) {
      Vec<Dim> sdx = Vec<Dim>::Zero(), sw = Vec<Dim>::Zero();
      for (int a = 0; a < S; ++a) {
        sdx += sp.dw[0][a] * nf.v[row + a];
        sw += sp.w[0][a] * nf.v[row + a];
      }
      L.col(0) += w_r * sdx;
      L.template rightCols<Dim - 1>() += sw * g_r.transpose();
    });
    ps.L[p] = L;
    Mat3& F = ps.F[p];
    double J;
    const MatD<Dim> dF = deformation_increment<Dim>(L, dt);
    if constexpr (Dim == 2) {
      // Plane strain: F = [[F2, 0], [0, 1]] stays block diagonal, so only the 2x2 block moves.
      const MatD<2> F2 = dF * F.template topLeftCorner<2, 2>();
      F.template topLeftCorner<2, 2>() = F2;
      J = F2.determinant() * F(2, 2);
    } else {
      F = dF * F;
      J = F.determinant();
    }
    ps.V[p] = J * ps.V0[p];
    if (!(J > 0.0) || !L.allFinite()) bad = std::min(bad, p);
  }
  return bad == no_particle ? -1 : bad;
}

}  // namespace swmpm::transfer
