// The stability indicators of a frame measured over the ranks (diagnostics::measure under mpirun):
// each rank holds a share of the sets, measures its own points with copies of the other ranks'
// points near them, and the parts are reduced. Whatever the split, the indicators are those of the
// whole set: the same points found (ties go to the smaller key, as the one-rank loop finds them
// first), the same values (the checkerboard's sum of squares differs in its order: round-off).
//
// Each rank builds the whole frame itself (a lattice with a rough stress patch, a cavitating patch,
// a moving part and a part at rest), then keeps a share of it: interleaved strips 0.03 m wide,
// narrower than the neighbourhood's radius (0.04 m), so that a point's neighbours lie on several
// ranks. The answer to match: the same measure with every point on rank 0 (the others empty), and
// the one-rank measures of indicators.hpp on the whole set.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>

#include "solver/diagnostics/indicators.hpp"
#include "solver/diagnostics/stability.hpp"
#include "solver/parallel/comm.hpp"
#include "solver/parallel/domain.hpp"

namespace swmpm::diagnostics {
namespace {

constexpr double kSpacing = 0.025;  // m

/// A lattice of points of spacing kSpacing (V0 = spacing^Dim) over [0, 1] x [0, 0.4] (x [0, 0.15]):
/// the left third at rest (displacement 0, slow), the rest displaced and moving; a smooth mean
/// stress with a checkerboard patch; porosity and J varying; water pressure below -100 kPa in a
/// patch; ids scrambled (places are reported by id).
template <int Dim>
State<Dim> frame(bool water_points) {
  State<Dim> s;
  ParticleSet<Dim>& ps = s.solid;
  const int nx = 40, ny = 16, nz = Dim == 3 ? 6 : 1;
  const std::size_t n = static_cast<std::size_t>(nx * ny * nz);
  if (!water_points) ps.add_fluid();
  ps.resize(n);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  std::size_t p = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i, ++p) {
        Vec<Dim> x = Vec<Dim>::Zero();
        x[0] = (i + 0.5) * kSpacing, x[1] = (j + 0.5) * kSpacing;
        if constexpr (Dim == 3) x[2] = (k + 0.5) * kSpacing;
        const bool moving = x[0] > 0.35;
        ps.id[p] = static_cast<std::int64_t>((p * 7919) % n) + 100;
        ps.x0[p] = x;
        ps.x[p] = x;
        if (moving) ps.x[p][0] += 0.01 * (x[0] - 0.35) + 1e-4 * jitter(rng);
        ps.v[p] = Vec<Dim>::Zero();
        ps.v[p][0] = moving ? 0.5 * x[0] : 1e-3 * (1.0 + jitter(rng));
        ps.V0[p] = std::pow(kSpacing, Dim);
        ps.V[p] = ps.V0[p] * (1.0 + 0.02 * std::sin(7.0 * x[0]) + 0.01 * (i == 23 && j == 5));
        const bool rough = x[0] > 0.5 && x[0] < 0.7 && x[1] > 0.1 && x[1] < 0.3;
        const double sm = 1e4 * (1.0 + x[0] + 0.4 - x[1]) + (rough ? 800.0 * ((i + j + k) % 2 ? 1.0 : -1.0) : 0.0);
        ps.sigma[p] = Sym::Zero();
        for (int a = 0; a < 3; ++a) ps.sigma[p][a] = -sm;
        if (!water_points) {
          ps.n[p] = 0.4 + 0.05 * std::cos(5.0 * x[1]) + 0.001 * jitter(rng);
          ps.p[p] = x[0] > 0.8 && x[1] < 0.1 ? -1.5e5 : 1e4 * (0.4 - x[1]) + 300.0 * jitter(rng);
          ps.m_f[p] = x[1] > 0.37 ? 0.0 : 1.0;  // the top row dry
        }
      }
  if (water_points) {  // double-point: the water on its own points, a copy of the lattice's lower half
    ParticleSet<Dim>& w = s.fluid;
    w.make_water_points();
    w.add_fluid();
    std::size_t m = 0;
    for (std::size_t q = 0; q < n; ++q) m += ps.x0[q][1] < 0.2;
    w.resize(m);
    for (std::size_t q = 0, k = 0; q < n; ++q) {
      if (!(ps.x0[q][1] < 0.2)) continue;
      w.id[k] = ps.id[q];
      w.x[k] = ps.x[q], w.x0[k] = ps.x0[q], w.v[k] = ps.v[q];
      w.V0[k] = w.V[k] = ps.V0[q];
      w.n[k] = 0.4;
      w.p[k] = ps.x[q][0] > 0.8 && ps.x[q][1] < 0.1 ? -1.5e5 : 1e4 * (0.2 - ps.x[q][1]) + 300.0 * jitter(rng);
      ++k;
    }
  }
  s.time = 0.5;
  return s;
}

/// This rank's share of `whole`: `interleaved` the strips of 0.03 m by x0 in turn, else all on rank 0.
/// Keys: the index in the whole set (the one-rank storage order).
template <int Dim>
ParticleSet<Dim> share(const ParticleSet<Dim>& whole, bool interleaved) {
  ParticleSet<Dim> mine = whole;
  const std::size_t n = whole.size();
  mine.key.resize(n);
  std::iota(mine.key.begin(), mine.key.end(), std::int64_t{0});
  std::vector<int> keep;
  for (std::size_t p = 0; p < n; ++p) {
    const int strip = static_cast<int>(std::floor(whole.x0[p][0] / 0.03));
    const int owner = interleaved ? strip % parallel::ranks() : 0;
    if (owner == parallel::rank()) keep.push_back(static_cast<int>(p));
  }
  parallel::FieldBytes layout;  // every field the set carries
  mine.for_each_field([&](auto& f) { layout.active.push_back(n > 0 && f.size() == n); });
  parallel::compact(mine, keep, layout);
  return mine;
}

template <int Dim>
FrameIndicators measure_shared(const State<Dim>& whole, bool interleaved) {
  State<Dim> mine;
  mine.solid = share(whole.solid, interleaved);
  mine.fluid = share(whole.fluid, interleaved);
  mine.time = whole.time;
  return measure<Dim>(mine, nullptr, Energies{1.0, 2.0, 3.0, 0.1}, {0.0, -9.81, 0.0}, 1.0);
}

template <int Dim>
void expect_split_independent(bool water_points) {
  const State<Dim> whole = frame<Dim>(water_points);
  const FrameIndicators split = measure_shared(whole, true), one = measure_shared(whole, false);
  for (int k = 0; k < kIndicators; ++k) {
    SCOPED_TRACE(kSpecs[k].key);
    EXPECT_EQ(split.omitted[k], one.omitted[k]);
    EXPECT_EQ(std::isnan(split.value[k]), std::isnan(one.value[k]));
    if (!std::isnan(one.value[k])) {
      EXPECT_NEAR(split.value[k], one.value[k], 1e-13 * std::abs(one.value[k]));
    }
    EXPECT_EQ(split.where[k].json().dump(), one.where[k].json().dump());
  }
  EXPECT_EQ(split.water_points, one.water_points);
  EXPECT_EQ(split.cavitating, one.cavitating);
  EXPECT_EQ(split.spurious_speed, one.spurious_speed);
  EXPECT_EQ(split.velocity_scale, one.velocity_scale);

  // What the frame holds, so that the comparison bites: a rough patch the index sees, points at
  // rest, cavitating water.
  EXPECT_GT(one.value[mean_stress_checkerboard], 0.01);
  EXPECT_EQ(one.where[mean_stress_checkerboard].set, "solid");
  EXPECT_GT(one.value[pressure_checkerboard], 0.0);
  EXPECT_GT(one.value[spurious_velocity], 0.0);
  EXPECT_GT(one.value[cavitation_fraction], 0.0);
  EXPECT_GT(one.cavitating, 10u);

  // The one-rank measures on the whole set.
  const ParticleSet<Dim>& ps = whole.solid;
  std::vector<Point> x(ps.size(), Point{0, 0, 0});
  std::vector<double> sm(ps.size()), J(ps.size());
  for (std::size_t p = 0; p < ps.size(); ++p) {
    for (int a = 0; a < Dim; ++a) x[p][a] = ps.x[p][a];
    sm[p] = mean_stress(ps.sigma[p]);
    J[p] = ps.V[p] / ps.V0[p];
  }
  const Neighbourhood nb(x, Dim, kRadiusInSpacings * typical_spacing(ps.V0, Dim));
  const Checkerboard c = checkerboard(nb, sm, kStressFloor);
  EXPECT_NEAR(split.value[mean_stress_checkerboard], c.index, 1e-13 * c.index);
  EXPECT_EQ(split.where[mean_stress_checkerboard].id, ps.id[static_cast<std::size_t>(c.worst)]);
  const Range r = range(J);
  EXPECT_EQ(split.value[J_max], r.max);
  EXPECT_EQ(split.where[J_max].id, ps.id[static_cast<std::size_t>(r.at_max)]);
  EXPECT_EQ(split.where[J_min].id, ps.id[static_cast<std::size_t>(r.at_min)]);
}

TEST(IndicatorsOverRanks, AnySplitOfTheSetsGivesTheWholeSetsIndicators2D) {
  expect_split_independent<2>(false);
  expect_split_independent<2>(true);
}

TEST(IndicatorsOverRanks, AnySplitOfTheSetsGivesTheWholeSetsIndicators3D) {
  expect_split_independent<3>(false);
  expect_split_independent<3>(true);
}

TEST(IndicatorsOverRanks, TheTypicalSpacingIsTheWholeSetsMedian) {
  // Spacings of many magnitudes, each rank a different count (rank r: 3 + 5 r values).
  std::vector<double> whole;
  std::vector<double> mine;
  for (int r = 0; r < parallel::ranks(); ++r)
    for (int k = 0; k < 3 + 5 * r; ++k) {
      const double v = std::pow(10.0, -3.0 + 0.37 * ((k * 13 + r * 7) % 17));
      whole.push_back(v);
      if (r == parallel::rank()) mine.push_back(v);
    }
  EXPECT_EQ(typical_spacing_over_ranks(mine, 2, static_cast<long>(whole.size())), typical_spacing(whole, 2));
  EXPECT_EQ(typical_spacing_over_ranks(mine, 3, static_cast<long>(whole.size())), typical_spacing(whole, 3));
}

}  // namespace
}  // namespace swmpm::diagnostics
