// Mohr-Coulomb perfect plasticity (`mohr-coulomb`, materials/mohr_coulomb.cpp): the return mapping
// in principal stress space of de Souza Neto, Perić & Owen, "Computational Methods for
// Plasticity" (2008), §8.2 (hardening modulus 0), with a non-associated flow rule (dilation angle
// ψ), a tension cut-off on the mean stress and strength reduction. docs/formulations.md,
// "Mohr-Coulomb", has the equations; this header holds the pure return mapping so that the unit
// tests can reach it, and the factory make_material calls.
//
// Principal stresses are tension positive, sorted σ1 >= σ2 >= σ3 inside the return. In finite
// strain they are Kirchhoff stresses τ_a, in small strain Cauchy stresses; the algorithm is the same.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <utility>

#include <Eigen/Core>

#include "solver/materials/material.hpp"

namespace swmpm {

/// The `mohr-coulomb` model of a scene material (`solver.kinematics` picks finite or small strain).
template <int Dim>
std::unique_ptr<MaterialModel<Dim>> make_mohr_coulomb(const scene::Material& m, const scene::Scene& s);

namespace mohr_coulomb {

using Principal = Eigen::Vector3d;  // principal values (stress Pa, or strain -)

/// Material constants of the return mapping, strengths already reduced by the SRF.
struct Params {
  double K = 0.0, G = 0.0, lambda = 0.0;  // Pa, bulk and shear modulus, Lamé λ = K - 2G/3
  double c = 0.0;                         // Pa, reduced cohesion c_f = c / SRF
  double sin_phi = 0.0, cos_phi = 1.0;    // reduced friction angle φ_f = atan(tan φ / SRF)
  double sin_psi = 0.0;                   // reduced dilation angle ψ_f = atan(tan ψ / SRF)
  double tension = 0.0;                   // Pa, tension cut-off T on the mean stress (tension positive)
  double apex = std::numeric_limits<double>::infinity();  // Pa, c_f cot φ_f: the cone's apex
  bool cutoff = false;                    // T < apex: the cut-off plane cuts the cone

  /// From the scene parameters: angles in degrees, SRF > 0, T >= 0 [Pa].
  static Params from(const Elastic& e, double cohesion, double phi_deg, double psi_deg, double srf,
                     double tension_cutoff) {
    Params p;
    p.K = e.K, p.G = e.mu, p.lambda = e.lambda;
    p.c = cohesion / srf;
    const double deg = std::numbers::pi / 180.0;
    const double tan_phi = std::tan(phi_deg * deg) / srf, tan_psi = std::tan(psi_deg * deg) / srf;
    p.sin_phi = tan_phi / std::sqrt(1.0 + tan_phi * tan_phi);
    p.cos_phi = 1.0 / std::sqrt(1.0 + tan_phi * tan_phi);
    p.sin_psi = tan_psi / std::sqrt(1.0 + tan_psi * tan_psi);
    p.tension = tension_cutoff;
    if (tan_phi > 0.0) p.apex = p.c / tan_phi;
    p.cutoff = p.tension < p.apex;
    return p;
  }
  /// 2 c cos φ [Pa], the yield function's constant.
  double k() const { return 2.0 * c * cos_phi; }
  /// Elastic stiffness on principal values: D v = λ (Σ v) 1 + 2G v.
  Principal stiffness(const Principal& v) const {
    return 2.0 * G * v + Principal::Constant(lambda * v.sum());
  }
  /// Elastic compliance on principal values: C⁻¹ s = dev s / 2G + (Σ s / 9K) 1.
  Principal compliance(const Principal& s) const {
    const double mean = s.sum() / 3.0;
    return (s - Principal::Constant(mean)) / (2.0 * G) + Principal::Constant(mean / (3.0 * K));
  }
};

/// Φ = (σ_max − σ_min) + (σ_max + σ_min) sin φ − 2 c cos φ [Pa], principal values in any order.
inline double yield_function(const Params& m, const Principal& s) {
  const double hi = s.maxCoeff(), lo = s.minCoeff();
  return (hi - lo) + (hi + lo) * m.sin_phi - m.k();
}

/// Where the return mapping ended. edge_12: the edge σ1 = σ2 (main plane and the plane of σ2, σ3:
/// triaxial compression); edge_23: the edge σ2 = σ3 (main plane and the plane of σ1, σ2: triaxial
/// extension). cutoff_*: on the tension cut-off plane (mean stress = T), alone or together with
/// the main plane or an edge of the cone.
enum class Region { elastic, plane, edge_12, edge_23, apex, cutoff, cutoff_plane, cutoff_edge_12, cutoff_edge_23 };

struct Return {
  Principal s;        // returned principal stresses, in the order of the trial [Pa]
  Principal deps_p;   // plastic strain increment C⁻¹ (trial − s), principal [-]
  Region region;
};

namespace detail {

/// Cut-off plane mean = T active (T < apex). s sorted, mean(s) > T. The volumetric part is fixed by
/// mean = T; the cone then needs only a deviatoric return, along dev of the flow vector.
inline Principal cutoff_return(const Params& m, const Principal& s, Region& region) {
  const double sf = m.sin_phi, sp = m.sin_psi, k = m.k(), T = m.tension;
  const Principal st = s - Principal::Constant(s.sum() / 3.0 - T);
  const Principal na(1.0 + sf, 0.0, sf - 1.0), ma(1.0 + sp, 0.0, sp - 1.0);
  const double phi = na.dot(st) - k;
  if (phi <= 0.0) {
    region = Region::cutoff;
    return st;
  }
  const Principal Dd = 2.0 * m.G * (ma - Principal::Constant(ma.sum() / 3.0));
  const Principal r = st - (phi / na.dot(Dd)) * Dd;  // na·Dd = 4G (1 + sin φ sin ψ / 3)
  if (r[0] >= r[1] && r[1] >= r[2]) {
    region = Region::cutoff_plane;
    return r;
  }
  // The corner of the cut-off plane with an edge of the cone: a point (three planes meet).
  if ((1.0 - sp) * st[0] - 2.0 * st[1] + (1.0 + sp) * st[2] > 0.0) {
    const double y = (k - 2.0 * T * sf) / (3.0 + sf);
    region = Region::cutoff_edge_23;
    return Principal(T + 2.0 * y, T - y, T - y);
  }
  const double x = (k - 2.0 * T * sf) / (3.0 - sf);
  region = Region::cutoff_edge_12;
  return Principal(T + x, T + x, T - 2.0 * x);
}

/// The cone alone (de Souza Neto et al. Box 8.5): main plane, then one edge, then the apex.
/// s sorted σ1 >= σ2 >= σ3 with Φ(s) = phi > 0.
inline Principal cone_return(const Params& m, const Principal& s, double phi, Region& region) {
  const double sf = m.sin_phi, sp = m.sin_psi, k = m.k();
  const Principal na(1.0 + sf, 0.0, sf - 1.0), ma(1.0 + sp, 0.0, sp - 1.0);
  // (i) one-vector return to the main plane: Δγ = Φ / a, a = na·D ma
  //     = 4G (1 + sin φ sin ψ / 3) + 4K sin φ sin ψ.
  const Principal Dma = m.stiffness(ma);
  const double a = na.dot(Dma);
  const Principal r = s - (phi / a) * Dma;
  if (r[0] >= r[1] && r[1] >= r[2]) {
    region = Region::plane;
    return r;
  }
  // (ii) two-vector return to the edge the main-plane return crossed first: σ1 − σ2 falls by
  //      2G(1 + sin ψ)Δγ, σ2 − σ3 by 2G(1 − sin ψ)Δγ.
  const bool e23 = (1.0 - sp) * s[0] - 2.0 * s[1] + (1.0 + sp) * s[2] > 0.0;
  const Principal n2 = e23 ? Principal(1.0 + sf, sf - 1.0, 0.0) : Principal(0.0, 1.0 + sf, sf - 1.0);
  const Principal m2 = e23 ? Principal(1.0 + sp, sp - 1.0, 0.0) : Principal(0.0, 1.0 + sp, sp - 1.0);
  const Principal Dm2 = m.stiffness(m2);
  const double phi2 = n2.dot(s) - k;
  const double a11 = a, a12 = na.dot(Dm2), a21 = n2.dot(Dma), a22 = n2.dot(Dm2);
  const double det = a11 * a22 - a12 * a21;
  const double g1 = (a22 * phi - a12 * phi2) / det, g2 = (a11 * phi2 - a21 * phi) / det;
  Principal r2 = s - g1 * Dma - g2 * Dm2;
  if (e23) {
    r2[1] = r2[2] = 0.5 * (r2[1] + r2[2]);
    if (r2[0] >= r2[1] || !(m.sin_phi > 0.0)) {
      region = Region::edge_23;
      return r2;
    }
  } else {
    r2[0] = r2[1] = 0.5 * (r2[0] + r2[1]);
    if (r2[1] >= r2[2] || !(m.sin_phi > 0.0)) {
      region = Region::edge_12;
      return r2;
    }
  }
  // (iii) apex: σ1 = σ2 = σ3 = c cot φ (perfect plasticity).
  region = Region::apex;
  return Principal::Constant(m.apex);
}

}  // namespace detail

/// Return mapping of a trial state given by its principal stresses (any order). Elastic trial
/// states come back unchanged (Region::elastic).
inline Return return_map(const Params& m, const Principal& trial) {
  int i0 = 0, i1 = 1, i2 = 2;  // trial[i0] >= trial[i1] >= trial[i2]
  if (trial[i0] < trial[i1]) std::swap(i0, i1);
  if (trial[i1] < trial[i2]) std::swap(i1, i2);
  if (trial[i0] < trial[i1]) std::swap(i0, i1);
  const Principal s(trial[i0], trial[i1], trial[i2]);
  const double phi = (1.0 + m.sin_phi) * s[0] + (m.sin_phi - 1.0) * s[2] - m.k();
  const bool over_cutoff = m.cutoff && s.sum() / 3.0 > m.tension;
  Return out{trial, Principal::Zero(), Region::elastic};
  if (!(phi > 0.0) && !over_cutoff) return out;
  Principal r;
  bool done = false;
  if (phi > 0.0) {
    r = detail::cone_return(m, s, phi, out.region);
    done = !m.cutoff || r.sum() / 3.0 <= m.tension;
  }
  if (!done) r = detail::cutoff_return(m, s, out.region);
  out.s[i0] = r[0], out.s[i1] = r[1], out.s[i2] = r[2];
  out.deps_p = m.compliance(trial - out.s);
  return out;
}

/// Increment of the accumulated equivalent plastic strain: sqrt(2/3 Δε^p : Δε^p) [-].
inline double equivalent_plastic_increment(const Principal& deps_p) {
  return std::sqrt(2.0 / 3.0 * deps_p.squaredNorm());
}

}  // namespace mohr_coulomb
}  // namespace swmpm
