// Types shared by the solver. Notation (docs/notation in docs/architecture.md): suffix _p particle,
// _i node; stress is Cauchy, tension positive, stored as 3x3 even in plane strain (Dim = 2 keeps the
// out-of-plane terms).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>

#include <Eigen/Dense>

namespace swmpm {

/// Loops over fewer particles than this run on one thread: below it, starting a parallel region
/// costs more than the work. Results do not depend on it (the summation orders are fixed).
inline constexpr long parallel_threshold = 2048;

template <int Dim>
using Vec = Eigen::Matrix<double, Dim, 1>;
template <int Dim>
using MatD = Eigen::Matrix<double, Dim, Dim>;
using Mat3 = Eigen::Matrix3d;
/// Two doubles in one SIMD register (GCC/Clang vector extension: SSE2, NEON), for hot sums that
/// add pairs with one packed multiply-add. Element-wise IEEE arithmetic: the same results as two
/// scalar operations. PairU: the same, 8-byte aligned and may alias double, to load or store a pair
/// at any double's address.
typedef double Pair __attribute__((vector_size(16)));
typedef double PairU __attribute__((vector_size(16), aligned(8), may_alias));
/// Symmetric tensor in Voigt order xx, yy, zz, xy, yz, xz (ParaView's order for 6-component arrays).
using Sym = Eigen::Matrix<double, 6, 1>;

inline Mat3 to_matrix(const Sym& s) {
  Mat3 m;
  m << s[0], s[3], s[5], s[3], s[1], s[4], s[5], s[4], s[2];
  return m;
}
inline Sym to_voigt(const Mat3& m) {
  Sym s;
  s << m(0, 0), m(1, 1), m(2, 2), 0.5 * (m(0, 1) + m(1, 0)), 0.5 * (m(1, 2) + m(2, 1)),
      0.5 * (m(0, 2) + m(2, 0));
  return s;
}
/// Embeds a Dim x Dim tensor (velocity gradient) into 3x3 with zero out-of-plane terms.
template <int Dim>
inline Mat3 embed(const MatD<Dim>& a) {
  Mat3 m = Mat3::Zero();
  m.template topLeftCorner<Dim, Dim>() = a;
  return m;
}
/// Mean stress p = -tr(sigma)/3 [Pa], compression positive (geotechnical sign).
inline double mean_stress(const Sym& s) { return -(s[0] + s[1] + s[2]) / 3.0; }
/// Deviatoric stress q = sqrt(3 J2) [Pa].
inline double deviatoric_stress(const Sym& s) {
  const double m = (s[0] + s[1] + s[2]) / 3.0;
  const double dxx = s[0] - m, dyy = s[1] - m, dzz = s[2] - m;
  const double j2 = 0.5 * (dxx * dxx + dyy * dyy + dzz * dzz) + s[3] * s[3] + s[4] * s[4] + s[5] * s[5];
  return std::sqrt(3.0 * j2);
}

}  // namespace swmpm
