// Structure-of-arrays storage of one phase's material points: one contiguous array per field.
// Units and signs beside each field; stress is Cauchy, tension positive.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>
#include <vector>

#include "solver/common.hpp"

namespace swmpm {

/// Internal variables of a constitutive model at one particle; their meaning is the model's (Nor-Sand:
/// image pressure, accumulated deviatoric plastic strain, ψ_i where the dilatancy cut-off starts).
using MaterialState = std::array<double, 4>;

template <int Dim>
struct ParticleSet {
  std::vector<std::int64_t> id;   // stable id from preprocess
  std::vector<Vec<Dim>> x;        // m, position
  std::vector<Vec<Dim>> x0;       // m, position at t = 0 (displacement = x - x0)
  std::vector<Vec<Dim>> v;        // m/s, velocity
  std::vector<Vec<Dim>> l;        // m, GIMP half-size of the particle domain (per axis, initial)
  std::vector<double> m;          // kg (per metre of thickness in 2D)
  std::vector<double> V;          // m^3 (m^2 per metre in 2D), current volume
  std::vector<double> V0;         // m^3, initial volume
  std::vector<Mat3> F;            // -, deformation gradient (F_zz = 1 in plane strain)
  std::vector<MatD<Dim>> L;       // 1/s, velocity gradient of the last step
  std::vector<Sym> sigma;         // Pa, Cauchy stress, tension positive
  std::vector<double> eps_p;      // -, accumulated equivalent plastic strain
  std::vector<std::int32_t> material;  // index into scene.materials
  std::vector<std::int32_t> body;      // index into scene.bodies
  std::vector<std::uint32_t> faces;    // bit f set: on face f (0 x_min, 1 x_max, 2 y_min, ...)

  // Pore fluid carried by the same points (single-point two-phase formulations only; these stay
  // empty otherwise — the solver models only what the scene has). With them, `sigma` is the
  // EFFECTIVE stress (tension positive) and `m` the solid mass.
  std::vector<double> n;               // -, porosity
  std::vector<double> p;               // Pa, pore pressure, compression positive
  std::vector<double> m_f;             // kg, pore fluid mass (n rho_f V)
  std::vector<Vec<Dim>> v_f;           // m/s, pore fluid velocity
  std::vector<std::int32_t> fluid_material;  // index into scene.materials

  // Internal variables of the constitutive model (stay empty unless a scene material needs them,
  // needs_material_state in materials/material.hpp; zero-initialised: "not set yet").
  std::vector<MaterialState> state;

  // Modified F-bar (seed 001 eq. 82; solver/transfer/fbar.hpp): the shift ln(J̄^e / J^e) [-] of the
  // elastic logarithmic volumetric strain that the material models add to b_e,n when they rebuild
  // it at the start of the step. Scratch of one step, like L: written by the F-bar stage right
  // before the stress update, empty unless solver.stabilisation.fbar is "modified"; not part of
  // for_each_field (nothing reads it across steps, so reordering and snapshots skip it).
  std::vector<double> ev_shift;

  // Under mpirun only (solver/parallel/domain.hpp): the point's place in the one-rank run's
  // storage order, which fixes the order of every sum a rank makes (empty at one rank).
  std::vector<std::int64_t> key;

  std::size_t size() const { return x.size(); }
  /// Point q's place in the one-rank run's storage order: its key under mpirun, q at one rank.
  std::int64_t place(std::size_t q) const { return key.size() == size() ? key[q] : static_cast<std::int64_t>(q); }
  bool two_phase() const { return carries_fluid_; }
  bool has_material_state() const { return carries_state_; }
  /// Allocates the model state (zero) for a set of the current size.
  void add_material_state() {
    carries_state_ = true;
    state.assign(size(), MaterialState{});
  }
  /// Allocates the pore-fluid fields (zero) for a set of the current size.
  void add_fluid() {
    carries_fluid_ = true;
    const std::size_t k = size();
    n.assign(k, 0.0);
    p.assign(k, 0.0);
    if (water_points_) return;
    m_f.assign(k, 0.0);
    v_f.assign(k, Vec<Dim>::Zero());
    fluid_material.assign(k, 0);
  }
  /// Double-point water points (semi-implicit): no skeleton and no pore fluid of their own, so F,
  /// L, sigma, eps_p and the single-point pore-fluid fields m_f, v_f, fluid_material are freed and
  /// stay empty (resize, add_fluid); reordering and snapshots then skip them. The set keeps n and p.
  /// keep_stress: `sigma` stays (explicit-double-point: the liquid's viscous deviatoric stress).
  void make_water_points(bool keep_stress = false) {
    water_points_ = true;
    water_stress_ = keep_stress;
    F.clear();
    L.clear();
    if (!keep_stress) sigma.clear();
    eps_p.clear();
    m_f.clear();
    v_f.clear();
    fluid_material.clear();
  }
  void resize(std::size_t k) {
    id.resize(k);
    x.resize(k);
    x0.resize(k);
    v.resize(k);
    l.resize(k);
    m.resize(k);
    V.resize(k);
    V0.resize(k);
    if (!water_points_) {
      F.assign(k, Mat3::Identity());
      L.assign(k, MatD<Dim>::Zero());
      sigma.assign(k, Sym::Zero());
      eps_p.assign(k, 0.0);
    } else if (water_stress_) {
      sigma.resize(k, Sym::Zero());
    }
    material.resize(k);
    body.resize(k);
    faces.resize(k);
    if (carries_fluid_) add_fluid();
    if (carries_state_) add_material_state();
    ev_shift.clear();
  }
  /// Calls f(field) for every per-particle array (the one list of fields; resize-free helpers use it).
  template <class Fn>
  void for_each_field(Fn&& f) {
    zip_fields(f, *this);
  }
  /// Calls f(field, o's same field) for every per-particle array of both sets.
  template <class Fn>
  void for_each_field_with(const ParticleSet& o, Fn&& f) {
    zip_fields(f, *this, o);
  }
  /// An empty set that carries the fields this one does (pore fluid, model state, water points).
  ParticleSet empty_like() const { return of_kind(kind()); }
  /// The flags empty_like copies, as one word (bit 0 pore fluid, 1 model state, 2 water points,
  /// 3 water stress), and a set of none made like a set of those flags: for sending a set's kind.
  int kind() const { return carries_fluid_ | carries_state_ << 1 | water_points_ << 2 | water_stress_ << 3; }
  static ParticleSet of_kind(int k) {
    ParticleSet e;
    if (k & 4) e.make_water_points((k & 8) != 0);
    if (k & 1) e.add_fluid();
    if (k & 2) e.add_material_state();
    return e;
  }
  /// Bytes held per particle by this set (for run.json and the memory benchmark): the fields every
  /// set has, plus the pore-fluid and model-state fields when allocated.
  std::size_t bytes_per_particle() const {
    if (water_points_)
      return sizeof(std::int64_t) + 4 * sizeof(Vec<Dim>) + 3 * sizeof(double) + 2 * sizeof(std::int32_t) +
             sizeof(std::uint32_t) + (carries_fluid_ ? 2 * sizeof(double) : 0) + (water_stress_ ? sizeof(Sym) : 0);
    return sizeof(std::int64_t) + 4 * sizeof(Vec<Dim>) + 3 * sizeof(double) + sizeof(Mat3) +
           sizeof(MatD<Dim>) + sizeof(Sym) + sizeof(double) + 2 * sizeof(std::int32_t) +
           sizeof(std::uint32_t) +
           (carries_fluid_ ? 3 * sizeof(double) + sizeof(Vec<Dim>) + sizeof(std::int32_t) : 0) +
           (carries_state_ ? sizeof(MaterialState) : 0) + (ev_shift.empty() ? 0 : sizeof(double));
  }
  /// Copies the state of `o` (every field but L, which each step recomputes) reusing this set's
  /// capacity: the snapshot of the last good state costs no allocation after the first.
  void copy_state_from(const ParticleSet& o) {
    id = o.id, x = o.x, x0 = o.x0, v = o.v, l = o.l, m = o.m, V = o.V, V0 = o.V0, F = o.F, sigma = o.sigma;
    eps_p = o.eps_p, material = o.material, body = o.body, faces = o.faces;
    n = o.n, p = o.p, m_f = o.m_f, v_f = o.v_f, fluid_material = o.fluid_material;
    state = o.state;
    key = o.key;
    carries_fluid_ = o.carries_fluid_;
    carries_state_ = o.carries_state_;
    water_points_ = o.water_points_;
    water_stress_ = o.water_stress_;
    L.clear();
  }

 private:
  /// The one list of per-particle fields, zipped over one or more sets.
  template <class Fn, class... Sets>
  static void zip_fields(Fn& f, Sets&... s) {
    f(s.id...), f(s.x...), f(s.x0...), f(s.v...), f(s.l...), f(s.m...), f(s.V...), f(s.V0...), f(s.F...), f(s.L...),
        f(s.sigma...), f(s.eps_p...), f(s.material...), f(s.body...), f(s.faces...), f(s.n...), f(s.p...),
        f(s.m_f...), f(s.v_f...), f(s.fluid_material...), f(s.state...), f(s.key...);
  }
  bool carries_fluid_ = false;
  bool carries_state_ = false;
  bool water_points_ = false;  // make_water_points()
  bool water_stress_ = false;  // make_water_points(true)
};

/// Reorders a particle set in place: particle k of the result is particle order[k] before.
/// Every field is gathered through one scratch buffer (the size of the largest field), kept across
/// calls. Used to keep particles in the scatter schedule's order, so that the transfers walk
/// memory sequentially.
/// Samples of the named surfaces the scene refers to (particles/surfaces.vtu, written by
/// preprocess): points on each surface, at t = 0, with the outward unit normal and the length (2D)
/// or area (3D) each stands for. Loads on a named surface share their force among the tagged
/// particles by these samples; boundary conditions on one constrain the grid nodes nearest them.
template <int Dim>
struct SurfaceSamples {
  std::vector<int> surface;  // k: the surface of face bit kFirstSurfaceBit + k
  std::vector<int> body;     // the body whose geometry the sample belongs to
  std::vector<Vec<Dim>> x;       // m
  std::vector<Vec<Dim>> normal;  // outward unit normal (out of `body`)
  std::vector<double> area;      // m (2D, per metre of thickness) or m^2
  std::size_t size() const { return x.size(); }
};

template <int Dim>
class Reorder {
 public:
  void apply(ParticleSet<Dim>& ps, const std::vector<int>& order) {
    const std::size_t n = ps.size();
    ps.for_each_field([&](auto& field) {
      if (field.size() != n) return;  // fields a formulation does not use stay empty
      using T = typename std::decay_t<decltype(field)>::value_type;
      static_assert(alignof(T) <= alignof(std::max_align_t) && std::is_trivially_destructible_v<T>);
      const std::size_t words = (n * sizeof(T) + sizeof(std::max_align_t) - 1) / sizeof(std::max_align_t);
      if (scratch_.size() < words) scratch_.resize(words);
      T* tmp = reinterpret_cast<T*>(scratch_.data());
      for (std::size_t k = 0; k < n; ++k) new (tmp + k) T(field[order[k]]);
      std::copy(tmp, tmp + n, field.begin());
    });
  }

 private:
  std::vector<std::max_align_t> scratch_;
};

}  // namespace swmpm
