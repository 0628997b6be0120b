// Stability indicators measured on a frame.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "scene/pointcloud.hpp"

namespace swmpm::testing {

/// Checkerboard indicator of a scalar field on particles (2D): the RMS deviation of each value from
/// the least-squares plane a + b x + c y through its neighbours within `radius`, divided by the
/// field's range (max - min). A smooth field gives ~0 (only curvature remains); a checkerboard of
/// amplitude A over a range R gives ~A/R.
inline double checkerboard_indicator(const scene::PointCloud& f, const std::vector<double>& value, double radius) {
  const std::size_t n = f.size();
  const auto [lo, hi] = std::minmax_element(value.begin(), value.end());
  const double range = *hi - *lo;
  if (!(range > 0.0)) return 0.0;
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t p = 0; p < n; ++p) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int neighbours = 0;
    for (std::size_t q = 0; q < n; ++q) {
      const double dx = f.points[q][0] - f.points[p][0], dy = f.points[q][1] - f.points[p][1];
      if (q == p || dx * dx + dy * dy > radius * radius) continue;
      const Eigen::Vector3d row(1.0, dx, dy);
      A += row * row.transpose();
      b += row * value[q];
      ++neighbours;
    }
    if (neighbours < 6) continue;  // edges and corners: too few points for a fit
    const double fit = A.ldlt().solve(b)[0];
    sum += (value[p] - fit) * (value[p] - fit);
    ++count;
  }
  return count ? std::sqrt(sum / static_cast<double>(count)) / range : 0.0;
}

}  // namespace swmpm::testing
