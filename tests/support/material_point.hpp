// One material point for constitutive-model tests: a ParticleSet of one particle (with the model
// state allocated, as the time loop does for models that need it) and the solver's update of F
// for a constant velocity gradient.
#pragma once

#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "solver/materials/material.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::testing {

template <int Dim>
ParticleSet<Dim> one_particle(const Sym& sigma0 = Sym::Zero()) {
  ParticleSet<Dim> ps;
  ps.resize(1);
  ps.add_material_state();
  ps.m[0] = 1.0;
  ps.V[0] = ps.V0[0] = 1.0;
  ps.sigma[0] = sigma0;
  return ps;
}

/// Drives one particle with a constant velocity gradient for `steps` steps, updating F as the
/// solver does (F <- dF F, transfer::deformation_increment, then update_stress).
template <int Dim>
void drive(const MaterialModel<Dim>& model, ParticleSet<Dim>& ps, const MatD<Dim>& L, double dt, int steps) {
  const std::vector<int> ids{0};
  for (int k = 0; k < steps; ++k) {
    ps.L[0] = L;
    Mat3 dF = Mat3::Identity();
    dF.template topLeftCorner<Dim, Dim>() = transfer::deformation_increment<Dim>(L, dt);
    ps.F[0] = dF * ps.F[0];
    ps.V[0] = ps.F[0].determinant() * ps.V0[0];
    ASSERT_EQ(model.update_stress(ps, ids, dt), -1) << "step " << k;
  }
}

/// One plastic plane-strain path (compression, shear and spin: L = [[0.3, 0.4], [−0.1, −0.6]] for
/// 1000 steps of 1e-4, about 10 % strain) from s0 through a Dim 2 model (closed-form 2x2
/// spectral decomposition) and a Dim 3 model (Eigen computeDirect): the two particles after it.
inline std::pair<ParticleSet<2>, ParticleSet<3>> plane_strain_path(const MaterialModel<2>& m2,
                                                                   const MaterialModel<3>& m3, const Sym& s0) {
  auto a = one_particle<2>(s0);
  auto b = one_particle<3>(s0);
  MatD<2> L2;
  L2 << 0.3, 0.4, -0.1, -0.6;
  MatD<3> L3 = MatD<3>::Zero();
  L3.topLeftCorner<2, 2>() = L2;
  drive<2>(m2, a, L2, 1e-4, 1000);
  drive<3>(m3, b, L3, 1e-4, 1000);
  return {std::move(a), std::move(b)};
}

}  // namespace swmpm::testing
