// Elastic trial of the finite-strain models with Hencky elasticity that rebuild b_e,n from the
// stress each step instead of storing it: `mohr-coulomb` in finite strain, and `hencky` under the
// modified F-bar (docs/formulations.md, "Mohr-Coulomb" and "F-bar"). For isotropic Hencky
// elasticity b_e = exp(2 ε_e) with ε_e = C⁻¹ : τ coaxial with τ, so with τ_n = J_n σ_n:
//
//   ε_e,n = C⁻¹ : τ_n + (shift / 3) 1          shift = ln(J̄^e / J^e) of the modified F-bar (seed 001
//                                               eq. 82: b̄_e = (J̄^e/J^e)^{2/3} b_e), 0 otherwise
//   b_e^tr = ΔF exp(2 ε_e,n) ΔFᵀ = Σ_a β_a n_a ⊗ n_a,   ε_a^tr = ½ ln β_a
//
// Plane strain: b_e and τ are block diagonal (in-plane 2x2, zz); ΔF_zz = 1 keeps ε_zz of step n.
#pragma once

#include <cmath>

#include <Eigen/Eigenvalues>

#include "solver/materials/material.hpp"
#include "solver/materials/spectral.hpp"

namespace swmpm::hencky {

using Principal = Eigen::Vector3d;  // principal values (strain -, stress Pa), zz last in plane strain

/// Principal logarithmic strains of b_e^tr and their directions.
template <int Dim>
struct Trial;
template <>
struct Trial<2> {
  spectral::Eig2 dirs;  // in-plane principal directions of b_e^tr (and of τ after an isotropic return)
  Principal eps;        // ε_1, ε_2 in plane, ε_zz
};
template <>
struct Trial<3> {
  Mat3 Q;        // eigenvectors of b_e^tr (columns)
  Principal eps;
};

/// Isotropic elasticity on principal values: τ = λ (Σ ε) 1 + 2μ ε.
inline Principal stress(const Elastic& e, const Principal& eps) {
  return 2.0 * e.mu * eps + Principal::Constant(e.lambda * eps.sum());
}
/// Its inverse: ε = dev τ / 2μ + (Σ τ / 9K) 1.
inline Principal strain(const Elastic& e, const Principal& tau) {
  const double mean = tau.sum() / 3.0;
  return (tau - Principal::Constant(mean)) / (2.0 * e.mu) + Principal::Constant(mean / (3.0 * e.K));
}

/// The trial above from σ_n, J_n and ΔF. False when b_e^tr is not positive definite.
template <int Dim>
bool trial(const Elastic& e, const Sym& s, double Jn, const MatD<Dim>& dF, double shift, Trial<Dim>& t) {
  if constexpr (Dim == 2) {
    const spectral::Eig2 en = spectral::eig2(s[0], s[1], s[3]);
    const Principal eps_n = strain(e, Jn * Principal(en.l1, en.l2, s[2])) + Principal::Constant(shift / 3.0);
    if (!spectral::plane_strain_trial(en, eps_n[0], eps_n[1], dF, t.dirs)) return false;
    t.eps = Principal(0.5 * std::log(t.dirs.l1), 0.5 * std::log(t.dirs.l2), eps_n[2]);
  } else {
    // ε_e,n as a tensor (no decomposition of σ_n): τ_n / 2μ + ((1/9K − 1/6μ) tr τ_n + shift/3) 1.
    const Mat3 tau_n = Jn * to_matrix(s);
    const double vol = (1.0 / (9.0 * e.K) - 1.0 / (6.0 * e.mu)) * tau_n.trace();
    const Mat3 B = spectral::sym_exp(tau_n / e.mu + Mat3::Identity() * (2.0 * vol + 2.0 * shift / 3.0));
    const Mat3 Bt = dF * B * dF.transpose();
    Eigen::SelfAdjointEigenSolver<Mat3> eig;
    eig.computeDirect(0.5 * (Bt + Bt.transpose()));
    const Principal beta = eig.eigenvalues();
    if (!(beta.minCoeff() > 0.0)) return false;
    t.eps = 0.5 * beta.array().log().matrix();
    t.Q = eig.eigenvectors();
  }
  return true;
}

/// σ = (1/J) Σ_a τ_a n_a ⊗ n_a on the trial's directions (plane strain: σ_yz = σ_xz = 0).
template <int Dim>
Sym cauchy(const Trial<Dim>& t, const Principal& tau, double J) {
  Sym s;
  if constexpr (Dim == 2) {
    const spectral::Sym2 r = spectral::rebuild(t.dirs, tau[0], tau[1]);
    s << r.xx / J, r.yy / J, tau[2] / J, r.xy / J, 0.0, 0.0;
  } else {
    s = to_voigt(t.Q * (tau / J).asDiagonal() * t.Q.transpose());
  }
  return s;
}

/// ε_v^e = tr ε_e,n = tr τ_n / 3K (the elastic volumetric strain the modified F-bar averages).
inline double volumetric_strain(const Elastic& e, const Sym& s, double Jn) {
  return Jn * (s[0] + s[1] + s[2]) / (3.0 * e.K);
}

/// Complementary elastic energy density ½ s : C⁻¹ : s [J/m³] of a stress s in Voigt form (shear
/// entries counted twice): (1 + ν)/(2E) s:s − ν/(2E) (tr s)². With s = τ it is Hencky's ψ per
/// reference volume (mohr-coulomb and drucker-prager multiply by J² V0 for τ = J σ).
inline double complementary_energy_density(const Elastic& e, const Sym& s) {
  const double tr = s[0] + s[1] + s[2];
  const double ss = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + 2.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]);
  return 0.5 * ((1.0 + e.nu) / e.E * ss - e.nu / e.E * tr * tr);
}

}  // namespace swmpm::hencky
