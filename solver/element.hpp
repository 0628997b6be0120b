// `swmpm element`: one material point driven by deformation-gradient increments through the
// solver's own constitutive models (calibration and checks of a scene's material; interface.md §1).
//
// Axes: z is the axial direction, x and y are lateral (radial). Signs as geotechnical practice:
// compression positive for stresses and strains. The point starts at the isotropic effective stress
// p0 (Cauchy σ = −p0 I) with F = I; each of `steps` equal increments of axial strain sets F_{n+1},
// the velocity gradient L over dt = 1 that the solver would have (ΔF = (I − L/2)⁻¹(I + L/2)), and
// calls MaterialModel<3>::update_stress once.
//  - oedometer:          F = diag(1, 1, 1 − ε_a) (lateral strain zero);
//  - undrained-triaxial: F = diag(λ^-1/2, λ^-1/2, λ), λ = 1 − ε_a (isochoric, J = 1);
//  - drained-triaxial:   F = diag(r, r, 1 − ε_a) with r solved each step (Newton, finite-difference
//                        tangent, every trial from the same saved state σ_n, F_n) so that the
//                        lateral stress stays −p0: conventional triaxial compression, Δq = 3Δp.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace swmpm {

enum class ElementTest { drained_triaxial, undrained_triaxial, oedometer };

/// "drained-triaxial" | "undrained-triaxial" | "oedometer"; throws std::invalid_argument otherwise.
ElementTest parse_element_test(const std::string& name);
std::string to_string(ElementTest t);

/// One row per state, the initial state first (steps + 1 rows). Compression positive, Pa.
struct ElementResult {
  std::string material, model;
  ElementTest test = ElementTest::oedometer;
  double p0 = 0.0;
  std::vector<double> axial_strain;       // 1 − F_zz [-]
  std::vector<double> p;                  // mean effective stress −tr σ / 3
  std::vector<double> q;                  // deviator stress σ_a − σ_r (positive in compression)
  std::vector<double> volumetric_strain;  // 1 − det F [-]
  std::vector<double> axial_stress;       // −σ_zz
  std::vector<double> radial_stress;      // −(σ_xx + σ_yy) / 2
  std::vector<double> radial_strain;      // 1 − F_xx [-]
  // Quantities the model reports besides the stress (MaterialModel::report_names: Nor-Sand's
  // specific_volume and state_parameter), one column per name.
  std::vector<std::string> state_names;
  std::vector<std::vector<double>> state_columns;
  std::size_t size() const { return axial_strain.size(); }
};

/// Runs the test on the scene's material `material`. Throws std::invalid_argument for wrong input
/// (unknown material name — the message lists the scene's materials —, a fluid material, p0 <= 0,
/// |axial_strain| >= 1, steps < 1) and std::runtime_error when the model fails (J <= 0, non-finite
/// stress) or the drained lateral-stress iteration does not converge.
ElementResult run_element(const scene::Scene& scene, const std::string& material, ElementTest test, double p0,
                          double axial_strain, int steps);

}  // namespace swmpm
