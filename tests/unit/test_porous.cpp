// The shared two-phase kernels of solver/porous/ against hand computations: permeability and
// drag laws, the implicit nodal drag solve, the skeleton update, nodal porosity and its value at
// a point, the per-set G2P with the FLIP/PIC blend, free-surface detection (node and point tests)
// and the coincident-point tie.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "solver/porous/drag.hpp"
#include "solver/porous/free_surface.hpp"
#include "solver/porous/permeability.hpp"
#include "solver/porous/points.hpp"
#include "solver/porous/porosity.hpp"
#include "solver/porous/tie.hpp"

using namespace swmpm;

namespace {

scene::Material water() {
  scene::Material w;
  w.name = "water";
  w.params = {{"density", 1000.0}, {"dynamic_viscosity", 1.0e-3}};
  return w;
}

scene::Material sand(const std::string& law) {
  scene::Material s;
  s.name = "sand";
  s.params = {{"porosity", 0.4}, {"hydraulic_conductivity", 1.0e-4}};
  s.permeability_law = law;
  return s;
}

/// A 2D grid of 4 x 4 linear cells of 0.5 m from the origin, one set of points with shape data.
struct Scene2 {
  Grid<2> g{Vec<2>(0.0, 0.0), Vec<2>(2.0, 2.0), 0.5, 1, false};
  ParticleSet<2> ps;
  std::vector<shape::ShapeData<2, 2>> sd;
  StripeSchedule schedule;
  NodeBox<2> box;
  std::size_t nodes() const { return static_cast<std::size_t>(g.nodes_per_axis()[0]) * g.nodes_per_axis()[1]; }

  struct Seed {
    Vec<2> x;
    double m, V, n;
  };
  std::vector<Seed> seeds;
  void add(const Vec<2>& x, double m, double V, double n) { seeds.push_back({x, m, V, n}); }
  /// The set of the points added (ParticleSet::resize resets the fields, so all at once).
  void build() {
    ps.resize(seeds.size());
    ps.add_fluid();
    for (std::size_t k = 0; k < seeds.size(); ++k) {
      ps.id[k] = static_cast<std::int64_t>(k);
      ps.x[k] = ps.x0[k] = seeds[k].x;
      ps.v[k] = Vec<2>::Zero();
      ps.l[k] = Vec<2>::Constant(0.125);
      ps.m[k] = seeds[k].m;
      ps.V[k] = ps.V0[k] = seeds[k].V;
      ps.n[k] = seeds[k].n;
    }
  }
  void evaluate() {
    build();
    sd.resize(ps.size());
    for (std::size_t p = 0; p < ps.size(); ++p) shape::evaluate<shape::Linear>(g, ps.x[p], ps.l[p], sd[p]);
    schedule.build(ps.size(), g.nodes_per_axis()[0], 2, [&](std::size_t p) { return sd[p].base[0]; });
    box.lo = {0, 0};
    box.hi = {g.nodes_per_axis()[0] - 1, g.nodes_per_axis()[1] - 1};
  }
};

std::array<int, 2> ijk_of(const Grid<2>& g, std::size_t i) {
  const int nx = g.nodes_per_axis()[0];
  return {static_cast<int>(i) % nx, static_cast<int>(i) / nx};
}

}  // namespace

// ---- permeability laws -----------------------------------------------------------------------

TEST(Porous, PermeabilityLawsByHand) {
  const auto w = water();
  // constant: k0 at any porosity.
  auto p = porous::permeability_of(sand("constant"), w);
  EXPECT_EQ(p.at(0.3, 0.4), 1.0e-4);
  // kozeny-carman from n0 = 0.4, k0: k(0.5) = k0 (0.125 / 0.25) / (0.064 / 0.36) = 2.8125 k0.
  p = porous::permeability_of(sand("kozeny-carman"), w);
  EXPECT_NEAR(p.at(0.5, 0.4), 2.8125e-4, 1e-16);
  EXPECT_NEAR(p.at(0.4, 0.4), 1.0e-4, 1e-18);
  // xie-leo: J = (1 - n0) / (1 - n) = 0.6 / 0.5 = 1.2, k = 1.44 k0.
  p = porous::permeability_of(sand("xie-leo"), w);
  EXPECT_NEAR(p.at(0.5, 0.4), 1.44e-4, 1e-16);
  // kozeny-carman from the grains: D = 1 mm, A = 150: kappa(0.4) = 1e-6 0.064 / (150 0.36)
  // = 1.185185e-9 m^2, k = kappa rho_w g / mu = 1.162667e-2 m/s.
  auto s = sand("kozeny-carman");
  s.params.erase("hydraulic_conductivity");
  s.params["grain_diameter"] = 1.0e-3;
  s.params["ergun_a"] = 150.0;
  p = porous::permeability_of(s, w);
  EXPECT_EQ(p.law, porous::Permeability::Law::kozeny_carman_grains);
  const double kappa = 1.0e-6 * 0.064 / (150.0 * 0.36);
  EXPECT_NEAR(p.at(0.4, 0.4), kappa * 1000.0 * 9.81 / 1.0e-3, 1e-15);
  EXPECT_NEAR(p.k0, 1.1626666666666667e-2, 1e-15);
  // at n = 0.5: kappa = 1e-6 0.125 / (150 0.25) = 3.3333e-9 m^2 (the porosity's own law).
  EXPECT_NEAR(p.at(0.5, 0.4), 1.0e-6 * 0.125 / (150.0 * 0.25) * 9.81e6, 1e-15);
}

TEST(Porous, ConductivityFromIntrinsicPermeability) {
  auto s = sand("constant");
  s.params.erase("hydraulic_conductivity");
  s.params["intrinsic_permeability"] = 1.0e-11;  // m^2
  EXPECT_NEAR(porous::conductivity_of(s, water()), 1.0e-11 * 1000.0 * 9.81 / 1.0e-3, 1e-20);
  s.params.erase("intrinsic_permeability");
  EXPECT_THROW(porous::conductivity_of(s, water()), std::runtime_error);
}

// ---- drag laws and the implicit nodal solve -------------------------------------------------

TEST(Porous, DragLawsByHand) {
  // Darcy: n^2 rho_w g / k = 0.16 1000 9.81 / 1e-4 = 1.5696e7 kg/(m^3 s).
  EXPECT_NEAR(porous::darcy_drag(0.4, 1000.0, 1.0e-4), 1.5696e7, 1e-6);
  // The same through the intrinsic permeability kappa = k mu / (rho_w g).
  const double kappa = 1.0e-4 * 1.0e-3 / (1000.0 * 9.81);
  porous::DragLaw darcy;
  EXPECT_NEAR(darcy.coefficient(0.4, kappa, 1.0e-3, 1000.0, 3.0), 1.5696e7, 1e-6);
  // Ergun (seed 003 eqs. 9-10), n = 0.4, kappa = 1e-9, w = 0.2 m/s: beta = 1.75 / sqrt(1e-9 150
  // 0.064) = 1.75 / 9.797959e-5 = 17860.86 1/m; c = 0.16 1e-3 / 1e-9 + beta 0.064 1000 0.2
  // = 1.6e5 + 228619.0 = 388619.0.
  porous::DragLaw ergun{porous::DragLaw::Kind::ergun};
  const double beta = 1.75 / std::sqrt(1e-9 * 150.0 * 0.064);
  EXPECT_NEAR(beta, 17860.86, 0.01);
  EXPECT_NEAR(ergun.coefficient(0.4, 1e-9, 1e-3, 1000.0, 0.2), 388619.0, 0.1);
  EXPECT_NEAR(ergun.coefficient(0.4, 1e-9, 1e-3, 1000.0, 0.2), 1.6e5 + beta * 0.064 * 1000.0 * 0.2, 1e-8);
  EXPECT_NEAR(ergun.coefficient(0.4, 1e-9, 1e-3, 1000.0, 0.0), 1.6e5, 1e-8);  // w = 0: Darcy
  // Forchheimer (seed 004 eq. 3): n^2 [mu / kappa + B rho_w w / (sqrt(A kappa) n^1.5)]
  // = 0.16 [1e6 + 1.75 1000 0.2 / (3.872983e-4 0.2529822)] = 0.16 [1e6 + 3.572173e6] = 731547.7.
  porous::DragLaw forch{porous::DragLaw::Kind::forchheimer};
  EXPECT_NEAR(forch.coefficient(0.4, 1e-9, 1e-3, 1000.0, 0.2), 731547.7, 0.5);
  // The impulse coefficient dt g n M_w / k (seed 001 eq. 58).
  EXPECT_NEAR(porous::darcy_drag_impulse(1e-3, 0.4, 2.0, 1e-4), 1e-3 * 9.81 * 0.4 * 2.0 / 1e-4, 1e-12);
}

TEST(Porous, ImplicitDragSolveSatisfiesBothEquations) {
  const double Ms = 3.0, Mw = 1.2;
  const Vec<2> As(0.6, -1.5), Aw(2.4, 0.3);
  for (double a : {0.0, 0.7, 1.0e3, 1.0e12}) {
    const auto u = porous::solve_drag<2>(Ms, Mw, a, As, Aw);
    // (M_w + a) v_w - a v_s = A_w,  (M_s + a) v_s - a v_w = A_s (residual relative to a |v|).
    const double scale = (Ms + Mw + a) * (u.v_s.norm() + u.v_w.norm());
    EXPECT_LT(((Mw + a) * u.v_w - a * u.v_s - Aw).norm(), 1e-14 * scale) << a;
    EXPECT_LT(((Ms + a) * u.v_s - a * u.v_w - As).norm(), 1e-14 * scale) << a;
    // The mixture's momentum is kept.
    EXPECT_LT((Ms * u.v_s + Mw * u.v_w - As - Aw).norm(), 1e-13 * (As + Aw).norm()) << a;
  }
  // a = 0: each phase alone; a -> infinity: one velocity, the mixture's.
  const auto free = porous::solve_drag<2>(Ms, Mw, 0.0, As, Aw);
  EXPECT_LT((free.v_s - As / Ms).norm(), 1e-15);
  EXPECT_LT((free.v_w - Aw / Mw).norm(), 1e-15);
  const auto stiff = porous::solve_drag<2>(Ms, Mw, 1.0e12, As, Aw);
  EXPECT_LT((stiff.v_s - stiff.v_w).norm(), 1e-10);
  EXPECT_LT((stiff.v_s - (As + Aw) / (Ms + Mw)).norm(), 1e-10);
}

// ---- the skeleton update ---------------------------------------------------------------------

TEST(Porous, SkeletonUpdateKeepsTheSolidVolume) {
  MatD<2> L;
  L << 0.3, 0.1, -0.05, -0.6;  // 1/s
  const double dt = 0.1;
  Mat3 F = Mat3::Identity();
  double V = 2.0, n = 0.4;
  const double V0 = 2.0;
  const double solid = (1 - n) * V;
  for (int k = 0; k < 5; ++k) {
    const double J = porous::update_skeleton<2>(L, dt, F, V, V0, n);
    EXPECT_DOUBLE_EQ(J, F.determinant());
    EXPECT_DOUBLE_EQ(V, J * V0);
    EXPECT_NEAR((1 - n) * V, solid, 1e-15);  // incompressible grains
  }
  // dF = (I - L dt/2)^-1 (I + L dt/2): det dF = det(I + L dt/2) / det(I - L dt/2) per step.
  const MatD<2> h = 0.05 * L;
  const double per_step = (MatD<2>::Identity() + h).determinant() / (MatD<2>::Identity() - h).determinant();
  EXPECT_NEAR(F.determinant(), std::pow(per_step, 5), 1e-14);
  EXPECT_NEAR(porous::initial_porosity(n, V, V0), 0.4, 1e-15);
}

// ---- nodal porosity and its interpolation --------------------------------------------------

TEST(Porous, NodalPorosityMassAndVolumeWeighted) {
  Scene2 s;
  // Two points in cell (1, 1) = [0.5, 1] x [0.5, 1]: local coordinates (0.25, 0.5) and (0.75, 0.5).
  s.add(Vec<2>(0.625, 0.75), 2.0, 0.1, 0.3);
  s.add(Vec<2>(0.875, 0.75), 1.0, 0.3, 0.5);
  s.evaluate();
  const int nx = s.g.nodes_per_axis()[0];
  const std::size_t n11 = static_cast<std::size_t>(1 * nx + 1), n21 = n11 + 1;
  NodeArray<std::array<double, 2>> sums(s.nodes());  // zero
  porous::nodal_porosity(s.g, s.box, s.schedule, s.sd, s.ps, porous::PorosityWeight::mass, 1.0, sums);
  // Node (1, 1): S = 0.75 0.5 and 0.25 0.5; n = (0.375 2 0.3 + 0.125 1 0.5) / (0.375 2 + 0.125 1).
  EXPECT_NEAR(sums[n11][0], (0.375 * 2 * 0.3 + 0.125 * 1 * 0.5) / (0.375 * 2 + 0.125), 1e-15);
  // Node (2, 1): S = 0.125 and 0.375.
  EXPECT_NEAR(sums[n21][0], (0.125 * 2 * 0.3 + 0.375 * 1 * 0.5) / (0.125 * 2 + 0.375), 1e-15);
  EXPECT_EQ(sums[0][0], 1.0);  // no soil: `empty`
  NodeArray<std::array<double, 2>> vol(s.nodes());
  porous::nodal_porosity(s.g, s.box, s.schedule, s.sd, s.ps, porous::PorosityWeight::volume, 0.0, vol);
  EXPECT_NEAR(vol[n11][0], (0.375 * 0.1 * 0.3 + 0.125 * 0.3 * 0.5) / (0.375 * 0.1 + 0.125 * 0.3), 1e-15);
  EXPECT_EQ(vol[0][0], 0.0);

  // At a point of the same cell all four nodes hold soil: n = sum S n_I (partition of unity),
  // grad n = sum grad S n_I.
  shape::ShapeData<2, 2> sd;
  shape::evaluate<shape::Linear>(s.g, Vec<2>(0.75, 0.6), Vec<2>(Vec<2>::Zero()), sd);
  const auto at = porous::porosity_at_point(s.g, sd, sums);
  double expect = 0.0;
  Vec<2> grad = Vec<2>::Zero();
  shape::for_each_node(s.g, sd, [&](std::size_t i, double N, const Vec<2>& dN) {
    expect += N * sums[i][0];
    grad += sums[i][0] * dN;
  });
  EXPECT_NEAR(at.n, expect, 1e-15);
  EXPECT_LT((at.grad - grad).norm(), 1e-13);
  // A point in the next cell up, (0.75, 1.1): its upper nodes hold no soil, so n is the lower
  // nodes' average weighted by S, renormalised: (n_11 + n_21) / 2 at x = 0.75.
  shape::evaluate<shape::Linear>(s.g, Vec<2>(0.75, 1.1), Vec<2>(Vec<2>::Zero()), sd);
  // Node (1, 2) and (2, 2) sit at y = 1 and hold soil; the upper ones (y = 1.5) do not.
  const std::size_t n12 = static_cast<std::size_t>(2 * nx + 1), n22 = n12 + 1;
  EXPECT_GT(sums[n12][1], 0.0);
  const auto top = porous::porosity_at_point(s.g, sd, sums);
  EXPECT_NEAR(top.n, 0.5 * (sums[n12][0] + sums[n22][0]), 1e-15);
}

// ---- per-set G2P: the FLIP/PIC blend, positions and the remap -------------------------------

TEST(Porous, GatherSoilPointsBlendsMovesAndRemaps) {
  Scene2 s;
  s.add(Vec<2>(0.625, 0.75), 2.0, 0.1, 0.3);
  s.evaluate();
  s.ps.v[0] = Vec<2>(0.3, -0.2);
  s.ps.v_f[0] = Vec<2>(0.1, 0.1);
  s.ps.m_f[0] = 0.5;
  NodeFields<2> soil, wat;
  soil.resize(s.nodes());
  wat.resize(s.nodes());
  // Node velocities linear in x, so the interpolation is exact: v(x) = (1 + x - y, 2 y), vL = v / 2.
  for (std::size_t i = 0; i < s.nodes(); ++i) {
    const Vec<2> x = s.g.node_position(ijk_of(s.g, i));
    soil.v[i] = Vec<2>(1.0 + x[0] - x[1], 2.0 * x[1]);
    soil.vL[i] = 0.5 * soil.v[i];
    wat.v[i] = -soil.v[i];
    wat.vL[i] = Vec<2>::Zero();
  }
  // The remap divides by the nodes' P2G masses: those of the one point, m S and m_f S.
  shape::for_each_node(s.g, s.sd[0], [&](std::size_t i, double N, const auto&) {
    soil.acc[i].m = N * s.ps.m[0];
    wat.acc[i].m = N * s.ps.m_f[0];
  });
  NodeFields<2> linear = soil;  // kept for the free points below (the remap overwrites soil.v)
  const Vec<2> x = s.ps.x[0], v = Vec<2>(1.0 + x[0] - x[1], 2.0 * x[1]);
  const double flip = 0.9, dt = 0.01;
  porous::gather_soil_points<true, true>(s.g, s.box, s.schedule, s.sd, flip, dt, s.ps, soil, wat);
  const Vec<2> vs = flip * (Vec<2>(0.3, -0.2) + v - 0.5 * v) + (1 - flip) * v;
  const Vec<2> vw = flip * (Vec<2>(0.1, 0.1) - v) + (1 - flip) * (-v);
  EXPECT_LT((s.ps.v[0] - vs).norm(), 1e-15);
  EXPECT_LT((s.ps.v_f[0] - vw).norm(), 1e-15);
  EXPECT_LT((s.ps.x[0] - (x + dt * v)).norm(), 1e-15);
  // One point: every node of its support remaps to its own velocity; the others to zero.
  shape::for_each_node(s.g, s.sd[0], [&](std::size_t i, double, const auto&) {
    EXPECT_LT((soil.v[i] - vs).norm(), 1e-14);
    EXPECT_LT((wat.v[i] - vw).norm(), 1e-14);
  });
  EXPECT_EQ(soil.v[0], Vec<2>::Zero());

  // The free points' G2P: the same blend, no remap.
  Scene2 f;
  f.add(Vec<2>(1.2, 0.3), 1.0, 0.1, 1.0);
  f.evaluate();
  f.ps.v[0] = Vec<2>(-1.0, 0.5);
  const Vec<2> xf = f.ps.x[0], vf = Vec<2>(1.0 + xf[0] - xf[1], 2.0 * xf[1]);
  porous::gather_free_points(f.g, f.sd, flip, dt, f.ps, linear);
  EXPECT_LT((f.ps.v[0] - (flip * (Vec<2>(-1.0, 0.5) + 0.5 * vf) + (1 - flip) * vf)).norm(), 1e-15);
  EXPECT_LT((f.ps.x[0] - (xf + dt * vf)).norm(), 1e-15);
}

// ---- free surface: node test and point test -------------------------------------------------

TEST(Porous, SupportCutFindsTheFreeSurfaceNodes) {
  // Water filling y <= 0.9 of the 4 x 4 grid of linear cells (h = 0.5): nodes at y = 0.5 have
  // supports [0, 1] in y: cut by 0.1 m = 0.2 h (not surface, < kSurfaceCut h); nodes at y = 1
  // have supports [0.5, 1.5]: cut by 0.6 m (surface); at y = 0 their supports [0, 0.5] are full.
  Scene2 s;
  for (double y = 0.05; y < 0.9; y += 0.1)
    for (double x = 0.05; x < 2.0; x += 0.1) s.add(Vec<2>(x, y), 1.0, 0.01, 1.0);
  s.evaluate();
  porous::SupportCut<2, shape::Linear> cut(s.nodes());
  for (std::size_t i = 0; i < s.nodes(); ++i) cut.clear(i);
  for (std::size_t p = 0; p < s.ps.size(); ++p) {
    const Vec<2> half = Vec<2>::Constant(0.05);
    cut.add_at_base(s.g, s.sd[p], Vec<2>(s.ps.x[p] - half), Vec<2>(s.ps.x[p] + half));
  }
  const int nx = s.g.nodes_per_axis()[0];
  auto test = [&](int ix, int iy, double& length) {
    int axis;
    bool hi;
    double xs;
    const std::size_t i = static_cast<std::size_t>(iy * nx + ix);
    length = cut.cut(s.g, s.box, i, {ix, iy}, axis, hi, xs);
    return cut.on_surface(length, s.g);
  };
  double c;
  EXPECT_FALSE(test(2, 0, c));
  EXPECT_NEAR(c, 0.0, 1e-12);
  EXPECT_FALSE(test(2, 1, c));
  EXPECT_NEAR(c, 0.1, 1e-12);
  EXPECT_TRUE(test(2, 2, c));
  EXPECT_NEAR(c, 0.6, 1e-12);
  EXPECT_TRUE(test(0, 2, c));  // a grid face is not a cut; the water's top is
}

TEST(Porous, VolumeFractionAtPointIsOneInsideAndHalfAtTheSurface) {
  Scene2 s;
  shape::ShapeData<2, 2> sd;
  // Water filling y <= 1: a node's volume is full (support integral) up to y = 0.5, half at y = 1
  // (its support [0.5, 1.5] is half under water), zero above.
  const double support = 0.25;  // int of a linear hat of h = 0.5 in 2D: h^2
  auto volume = [&](std::size_t i) {
    const double y = s.g.node_position(ijk_of(s.g, i))[1];
    return y < 0.75 ? support : y < 1.25 ? 0.5 * support : 0.0;
  };
  auto integral = [&](std::size_t) { return support; };
  shape::evaluate<shape::Linear>(s.g, Vec<2>(0.7, 0.3), Vec<2>(Vec<2>::Zero()), sd);
  EXPECT_NEAR(porous::volume_fraction_at_point(s.g, sd, volume, integral), 1.0, 1e-15);
  shape::evaluate<shape::Linear>(s.g, Vec<2>(0.7, 1.0), Vec<2>(Vec<2>::Zero()), sd);
  EXPECT_NEAR(porous::volume_fraction_at_point(s.g, sd, volume, integral), 0.5, 1e-15);
  shape::evaluate<shape::Linear>(s.g, Vec<2>(0.7, 1.25), Vec<2>(Vec<2>::Zero()), sd);
  EXPECT_NEAR(porous::volume_fraction_at_point(s.g, sd, volume, integral), 0.25, 1e-15);
}

// ---- the coincident-point tie --------------------------------------------------------------

TEST(Porous, CoincidentPointsTieWaterToSoil) {
  Scene2 soil, wat;
  soil.add(Vec<2>(0.25, 0.25), 1, 1, 0.4);
  soil.add(Vec<2>(0.75, 0.25), 1, 1, 0.4);
  soil.add(Vec<2>(0.25, 0.75), 1, 1, 0.4);
  soil.build();
  for (int k = 0; k < 3; ++k) soil.ps.id[k] = 10 + k;
  wat.add(Vec<2>(0.25, 0.75), 1, 1, 1);  // on soil id 12
  wat.add(Vec<2>(1.75, 1.75), 1, 1, 1);  // free water
  wat.add(Vec<2>(0.75, 0.25), 1, 1, 1);  // on soil id 11
  wat.build();
  const auto partner = porous::coincident_points(soil.ps, wat.ps);
  ASSERT_EQ(partner.size(), 3u);
  EXPECT_EQ(partner[0], 12);
  EXPECT_EQ(partner[1], -1);
  EXPECT_EQ(partner[2], 11);
  // The soil has moved (and its index of id 11 is 1, of 12 is 2).
  std::vector<int> index_of_id(13, -1);
  for (int k = 0; k < 3; ++k) {
    soil.ps.x[k] += Vec<2>(0.01 * (k + 1), -0.02);
    soil.ps.v[k] = Vec<2>(k, 1.0);
    index_of_id[soil.ps.id[k]] = k;
  }
  porous::tie_positions(soil.ps, index_of_id, partner, wat.ps);
  porous::tie_velocities(soil.ps, index_of_id, partner, wat.ps);
  EXPECT_EQ(wat.ps.x[0], soil.ps.x[2]);
  EXPECT_EQ(wat.ps.x[2], soil.ps.x[1]);
  EXPECT_EQ(wat.ps.x[1], Vec<2>(1.75, 1.75));
  EXPECT_EQ(wat.ps.v[0], soil.ps.v[2]);
  EXPECT_EQ(wat.ps.v[1], Vec<2>::Zero());
}
