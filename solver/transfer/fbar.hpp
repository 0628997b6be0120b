// F-bar stabilisation of volumetric locking (seed 001, Xie, Navas & López-Querol 2025, §4.4.2,
// eqs. 78-83; algorithm step (9)(b)-(g)), one stage shared by every formulation
// (`solver.stabilisation.fbar`). It runs after the velocity gradient and the F update of a step and
// before the stress update; docs/formulations.md, "F-bar", derives every line.
//
// On entry:  ps.L = L (this step's velocity gradient), ps.F = F_{n+1} = ΔF F_n with
//            ΔF = transfer::deformation_increment(L, dt), ps.V = det F_{n+1} V0, σ_n in ps.sigma.
// standard:  ΔJ = det ΔF                                                        (step 9(c))
//            ΔJ̄_p = Σ_I N_Ip (Σ_q N_Iq m_q ΔJ_q) / m_I                         (eq. 80)
//            ΔF̄ = (ΔJ̄/ΔJ)^{1/dim} ΔF, dim = 2 in plane strain (F_zz = 1 kept)  (eq. 79, step 9(d))
//            ps.F = F̄_{n+1} = ΔF̄ F_n,  ps.V = det F̄_{n+1} V0,
//            ps.L = L̄ = (2/dt)(ΔF̄ − I)(ΔF̄ + I)⁻¹, the rate whose midpoint increment
//            deformation_increment(L̄, dt) is exactly ΔF̄ (the materials rebuild ΔF from L, and the
//            hypoelastic ones integrate L̄: all of them see the stabilised increment);
//            two-phase points: porosity from (1 − n) V = const and m_f ∝ n V follow V̄.
// modified:  also ε_v^e = ln J^e of b_e,n reported by each material (step 9(e)),
//            J̄^e = Σ_patch m J^e / Σ_patch m over a fixed lattice of patches (eq. 83, step 9(f)),
//            ps.ev_shift = ln(J̄^e / J^e), which the materials apply as b̄_e,n = (J̄^e/J^e)^{2/3} b_e,n
//            (eq. 82, step 9(g)) when they rebuild b_e,n in update_stress.
//
// Patches: squares (cubes) of side h_patch = fbar_patch × h on a lattice anchored at grid.min,
// fixed for the whole run (the last patch of an axis may be cut by the grid's end); a particle
// belongs to the patch holding its current position (x_{n+1}: the stage runs after G2P).
//
// Under mpirun the nodal sums go through the schedule's exchange like any scatter. A patch of
// `modified` may hold particles of several ranks near a cut, and one rank sums it in storage
// order: each rank sums the patches only its particles can reach as one rank does, and the
// patches within reach of a cut (boundary_patches) from every rank's records of them, added in
// key order (the one-rank storage order): the one-rank sums bit for bit.
//
// Determinism: the nodal sums go through the formulation's StripeSchedule, the
// patch sums through a second StripeSchedule of width 1 keyed by the row of patches (one row = one
// "stripe": each patch is summed by one thread in increasing particle index); everything else writes per
// particle. Results are bitwise identical for any thread count. No allocation after the first step.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <vector>

#include "scene/scene.hpp"
#include "solver/formulation.hpp"
#include "solver/grid/grid.hpp"
#include "solver/materials/material.hpp"
#include "solver/parallel/domain.hpp"
#include "solver/particles/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {

namespace fbar {

/// The rate whose midpoint increment is dF: L = (2/dt)(dF − I)(dF + I)⁻¹, the inverse of
/// transfer::deformation_increment (with A = dt L / 2, dF = (I − A)⁻¹(I + A) gives dF − I =
/// 2 (I − A)⁻¹ A and dF + I = 2 (I − A)⁻¹, and A commutes with (I − A)).
template <int Dim>
inline MatD<Dim> rate_of_increment(const MatD<Dim>& dF, double dt) {
  const MatD<Dim> I = MatD<Dim>::Identity();
  return (2.0 / dt) * (dF - I) * (dF + I).inverse();
}

/// rate_of_increment(c ΔF(L), dt) with one inverse: with A = dt L / 2 and ΔF = (I − A)⁻¹(I + A),
/// c ΔF ∓ I = (I − A)⁻¹ [(c ∓ 1) I + (c ± 1) A], and polynomials in A commute, so
/// L̄ = (2/dt) [(c − 1) I + (c + 1) A] [(c + 1) I + (c − 1) A]⁻¹ (= L for c = 1).
template <int Dim>
inline MatD<Dim> scaled_rate(const MatD<Dim>& L, double c, double dt) {
  const MatD<Dim> A = 0.5 * dt * L, I = MatD<Dim>::Identity();
  return (2.0 / dt) * ((c - 1.0) * I + (c + 1.0) * A) * ((c + 1.0) * I + (c - 1.0) * A).inverse();
}

/// (ΔJ̄ / ΔJ)^{1/dim} of eq. 79 (dim = Dim: 2 in plane strain, where only the in-plane block
/// scales); NaN unless both are positive.
template <int Dim>
inline double scale(double dJ, double dJbar) {
  if (!(dJ > 0.0 && dJbar > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return Dim == 2 ? std::sqrt(dJbar / dJ) : std::cbrt(dJbar / dJ);
}

}  // namespace fbar

enum class FBarMode { none, standard, modified };

template <int Dim, int S>
class FBar {
 public:
  FBar(const scene::Scene& s, const Grid<Dim>& g) {
    const std::string& m = s.solver.stabilisation.fbar;
    if (m == "none") mode_ = FBarMode::none;
    else if (m == "standard") mode_ = FBarMode::standard;
    else if (m == "modified") mode_ = FBarMode::modified;
    else throw std::runtime_error("solver.stabilisation.fbar: \"" + m + "\" is not one of none, standard, modified");
    const double ratio = s.solver.stabilisation.fbar_patch > 0.0 ? s.solver.stabilisation.fbar_patch
                                                                 : scene::default_fbar_patch(s.grid.shape_function);
    h_patch_ = ratio * g.h();
    h_ = g.h();
    patches_ = 1;
    for (int a = 0; a < Dim; ++a) {
      origin_[a] = g.axis(a).origin;
      per_axis_[a] = std::max(1, static_cast<int>(std::ceil(g.axis(a).cells * g.h() / h_patch_ - 1e-9)));
      patches_ *= per_axis_[a];
    }
  }

  bool active() const { return mode_ != FBarMode::none; }
  FBarMode mode() const { return mode_; }
  double patch_size() const { return h_patch_; }  // m
  /// Under mpirun: the decomposition whose cuts the patch sums of `modified` cross (nothing at
  /// one rank). Called by the formulation's distribute().
  void distribute(const parallel::Domain<Dim>& d) {
    if (d.active()) domain_ = &d;
  }
  std::size_t patches() const { return patches_; }

  /// Flat index of the patch holding x (clamped to the lattice).
  std::size_t patch_of(const Vec<Dim>& x) const {
    std::size_t idx = 0;
    for (int a = Dim - 1; a >= 0; --a)
      idx = idx * per_axis_[a] + shape::cell_of((x[a] - origin_[a]) / h_patch_, per_axis_[a]);
    return idx;
  }

  /// The stage on st.solid (see the header comment), with the shape data `sd` at x_n, the active
  /// node box and the scatter schedule of this step. Failures (ΔJ̄ or J̄ not positive, a non-finite
  /// value) go to st.health. Returns whether it ran (fbar != none), for the stage timer.
  bool apply(const Grid<Dim>& g, const NodeBox<Dim>& box, const StripeSchedule& schedule,
             const std::vector<shape::ShapeData<Dim, S>>& sd, double dt, State<Dim>& st,
             const std::vector<std::unique_ptr<MaterialModel<Dim>>>& materials,
             const std::vector<std::vector<int>>& material_particles) {
    if (mode_ == FBarMode::none) return false;
    ParticleSet<Dim>& ps = st.solid;
    const long n = static_cast<long>(ps.size());
    dJ_.resize(ps.size());
    if (node_.size() != g.num_nodes()) node_ = NodeArray<std::array<double, 2>>(g.num_nodes());  // zero until used
    // (9)(c) ΔJ = det ΔF; eq. 80's nodal sums Σ N m, Σ N m ΔJ through the schedule.
    g.parallel_for_each_node(box, [&](std::size_t i, const auto&) { node_[i] = {0.0, 0.0}; });
    schedule.run([&](int p) {
      const double dJ = dJ_[p] = transfer::deformation_jacobian<Dim>(ps.L[p], dt);
      const double m = ps.m[p];
      shape::for_each_row(g, sd[p], [&](std::size_t row, double w_r, const Vec<Dim - 1>&) {
        const double m_r = w_r * m, mdJ_r = m_r * dJ;
        for (int a = 0; a < S; ++a) {
          node_[row + a][0] += sd[p].w[0][a] * m_r;
          node_[row + a][1] += sd[p].w[0][a] * mdJ_r;
        }
      });
    }, node_);
    g.parallel_for_each_node(box, [&](std::size_t i, const auto&) {
      if (node_[i][0] > 0.0) node_[i][1] /= node_[i][0];  // the nodal average of ΔJ
    });
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      // eq. 80 back at the particle; eq. 79: ΔF̄ = c ΔF, so F̄_{n+1} = ΔF̄ F_n = c F_{n+1} (in-plane
      // block in plane strain) and L̄ = rate_of_increment(c ΔF).
      double dJbar = 0.0;
      shape::for_each_row(g, sd[p], [&](std::size_t row, double w_r, const Vec<Dim - 1>&) {
        double sum = 0.0;
        for (int a = 0; a < S; ++a) sum += sd[p].w[0][a] * node_[row + a][1];
        dJbar += w_r * sum;
      });
      const double c = fbar::scale<Dim>(dJ_[p], dJbar);
      Mat3& F = ps.F[p];
      F.template topLeftCorner<Dim, Dim>() *= c;
      const double J = F.determinant(), V_old = ps.V[p];
      ps.V[p] = J * ps.V0[p];
      ps.L[p] = fbar::scaled_rate<Dim>(ps.L[p], c, dt);
      if (ps.two_phase()) {
        // Porosity from (1 − n) V = const (incompressible grains), pore-fluid mass n ρ_f V.
        const double n_old = ps.n[p];
        ps.n[p] = 1.0 - (1.0 - n_old) * V_old / ps.V[p];
        if (n_old * V_old > 0.0) ps.m_f[p] *= ps.n[p] * ps.V[p] / (n_old * V_old);
      }
      if (!(J > 0.0) || !ps.L[p].allFinite() || (ps.two_phase() && !(ps.n[p] >= 0.0 && ps.n[p] < 1.0)))
        bad = std::min(bad, p);
    }
    if (bad != transfer::no_particle) st.health.report(bad, "solid", "F-bar: stabilised J = det F <= 0, porosity outside [0, 1) or not finite");
    if (mode_ == FBarMode::modified) modify_elastic_strain(dt, ps, materials, material_particles);
    return true;
  }

 private:
  /// Steps (9)(e)-(g): ε_v^e of every particle from its material, the patch averages of
  /// J^e = exp(ε_v^e) (eq. 83), and the shift ln(J̄^e / J^e) for the stress update (eq. 82).
  void modify_elastic_strain(double dt, ParticleSet<Dim>& ps,
                             const std::vector<std::unique_ptr<MaterialModel<Dim>>>& materials,
                             const std::vector<std::vector<int>>& material_particles) {
    const long n = static_cast<long>(ps.size());
    ev_.resize(ps.size());
    ps.ev_shift.resize(ps.size());
    patch_.resize(ps.size());
    sum_.assign(patches_, {0.0, 0.0});  // O(patches) <= O(cells); no allocation after the first step
    for (std::size_t k = 0; k < materials.size(); ++k)  // one virtual call per material
      if (materials[k] && !material_particles[k].empty())
        materials[k]->elastic_volumetric_strain(ps, material_particles[k], dt, ev_);
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) patch_[p] = static_cast<int>(patch_of(ps.x[p]));
    // Bins of one row of patches each (the patch index along the last axis): distinct rows share
    // no patch, and inside a row the particles go in increasing index.
    const std::size_t row_size = patches_ / static_cast<std::size_t>(per_axis_[Dim - 1]);
    by_patch_.build(ps.size(), per_axis_[Dim - 1], 1,
                    [&](std::size_t p) { return static_cast<int>(static_cast<std::size_t>(patch_[p]) / row_size); });
    by_patch_.run([&](int p) {
      sum_[patch_[p]][0] += ps.m[p] * std::exp(ev_[p]);  // Σ m J^e
      sum_[patch_[p]][1] += ps.m[p];                     // Σ m
    });
    if (domain_) sum_boundary_patches(ps);
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      const auto& s = sum_[patch_[p]];
      ps.ev_shift[p] = std::log(s[0] / s[1]) - ev_[p];  // ln(J̄^e / J^e)
    }
  }

  /// mpirun: the patches within reach of a cut summed over every rank's particles in key order.
  /// A particle of rank r has its first node in r's columns [c_r, c_{r+1}) and lies within S + 1
  /// cells of it after the step's move, so a patch whose cells along the cut axis keep S + 2 from
  /// every cut holds one rank's particles only (summed above, in key order already); the others
  /// are summed here from the records (patch, key, m J^e, m) that every rank sends of them (an
  /// all-gather: the particles near the cuts).
  void sum_boundary_patches(const ParticleSet<Dim>& ps) {
    const parallel::Domain<Dim>& d = *domain_;
    const int axis = d.axis();
    const std::vector<int> cuts = d.column_cuts();
    std::size_t stride = 1;  // of the axis in the patch index (patch_of: x fastest)
    for (int a = 0; a < axis; ++a) stride *= static_cast<std::size_t>(per_axis_[a]);
    near_cut_.assign(static_cast<std::size_t>(per_axis_[axis]), 0);
    const double cells_per_patch = h_patch_ / h_;
    for (int j = 0; j < per_axis_[axis]; ++j) {
      const int c0 = static_cast<int>(std::floor(j * cells_per_patch)), c1 = static_cast<int>(std::ceil((j + 1) * cells_per_patch));
      for (std::size_t r = 1; r + 1 < cuts.size(); ++r)
        if (c1 > cuts[r] - (S + 2) && c0 < cuts[r] + (S + 2)) near_cut_[static_cast<std::size_t>(j)] = 1;
    }
    struct Record {
      std::int64_t patch, key;
      double mJ, m;
    };
    std::vector<char> mine;
    for (std::size_t p = 0; p < ps.size(); ++p) {
      const std::size_t q = static_cast<std::size_t>(patch_[p]);
      if (!near_cut_[(q / stride) % static_cast<std::size_t>(per_axis_[axis])]) continue;
      const Record rec{static_cast<std::int64_t>(q), ps.key[p], ps.m[p] * std::exp(ev_[p]), ps.m[p]};
      const char* b = reinterpret_cast<const char*>(&rec);
      mine.insert(mine.end(), b, b + sizeof rec);
    }
    std::vector<Record> all;
    for (const auto& part : parallel::all_gather(mine))
      for (std::size_t k = 0; k < part.size() / sizeof(Record); ++k) {
        Record rec;
        std::memcpy(&rec, part.data() + k * sizeof rec, sizeof rec);
        all.push_back(rec);
      }
    std::sort(all.begin(), all.end(), [](const Record& a, const Record& b) {
      return a.patch != b.patch ? a.patch < b.patch : a.key < b.key;
    });
    for (std::size_t k = 0; k < all.size();) {  // each patch from zero, in key order, as one rank adds it
      const std::size_t q = static_cast<std::size_t>(all[k].patch);
      std::array<double, 2> sum{0.0, 0.0};
      for (; k < all.size() && static_cast<std::size_t>(all[k].patch) == q; ++k) sum[0] += all[k].mJ, sum[1] += all[k].m;
      sum_[q] = sum;
    }
  }

  FBarMode mode_ = FBarMode::none;
  const parallel::Domain<Dim>* domain_ = nullptr;  // mpirun (distribute)
  std::vector<char> near_cut_;                     // per patch column along the cut axis (mpirun)
  double h_ = 0.0;                       // m, the grid's cell size
  double h_patch_ = 0.0;                 // m
  Vec<Dim> origin_ = Vec<Dim>::Zero();   // m, the lattice's corner (grid.min)
  std::array<int, Dim> per_axis_{};      // patches per axis
  std::size_t patches_ = 0;
  NodeArray<std::array<double, 2>> node_;  // per node: Σ N m, Σ N m ΔJ (then the average ΔJ)
  StripeSchedule by_patch_;              // particles by row of patches (width 1: one row per "stripe")
  std::vector<double> dJ_, ev_;          // per particle: ΔJ, ε_v^e
  std::vector<int> patch_;               // per particle
  std::vector<std::array<double, 2>> sum_;  // per patch: Σ m J^e, Σ m
};

}  // namespace swmpm
