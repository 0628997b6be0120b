// Stability indicators measured on a frame: the solver library's own (solver/diagnostics/
// indicators.hpp), which every run reports in run.json's "stability", so that the suite and the
// user see the same numbers.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "scene/pointcloud.hpp"
#include "solver/diagnostics/indicators.hpp"

namespace swmpm::testing {

/// Checkerboard index of a scalar field on particles (2D; dim 3 for 3D points): the RMS deviation
/// of each value from the least-squares plane through its neighbours within `radius`, divided by
/// the field's range (diagnostics::checkerboard, with its floor of 1 % of max |value| on the
/// range). A smooth field gives ~0 (only curvature remains); a checkerboard of amplitude A over a
/// range R gives ~A/R. A run reports the same index of its pressures and stresses (with radius
/// 1.6 x the points' typical spacing, and a floor of 1 Pa, which fields of a few Pa never reach).
inline double checkerboard_indicator(const scene::PointCloud& f, const std::vector<double>& value, double radius,
                                     int dim = 2) {
  if (f.size() == 0) return 0.0;
  const diagnostics::Neighbourhood nb(f.points, dim, radius);
  return diagnostics::checkerboard(nb, value).index;
}

/// The same indicator on cell averages: the values of the points whose centre lies in one grid cell
/// (side h, lattice from `origin`) are averaged and placed at the cell centre, and the indicator is
/// taken over the cell centres within 1.6 h (the eight neighbours). For fields that are constant
/// per cell (explicit-single-point's `cell-constant` pressure), where the indicator on the points
/// would mostly measure the steps between cells; a cell checkerboard still shows.
inline double cell_checkerboard_indicator(const scene::PointCloud& f, const std::vector<double>& value, double h,
                                          double origin_x, double origin_y) {
  std::map<std::pair<long, long>, std::pair<double, int>> cells;  // ordered: a fixed summation order
  for (std::size_t p = 0; p < f.size(); ++p) {
    const auto key = std::make_pair(static_cast<long>(std::floor((f.points[p][0] - origin_x) / h)),
                                    static_cast<long>(std::floor((f.points[p][1] - origin_y) / h)));
    auto& c = cells[key];
    c.first += value[p];
    c.second += 1;
  }
  scene::PointCloud centres;
  std::vector<double> mean;
  for (const auto& [key, c] : cells) {
    centres.points.push_back({origin_x + (static_cast<double>(key.first) + 0.5) * h,
                              origin_y + (static_cast<double>(key.second) + 0.5) * h, 0.0});
    mean.push_back(c.first / c.second);
  }
  return checkerboard_indicator(centres, mean, 1.6 * h);
}

}  // namespace swmpm::testing
