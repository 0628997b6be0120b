// Coincident soil and water points of the double-point formulations: preprocess seeds the water
// of a saturated body on the soil's lattice, so each such water point has a soil point at the
// same initial position. An initialisation phase ties them (seed 001 §5.4: the points do not seep
// while gravity grows).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "solver/particles/particles.hpp"

namespace swmpm::porous {

/// For each water-point id, the id of the soil point whose initial position x0 is the same
/// (bitwise), -1 for free water. O((N_s + N_w) log N_s).
template <int Dim>
std::vector<std::int64_t> coincident_points(const ParticleSet<Dim>& soil, const ParticleSet<Dim>& water) {
  auto less = [](const Vec<Dim>& a, const Vec<Dim>& b) {
    return std::lexicographical_compare(a.data(), a.data() + Dim, b.data(), b.data() + Dim);
  };
  std::vector<int> order(soil.size());
  for (std::size_t p = 0; p < soil.size(); ++p) order[p] = static_cast<int>(p);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return less(soil.x0[a], soil.x0[b]); });
  std::int64_t max_id = -1;
  for (auto id : water.id) max_id = std::max(max_id, id);
  std::vector<std::int64_t> out(static_cast<std::size_t>(max_id + 1), -1);
  for (std::size_t w = 0; w < water.size(); ++w) {
    const auto it = std::lower_bound(order.begin(), order.end(), water.x0[w],
                                     [&](int q, const Vec<Dim>& x) { return less(soil.x0[q], x); });
    if (it != order.end() && soil.x0[*it] == water.x0[w]) out[water.id[w]] = soil.id[*it];
  }
  return out;
}

/// Each water point with a partner takes its soil point's position (partner: per water-point id,
/// the soil point's id; soil_index_of_id: the soil points' current index of each id). The
/// velocities stay the water's own. Returns the first water point whose partner this process does
/// not hold (-1: none; under mpirun a tied pair has one position and one support, so one rank
/// holds both).
template <int Dim>
long tie_positions(const ParticleSet<Dim>& soil, const std::vector<int>& soil_index_of_id,
                   const std::vector<std::int64_t>& partner, ParticleSet<Dim>& water) {
  const long n = static_cast<long>(water.size());
  long missing = n;
#pragma omp parallel for schedule(static) reduction(min : missing) if (n > parallel_threshold)
  for (long p = 0; p < n; ++p) {
    const std::int64_t sid = partner[water.id[p]];
    if (sid < 0) continue;
    if (const int q = soil_index_of_id[sid]; q >= 0) water.x[p] = soil.x[q];
    else missing = std::min(missing, p);
  }
  return missing == n ? -1 : missing;
}

/// Each water point with a partner takes its soil point's velocity; returns as tie_positions.
template <int Dim>
long tie_velocities(const ParticleSet<Dim>& soil, const std::vector<int>& soil_index_of_id,
                    const std::vector<std::int64_t>& partner, ParticleSet<Dim>& water) {
  long missing = -1;
  for (std::size_t p = 0; p < water.size(); ++p) {
    const std::int64_t sid = partner[water.id[p]];
    if (sid < 0) continue;
    if (const int q = soil_index_of_id[sid]; q >= 0) water.v[p] = soil.v[q];
    else if (missing < 0) missing = static_cast<long>(p);
  }
  return missing;
}

}  // namespace swmpm::porous
