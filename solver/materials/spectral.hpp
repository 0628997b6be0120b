// Spectral helpers the finite-strain material models share (mohr-coulomb, nor-sand): the closed-form
// eigen-decomposition of a symmetric 2x2 (plane strain, in-plane block) and its rebuild from
// principal values, and the exponential of a symmetric 3x3 (b_e = exp(2 ε_e) rebuilt from the stress).
#pragma once

#include <cmath>

#include "solver/common.hpp"

namespace swmpm::spectral {

/// Spectral decomposition of the symmetric 2x2 [[a, b], [b, d]]: eigenvalues l1 >= l2 and the
/// double angle of the first eigenvector (cos 2θ, sin 2θ), so that
/// T = ½(t1 + t2) I + ½(t1 − t2) [[cos 2θ, sin 2θ], [sin 2θ, −cos 2θ]] rebuilds a coaxial tensor.
struct Eig2 {
  double l1, l2, c2, s2;
};
inline Eig2 eig2(double a, double d, double b) {
  const double h = 0.5 * (a - d), m = 0.5 * (a + d), r = std::sqrt(h * h + b * b);
  if (!(r > 0.0)) return {m, m, 1.0, 0.0};
  return {m + r, m - r, h / r, b / r};
}
/// xx, yy, xy of the tensor with principal values t1, t2 on the directions of e.
struct Sym2 {
  double xx, yy, xy;
};
inline Sym2 rebuild(const Eig2& e, double t1, double t2) {
  const double m = 0.5 * (t1 + t2), h = 0.5 * (t1 - t2);
  return {m + h * e.c2, m - h * e.c2, h * e.s2};
}

/// Plane-strain trial of a finite-strain model: b_e,n (in-plane block) from its principal elastic
/// strains eps1, eps2 on the directions of `en` (b_e = Σ exp(2 ε_a) n_a ⊗ n_a), then
/// b_e^tr = ΔF b_e,n ΔFᵀ and its decomposition. False when b_e^tr is not positive definite.
inline bool plane_strain_trial(const Eig2& en, double eps1, double eps2, const Eigen::Matrix2d& dF, Eig2& trial) {
  const Sym2 b = rebuild(en, std::exp(2.0 * eps1), std::exp(2.0 * eps2));
  Eigen::Matrix2d B;
  B << b.xx, b.xy, b.xy, b.yy;
  const Eigen::Matrix2d Bt = dF * B * dF.transpose();
  trial = eig2(Bt(0, 0), Bt(1, 1), 0.5 * (Bt(0, 1) + Bt(1, 0)));
  return trial.l2 > 0.0;
}

/// exp(X) of a symmetric 3x3 (the elastic b_e = exp(2 ε_e) in 3D): e^{tr X / 3} times the Taylor
/// series of the deviator A in Horner form, A first scaled to a norm <= 1/8 and the result squared
/// back. The degree d is the smallest with ‖A‖^{d+1}/(d+1)! < 1e-17 (d <= 10; 6-8 for elastic
/// strains of 0.5-5 %). As fast as an eigendecomposition (computeDirect, ~170 ns here) and free
/// of its loss of accuracy for close eigenvalues (K0 = 1, the apex).
inline Mat3 sym_exp(const Mat3& X) {
  const double m = X.trace() / 3.0;
  Mat3 A = X - m * Mat3::Identity();
  double nrm = A.norm();
  int squarings = 0;
  for (; nrm > 0.125 && squarings < 60; nrm *= 0.5) ++squarings;
  A *= std::ldexp(1.0, -squarings);
  int d = 1;
  for (double term = nrm * nrm / 2.0; term >= 1e-17 && d < 10; term *= nrm / (d + 1.0)) ++d;
  Mat3 E = Mat3::Identity() + A / static_cast<double>(d);
  for (int k = d - 1; k >= 1; --k) E = Mat3::Identity() + (A * E) / static_cast<double>(k);
  for (int k = 0; k < squarings; ++k) E = E * E;
  return std::exp(m) * E;
}

}  // namespace swmpm::spectral
