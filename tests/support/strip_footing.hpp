// B6 (seed 001 App. A), the elastic strip footing of examples/strip-footing-fbar: one MPM run of a
// variant (shape function, F-bar mode, patch size, cell size) and what the verification and
// stability tests measure on its last frame, against the independent Q2/P1 finite-element
// solution of support/strip_footing_fe.hpp.
#pragma once

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "support/indicators.hpp"
#include "support/run_helpers.hpp"
#include "support/strip_footing_fe.hpp"

namespace swmpm::testing {

struct StripFootingRun {
  int status = -1;
  double settlement = 0.0;      // m, -u_y of the particle at the footing centre (0.05, 9.95 at h = 0.2)
  double settlement_fe = 0.0;   // m, the FE's at the same point
  double settlement_error = 0.0;  // -, settlement / settlement_fe - 1
  double syy_error = 0.0;       // -, RMS over the centreline column (x0 < h/2) of (σ_yy − σ_yy^FE) / q
  double p_error = 0.0;         // -, RMS over every particle of (p − p^FE) / q
  double checkerboard = 0.0;    // of p on the last frame (support/indicators.hpp, radius 1.6 spacings)
  double checkerboard_fe = 0.0;  // of p^FE at the particles (the smooth field's own floor)
  double us_per_particle_step = 0.0;
};

constexpr double kFootingLoad = 2.0e4;  // Pa

/// The finite-element reference, built once (80 x 80 elements of 0.125 m: the settlement changes by
/// 4e-6 relative from 40 x 40).
inline const StripFootingFE& strip_footing_fe() {
  static const StripFootingFE fe(10.0, 10.0, 3.0, kFootingLoad, 1.0e7, 0.49, 80);
  return fe;
}

/// Runs examples/strip-footing-fbar/scene.json with the given variant on one thread. patch <= 0:
/// no fbar_patch key (the default by shape function); damping < 0: the scene's; end <= 0: the scene's.
inline StripFootingRun run_strip_footing(const std::string& shape, const std::string& fbar, double patch,
                                         double cell, const std::string& name, double damping = -1.0,
                                         double end = 0.0) {
  nlohmann::json s = load_json(SWMPM_SOURCE_DIR "/examples/strip-footing-fbar/scene.json");
  s["grid"]["shape_function"] = shape;
  s["grid"]["cell_size"] = cell;
  s["grid"]["max"] = {10.0, 10.0 + 2.0 * cell};
  s["solver"]["stabilisation"] = {{"fbar", fbar}};
  if (patch > 0.0) s["solver"]["stabilisation"]["fbar_patch"] = patch;
  if (damping >= 0.0) s["solver"]["damping"] = damping;
  if (end > 0.0) s["time"]["end"] = end;
  s["output"]["interval"] = 0.0;  // first and last frame only
  StripFootingRun r;
  const std::string run = run_scene(s, name, 1, &r.status);
  r.us_per_particle_step = load_json(run + "/run.json")["us_per_particle_step"].get<double>();
  const auto f = last_frame(run);
  const auto& u = f.get("displacement", name).values;
  const auto& sigma = f.get("stress", name).values;
  const auto& p = f.get("mean_effective_stress", name).values;
  const StripFootingFE& fe = strip_footing_fe();
  const double q = kFootingLoad;
  std::vector<double> p_fe(f.size());
  double best = std::numeric_limits<double>::max(), sum_p = 0.0, sum_s = 0.0;
  int column = 0;
  for (std::size_t k = 0; k < f.size(); ++k) {
    // FE at the initial position (small strain: displacements are < 1 % of the particle spacing).
    const double x0 = f.points[k][0] - u[3 * k], y0 = f.points[k][1] - u[3 * k + 1];
    const auto st = fe.stress(x0, y0);
    p_fe[k] = st.mean();
    sum_p += (p[k] - p_fe[k]) * (p[k] - p_fe[k]);
    if (x0 < 0.5 * cell) {
      sum_s += (sigma[6 * k + 1] - st.yy) * (sigma[6 * k + 1] - st.yy);
      ++column;
    }
    const double d = x0 * x0 + (10.0 - y0) * (10.0 - y0);
    if (d < best) {
      best = d;
      r.settlement = -u[3 * k + 1];
      r.settlement_fe = -fe.displacement(x0, y0)[1];
    }
  }
  r.settlement_error = r.settlement / r.settlement_fe - 1.0;
  r.p_error = std::sqrt(sum_p / static_cast<double>(f.size())) / q;
  r.syy_error = std::sqrt(sum_s / std::max(column, 1)) / q;
  const double radius = 1.6 * cell / 2.0;  // 1.6 lattice spacings (2 particles per cell)
  r.checkerboard = checkerboard_indicator(f, p, radius);
  r.checkerboard_fe = checkerboard_indicator(f, p_fe, radius);
  std::printf(
      "B6 %s, fbar %s, patch %.2g, h %.3g m, damping %.2g: status %d, settlement %.4f mm (FE %.4f, error %+.2f %%), "
      "sigma_yy centreline RMS %.4f q, p RMS %.4f q, checkerboard %.4f (FE field %.4f), %.3f us/particle-step\n",
      shape.c_str(), fbar.c_str(), patch, cell, s["solver"]["damping"].get<double>(), r.status, 1e3 * r.settlement, 1e3 * r.settlement_fe,
      100.0 * r.settlement_error, r.syy_error, r.p_error, r.checkerboard, r.checkerboard_fe, r.us_per_particle_step);
  return r;
}

}  // namespace swmpm::testing
