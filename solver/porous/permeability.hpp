// Permeability of a porous skeleton, shared by every two-phase formulation.
//
// swmpm carries the hydraulic conductivity k [m/s] (Darcy: q = -k grad h); the intrinsic
// permeability kappa [m^2] of the seeds converts as k = kappa rho_w g / mu.
//
// Laws (scene key materials[].permeability_law):
//   constant                 k = k0
//   kozeny-carman            k = k0 [n^3 / (1 - n)^2] / [n0^3 / (1 - n0)^2]     (seed 001 step 8g: C1 from n0, k0)
//   kozeny-carman, grains    kappa = D^2 n^3 / (A (1 - n)^2),  k = kappa rho_w g / mu
//                            (seed 003 eq. 11 with D the grain diameter; seed 004 eq. 4: A = 150, D = D50)
//   xie-leo                  k = k0 J^2,  J = (1 - n0) / (1 - n)                 (incompressible grains)
#pragma once

#include <stdexcept>
#include <string>

#include "scene/scene.hpp"

namespace swmpm::porous {

constexpr double g_earth = 9.81;  // m/s^2: k = rho_w g kappa / mu, and the Darcy drag rho_w g / k

/// The initial porosity n0 of a point from its current n, V and initial V0 ((1 - n) V is constant).
inline double initial_porosity(double n, double V, double V0) { return 1.0 - (1.0 - n) * V / V0; }

/// Permeability of one solid material with its pore water.
struct Permeability {
  enum class Law { constant, kozeny_carman, kozeny_carman_grains, xie_leo };
  Law law = Law::constant;
  double k0 = 0.0;  // m/s, conductivity at the initial porosity (constant, kozeny-carman, xie-leo)
  /// kozeny-carman from the grains: D^2 / A * rho_w g / mu [m/s], so k = grains * n^3 / (1 - n)^2.
  double grains = 0.0;

  /// k [m/s] at porosity n of a point whose initial porosity was n0.
  double at(double n, double n0) const {
    switch (law) {
      case Law::constant: return k0;
      case Law::kozeny_carman: return k0 * (n * n * n / ((1 - n) * (1 - n))) / (n0 * n0 * n0 / ((1 - n0) * (1 - n0)));
      case Law::kozeny_carman_grains: return grains * (n * n * n / ((1 - n) * (1 - n)));
      case Law::xie_leo: {
        const double J = (1 - n0) / (1 - n);
        return k0 * J * J;
      }
    }
    return k0;
  }
  /// k [m/s] at a point of porosity n, volume V and initial volume V0: its n0 is computed only for
  /// the laws that read it (the per-point, per-step call of the drag scatters).
  double at_point(double n, double V, double V0) const {
    return law == Law::constant ? k0 : at(n, initial_porosity(n, V, V0));
  }
};

/// The law of a scene's permeability_law ("constant", "kozeny-carman", "xie-leo"), with k0.
inline Permeability::Law law_of(const std::string& name) {
  return name == "kozeny-carman" ? Permeability::Law::kozeny_carman
         : name == "xie-leo"     ? Permeability::Law::xie_leo
                                 : Permeability::Law::constant;
}

/// Hydraulic conductivity [m/s] the scene gives a solid material whose pore water is `fluid`:
/// hydraulic_conductivity, or intrinsic_permeability rho_w g / mu. A saturated skeleton needs one.
inline double conductivity_of(const scene::Material& solid, const scene::Material& fluid) {
  double k = solid.has("hydraulic_conductivity") ? solid.at("hydraulic_conductivity") : 0.0;
  if (k == 0.0 && solid.has("intrinsic_permeability"))
    k = solid.at("intrinsic_permeability") * fluid.at("density") * g_earth / fluid.at("dynamic_viscosity");
  if (!(k > 0.0))
    throw std::runtime_error("material \"" + solid.name +
                             "\": a saturated skeleton needs hydraulic_conductivity or intrinsic_permeability");
  return k;
}

/// The permeability law of a solid material with its pore water `fluid`, as the scene gives it.
inline Permeability permeability_of(const scene::Material& solid, const scene::Material& fluid) {
  Permeability p;
  if (solid.has("grain_diameter")) {
    // Seed 003 eq. 11 with A = ergun_a: at the current porosity (kozeny-carman) or held at the
    // initial porosity's value (constant: the drag study's case (a)).
    const double D = solid.at("grain_diameter"), A = solid.has("ergun_a") ? solid.at("ergun_a") : 150.0;
    p.law = Permeability::Law::kozeny_carman_grains;
    p.grains = D * D / A * fluid.at("density") * g_earth / fluid.at("dynamic_viscosity");
    const double n0 = solid.at("porosity");
    p.k0 = p.at(n0, n0);
    if (solid.permeability_law != "kozeny-carman") p.law = Permeability::Law::constant;
    return p;
  }
  p.k0 = conductivity_of(solid, fluid);
  p.law = law_of(solid.permeability_law);
  return p;
}

}  // namespace swmpm::porous
