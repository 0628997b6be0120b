// The seepage layer of examples/seepage-double-point, shared by its verification and its hard
// case: a fixed gravel layer (L = 0.2 m, n = 0.4, grains D) under a pond of H = 0.4 m that drains
// through it into the empty chamber below. The pond's top point falls at the flux q; over a time
// window q is compared with Darcy, q = k i, and with the root of the quadratic drag balance
// rho g i = (mu / kappa) q + beta rho q^2 (Ergun, beta = B / sqrt(kappa A n^3), seed 003 eqs. 9-10),
// i = (H + L) / L at the window's mean pond depth, kappa = D^2 n^3 / (150 (1 - n)^2) (eq. 11).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>

#include "postprocess/postprocess.hpp"

namespace swmpm::testing {

struct SeepageFlux {
  double q, q_darcy, q_ergun;
  double inertial_over_viscous;  // beta rho q / (mu / kappa) at the measured q
};

/// From RUN/monitors.csv's `pond_top.displacement_y` over [t0, t1] (the rows nearest them).
inline SeepageFlux seepage_flux(const std::string& run, double D, double t0, double t1) {
  const auto tab = post::read_csv(run + "/monitors.csv");
  const auto& t = tab.column("time");
  const auto& d = tab.column("pond_top.displacement_y");
  auto nearest = [&](double at) {
    return static_cast<std::size_t>(std::min_element(t.begin(), t.end(), [&](double a, double b) {
                                      return std::abs(a - at) < std::abs(b - at);
                                    }) - t.begin());
  };
  const std::size_t a = nearest(t0), b = nearest(t1);
  const double n = 0.4, L = 0.2, mu = 1e-3, rho = 1000, g = 9.81;
  const double kappa = D * D / 150 * n * n * n / ((1 - n) * (1 - n)), beta = 1.75 / std::sqrt(kappa * 150 * n * n * n);
  const double q = (d[a] - d[b]) / (t[b] - t[a]);
  const double H = 0.4 + 0.5 * (d[a] + d[b]), i = (H + L) / L;
  const double q_darcy = kappa * rho * g / mu * i;
  const double q_ergun = (-mu / kappa + std::sqrt(std::pow(mu / kappa, 2) + 4 * beta * rho * rho * g * i)) / (2 * beta * rho);
  return {q, q_darcy, q_ergun, beta * rho * q / (mu / kappa)};
}

}  // namespace swmpm::testing
