// Soil–water drag, shared by every two-phase formulation: the drag laws and the implicit
// solve of the two phases' nodal momenta coupled by the drag.
//
// A drag law gives the coefficient c [kg/(m^3 s)] of the interaction force per unit mixture
// volume on the water, f_d = -c (v_w - v_s) (and +c (v_w - v_s) on the soil), with n the
// porosity, kappa the intrinsic permeability [m^2], mu the water's dynamic viscosity [Pa s],
// rho_w its density and w = |v_w - v_s| [m/s]:
//   darcy        c = n^2 mu / kappa = n^2 rho_w g / k                           (seed 000 eq. 12, seed 003 eq. 5)
//   ergun        c = n^2 mu / kappa + beta n^3 rho_w w,  beta = B / sqrt(kappa A n^3)  (seed 003 eqs. 9-10)
//   forchheimer  c = n^2 [mu / kappa + B rho_w w / (sqrt(A kappa) n^(3/2))]      (seed 004 eq. 3: A = 150, B = 1.75)
// (The sigma_L . grad n part of seed 003 eq. 9 is a stress term, not a drag coefficient.)
#pragma once

#include <cmath>

#include "solver/common.hpp"
#include "solver/porous/permeability.hpp"

namespace swmpm::porous {

/// Darcy drag coefficient n^2 rho_w g / k [kg/(m^3 s)] from the hydraulic conductivity k [m/s].
inline double darcy_drag(double n, double rho_w, double k) { return n * n * rho_w * g_earth / k; }

/// The drag impulse coefficient of a node, dt Q with Q = g n_I M_w / k_I [kg] (seed 001 eq. 58:
/// the Darcy law with the nodal porosity, water mass and conductivity).
inline double darcy_drag_impulse(double dt, double n, double M_w, double k) { return dt * g_earth * n * M_w / k; }

/// A drag law of the scene (Darcy, or one of the non-linear laws of the double-point seeds).
struct DragLaw {
  enum class Kind { darcy, ergun, forchheimer };
  Kind kind = Kind::darcy;
  double A = 150.0;  // -, Ergun's constant of the viscous term (and of Kozeny–Carman)
  double B = 1.75;   // -, Ergun's constant of the inertial term

  /// c [kg/(m^3 s)] at porosity n, intrinsic permeability kappa [m^2], viscosity mu [Pa s],
  /// water density rho_w [kg/m^3] and relative speed w = |v_w - v_s| [m/s].
  double coefficient(double n, double kappa, double mu, double rho_w, double w) const {
    const double viscous = n * n * mu / kappa;
    switch (kind) {
      case Kind::darcy: return viscous;
      case Kind::ergun: {
        const double beta = B / std::sqrt(kappa * A * n * n * n);  // 1/m, eq. 10
        return viscous + beta * n * n * n * rho_w * w;
      }
      case Kind::forchheimer: return n * n * (mu / kappa + B * rho_w * w / (std::sqrt(A * kappa) * std::pow(n, 1.5)));
    }
    return viscous;
  }
};

/// One node's two momentum equations with the drag implicit in both velocities:
///   (M_w + a) v_w - a v_s = A_w,   (M_s + a) v_s - a v_w = A_s,
/// with a = dt Q the drag impulse coefficient [kg] and A = M v^t + dt f each phase's momentum
/// after the other forces [kg m/s]. det = M_w M_s + a (M_w + M_s) (no cancellation for a stiff
/// drag); the mixture's momentum A_w + A_s is conserved, and the relative velocity is damped,
/// never amplified, however large a is. Both masses must be positive.
template <int Dim>
struct DragSolution {
  Vec<Dim> v_s, v_w;
};
template <int Dim>
inline DragSolution<Dim> solve_drag(double M_s, double M_w, double a, const Vec<Dim>& A_s, const Vec<Dim>& A_w) {
  const double det = M_w * M_s + a * (M_w + M_s);
  return {((M_w + a) * A_s + a * A_w) / det, ((M_s + a) * A_w + a * A_s) / det};
}

}  // namespace swmpm::porous
