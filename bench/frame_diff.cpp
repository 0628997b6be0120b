// frame_diff A.vtu B.vtu: the largest difference between two frames of the same run, per point
// array, relative to that array's largest magnitude in A (and of the positions, relative to the
// extent of A's points). Prints one line per array that differs, with the point (in A) where the
// difference is largest, and, last, "max_relative R".
// bench/bitwise.py uses it to say by how much a case whose hashes moved differs. Points are matched
// by their `id` array where both frames have one (a .pvtu of a run on several ranks holds them in
// another order than the one-rank .vtu), else by position in the file.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>

#include "scene/pointcloud.hpp"

namespace {
/// The largest |a - b| relative to max |a|; `at`: the value index where it is.
double relative(const std::vector<double>& a, const std::vector<double>& b, std::size_t& at) {
  double scale = 0.0, diff = 0.0;
  at = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    scale = std::max(scale, std::abs(a[i]));
    if (std::abs(a[i] - b[i]) > diff) diff = std::abs(a[i] - b[i]), at = i;
  }
  return scale > 0.0 ? diff / scale : diff;
}
/// The cloud with its points in increasing `id` (unchanged without an id array).
swmpm::scene::PointCloud by_id(swmpm::scene::PointCloud c) {
  const auto* id = c.find("id");
  if (!id) return c;
  std::vector<std::size_t> order(c.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return id->values[x] < id->values[y]; });
  auto points = c.points;
  for (std::size_t k = 0; k < order.size(); ++k) c.points[k] = points[order[k]];
  for (auto& arr : c.arrays) {
    const auto values = arr.values;
    const auto n = static_cast<std::size_t>(arr.components);
    for (std::size_t k = 0; k < order.size(); ++k)
      for (std::size_t j = 0; j < n; ++j) arr.values[k * n + j] = values[order[k] * n + j];
  }
  return c;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: frame_diff A.vtu B.vtu\n");
    return 2;
  }
  try {
    const auto a = by_id(swmpm::scene::read_vtu(argv[1])), b = by_id(swmpm::scene::read_vtu(argv[2]));
    if (a.size() != b.size() || a.arrays.size() != b.arrays.size()) {
      std::printf("structure differs: %zu/%zu points, %zu/%zu arrays\nmax_relative inf\n", a.size(), b.size(),
                  a.arrays.size(), b.arrays.size());
      return 1;
    }
    std::vector<double> pa, pb;
    for (std::size_t p = 0; p < a.size(); ++p)
      for (int d = 0; d < 3; ++d) {
        pa.push_back(a.points[p][d]);
        pb.push_back(b.points[p][d]);
      }
    // Each line: the array, its largest relative difference and the point where it is (x y z in A).
    auto where = [&](std::size_t p) {
      std::printf(" at %.6g %.6g %.6g\n", a.points[p][0], a.points[p][1], a.points[p][2]);
    };
    std::size_t at = 0;
    double worst = relative(pa, pb, at);
    if (worst > 0) std::printf("points %.3e", worst), where(at / 3);
    for (const auto& arr : a.arrays) {
      const auto* other = b.find(arr.name);
      if (!other || other->values.size() != arr.values.size()) {
        std::printf("%s missing or resized\nmax_relative inf\n", arr.name.c_str());
        return 1;
      }
      const double r = relative(arr.values, other->values, at);
      if (r > 0) std::printf("%s %.3e", arr.name.c_str(), r), where(at / static_cast<std::size_t>(arr.components));
      worst = std::max(worst, r);
    }
    std::printf("max_relative %.3e\n", worst);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "frame_diff: %s\n", e.what());
    return 2;
  }
}
