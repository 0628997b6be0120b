// Structure-of-arrays storage of one phase's material points: one contiguous array per field.
// Units and signs beside each field; stress is Cauchy, tension positive.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>
#include <vector>

#include "solver/common.hpp"

namespace swmpm {

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

  std::size_t size() const { return x.size(); }
  void resize(std::size_t n) {
    id.resize(n);
    x.resize(n);
    x0.resize(n);
    v.resize(n);
    l.resize(n);
    m.resize(n);
    V.resize(n);
    V0.resize(n);
    F.assign(n, Mat3::Identity());
    L.assign(n, MatD<Dim>::Zero());
    sigma.assign(n, Sym::Zero());
    eps_p.assign(n, 0.0);
    material.resize(n);
    body.resize(n);
    faces.resize(n);
  }
  /// Calls f(field) for every per-particle array (the one list of fields; resize-free helpers use it).
  template <class Fn>
  void for_each_field(Fn&& f) {
    f(id), f(x), f(x0), f(v), f(l), f(m), f(V), f(V0), f(F), f(L), f(sigma), f(eps_p), f(material), f(body),
        f(faces);
  }
  /// Bytes held per particle by this set (for run.json and the memory benchmark).
  static constexpr std::size_t bytes_per_particle() {
    return sizeof(std::int64_t) + 4 * sizeof(Vec<Dim>) + 3 * sizeof(double) + sizeof(Mat3) +
           sizeof(MatD<Dim>) + sizeof(Sym) + sizeof(double) + 2 * sizeof(std::int32_t) +
           sizeof(std::uint32_t);
  }
  /// Copies the state of `o` (every field but L, which each step recomputes) reusing this set's
  /// capacity: the snapshot of the last good state costs no allocation after the first.
  void copy_state_from(const ParticleSet& o) {
    id = o.id, x = o.x, x0 = o.x0, v = o.v, l = o.l, m = o.m, V = o.V, V0 = o.V0, F = o.F, sigma = o.sigma;
    eps_p = o.eps_p, material = o.material, body = o.body, faces = o.faces;
    L.clear();
  }
};

/// Reorders a particle set in place: particle k of the result is particle order[k] before.
/// Every field is gathered through one scratch buffer (the size of the largest field), kept across
/// calls. Used to keep particles in the scatter schedule's order, so that the transfers walk
/// memory sequentially.
template <int Dim>
class Reorder {
 public:
  void apply(ParticleSet<Dim>& ps, const std::vector<int>& order) {
    const std::size_t n = ps.size();
    ps.for_each_field([&](auto& field) {
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
