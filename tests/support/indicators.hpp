// Stability indicators measured on a frame.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
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
  // Neighbours through square bins of side `radius` (the 3 x 3 bins around a point hold every
  // point within the radius), visited in increasing index as a plain scan would.
  double x0 = f.points[0][0], y0 = f.points[0][1], x1 = x0, y1 = y0;
  for (const auto& q : f.points) {
    x0 = std::min(x0, q[0]), x1 = std::max(x1, q[0]);
    y0 = std::min(y0, q[1]), y1 = std::max(y1, q[1]);
  }
  const int nx = static_cast<int>((x1 - x0) / radius) + 1, ny = static_cast<int>((y1 - y0) / radius) + 1;
  auto bin = [&](double x, double y) {
    return std::pair<int, int>(std::min(nx - 1, static_cast<int>((x - x0) / radius)),
                               std::min(ny - 1, static_cast<int>((y - y0) / radius)));
  };
  std::vector<std::vector<std::size_t>> bins(static_cast<std::size_t>(nx) * ny);
  for (std::size_t q = 0; q < n; ++q) {
    const auto [i, j] = bin(f.points[q][0], f.points[q][1]);
    bins[static_cast<std::size_t>(j) * nx + i].push_back(q);
  }
  double sum = 0.0;
  std::size_t count = 0;
  std::vector<std::size_t> near;
  for (std::size_t p = 0; p < n; ++p) {
    near.clear();
    const auto [bi, bj] = bin(f.points[p][0], f.points[p][1]);
    for (int j = std::max(0, bj - 1); j <= std::min(ny - 1, bj + 1); ++j)
      for (int i = std::max(0, bi - 1); i <= std::min(nx - 1, bi + 1); ++i)
        for (std::size_t q : bins[static_cast<std::size_t>(j) * nx + i]) near.push_back(q);
    std::sort(near.begin(), near.end());
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int neighbours = 0;
    for (std::size_t q : near) {
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
