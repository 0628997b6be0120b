// Structure-of-arrays storage of one phase's material points: one contiguous array per field.
// Units and signs beside each field; stress is Cauchy, tension positive.
#pragma once

#include <cstdint>
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
  /// Bytes held per particle by this set (for run.json and the memory benchmark).
  static constexpr std::size_t bytes_per_particle() {
    return sizeof(std::int64_t) + 4 * sizeof(Vec<Dim>) + 3 * sizeof(double) + sizeof(Mat3) +
           sizeof(MatD<Dim>) + sizeof(Sym) + sizeof(double) + 2 * sizeof(std::int32_t) +
           sizeof(std::uint32_t);
  }
};

}  // namespace swmpm
