// Nor-Sand (`nor-sand`, materials/nor_sand.cpp): the critical-state sand model of Jefferies (1993)
// in the finite-deformation variant of Borja & Andrade, "Critical state plasticity. Part VI:
// Meso-scale finite element simulation of strain localization in discrete granular materials",
// CMAME 195 (2006) 5115–5140 (B&A below), with the modifications of seed 001 (Xie, Navas &
// López-Querol 2025, App. B): the dilatancy cut-off (eq. 92) and the gas-like state (eq. 93).
// docs/formulations.md, "Nor-Sand", has the equations with their labels (NS1…NS12) used below.
//
// This header holds the pure return mapping in principal elastic logarithmic strains so that the
// unit tests reach it; the kinematics (b_e, spectral decomposition, σ = τ/J) are in nor_sand.cpp.
//
// Signs: strains tension positive (ε_e = ½ ln b_e), principal Kirchhoff stresses τ_a tension
// positive, but p = −Σ τ_a / 3 and the image pressure π_i compression positive (B&A write p, π_i
// negative); q = √(3/2) ‖dev τ‖ ≥ 0. Pressures in Pa.
#pragma once

#include <array>
#include <cmath>
#include <memory>

#include <Eigen/Core>
#include <Eigen/LU>

#include "solver/materials/material.hpp"

namespace swmpm {

/// The `nor-sand` model of a scene material (needs `solver.kinematics` finite-strain).
template <int Dim>
std::unique_ptr<MaterialModel<Dim>> make_nor_sand(const scene::Material& m, const scene::Scene& s);

namespace nor_sand {

using Principal = Eigen::Vector3d;  // principal values (strain -, Kirchhoff stress Pa)

/// Material constants, by their scene names (docs/scene-format.md, "Nor-Sand").
struct Params {
  double mu0 = 0.0;     // Pa, shear_modulus μ0
  double alpha0 = 0.0;  // -, shear_modulus_coupling α0 (μ_e = μ0 + α0 p̂)
  double kappa = 0.0;   // -, swelling_index κ̃
  double p_ref = 0.0;   // Pa, reference_pressure p0 of the hyperelastic law
  double eps_v0 = 0.0;  // -, reference_elastic_volumetric_strain ε_v0^e
  double lambda = 0.0;  // -, compression_index λ̃
  double v_c0 = 0.0;    // -, reference_specific_volume
  double p_csl = 0.0;   // Pa, csl_reference_pressure (the unit of the CSL's logarithm)
  double M = 0.0, N = 0.0, N_bar = 0.0;  // critical_state_ratio, yield_coefficient, potential_coefficient
  double h = 0.0;       // -, hardening_modulus
  double alpha = 0.0;   // -, dilatancy_multiplier
  double v0 = 0.0;      // -, initial_specific_volume
  double ocr = 1.0;     // -, overconsolidation_ratio
  double cutoff_start = 1.0, cutoff_end = 1.5;  // -, Ē_d^p of eq. 92
  double gas_ratio = 1.6;                       // -, v_crit / v0 (eq. 93)

  static Params from(const scene::Material& m);
  double v_crit() const { return gas_ratio * v0; }
  /// Critical state line (NS6): v_c(p) = v_c0 − λ̃ ln(p / p_csl).
  double v_csl(double p) const { return v_c0 - lambda * std::log(p / p_csl); }
  /// p̂ at zero elastic strain, p_ref e^{ε_v0/κ̃} [Pa]: the pressure of a gas-like or unstressed
  /// point once it is compressed again.
  double p_unstrained() const { return p_ref * std::exp(eps_v0 / kappa); }
};

/// Internal variables of one particle (ParticleSet::state: [0] π_i, [1] Ē_d^p, [2] ψ_start).
struct State {
  double pi = 0.0;         // Pa, image pressure π_i (0: not initialised yet)
  double Ed = 0.0;         // -, accumulated deviatoric plastic strain Ē_d^p = Σ Δε_s^p
  double psi_start = 0.0;  // -, ψ_i when Ē_d^p passed dilatancy_cutoff_start (eq. 92)
  static State load(const MaterialState& s) { return {s[0], s[1], s[2]}; }
  void store(MaterialState& s) const { s[0] = pi, s[1] = Ed, s[2] = psi_start; }
};

// ---- hyperelasticity (B&A §2.1; NS1–NS3) -------------------------------------------------------

/// The stress of a principal elastic strain with the invariants the return mapping needs.
struct Elastic {
  double eps_v = 0.0, eps_s = 0.0;  // ε_v = Σ ε_a (tension +), ε_s = √(2/3) ‖e‖
  Principal e = Principal::Zero();  // deviatoric elastic strain e_a = ε_a − ε_v / 3
  double p_hat = 0.0;               // Pa, p̂ = p_ref exp(−(ε_v − ε_v0)/κ̃)       (NS1)
  double mu = 0.0;                  // Pa, μ_e = μ0 + α0 p̂                      (NS1)
  double p = 0.0, q = 0.0;          // Pa, p = p̂ (1 + 3α0 ε_s² / 2κ̃), q = 3 μ_e ε_s   (NS2)
  Principal tau = Principal::Zero();  // Pa, τ_a = −p + 2 μ_e e_a                 (NS2)
};

inline Elastic elastic(const Params& m, const Principal& eps) {
  Elastic s;
  s.eps_v = eps.sum();
  s.e = eps - Principal::Constant(s.eps_v / 3.0);
  s.eps_s = std::sqrt(2.0 / 3.0 * s.e.squaredNorm());
  s.p_hat = m.p_ref * std::exp(-(s.eps_v - m.eps_v0) / m.kappa);
  s.mu = m.mu0 + m.alpha0 * s.p_hat;
  s.p = s.p_hat * (1.0 + 1.5 * m.alpha0 / m.kappa * s.eps_s * s.eps_s);
  s.q = 3.0 * s.mu * s.eps_s;
  s.tau = 2.0 * s.mu * s.e - Principal::Constant(s.p);
  return s;
}

/// Stored energy per unit reference volume measured from zero elastic strain [Pa = J/m³] (NS1):
/// Ψ = κ̃ (p̂ − p̂(0)) + (3/2) μ_e ε_s².
inline double stored_energy(const Params& m, const Elastic& s) {
  return m.kappa * (s.p_hat - m.p_unstrained()) + 1.5 * s.mu * s.eps_s * s.eps_s;
}

/// Elastic tangent a_ab = ∂τ_a/∂ε_b (NS3):
/// p/κ̃ − (2 α0 p̂ / κ̃)(e_a + e_b) + 2 μ_e (δ_ab − 1/3).
inline Eigen::Matrix3d elastic_tangent(const Params& m, const Elastic& s) {
  Eigen::Matrix3d a;
  const double c = 2.0 * m.alpha0 * s.p_hat / m.kappa;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      a(i, j) = s.p / m.kappa - c * (s.e[i] + s.e[j]) + 2.0 * s.mu * ((i == j ? 1.0 : 0.0) - 1.0 / 3.0);
  return a;
}

/// The inverse of NS2 for a stress (p > 0, q): the elastic strain is coaxial with τ,
/// ε_e = A 1 + B τ with B = 1 / 2μ_e, A = ε_v / 3 + p / 2μ_e (NS4). With α0 > 0, p̂ solves
/// p̂ (1 + α0 q² / (6 κ̃ μ_e(p̂)²)) = p by Newton from p̂ = p (a few iterations).
struct Coaxial {
  double A = 0.0, B = 0.0;
};
inline Coaxial elastic_strain_of(const Params& m, double p, double q) {
  double p_hat = p;
  if (m.alpha0 > 0.0 && q > 0.0) {
    const double c = m.alpha0 * q * q / (6.0 * m.kappa);
    for (int k = 0; k < 50; ++k) {
      const double mu = m.mu0 + m.alpha0 * p_hat;
      const double g = p_hat * (1.0 + c / (mu * mu)) - p;
      const double dg = 1.0 + c / (mu * mu) - 2.0 * p_hat * c * m.alpha0 / (mu * mu * mu);
      const double step = g / dg;
      p_hat -= step;
      if (std::abs(step) <= 1e-15 * p) break;
    }
  }
  const double mu = m.mu0 + m.alpha0 * p_hat;
  const double eps_v = m.eps_v0 - m.kappa * std::log(p_hat / m.p_ref);
  return {eps_v / 3.0 + p / (2.0 * mu), 1.0 / (2.0 * mu)};
}

// ---- yield function, plastic potential, hardening (B&A §2.2–2.3; NS5–NS9) -----------------------

/// The yield function's stress ratio η(p, π_i) and the derivatives of p η (NS5):
/// N > 0: η = (M/N)[1 − (1 − N)(p/π_i)^{N/(1−N)}];  N = 0: η = M [1 + ln(π_i / p)].
struct Eta {
  double eta = 0.0;
  double d_p = 0.0;   // ∂(p η)/∂p
  double d_pi = 0.0;  // ∂(p η)/∂π_i
};
inline Eta yield_ratio(const Params& m, double p, double pi) {
  if (m.N == 0.0) {
    const double l = std::log(pi / p);
    return {m.M * (1.0 + l), m.M * l, m.M * p / pi};
  }
  const double r = std::pow(p / pi, m.N / (1.0 - m.N));
  return {m.M / m.N * (1.0 - (1.0 - m.N) * r), m.M / m.N * (1.0 - r), m.M * r * p / pi};
}

/// F = q − η(p, π_i) p [Pa] (NS5); F <= 0 admissible.
inline double yield_function(const Params& m, double p, double q, double pi) {
  return q - yield_ratio(m, p, pi).eta * p;
}

/// π_i that puts (p, q) on the yield surface, times OCR (seed 001 eq. 113, which is its q = 0
/// case: π_i = OCR p (1 − N)^{(1−N)/N}, or OCR p / e for N = 0). η is capped below M/N, the
/// largest stress ratio a surface with N > 0 reaches.
inline double initial_image_pressure(const Params& m, double p, double q) {
  double eta = q / p;
  if (m.N > 0.0) {
    eta = std::min(eta, 0.99 * m.M / m.N);
    return m.ocr * p * std::pow((1.0 - m.N) / (1.0 - m.N * eta / m.M), (1.0 - m.N) / m.N);
  }
  return m.ocr * p * std::exp(eta / m.M - 1.0);
}

/// Plastic dilatancy (NS7), compression positive: the plastic potential Q = q − η̄ p with N̄ that
/// passes through the stress point has ∂Q/∂q = 1 and −∂Q/∂p = (M − η)/(1 − N̄), so that
/// ε̇_s^p = λ̇ and ε̇_v^p (compression +) = λ̇ (M − η)/(1 − N̄). As in B&A, η is the yield surface's
/// η(p, π_i) (equal to q/p once F = 0; better behaved during the iterations when the trial q/p is
/// far above M).
inline double flow_d(const Params& m, double eta) { return (m.M - eta) / (1.0 - m.N_bar); }

/// State parameter at the image pressure with the dilatancy cut-off of seed 001 eq. 92 (NS8):
/// ψ_i = v − v_c0 + λ̃ ln(π_i / p_csl) while Ē_d^p ≤ start, faded linearly from ψ_start to 0
/// between start and end, 0 beyond. Ē_d^p is taken at the start of the step (explicit).
struct StateParameter {
  double psi = 0.0, d_pi = 0.0, d_v = 0.0;  // ψ_i, ∂ψ_i/∂π_i, ∂ψ_i/∂v
};
inline StateParameter image_state_parameter(const Params& m, double v, double pi, const State& n) {
  if (n.Ed <= m.cutoff_start) return {v - m.v_c0 + m.lambda * std::log(pi / m.p_csl), m.lambda / pi, 1.0};
  if (n.Ed >= m.cutoff_end) return {};
  return {(1.0 - (n.Ed - m.cutoff_start) / (m.cutoff_end - m.cutoff_start)) * n.psi_start, 0.0, 0.0};
}

/// Hardening limit π_i* = p R(ψ_i) (NS9), with the maximum dilatancy D* = α ψ_i:
/// N > 0: R = (1 − N α ψ_i / M)^{(N−1)/N};  N = 0: R = exp(α ψ_i / M). dR = dR/dψ_i.
/// NaN when 1 − N α ψ_i / M <= 0 (no finite limit: B&A's "complex number").
struct Limit {
  double R = 0.0, dR = 0.0;
};
inline Limit hardening_limit(const Params& m, double psi) {
  if (m.N == 0.0) {
    const double R = std::exp(m.alpha * psi / m.M);
    return {R, m.alpha / m.M * R};
  }
  const double b = 1.0 - m.N * m.alpha * psi / m.M;
  if (!(b > 0.0)) return {std::nan(""), std::nan("")};
  return {std::pow(b, (m.N - 1.0) / m.N), (1.0 - m.N) * m.alpha / m.M * std::pow(b, -1.0 / m.N)};
}

// ---- the return mapping (B&A §3; NS10–NS12) -------------------------------------------------------

inline constexpr int kMaxIterations = 30;
inline constexpr double kTolerance = 1e-12;  // on ‖r‖ (strains, and stresses scaled by π_i,n)

/// elastic: F(τ^tr, π_i,n) <= 0. smooth: the Newton on the smooth part of the surface (NS10).
/// vertex: the tip q = 0 (NS11), when the deviatoric trial strain is too small to reach the smooth
/// part (the trial lies beyond the isotropic tip of the yield surface).
enum class Region { elastic, smooth, vertex };

struct Return {
  Principal tau = Principal::Zero();    // Pa, principal Kirchhoff stress at n+1
  Principal eps_e = Principal::Zero();  // -, principal elastic strain at n+1
  double pi = 0.0;                      // Pa, π_i at n+1
  double dlambda = 0.0;                 // -, Δλ
  double dEd = 0.0;                     // -, increment of Ē_d^p: √(2/3) ‖dev(ε^tr − ε_e)‖
  double dEp = 0.0;                     // -, equivalent plastic strain increment √(2/3) ‖ε^tr − ε_e‖
  double psi_i = 0.0;                   // -, ψ_i at n+1 (the cut-off's ψ_start when Ē_d^p passes start)
  Region region = Region::elastic;
  bool converged = true;
  int iterations = 0;
  std::array<double, kMaxIterations + 1> residual{};  // ‖r_k‖, k = 0..iterations (last Newton run)
  Eigen::Matrix3d dtau_deps = Eigen::Matrix3d::Zero();  // ∂τ_a/∂ε^tr_b at fixed v (NS12)
  Principal dtau_dv = Principal::Zero();                // ∂τ_a/∂v at fixed ε^tr
};

namespace detail {

using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;

/// NS10 / NS11: residual r(x) and Jacobian at x = (ε_v, ε_s, Δλ, π_i) for a trial (ε_v^tr, ε_s^tr):
///   r_1 = ε_v − ε_v^tr − Δλ d(p, π_i)                          (volumetric flow, NS7)
///   r_2 = ε_s − ε_s^tr + Δλ        (smooth: deviatoric flow ∂Q/∂q = 1 along n̂^tr)
///   r_2 = ε_s                      (vertex: q = 0, all deviatoric trial strain plastic)
///   r_3 = (q − η(p, π_i) p) / π_i,n                           (F = 0, NS5)
///   r_4 = (π_i − π_i,n − h Δλ (π_i* − π_i)) / π_i,n          (backward-Euler hardening, NS9)
/// p, q of (ε_v, ε_s) by NS2. Returns false outside the model's domain (π_i <= 0, no finite π_i*).
/// dr4_dv: ∂r_4/∂v (the only residual that depends on the specific volume).
inline bool residual(const Params& m, double ev_tr, double es_tr, bool vertex, double v, const State& n,
                     const Vec4& x, Vec4& r, Mat4* J, double* dr4_dv) {
  const double ev = x[0], es = x[1], dl = x[2], pi = x[3], s = n.pi;
  if (!(pi > 0.0)) return false;
  // NS2 and its derivatives with respect to ε_v, ε_s.
  const double p_hat = m.p_ref * std::exp(-(ev - m.eps_v0) / m.kappa), mu = m.mu0 + m.alpha0 * p_hat;
  const double p = p_hat * (1.0 + 1.5 * m.alpha0 / m.kappa * es * es), q = 3.0 * mu * es;
  const double dp_dv = -p / m.kappa, dp_ds = 3.0 * m.alpha0 * p_hat * es / m.kappa;
  const double dq_dv = -3.0 * m.alpha0 * p_hat * es / m.kappa, dq_ds = 3.0 * mu;
  const Eta y = yield_ratio(m, p, pi);
  const double d = flow_d(m, y.eta);
  const StateParameter psi = image_state_parameter(m, v, pi, n);
  const Limit lim = hardening_limit(m, psi.psi);
  if (!std::isfinite(lim.R) || !std::isfinite(y.eta)) return false;
  const double pi_star = p * lim.R;
  // (Written element by element: GCC 12 at -O3 miscompiled the comma-initializer form here, the
  // caller then saw the residual of the first iterate at every iteration.)
  r[0] = ev - ev_tr - dl * d;
  r[1] = vertex ? es : es - es_tr + dl;
  r[2] = (q - y.eta * p) / s;
  r[3] = (pi - n.pi - m.h * dl * (pi_star - pi)) / s;
  if (dr4_dv) *dr4_dv = -m.h * dl * p * lim.dR * psi.d_v / s;
  if (!J) return true;
  // η = (p η)/p: ∂η/∂p = (∂(pη)/∂p − η)/p, ∂η/∂π_i = ∂(pη)/∂π_i / p; d = (M − η)/(1 − N̄).
  const double dd_dp = -(y.d_p - y.eta) / p / (1.0 - m.N_bar), dd_dpi = -y.d_pi / p / (1.0 - m.N_bar);
  Mat4& j = *J;
  j(0, 0) = 1.0 - dl * dd_dp * dp_dv, j(0, 1) = -dl * dd_dp * dp_ds, j(0, 2) = -d, j(0, 3) = -dl * dd_dpi;
  j(1, 0) = 0.0, j(1, 1) = 1.0, j(1, 2) = vertex ? 0.0 : 1.0, j(1, 3) = 0.0;
  j(2, 0) = (dq_dv - y.d_p * dp_dv) / s, j(2, 1) = (dq_ds - y.d_p * dp_ds) / s, j(2, 2) = 0.0, j(2, 3) = -y.d_pi / s;
  j(3, 0) = -m.h * dl * lim.R * dp_dv / s, j(3, 1) = -m.h * dl * lim.R * dp_ds / s;
  j(3, 2) = -m.h * (pi_star - pi) / s, j(3, 3) = (1.0 + m.h * dl - m.h * dl * p * lim.dR * psi.d_pi) / s;
  return true;
}

/// Newton with backtracking on ‖r‖ (full steps near the solution, so the rate stays quadratic);
/// fills out.residual and out.iterations; returns convergence.
template <class Res>
bool newton(Vec4& x, Res&& res, Return& out) {
  Vec4 r, r_try, x_try;
  Mat4 J;
  out.residual = {};
  out.iterations = 0;
  if (!res(x, r, &J)) return false;
  double norm = r.norm();
  out.residual[0] = norm;
  for (int k = 1; k <= kMaxIterations; ++k) {
    if (norm <= kTolerance) return true;
    const Vec4 dx = J.partialPivLu().solve(r);
    if (!dx.allFinite()) return false;
    double step = 1.0;
    bool accepted = false;
    for (int half = 0; half < 40 && !accepted; ++half, step *= 0.5) {
      x_try = x - step * dx;
      accepted = res(x_try, r_try, nullptr) && r_try.allFinite() && r_try.norm() < norm;
    }
    if (!accepted) return false;
    x = x_try;
    if (!res(x, r, &J)) return false;
    norm = r.norm();
    out.residual[k] = norm;
    out.iterations = k;
  }
  return norm <= kTolerance;
}

}  // namespace detail

/// Return mapping from the principal trial elastic strain ε^tr (any order) at specific volume v
/// (= J v0, fixed during the return) and the internal variables of step n (n.pi > 0).
/// The yield function has no Lode-angle dependence, so the deviatoric direction n̂ = e/‖e‖ of the
/// principal elastic strains is that of the trial (radial in the deviatoric plane) and the three
/// principal unknowns reduce to (ε_v, ε_s): ε_a = ε_v/3 + √(3/2) ε_s n̂^tr_a (NS10).
/// `tangent`: also fill dtau_deps and dtau_dv (NS12).
inline Return return_map(const Params& m, const Principal& eps_tr, double v, const State& n, bool tangent = false) {
  Return out;
  const Elastic tr = elastic(m, eps_tr);
  out.tau = tr.tau;
  out.eps_e = eps_tr;
  out.pi = n.pi;
  out.psi_i = image_state_parameter(m, v, n.pi, n).psi;
  if (yield_function(m, tr.p, tr.q, n.pi) <= kTolerance * n.pi) {
    if (tangent) out.dtau_deps = elastic_tangent(m, tr);
    return out;
  }
  const double ne = tr.e.norm();
  const Principal nh = ne > 0.0 ? Principal(tr.e / ne) : Principal::Zero();
  // Smooth part, from the trial state (ε_v^tr, ε_s^tr, Δλ = 0, π_i,n); valid when ε_s >= 0, i.e.
  // Δλ <= ε_s^tr. Otherwise the vertex, from (ε_v^tr, 0, ε_s^tr, π_i,n); valid when Δλ >= ε_s^tr.
  detail::Vec4 x(tr.eps_v, tr.eps_s, 0.0, n.pi);
  bool vertex = !(ne > 0.0);
  const auto solve = [&](bool at_vertex) {
    return detail::newton(x, [&](const detail::Vec4& xx, detail::Vec4& r, detail::Mat4* J) {
      return detail::residual(m, tr.eps_v, tr.eps_s, at_vertex, v, n, xx, r, J, nullptr);
    }, out);
  };
  if (vertex || !solve(false) || !(x[1] >= 0.0) || !(x[2] >= 0.0)) {
    vertex = true;
    x << tr.eps_v, 0.0, tr.eps_s, n.pi;
    if (!solve(true) || !(x[2] >= tr.eps_s * (1.0 - 1e-12))) {
      out.converged = false;
      return out;
    }
  }
  out.region = vertex ? Region::vertex : Region::smooth;
  out.eps_e = Principal::Constant(x[0] / 3.0) + std::sqrt(1.5) * x[1] * nh;
  out.dlambda = x[2];
  out.pi = x[3];
  const Elastic el = elastic(m, out.eps_e);
  out.tau = el.tau;
  out.psi_i = image_state_parameter(m, v, out.pi, n).psi;
  const Principal dep = eps_tr - out.eps_e;
  out.dEd = std::sqrt(2.0 / 3.0 * (dep - Principal::Constant(dep.sum() / 3.0)).squaredNorm());
  out.dEp = std::sqrt(2.0 / 3.0 * dep.squaredNorm());
  if (!tangent) return out;
  // NS12: J dx = −∂r/∂ε_v^tr dε_v^tr − ∂r/∂ε_s^tr dε_s^tr − ∂r/∂v dv, with ∂ε_v^tr/∂ε^tr_b = 1,
  // ∂ε_s^tr/∂ε^tr_b = √(2/3) n̂_b, ∂n̂_a/∂ε^tr_b = (δ_ab − 1/3 − n̂_a n̂_b)/‖e^tr‖; then
  // dε_a = dε_v/3 + √(3/2) (dε_s n̂_a + ε_s dn̂_a) and dτ = a^e dε.
  detail::Vec4 r;
  detail::Mat4 J = detail::Mat4::Zero();
  double dr4_dv = 0.0;
  detail::residual(m, tr.eps_v, tr.eps_s, vertex, v, n, x, r, &J, &dr4_dv);
  const auto lu = J.partialPivLu();
  const detail::Vec4 d_ev = lu.solve(detail::Vec4(1.0, 0.0, 0.0, 0.0));
  const detail::Vec4 d_es = vertex ? detail::Vec4::Zero() : detail::Vec4(lu.solve(detail::Vec4(0.0, 1.0, 0.0, 0.0)));
  const detail::Vec4 d_v = lu.solve(detail::Vec4(0.0, 0.0, 0.0, -dr4_dv));
  Eigen::Matrix3d deps;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const double dn = ne > 0.0 ? ((a == b ? 1.0 : 0.0) - 1.0 / 3.0 - nh[a] * nh[b]) / ne : 0.0;
      const double dev_b = d_ev[0] + d_es[0] * std::sqrt(2.0 / 3.0) * nh[b];
      const double des_b = d_ev[1] + d_es[1] * std::sqrt(2.0 / 3.0) * nh[b];
      deps(a, b) = dev_b / 3.0 + std::sqrt(1.5) * (des_b * nh[a] + x[1] * dn);
    }
  const Eigen::Matrix3d ae = elastic_tangent(m, el);
  out.dtau_deps = ae * deps;
  out.dtau_dv = ae * (Principal::Constant(d_v[0] / 3.0) + std::sqrt(1.5) * d_v[1] * nh);
  return out;
}

}  // namespace nor_sand
}  // namespace swmpm
