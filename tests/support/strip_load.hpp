// A3 (seed 000 §4.2), the strip-load consolidation of examples/strip-load-consolidation: one run
// and what the verification and stability tests read from it.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>

#include "support/indicators.hpp"
#include "support/run_helpers.hpp"

namespace swmpm::testing {

struct StripLoadRun {
  int status = -1;
  double corner_uy = 0.0;     // m, corner monitor displacement_y at the end (negative: settlement)
  double corner_max = 0.0;    // m, largest |displacement_y| of the corner monitor over the run
  double corner_late = 0.0;   // m, mean displacement_y of the corner monitor over the second half
  double max_abs_p = 0.0;     // Pa, largest |p| over every frame
  bool finite = true;         // every p, velocity and displacement of every frame finite
  double checkerboard = 0.0;  // of p in the last frame
};

/// Runs examples/strip-load-consolidation/`file` with the given stabilisation on one thread.
/// `radius` of the checkerboard fit: 1.6 lattice spacings of the scene. `continuity`: the scene's
/// solver.continuity (empty: the formulation's default).
inline StripLoadRun run_strip_load(const std::string& file, const std::string& pressure, bool smoothing, double radius,
                                   const std::string& name, const std::string& continuity = "") {
  nlohmann::json s = load_json(std::string(SWMPM_SOURCE_DIR "/examples/strip-load-consolidation/") + file);
  s["solver"]["stabilisation"] = {{"pressure", pressure}, {"strain_smoothing", smoothing}};
  if (!continuity.empty()) s["solver"]["continuity"] = continuity;
  StripLoadRun r;
  const std::string run = run_scene(s, name, 1, &r.status);
  const auto t = post::read_csv(run + "/monitors.csv");
  const auto& time = t.column("time");
  const auto& uy = t.column("corner.displacement_y");
  const double end = time.back();
  int late = 0;
  for (std::size_t k = 0; k < uy.size(); ++k) {
    r.corner_max = std::max(r.corner_max, std::abs(uy[k]));
    if (time[k] >= 0.5 * end) {
      r.corner_late += uy[k];
      ++late;
    }
  }
  r.corner_late /= std::max(late, 1);
  r.corner_uy = uy.back();
  const auto entries = scene::read_pvd(run + "/output/results.pvd");
  for (const auto& e : entries) {
    const auto f = scene::read_vtu(run + "/output/" + e.file);
    for (const char* name_of : {"velocity", "displacement", "pore_pressure"})
      for (double v : f.get(name_of, e.file).values) r.finite = r.finite && std::isfinite(v);
    for (double p : f.get("pore_pressure", e.file).values) r.max_abs_p = std::max(r.max_abs_p, std::abs(p));
  }
  const auto f = last_frame(run);
  r.checkerboard = checkerboard_indicator(f, f.get("pore_pressure", "last frame").values, radius);
  std::printf(
      "A3 %s, %s, smoothing %d: status %d, corner u_y %.4f mm at t = %.3f s (max %.4f, mean of the second "
      "half %.4f), max |p| %.0f Pa, checkerboard %.4f\n",
      file.c_str(), pressure.c_str(), smoothing ? 1 : 0, r.status, 1e3 * r.corner_uy, end, 1e3 * r.corner_max,
      1e3 * r.corner_late, r.max_abs_p, r.checkerboard);
  return r;
}

}  // namespace swmpm::testing
