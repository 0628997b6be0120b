// Drucker-Prager perfect plasticity (`drucker-prager`, materials/drucker_prager.cpp): the yield
// function of seed 004 (Pan, Yamaguchi, Moriguchi & Terada), eqs. 17-19, with a non-associated flow
// rule (dilation angle ψ), strength reduction and a tension cut-off on the mean stress, returned
// in principal stresses as in de Souza Neto, Perić & Owen, "Computational Methods for Plasticity"
// (2008), Box 8.8 (hardening modulus 0): a radial return in the deviatoric plane, or to the apex.
// docs/formulations.md, "Drucker-Prager", has the equations; this header holds the pure return
// mapping the unit tests call, and the factory make_material calls.
//
// Principal stresses are tension positive and in any order (the return is isotropic). They are
// Kirchhoff stresses τ_a (finite strain, Hencky elasticity). σ_m = (σ1 + σ2 + σ3)/3 is the mean
// stress, tension positive: de Souza Neto's p, i.e. minus the code's p (solver/common.hpp).
#pragma once

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include <Eigen/Core>

#include "solver/materials/material.hpp"

namespace swmpm {

/// The `drucker-prager` model of a scene material (finite strain; `solver.kinematics` must be
/// finite-strain).
template <int Dim>
std::unique_ptr<MaterialModel<Dim>> make_drucker_prager(const scene::Material& m, const scene::Scene& s);

namespace drucker_prager {

using Principal = Eigen::Vector3d;  // principal values (stress Pa, or strain -)

/// Seed 004 eqs. 18-19, the plane-strain match of the cone to Mohr-Coulomb:
/// η = 3 tan φ / √(9 + 12 tan² φ) (and ξ = 3 / √(9 + 12 tan² φ) from the same root).
inline double eta_of(double tan_angle) { return 3.0 * tan_angle / std::sqrt(9.0 + 12.0 * tan_angle * tan_angle); }
inline double xi_of(double tan_angle) { return 3.0 / std::sqrt(9.0 + 12.0 * tan_angle * tan_angle); }

/// Material constants of the return mapping, strengths already reduced by the SRF.
struct Params {
  double K = 0.0, G = 0.0;  // Pa, bulk and shear modulus
  double c = 0.0;           // Pa, reduced cohesion c_f = c / SRF
  double eta = 0.0;         // -, η of the yield function (friction φ_f), seed 004 eq. 18
  double xi = 1.0;          // -, ξ of the yield function, seed 004 eq. 19
  double eta_bar = 0.0;     // -, η̄ of the plastic potential: η of eq. 18 with ψ_f for φ_f
  double tension = 0.0;     // Pa, tension cut-off T on the mean stress (tension positive)
  double apex = std::numeric_limits<double>::infinity();  // Pa, σ_m = ξ c_f / η: the cone's apex
  bool cutoff = false;      // T < apex: the cut-off plane cuts the cone

  /// From the scene parameters: angles in degrees, SRF > 0, T >= 0 [Pa]. Strength reduction as
  /// `mohr-coulomb`: c_f = c / SRF, tan φ_f = tan φ / SRF, tan ψ_f = tan ψ / SRF; T not reduced.
  static Params from(const Elastic& e, double cohesion, double phi_deg, double psi_deg, double srf,
                     double tension_cutoff) {
    Params p;
    p.K = e.K, p.G = e.mu;
    p.c = cohesion / srf;
    const double deg = std::numbers::pi / 180.0;
    const double tan_phi = std::tan(phi_deg * deg) / srf, tan_psi = std::tan(psi_deg * deg) / srf;
    p.eta = eta_of(tan_phi), p.xi = xi_of(tan_phi), p.eta_bar = eta_of(tan_psi);
    p.tension = tension_cutoff;
    if (p.eta > 0.0) p.apex = p.xi * p.c / p.eta;
    p.cutoff = p.tension < p.apex;
    return p;
  }
  /// Elastic compliance on principal values: C⁻¹ s = dev s / 2G + (Σ s / 9K) 1.
  Principal compliance(const Principal& s) const {
    const double mean = s.sum() / 3.0;
    return (s - Principal::Constant(mean)) / (2.0 * G) + Principal::Constant(mean / (3.0 * K));
  }
};

/// √J2 = √(½ s:s) of principal values [Pa], s = dev σ.
inline double sqrt_J2(const Principal& s) {
  const Principal d = s - Principal::Constant(s.sum() / 3.0);
  return std::sqrt(0.5 * d.squaredNorm());
}

/// Φ = √J2(s) + η σ_m − ξ c_f [Pa] (seed 004 eq. 17, σ_m tension positive; Φ <= 0 admissible).
inline double yield_function(const Params& m, const Principal& s) {
  return sqrt_J2(s) + m.eta * s.sum() / 3.0 - m.xi * m.c;
}

/// Where the return mapping ended: the smooth cone, its apex, the cut-off plane σ_m = T alone, or
/// the circle where the cut-off plane meets the cone.
enum class Region { elastic, cone, apex, cutoff, cutoff_cone };

struct Return {
  Principal s;        // returned principal stresses, in the order of the trial [Pa]
  Principal deps_p;   // plastic strain increment C⁻¹ (trial − s), principal [-]
  Region region;
};

/// Return mapping of a trial state given by its principal stresses. Elastic trial states come
/// back unchanged (Region::elastic).
inline Return return_map(const Params& m, const Principal& trial) {
  const double sm = trial.sum() / 3.0;                       // Pa, σ_m^tr, tension positive
  const Principal dev = trial - Principal::Constant(sm);     // Pa, s^tr
  const double q = std::sqrt(0.5 * dev.squaredNorm());       // Pa, √J2(s^tr)
  const double phi = q + m.eta * sm - m.xi * m.c;            // Pa, Φ^tr
  const bool over_cutoff = m.cutoff && sm > m.tension;
  Return out{trial, Principal::Zero(), Region::elastic};
  if (!(phi > 0.0) && !over_cutoff) return out;
  bool done = false;
  if (phi > 0.0) {
    // Cone (Box 8.8 (i)): flow along ∂Ψ/∂σ = s / (2√J2) + (η̄/3) 1 with Ψ = √J2 + η̄ σ_m; s scales
    // radially, √J2 = √J2^tr − G Δγ, σ_m = σ_m^tr − K η̄ Δγ, and Φ = 0 gives Δγ = Φ^tr / (G + K η η̄).
    const double dgamma = phi / (m.G + m.K * m.eta * m.eta_bar);
    if (q - m.G * dgamma >= 0.0) {
      out.s = (1.0 - m.G * dgamma / q) * dev + Principal::Constant(sm - m.K * m.eta_bar * dgamma);
      out.region = Region::cone;
    } else {
      // Apex (Box 8.8 (ii), H = 0): the radial return would cross the hydrostatic axis; the state
      // goes to the apex σ_m = ξ c_f / η with s = 0 (plastic volumetric strain (σ_m^tr − apex) / K,
      // also when η̄ = 0).
      out.s = Principal::Constant(m.apex);
      out.region = Region::apex;
    }
    done = !m.cutoff || out.s.sum() / 3.0 <= m.tension;
  }
  if (!done) {
    // Cut-off plane σ_m = T (associated: volumetric flow only). At σ_m = T the cone allows
    // √J2 <= ξ c_f − η T (> 0 since T < apex); beyond it the state returns radially onto that
    // circle (both multipliers active: the cone's volumetric flow is absorbed by the cut-off's).
    const double r = m.xi * m.c - m.eta * m.tension;  // Pa, √J2 of the cone at σ_m = T
    if (q <= r) {
      out.s = dev + Principal::Constant(m.tension);
      out.region = Region::cutoff;
    } else {
      out.s = (r / q) * dev + Principal::Constant(m.tension);
      out.region = Region::cutoff_cone;
    }
  }
  out.deps_p = m.compliance(trial - out.s);
  return out;
}

/// Increment of the accumulated equivalent plastic strain: sqrt(2/3 Δε^p : Δε^p) [-].
inline double equivalent_plastic_increment(const Principal& deps_p) {
  return std::sqrt(2.0 / 3.0 * deps_p.squaredNorm());
}

}  // namespace drucker_prager
}  // namespace swmpm
