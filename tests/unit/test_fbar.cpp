// The F-bar stage (solver/transfer/fbar.hpp, seed 001 eqs. 78-83) on small particle blocks, and
// the material side of the modified F-bar (elastic_volumetric_strain, ps.ev_shift) for every model.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <vector>

#include "scene/scene.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/materials/material.hpp"
#include "solver/transfer/fbar.hpp"
#include "solver/transfer/transfer.hpp"
#include "support/material_point.hpp"

using namespace swmpm;

namespace {

scene::Material material(scene::MaterialModel model) {
  scene::Material m;
  m.name = "m";
  m.model = model;
  m.params = {{"youngs_modulus", 1.0e7}, {"poisson_ratio", 0.45}, {"density", 2000.0}, {"cohesion", 1.0e6},
              {"friction_angle", 30.0}, {"tension_cutoff", 1.0e6}};
  if (model == scene::MaterialModel::nor_sand) {
    m.params = {{"shear_modulus", 4.0e7},           {"shear_modulus_coupling", 0.0},
                {"swelling_index", 0.002},          {"reference_pressure", 1.0e5},
                {"reference_elastic_volumetric_strain", 0.0},
                {"compression_index", 0.02},        {"reference_specific_volume", 1.892},
                {"csl_reference_pressure", 1.0e3},  {"critical_state_ratio", 1.0},
                {"yield_coefficient", 0.1},         {"potential_coefficient", 0.1},
                {"hardening_modulus", 100.0},       {"dilatancy_multiplier", -2.0},
                {"initial_specific_volume", 1.8},   {"overconsolidation_ratio", 5.0},
                {"dilatancy_cutoff_start", 1.0},    {"dilatancy_cutoff_end", 1.5},
                {"gas_specific_volume_ratio", 1.6}, {"density", 2000.0}};
  }
  return m;
}

/// A block of particles, 2 per cell and axis, on a grid of 6 cells of 0.25 m per axis, with the
/// shape data, node box and schedule of one step, and the F-bar stage of a scene.
template <int Dim, class Shape>
struct Block {
  static constexpr int S = Shape::support;
  scene::Scene scene;
  Grid<Dim> grid;
  State<Dim> st;
  std::vector<shape::ShapeData<Dim, S>> sd;
  NodeBox<Dim> box;
  StripeSchedule schedule;
  std::vector<std::unique_ptr<MaterialModel<Dim>>> materials;
  std::vector<std::vector<int>> groups;

  Block(const std::string& fbar, double patch, scene::MaterialModel model = scene::MaterialModel::hencky,
        const std::string& kinematics = "finite-strain") {
    scene.dimension = Dim;
    scene.grid.cell_size = 0.25;
    scene.grid.min = {0.0, 0.0, 0.0};
    scene.grid.max = {1.5, 1.5, Dim == 3 ? 1.5 : 0.0};
    scene.grid.shape_function = Shape::bspline ? (Shape::degree == 2 ? scene::ShapeFunction::bspline2
                                                                     : scene::ShapeFunction::bspline3)
                                               : scene::ShapeFunction::gimp;
    scene.solver.stabilisation.fbar = fbar;
    scene.solver.stabilisation.fbar_patch = patch;
    scene.solver.kinematics = kinematics;
    scene.materials.push_back(material(model));
    grid = make_grid<Dim>(scene, Shape::degree, Shape::bspline);
    ParticleSet<Dim>& ps = st.solid;
    const int n1 = 12;  // particles per axis, spacing 0.125 m
    const int n = Dim == 2 ? n1 * n1 : n1 * n1 * n1;
    ps.resize(n);
    ps.add_material_state();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> mass(0.5, 1.5);
    for (int k = 0; k < n; ++k) {
      int r = k;
      for (int a = 0; a < Dim; ++a) {
        ps.x[k][a] = (r % n1 + 0.5) * 0.125;
        r /= n1;
      }
      ps.x0[k] = ps.x[k];
      ps.l[k] = Vec<Dim>::Constant(0.0625);
      ps.m[k] = mass(rng);  // uneven masses: the averages are mass-weighted
      ps.V0[k] = ps.V[k] = std::pow(0.125, Dim);
      ps.id[k] = k;
    }
    long bad = -1;
    box = transfer::evaluate_shapes<Shape>(grid, ps, sd, bad);
    transfer::build_schedule(grid, sd, schedule);
    materials = make_materials<Dim>(scene);
    groups = group_by_material(ps, 1);
  }
  ParticleSet<Dim>& ps() { return st.solid; }
  /// Sets L of every particle and F_{n+1} = ΔF(L) F_n as the formulations do before the stage.
  void deform(const std::function<MatD<Dim>(int)>& L_of, double dt) {
    for (std::size_t p = 0; p < ps().size(); ++p) {
      ps().L[p] = L_of(static_cast<int>(p));
      ps().F[p].template topLeftCorner<Dim, Dim>() =
          transfer::deformation_increment<Dim>(ps().L[p], dt) * ps().F[p].template topLeftCorner<Dim, Dim>();
      ps().V[p] = ps().F[p].determinant() * ps().V0[p];
    }
  }
  bool apply(FBar<Dim, S>& fb, double dt) { return fb.apply(grid, box, schedule, sd, dt, st, materials, groups); }
};

template <int Dim>
MatD<Dim> random_matrix(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  MatD<Dim> m;
  for (int i = 0; i < Dim; ++i)
    for (int j = 0; j < Dim; ++j) m(i, j) = u(rng);
  return m;
}

/// Eq. 80 written out independently: ΔJ̄_p = Σ_I N_Ip (Σ_q N_Iq m_q ΔJ_q) / (Σ_q N_Iq m_q).
template <int Dim, class Shape>
std::vector<double> nodal_average(Block<Dim, Shape>& b, const std::vector<double>& dJ) {
  std::map<std::size_t, std::pair<double, double>> node;
  const auto& ps = b.ps();
  for (std::size_t p = 0; p < ps.size(); ++p)
    shape::for_each_node(b.grid, b.sd[p], [&](std::size_t i, double N, const Vec<Dim>&) {
      node[i].first += N * ps.m[p] * dJ[p];
      node[i].second += N * ps.m[p];
    });
  std::vector<double> out(ps.size(), 0.0);
  for (std::size_t p = 0; p < ps.size(); ++p)
    shape::for_each_node(b.grid, b.sd[p], [&](std::size_t i, double N, const Vec<Dim>&) {
      if (N > 0.0) out[p] += N * node[i].first / node[i].second;
    });
  return out;
}

}  // namespace

TEST(FBar, RateOfIncrementInvertsTheMidpointIncrement) {
  std::mt19937 rng(3);
  const double dt = 1e-3;
  for (int trial = 0; trial < 100; ++trial) {
    const MatD<2> L2 = random_matrix<2>(rng, 5.0);
    const MatD<3> L3 = random_matrix<3>(rng, 5.0);
    EXPECT_LT((fbar::rate_of_increment<2>(transfer::deformation_increment<2>(L2, dt), dt) - L2).norm(), 1e-10 * L2.norm());
    EXPECT_LT((fbar::rate_of_increment<3>(transfer::deformation_increment<3>(L3, dt), dt) - L3).norm(), 1e-10 * L3.norm());
    // And the other way round, for a scaled increment c ΔF (what the stage writes back).
    const MatD<3> dFbar = 1.003 * transfer::deformation_increment<3>(L3, dt);
    EXPECT_LT((transfer::deformation_increment<3>(fbar::rate_of_increment<3>(dFbar, dt), dt) - dFbar).norm(), 1e-14);
    // The stage's one-inverse form of the same, and det ΔF without forming ΔF.
    EXPECT_LT((fbar::scaled_rate<3>(L3, 1.003, dt) - fbar::rate_of_increment<3>(dFbar, dt)).norm(), 1e-10 * L3.norm());
    EXPECT_LT((fbar::scaled_rate<2>(L2, 0.997, dt) -
               fbar::rate_of_increment<2>(0.997 * transfer::deformation_increment<2>(L2, dt), dt)).norm(),
              1e-10 * L2.norm());
    EXPECT_NEAR(transfer::deformation_jacobian<3>(L3, dt), transfer::deformation_increment<3>(L3, dt).determinant(), 1e-15);
    EXPECT_NEAR(transfer::deformation_jacobian<2>(L2, dt), transfer::deformation_increment<2>(L2, dt).determinant(), 1e-15);
  }
}

TEST(FBar, UniformDeformationIsLeftExactlyAsItWas) {
  // ΔJ̄ = ΔJ when every particle has the same ΔJ: F̄ = F, L̄ = L, V unchanged (to round-off).
  Block<2, shape::Gimp> b("standard", 0.0);
  MatD<2> L;
  L << -2.0, 0.7, 0.3, 1.1;
  const double dt = 1e-3;
  b.deform([&](int) { return L; }, dt);
  const auto F0 = b.ps().F;
  const auto L0 = b.ps().L;
  const auto V0 = b.ps().V;
  FBar<2, 3> fb(b.scene, b.grid);
  ASSERT_TRUE(b.apply(fb, dt));
  EXPECT_TRUE(b.st.health.ok());
  for (std::size_t p = 0; p < b.ps().size(); ++p) {
    EXPECT_LT((b.ps().F[p] - F0[p]).norm(), 1e-14) << p;
    EXPECT_LT((b.ps().L[p] - L0[p]).norm(), 1e-11 * L.norm()) << p;
    EXPECT_NEAR(b.ps().V[p], V0[p], 1e-15 * V0[p]) << p;
  }
}

template <int Dim, class Shape>
void check_standard(double scale) {
  Block<Dim, Shape> b("standard", 0.0);
  std::mt19937 rng(11);
  const double dt = 1e-3;
  // A prior deformation F_n, then a different L at every particle.
  b.deform([&](int) { return random_matrix<Dim>(rng, 20.0); }, dt);
  const auto Fn = b.ps().F;
  b.deform([&](int) { return random_matrix<Dim>(rng, scale); }, dt);
  const auto F1 = b.ps().F;
  std::vector<double> dJ(b.ps().size());
  std::vector<MatD<Dim>> dF(b.ps().size());
  for (std::size_t p = 0; p < dJ.size(); ++p) {
    dF[p] = transfer::deformation_increment<Dim>(b.ps().L[p], dt);
    dJ[p] = dF[p].determinant();
  }
  const std::vector<double> dJbar = nodal_average(b, dJ);
  FBar<Dim, Shape::support> fb(b.scene, b.grid);
  ASSERT_TRUE(b.apply(fb, dt));
  ASSERT_TRUE(b.st.health.ok());
  double sum = 0.0, sum_bar = 0.0, spread = 0.0;
  for (std::size_t p = 0; p < dJ.size(); ++p) {
    const auto& ps = b.ps();
    // The increment the materials rebuild from L̄ is ΔF̄: det ΔF̄ = ΔJ̄ (eq. 79), same isochoric part.
    const MatD<Dim> dFbar = transfer::deformation_increment<Dim>(ps.L[p], dt);
    EXPECT_NEAR(dFbar.determinant(), dJbar[p], 1e-13) << p;
    // What a hypoelastic model integrates: Δt tr L̄ = ln ΔJ̄ + O(Δt³) (here |Δt L| ~ 0.02).
    EXPECT_NEAR(dt * ps.L[p].trace(), std::log(dJbar[p]), 1e-5) << p;
    const double c = std::pow(dJbar[p] / dJ[p], 1.0 / Dim);
    EXPECT_LT((dFbar - c * dF[p]).norm(), 1e-13) << p;
    // F̄_{n+1} = ΔF̄ F_n, V = det F̄ V0; plane strain keeps F_zz = 1 and no out-of-plane shear.
    Mat3 D = Mat3::Identity();
    D.template topLeftCorner<Dim, Dim>() = dFbar;
    EXPECT_LT((ps.F[p] - D * Fn[p]).norm(), 1e-13) << p;
    EXPECT_NEAR(ps.V[p], ps.F[p].determinant() * ps.V0[p], 1e-15) << p;
    if (Dim == 2) {
      EXPECT_EQ(ps.F[p](2, 2), 1.0);
      EXPECT_EQ(ps.F[p](0, 2), 0.0);
      EXPECT_EQ(ps.F[p](2, 1), 0.0);
    }
    sum += ps.m[p] * dJ[p];
    sum_bar += ps.m[p] * dJbar[p];
    spread = std::max(spread, std::abs(F1[p].determinant() / ps.F[p].determinant() - 1.0));
  }
  // The mass-weighted map/remap conserves Σ m ΔJ (partition of unity), and it did change things.
  EXPECT_NEAR(sum_bar, sum, 1e-13 * sum);
  EXPECT_GT(spread, 1e-4);
}

TEST(FBar, StandardGivesTheNodalAverageOfDetDeltaF2dGimp) { check_standard<2, shape::Gimp>(20.0); }
TEST(FBar, StandardGivesTheNodalAverageOfDetDeltaF2dBspline2) { check_standard<2, shape::BSpline2>(20.0); }
TEST(FBar, StandardGivesTheNodalAverageOfDetDeltaF3dLinear) { check_standard<3, shape::Linear>(20.0); }
TEST(FBar, StandardGivesTheNodalAverageOfDetDeltaF3dBspline3) { check_standard<3, shape::BSpline3>(20.0); }

TEST(FBar, RigidRotationStaysObjective) {
  // The same spin everywhere: ΔJ = 1, so ΔF̄ = ΔF is a rotation; under the modified F-bar a
  // prestressed Hencky block rotates its stress, σ_{n+1} = R σ_n Rᵀ, with J = 1.
  Block<2, shape::BSpline2> b("modified", 1.5);
  Sym s0;
  s0 << -3.0e4, -1.0e4, -2.0e4, 5.0e3, 0.0, 0.0;
  for (auto& s : b.ps().sigma) s = s0;
  MatD<2> W;
  W << 0.0, -2.0, 2.0, 0.0;
  const double dt = 1e-3;
  b.deform([&](int) { return W; }, dt);
  FBar<2, 3> fb(b.scene, b.grid);
  ASSERT_TRUE(b.apply(fb, dt));
  ASSERT_EQ(b.materials[0]->update_stress(b.ps(), b.groups[0], dt), -1);
  const MatD<2> R = transfer::deformation_increment<2>(W, dt);
  Mat3 R3 = Mat3::Identity();
  R3.topLeftCorner<2, 2>() = R;
  const Sym expected = to_voigt(R3 * to_matrix(s0) * R3.transpose());
  for (std::size_t p = 0; p < b.ps().size(); ++p) {
    EXPECT_LT((b.ps().L[p] - W).norm(), 1e-11) << p;
    EXPECT_NEAR(b.ps().F[p].determinant(), 1.0, 1e-14) << p;
    EXPECT_LT(std::abs(b.ps().ev_shift[p]), 1e-13) << p;
    EXPECT_LT((b.ps().sigma[p] - expected).norm(), 1e-9 * s0.norm()) << p;
  }
}

TEST(FBar, PatchesAreAFixedLatticeFromTheGridOrigin) {
  Block<2, shape::BSpline2> b("modified", 1.5);
  FBar<2, 3> fb(b.scene, b.grid);
  EXPECT_DOUBLE_EQ(fb.patch_size(), 0.375);
  EXPECT_EQ(fb.patches(), 16u);  // 1.5 m / 0.375 m = 4 per axis
  EXPECT_EQ(fb.patch_of(Vec<2>(0.01, 0.01)), 0u);
  EXPECT_EQ(fb.patch_of(Vec<2>(0.376, 0.01)), 1u);
  EXPECT_EQ(fb.patch_of(Vec<2>(0.01, 0.376)), 4u);
  EXPECT_EQ(fb.patch_of(Vec<2>(1.49, 1.49)), 15u);
  // The default by shape function: cell-wise for GIMP, 1.5 h for the B-splines.
  Block<2, shape::Gimp> g("modified", 0.0);
  EXPECT_DOUBLE_EQ((FBar<2, 3>(g.scene, g.grid).patch_size()), 0.25);
  g.scene.grid.shape_function = scene::ShapeFunction::bspline3;
  EXPECT_DOUBLE_EQ((FBar<2, 3>(g.scene, g.grid).patch_size()), 0.375);
}

template <int Dim, class Shape>
void check_patch_average(double patch) {
  // Uneven elastic volumetric strains (prestress), no deformation this step: after the stage every
  // particle of a patch has J^e = J̄^e, and Σ m J^e per patch is unchanged (eq. 83).
  Block<Dim, Shape> b("modified", patch);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2.0e5, -1.0e4);
  for (auto& s : b.ps().sigma) {
    const double m = u(rng);
    s << m, m + 2.0e3, m - 1.0e3, 500.0, 0.0, 0.0;
  }
  const double dt = 1e-3;
  b.deform([&](int) { return MatD<Dim>::Zero(); }, dt);
  FBar<Dim, Shape::support> fb(b.scene, b.grid);
  std::vector<double> ev(b.ps().size());
  b.materials[0]->elastic_volumetric_strain(b.ps(), b.groups[0], dt, ev);
  ASSERT_TRUE(b.apply(fb, dt));
  std::vector<double> before(fb.patches(), 0.0), after(fb.patches(), 0.0), lo(fb.patches(), 1e9), hi(fb.patches(), -1e9);
  double moved = 0.0;
  for (std::size_t p = 0; p < ev.size(); ++p) {
    const std::size_t k = fb.patch_of(b.ps().x[p]);
    const double Je = std::exp(ev[p]), Jbar = std::exp(ev[p] + b.ps().ev_shift[p]);
    before[k] += b.ps().m[p] * Je;
    after[k] += b.ps().m[p] * Jbar;
    lo[k] = std::min(lo[k], Jbar);
    hi[k] = std::max(hi[k], Jbar);
    moved = std::max(moved, std::abs(b.ps().ev_shift[p]));
  }
  for (std::size_t k = 0; k < fb.patches(); ++k) {
    EXPECT_NEAR(after[k], before[k], 1e-14 * before[k]) << "patch " << k;
    EXPECT_LT(hi[k] - lo[k], 1e-14) << "patch " << k;
  }
  EXPECT_GT(moved, 1e-4);
  // The stress update realises it: with no increment the Kirchhoff mean stress K ln J̄^e is the
  // same within a patch and the deviatoric stress is untouched.
  const auto sigma0 = b.ps().sigma;
  ASSERT_EQ(b.materials[0]->update_stress(b.ps(), b.groups[0], dt), -1);
  std::vector<double> e1(ev.size());
  b.ps().ev_shift.clear();
  b.materials[0]->elastic_volumetric_strain(b.ps(), b.groups[0], dt, e1);
  for (std::size_t p = 0; p < ev.size(); ++p) {
    EXPECT_NEAR(std::exp(e1[p]), lo[fb.patch_of(b.ps().x[p])], 1e-12) << p;
    EXPECT_NEAR(deviatoric_stress(b.ps().sigma[p]), deviatoric_stress(sigma0[p]), 1e-8 * 2e5) << p;
  }
}

TEST(FBar, PatchAverageConservesMassWeightedJeCellWise2dGimp) { check_patch_average<2, shape::Gimp>(1.0); }
TEST(FBar, PatchAverageConservesMassWeightedJePatchWise2dBspline2) { check_patch_average<2, shape::BSpline2>(1.5); }
TEST(FBar, PatchAverageConservesMassWeightedJePatchWise3dBspline2) { check_patch_average<3, shape::BSpline2>(1.5); }

/// Every model: a homogeneous block under a homogeneous increment gives the same stress with the
/// modified F-bar as without; and a shift moves the model's ε_v^e by exactly that much.
template <int Dim>
void check_model(scene::MaterialModel model, const std::string& kinematics, const Sym& s0) {
  SCOPED_TRACE(scene::to_string(model) + " " + kinematics + " " + std::to_string(Dim) + "D");
  MatD<Dim> L = MatD<Dim>::Zero();
  L(0, 0) = -1.0, L(1, 1) = 0.4, L(0, 1) = 0.3;
  const double dt = 1e-3;
  Block<Dim, shape::Gimp> with("modified", 1.0, model, kinematics), without("none", 0.0, model, kinematics);
  // hencky without F-bar is the total form, which ignores a prestress: start it stress free.
  const Sym start = model == scene::MaterialModel::hencky ? Sym::Zero() : s0;
  FBar<Dim, 3> fb(with.scene, with.grid);
  for (auto* b : {&with, &without})
    for (auto& s : b->ps().sigma) s = start;
  for (int step = 0; step < 5; ++step) {
    for (auto* b : {&with, &without}) b->deform([&](int) { return L; }, dt);
    ASSERT_TRUE(with.apply(fb, dt));
    ASSERT_EQ(with.materials[0]->update_stress(with.ps(), with.groups[0], dt), -1);
    ASSERT_EQ(without.materials[0]->update_stress(without.ps(), without.groups[0], dt), -1);
  }
  for (std::size_t p = 0; p < with.ps().size(); ++p)
    ASSERT_LT((with.ps().sigma[p] - without.ps().sigma[p]).norm(), 1e-9 * s0.norm()) << p;
  // One particle, no increment, a shift of 1e-4: ε_v^e moves by 1e-4, q does not.
  auto one = swmpm::testing::one_particle<Dim>(s0);
  const std::vector<int> ids{0};
  const auto m = make_material<Dim>(material(model), with.scene);
  std::vector<double> e0(1), e1(1);
  m->elastic_volumetric_strain(one, ids, dt, e0);
  one.ev_shift.assign(1, 1e-4);
  ASSERT_EQ(m->update_stress(one, ids, dt), -1);
  one.ev_shift.clear();
  m->elastic_volumetric_strain(one, ids, dt, e1);
  EXPECT_NEAR(e1[0] - e0[0], 1e-4, 1e-10);
  EXPECT_NEAR(deviatoric_stress(one.sigma[0]), deviatoric_stress(s0), 1e-9 * s0.norm());
}

TEST(FBar, EveryModelRealisesTheShiftAndIgnoresAHomogeneousState) {
  Sym s0;
  s0 << -1.2e5, -0.8e5, -1.0e5, 1.0e4, 0.0, 0.0;
  using M = scene::MaterialModel;
  for (const char* kin : {"finite-strain", "small-strain"}) {
    check_model<2>(M::mohr_coulomb, kin, s0);
    check_model<3>(M::mohr_coulomb, kin, s0);
  }
  for (M model : {M::linear_elastic, M::hencky, M::drucker_prager, M::nor_sand}) {
    check_model<2>(model, "finite-strain", s0);
    check_model<3>(model, "finite-strain", s0);
  }
}

TEST(FBar, BadModeIsRejected) {
  Block<2, shape::Gimp> b("none", 0.0);
  b.scene.solver.stabilisation.fbar = "bar";
  EXPECT_THROW((FBar<2, 3>(b.scene, b.grid)), std::runtime_error);
}
