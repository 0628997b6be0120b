// The dam break of examples/dam-break-mpm-fem against Martin & Moyce (1952), Table 2: the surge
// front of each grid frame (phi = 1/2 on the lowest row of nodes) over T = t sqrt(2 g / a) >= 1.
// Shared by the verification test and the largest-stable-step hard case.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "postprocess/postprocess.hpp"
#include "scene/pointcloud.hpp"

namespace swmpm::testing {

/// The surge front of a grid frame: the largest x where phi = 1/2 on the lowest row of nodes above
/// the floor (y = h/2), interpolated between the nodes.
inline double front_of(const scene::PointCloud& grid, double h) {
  const auto* phi = grid.find("phase_field");
  std::vector<std::pair<double, double>> row;  // (x, phi)
  for (std::size_t i = 0; i < grid.points.size(); ++i)
    if (std::abs(grid.points[i][1] - 0.5 * h) < 1e-9) row.emplace_back(grid.points[i][0], phi->values[i]);
  std::sort(row.begin(), row.end());
  for (std::size_t k = row.size() - 1; k > 0; --k)
    if (row[k - 1].second >= 0.5 && row[k].second < 0.5)
      return row[k - 1].first + (row[k - 1].second - 0.5) / (row[k - 1].second - row[k].second) * (row[k].first - row[k - 1].first);
  return row.empty() || row.back().second < 0.5 ? 0.0 : row.back().first;
}

struct FrontError {
  int compared = 0;     // frames compared
  double worst = 0.0;   // largest |x/a - Z| / Z
  double phi_lo = 1.0, phi_hi = 0.0;  // the phase field's range over the frames
  std::vector<double> x_over_a;  // the front of each frame compared, x / a
};

/// The run's fronts against the table (a = 57.15 mm, h = a/10, g = 9.81), printed with `label`.
inline FrontError dam_break_front_error(const std::string& run, const std::string& reference, const char* label) {
  const auto mm = post::read_reference(reference);
  const double a = 0.05715, g = 9.81, h = 0.005715;
  FrontError out;
  for (const auto& e : scene::read_pvd(run + "/output/results.pvd")) {
    if (e.group != "grid") continue;
    const auto grid = scene::read_vtu(run + "/output/" + e.file);
    for (double v : grid.find("phase_field")->values) out.phi_lo = std::min(out.phi_lo, v), out.phi_hi = std::max(out.phi_hi, v);
    const double T = e.time * std::sqrt(2 * g / a);
    if (T < 1.0 || T > mm.t.back()) continue;
    const double x = front_of(grid, h);
    double Z = 0.0;
    for (std::size_t k = 1; k < mm.t.size(); ++k)
      if (T <= mm.t[k]) {
        Z = mm.v[k - 1] + (mm.v[k] - mm.v[k - 1]) * (T - mm.t[k - 1]) / (mm.t[k] - mm.t[k - 1]);
        break;
      }
    const double err = (x / a - Z) / Z;
    std::printf("%s: T = %.2f, x/a = %.3f, Martin & Moyce %.3f (%+.1f %%)\n", label, T, x / a, Z, 100 * err);
    out.worst = std::max(out.worst, std::abs(err));
    out.x_over_a.push_back(x / a);
    ++out.compared;
  }
  return out;
}

}  // namespace swmpm::testing
