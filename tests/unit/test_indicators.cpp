// The stability indicators of every run (solver/diagnostics/) on constructed fields with known
// answers: the checkerboard index of a smooth field and of a checkerboard on a lattice (2D and
// 3D), the neighbour search against brute force, the at-rest speed, ranges, cavitation, the energy
// balance error, the independence from the thread count, and the run's record (first-crossing
// warnings, summary, run.json round trip), and measure() on particle sets of each kind.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "solver/diagnostics/indicators.hpp"
#include "solver/diagnostics/stability.hpp"

using namespace swmpm;
using namespace swmpm::diagnostics;

namespace {

/// An n x n (x n in 3D) lattice of spacing s.
std::vector<Point> lattice(int n, int dim, double s) {
  std::vector<Point> x;
  for (int k = 0; k < (dim == 3 ? n : 1); ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) x.push_back({i * s, j * s, dim == 3 ? k * s : 0.0});
  return x;
}

int parity(const Point& x, double s) {
  const long sum = std::lround(x[0] / s) + std::lround(x[1] / s) + std::lround(x[2] / s);
  return sum % 2 == 0 ? 1 : -1;
}

double field_range(const std::vector<double>& v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

}  // namespace

TEST(Indicators, CheckerboardOfALinearFieldIsZeroAndOfAQuadraticOneSmall) {
  for (int dim : {2, 3}) {
    SCOPED_TRACE(dim);
    const double s = 0.1;
    const auto x = lattice(dim == 3 ? 12 : 30, dim, s);
    const Neighbourhood nb(x, dim, kRadiusInSpacings * s);
    std::vector<double> linear(x.size()), quadratic(x.size());
    for (std::size_t p = 0; p < x.size(); ++p) {
      linear[p] = 1.0e4 * (2.0 + x[p][0] - 3.0 * x[p][1] + 0.5 * x[p][2]);
      quadratic[p] = 1.0e4 * (x[p][0] * x[p][0] + x[p][1] * x[p][1]);
    }
    const Checkerboard c = checkerboard(nb, linear);
    EXPECT_LT(c.index, 1e-12);
    EXPECT_GT(c.fitted, 0u);
    // Curvature only: at an interior point the plane through the neighbours of x^2 + y^2 passes
    // the mean of their dx^2 + dy^2 above it: 12 s^2 / 8 (2D), 20 s^2 / 18 (3D); over the range
    // 2 L^2 (L the lattice's side) that is 8.9e-4 (2D, L = 2.9 m) and 4.6e-3 (3D, L = 1.1 m).
    const double L = (dim == 3 ? 11 : 29) * s;
    const double expected = (dim == 3 ? 20.0 / 18.0 : 12.0 / 8.0) * s * s / (2.0 * L * L);
    EXPECT_NEAR(checkerboard(nb, quadratic).index, expected, 1e-9 * expected);
  }
}

// A checkerboard of amplitude A on a linear field: every interior lattice point's 8 neighbours (2D)
// hold 4 of each sign, so its plane passes through the linear field and the residual is exactly A:
// index = A / R with R the field's range. In 3D the 18 neighbours hold 6 of the opposite sign
// (faces) and 12 of the same (edges): the plane is off by A / 3, residual 2A/3, index 2A / (3R).
TEST(Indicators, CheckerboardOfAmplitudeAOverRangeRGivesAOverR) {
  for (int dim : {2, 3}) {
    SCOPED_TRACE(dim);
    const double s = 0.05, A = 500.0;  // m, Pa
    const auto x = lattice(dim == 3 ? 10 : 24, dim, s);
    const Neighbourhood nb(x, dim, kRadiusInSpacings * s);
    std::vector<double> v(x.size());
    for (std::size_t p = 0; p < x.size(); ++p) v[p] = 2.0e4 * x[p][1] + A * parity(x[p], s);
    const double R = field_range(v);
    const Checkerboard c = checkerboard(nb, v);
    const double expected = (dim == 3 ? 2.0 / 3.0 : 1.0) * A / R;
    EXPECT_NEAR(c.index, expected, 1e-9 * expected);
    EXPECT_NEAR(std::abs(c.worst_residual), (dim == 3 ? 2.0 / 3.0 : 1.0) * A, 1e-6);
    // Only interior points are fitted: free faces, edges and corners have too few neighbours.
    const int n = dim == 3 ? 10 : 24;
    EXPECT_EQ(c.fitted, static_cast<std::size_t>(std::pow(n - 2, dim)));
    // Half the amplitude, half the index.
    for (std::size_t p = 0; p < x.size(); ++p) v[p] = 2.0e4 * x[p][1] + 0.5 * A * parity(x[p], s);
    EXPECT_NEAR(checkerboard(nb, v).index, 0.5 * (dim == 3 ? 2.0 / 3.0 : 1.0) * A / field_range(v), 1e-9);
  }
}

TEST(Indicators, NearlyUniformFieldIsNotJudgedRough) {
  // Round-off on a uniform 10 kPa field: the range (2e-6 Pa) is below the floor 1 % of 10 kPa.
  const auto x = lattice(20, 2, 0.1);
  const Neighbourhood nb(x, 2, 0.16);
  std::vector<double> v(x.size());
  for (std::size_t p = 0; p < x.size(); ++p) v[p] = 1.0e4 + 1e-6 * parity(x[p], 0.1);
  const Checkerboard c = checkerboard(nb, v);
  EXPECT_NEAR(c.scale, 100.0, 1e-6);
  EXPECT_LT(c.index, 1e-7);
}

TEST(Indicators, NeighbourSearchMatchesBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int dim : {2, 3}) {
    std::vector<Point> x(600);
    for (auto& q : x) q = {u(rng), u(rng), dim == 3 ? u(rng) : 0.0};
    x.push_back({1.0e6, -3.0e5, 0.0});  // a point far away costs nothing and has no neighbours
    const double r = 0.11;
    const Neighbourhood nb(x, dim, r);
    for (std::size_t p = 0; p < x.size(); ++p) {
      std::set<std::size_t> found, expected;
      nb.for_each_neighbour(p, [&](std::size_t q) { EXPECT_TRUE(found.insert(q).second); });
      for (std::size_t q = 0; q < x.size(); ++q) {
        double d2 = 0.0;
        for (int a = 0; a < 3; ++a) d2 += (x[q][a] - x[p][a]) * (x[q][a] - x[p][a]);
        if (q != p && d2 <= r * r) expected.insert(q);
      }
      ASSERT_EQ(found, expected) << "dim " << dim << ", point " << p;
    }
  }
}

TEST(Indicators, TypicalSpacingIsTheMedianSideOfTheInitialVolumes) {
  EXPECT_DOUBLE_EQ(typical_spacing(std::vector<double>{0.01, 0.0025, 0.0025, 0.04, 0.0025}, 2), 0.05);
  EXPECT_NEAR(typical_spacing(std::vector<double>{1e-3, 1e-3, 8e-3}, 3), 0.1, 1e-15);
  EXPECT_EQ(typical_spacing(std::vector<double>{}, 2), 0.0);
}

// A bar whose right half slides at 1 m/s (displaced 0.1 m) while the left half is at rest with one
// point jittering at 0.02 m/s. At rest: the left points whose neighbours within 1.6 spacings are at
// rest too; the column next to the moving half is not (its neighbours moved).
TEST(Indicators, AtRestSpeedIsTheFastestPointAwayFromTheMotion) {
  const double s = 0.1;
  const auto x = lattice(20, 2, s);  // columns i = 0..19; moving: i >= 10
  const Neighbourhood nb(x, 2, kRadiusInSpacings * s);
  std::vector<double> u(x.size()), v(x.size());
  long jitter = -1, edge = -1;
  for (std::size_t p = 0; p < x.size(); ++p) {
    const long i = std::lround(x[p][0] / s), j = std::lround(x[p][1] / s);
    const bool moving = i >= 10;
    u[p] = moving ? 0.1 : 4e-3;  // 4 % of the largest: at rest (below 5 %)
    v[p] = moving ? 1.0 : 1e-3;
    if (i == 4 && j == 7) v[p] = 0.02, jitter = static_cast<long>(p);
    if (i == 9 && j == 5) v[p] = 0.5, edge = static_cast<long>(p);  // next to the moving half
  }
  const AtRest a = at_rest(nb, u, v);
  EXPECT_EQ(a.count, 9u * 20u);  // columns 0..8
  EXPECT_DOUBLE_EQ(a.speed, 0.02);
  EXPECT_EQ(a.worst, jitter);
  EXPECT_DOUBLE_EQ(a.displacement_max, 0.1);
  EXPECT_DOUBLE_EQ(a.speed_max, 1.0);
  EXPECT_NE(a.worst, edge);
  // Nothing moved yet: no region is at rest relative to motion.
  std::fill(u.begin(), u.end(), 0.0);
  EXPECT_EQ(at_rest(nb, u, v).count, 0u);
}

TEST(Indicators, RangeCavitationAndEnergyError) {
  const Range r = range(std::vector<double>{0.3, 0.25, 0.41, 0.25, 0.41});
  EXPECT_EQ(r.min, 0.25);
  EXPECT_EQ(r.at_min, 1);
  EXPECT_EQ(r.max, 0.41);
  EXPECT_EQ(r.at_max, 2);
  std::vector<double> p(200, 5.0e3);
  p[17] = -1.5e5, p[40] = -1.01e5, p[41] = -0.99e5;  // two beyond -100 kPa, one just above it
  const Cavitation c = cavitation(p);
  EXPECT_EQ(c.below, 2u);
  EXPECT_DOUBLE_EQ(c.fraction, 0.01);
  EXPECT_EQ(c.lowest, 17);
  EXPECT_EQ(c.p_min, -1.5e5);
  // K + U = 3 J from E0 = 2 J with 0.5 J of work: 0.5 J created, over max(2.5, 3) J.
  EXPECT_DOUBLE_EQ(energy_balance_error(1.0, 2.0, 2.0, 0.5), 0.5 / 3.0);
  // Dissipation is negative; nothing at all is 0.
  EXPECT_DOUBLE_EQ(energy_balance_error(0.0, 1.0, 1.0, 1.0), -0.5);
  EXPECT_EQ(energy_balance_error(0.0, 0.0, 0.0, 0.0), 0.0);
}

TEST(Indicators, ThreadCountDoesNotChangeTheBits) {
  const double s = 0.01;
  const auto x = lattice(90, 2, s);  // 8100 points: the parallel loops run
  std::vector<double> v(x.size()), u(x.size()), w(x.size());
  for (std::size_t p = 0; p < x.size(); ++p) {
    v[p] = std::sin(7.0 * x[p][0]) * std::exp(x[p][1]) * 1e4 + 30.0 * std::cos(1e3 * x[p][0] * x[p][1]);
    u[p] = x[p][0] > 0.5 ? 1e-2 * x[p][0] : 1e-7;
    w[p] = std::abs(std::sin(31.0 * x[p][0] + 17.0 * x[p][1]));
  }
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Neighbourhood nb1(x, 2, 1.6 * s);
  const Checkerboard c1 = checkerboard(nb1, v);
  const AtRest a1 = at_rest(nb1, u, w);
  omp_set_num_threads(std::max(threads, 3));
  const Neighbourhood nb2(x, 2, 1.6 * s);
  const Checkerboard c2 = checkerboard(nb2, v);
  const AtRest a2 = at_rest(nb2, u, w);
  omp_set_num_threads(threads);
  EXPECT_EQ(c1.index, c2.index);
  EXPECT_EQ(c1.worst, c2.worst);
  EXPECT_EQ(a1.speed, a2.speed);
  EXPECT_EQ(a1.count, a2.count);
  EXPECT_GT(c1.index, 1e-4);
}

namespace {

/// A frame whose only measured indicator is the mean-stress checkerboard, with value v.
FrameIndicators frame(double t, double v) {
  FrameIndicators f;
  f.time = t;
  f.value[mean_stress_checkerboard] = v;
  f.where[mean_stress_checkerboard] = Place{"solid", 42, {0.5, 0.25, 0.0}, 2};
  f.value[energy_error] = -0.01;
  f.omitted[pressure_checkerboard] = "no pore or free water in this run";
  return f;
}

}  // namespace

TEST(StabilityReport, WarnsAtTheFirstCrossingOnlyAndSummarisesTheRest) {
  StabilityReport r;
  EXPECT_TRUE(r.add(frame(0.0, 0.01)).empty());
  const auto w = r.add(frame(0.1, 0.15));
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("mean-stress checkerboard index 0.15 above its threshold 0.1"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("t = 0.1 s"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("solid particle 42 at (0.5, 0.25)"), std::string::npos) << w[0];
  EXPECT_TRUE(r.add(frame(0.2, 0.3)).empty());  // crossed again: no second warning
  EXPECT_TRUE(r.add(frame(0.3, 0.2)).empty());
  EXPECT_EQ(r.crossings(mean_stress_checkerboard), 3);
  EXPECT_EQ(r.worst(mean_stress_checkerboard), 0.3);
  const auto lines = r.summary();
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[1].find("in 3 of 4 frames; worst 0.3 at t = 0.2 s"), std::string::npos) << lines[1];

  const auto j = nlohmann::ordered_json::parse(r.json().dump());  // as run.json holds it
  EXPECT_EQ(j["frames"]["time"].size(), 4u);
  EXPECT_EQ(j["frames"]["mean_stress_checkerboard"][3].get<double>(), 0.2);
  EXPECT_TRUE(j["frames"]["porosity_min"][0].is_null());  // not measured: null
  EXPECT_FALSE(j["frames"].contains("pressure_checkerboard"));  // omitted: absent, with the reason
  EXPECT_EQ(j["omitted"]["pressure_checkerboard"], "no pore or free water in this run");
  EXPECT_TRUE(j["worst"]["pressure_checkerboard"].is_null());
  EXPECT_EQ(j["worst"]["mean_stress_checkerboard"]["where"]["particle"], 42);
  EXPECT_EQ(j["thresholds"]["J_min"]["below"], 0.5);
  EXPECT_EQ(j["warnings"].size(), 1u);

  StabilityReport back;  // a resumed run continues the record
  back.restore(j);
  EXPECT_EQ(back.json().dump(), j.dump());
  EXPECT_TRUE(back.add(frame(0.4, 0.5)).empty());
  EXPECT_EQ(back.crossings(mean_stress_checkerboard), 4);
}

namespace {

template <int Dim>
ParticleSet<Dim> lattice_set(int n, double s) {
  const auto x = lattice(n, Dim, s);
  ParticleSet<Dim> ps;
  ps.resize(x.size());
  for (std::size_t p = 0; p < x.size(); ++p) {
    ps.id[p] = static_cast<std::int64_t>(1000 + p);
    for (int a = 0; a < Dim; ++a) ps.x[p][a] = ps.x0[p][a] = x[p][a];
    ps.V[p] = ps.V0[p] = std::pow(s, Dim);
    ps.m[p] = 1.0;
    ps.v[p].setZero();
  }
  return ps;
}

}  // namespace

// measure() on a state: which set carries the pressure, what is omitted, and the places.
template <int Dim>
void measure_on_sets() {
  const double s = 0.1, A = 1.0e3;
  const std::array<double, 3> g{0.0, -9.81, 0.0};
  const int n = Dim == 3 ? 8 : 16;
  // Dry: the mean stress is a linear field plus a checkerboard; no pore pressure, no porosity.
  State<Dim> dry;
  dry.solid = lattice_set<Dim>(n, s);
  for (std::size_t p = 0; p < dry.solid.size(); ++p) {
    const double pm = 1.0e4 * dry.solid.x[p][1] + A * parity(lattice(n, Dim, s)[p], s);
    dry.solid.sigma[p] << -pm, -pm, -pm, 0, 0, 0;
  }
  FrameIndicators f = measure<Dim>(dry, nullptr, Energies{1.0, 1.0, 2.0, 0.0}, g, 1.0);
  EXPECT_FALSE(f.omitted[pressure_checkerboard].empty());
  EXPECT_FALSE(f.omitted[porosity_min].empty());
  EXPECT_TRUE(f.omitted[mean_stress_checkerboard].empty());
  const double R = 1.0e4 * (n - 1) * s + 2 * A;
  EXPECT_NEAR(f.value[mean_stress_checkerboard], (Dim == 3 ? 2.0 / 3.0 : 1.0) * A / R, 1e-6);
  EXPECT_EQ(f.where[mean_stress_checkerboard].set, "solid");
  EXPECT_GE(f.where[mean_stress_checkerboard].id, 1000);
  EXPECT_DOUBLE_EQ(f.value[J_min], 1.0);
  EXPECT_DOUBLE_EQ(f.value[energy_error], 0.0);
  EXPECT_TRUE(std::isnan(f.value[spurious_velocity]));  // nothing moved yet

  // Single-point: the pore pressure on the soil points; 3 points beyond -100 kPa; one point
  // squeezed to J = 0.4; a corner slides away while the rest jitters at 1 mm/s.
  State<Dim> sp;
  sp.solid = lattice_set<Dim>(n, s);
  sp.solid.add_fluid();
  for (std::size_t p = 0; p < sp.solid.size(); ++p) {
    sp.solid.p[p] = 5.0e3;
    sp.solid.n[p] = 0.3 + 0.001 * static_cast<double>(p % 7);
    sp.solid.m_f[p] = 0.3;
    sp.solid.v[p][0] = 1e-3;
  }
  sp.solid.p[5] = sp.solid.p[6] = sp.solid.p[7] = -2.0e5;
  sp.solid.V[9] = 0.4 * sp.solid.V0[9];
  const std::size_t last = sp.solid.size() - 1;
  sp.solid.x[last][0] += 0.5;
  sp.solid.v[last][0] = 2.0;
  f = measure<Dim>(sp, nullptr, Energies{1.0, 1.3, 2.0, 0.0}, g, 1.0);
  const double N = static_cast<double>(sp.solid.size());
  EXPECT_DOUBLE_EQ(f.value[cavitation_fraction], 3.0 / N);
  EXPECT_EQ(f.where[cavitation_fraction].id, 1005);
  EXPECT_DOUBLE_EQ(f.value[J_min], 0.4);
  EXPECT_EQ(f.where[J_min].id, 1009);
  EXPECT_DOUBLE_EQ(f.value[porosity_min], 0.3);
  EXPECT_DOUBLE_EQ(f.value[porosity_max], 0.306);
  EXPECT_NEAR(f.value[energy_error], 0.3 / 2.3, 1e-12);
  EXPECT_EQ(f.where[energy_error].id, static_cast<long>(1000 + last));  // the fastest point
  EXPECT_DOUBLE_EQ(f.spurious_speed, 1e-3);
  // The velocity scale: the fastest point, 2 m/s (above sqrt(g L) and 0.5 m / 1 s).
  const double L = (n - 1) * s + 0.5;
  EXPECT_DOUBLE_EQ(f.velocity_scale, std::max(2.0, std::sqrt(9.81 * L)));
  EXPECT_DOUBLE_EQ(f.value[spurious_velocity], 1e-3 / f.velocity_scale);
  EXPECT_TRUE(f.omitted[pressure_checkerboard].empty());

  // Double-point: the pressure on the water points, named as such.
  State<Dim> dp;
  dp.solid = lattice_set<Dim>(n, s);
  dp.solid.add_fluid();
  dp.fluid = lattice_set<Dim>(n, s);
  dp.fluid.make_water_points();
  dp.fluid.add_fluid();
  for (std::size_t p = 0; p < dp.fluid.size(); ++p) dp.fluid.p[p] = 1.0e4 * dp.fluid.x[p][1];
  dp.fluid.p[3] = -1.2e5;
  f = measure<Dim>(dp, nullptr, Energies{}, g, 1.0);
  EXPECT_EQ(f.where[cavitation_fraction].set, "water");
  EXPECT_EQ(f.where[cavitation_fraction].id, 1003);
  EXPECT_DOUBLE_EQ(f.value[cavitation_fraction], 1.0 / static_cast<double>(dp.fluid.size()));

  // mpm-fem: the pressure on the grid's water nodes (phi >= 1/2); the air's nodes do not count.
  // A B-spline lattice: the boundary node at x = 0, the next at s/2, then every s. The water (x >
  // 2 s, the lower half) holds a linear pressure with a checkerboard of amplitude A: index A / R
  // (2D; 3D 2A / (3R)) with the water's range R, found only with the radius from the spacing s.
  State<Dim> fem;
  fem.solid = lattice_set<Dim>(n, s);
  GridFields grid;
  grid.nodes = {n, n, Dim == 3 ? n : 1};
  grid.cloud.points = lattice(n, Dim, s);
  for (auto& q : grid.cloud.points) q[0] = q[0] < 0.5 * s ? 0.0 : q[0] - 0.5 * s;
  auto& pg = grid.cloud.add("pressure", 1).values;
  auto& phi = grid.cloud.add("phase_field", 1).values;
  double lo = 1e300, hi = -1e300;
  for (std::size_t i = 0; i < grid.cloud.size(); ++i) {
    const auto& q = grid.cloud.points[i];
    const bool water = q[0] > 2.0 * s && q[1] < 0.5 * (n - 1) * s;
    phi[i] = water ? 1.0 : 0.0;
    const Point lattice_point{q[0] + 0.5 * s, q[1], q[2]};
    pg[i] = water ? 1.0e4 * (1.0 - q[1]) + A * parity(lattice_point, s) : -5.0e5;  // the air's are not judged
    if (water) lo = std::min(lo, pg[i]), hi = std::max(hi, pg[i]);
  }
  f = measure<Dim>(fem, &grid, Energies{}, g, 1.0);
  EXPECT_EQ(f.value[cavitation_fraction], 0.0);
  EXPECT_NEAR(f.value[pressure_checkerboard], (Dim == 3 ? 2.0 / 3.0 : 1.0) * A / (hi - lo), 1e-9);
  EXPECT_EQ(f.where[pressure_checkerboard].set, "grid");
  EXPECT_GT(f.water_points, 0u);
  EXPECT_LT(f.water_points, grid.cloud.size());
}

TEST(Indicators, MeasureOnParticleSets2D) { measure_on_sets<2>(); }
TEST(Indicators, MeasureOnParticleSets3D) { measure_on_sets<3>(); }
