// Constitutive models on one particle: objectivity under rigid rotation (Jaumann-rate linear
// elasticity and Hencky), a uniaxial-strain stress against Hooke's law, and time functions.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "scene/scene.hpp"
#include "solver/loads.hpp"
#include "solver/materials/material.hpp"
#include "solver/transfer/transfer.hpp"

using namespace swmpm;

namespace {

scene::Material elastic(const std::string& model) {
  scene::Material m;
  m.name = "m";
  m.model = model == "hencky" ? scene::MaterialModel::hencky : scene::MaterialModel::linear_elastic;
  m.params = {{"youngs_modulus", 1.0e7}, {"poisson_ratio", 0.25}, {"density", 2000.0}};
  return m;
}

ParticleSet<2> one_particle() {
  ParticleSet<2> ps;
  ps.resize(1);
  ps.m[0] = 1.0;
  ps.V[0] = ps.V0[0] = 1.0;
  return ps;
}

/// Drives one particle with a constant velocity gradient L for `steps` steps of dt, updating F as
/// the solver does (F <- dF F, transfer::deformation_increment).
void drive(const MaterialModel<2>& model, ParticleSet<2>& ps, const MatD<2>& L, double dt, int steps) {
  const std::vector<int> ids{0};
  for (int k = 0; k < steps; ++k) {
    ps.L[0] = L;
    Mat3 dF = Mat3::Identity();
    dF.topLeftCorner<2, 2>() = transfer::deformation_increment<2>(L, dt);
    ps.F[0] = dF * ps.F[0];
    ps.V[0] = ps.F[0].determinant() * ps.V0[0];
    ASSERT_EQ(model.update_stress(ps, ids, dt), -1);
  }
}

}  // namespace

TEST(Materials, JaumannRateRotatesAPrestressWithTheBody) {
  // A uniaxial prestress sigma_xx = -100 kPa, rotated rigidly by 90 degrees, must become sigma_yy.
  scene::Scene s;
  const auto model = make_material<2>(elastic("linear-elastic"), s);
  auto ps = one_particle();
  ps.sigma[0] << -1.0e5, 0, 0, 0, 0, 0;
  const double omega = 1.0, T = M_PI / 2;  // rad/s, s
  const int steps = 20000;
  MatD<2> L;
  L << 0, -omega, omega, 0;  // spin only: D = 0
  drive(*model, ps, L, T / steps, steps);
  EXPECT_NEAR(ps.sigma[0][0], 0.0, 1e5 * 1e-3);
  EXPECT_NEAR(ps.sigma[0][1], -1.0e5, 1e5 * 1e-3);
  EXPECT_NEAR(ps.sigma[0][3], 0.0, 1e5 * 1e-3);
}

TEST(Materials, HenckyIsStressFreeUnderRigidRotationAndRotatesItsStress) {
  scene::Scene s;
  const auto model = make_material<2>(elastic("hencky"), s);
  auto ps = one_particle();
  MatD<2> L;
  L << 0, -1.0, 1.0, 0;
  drive(*model, ps, L, M_PI / 2 / 1000, 1000);
  EXPECT_LT(ps.sigma[0].norm(), 1e-6 * 1e7);
  // Stretch along x by 1 %, then rotate 90 degrees: the stress of the stretch turns to y.
  auto qs = one_particle();
  qs.F[0](0, 0) = 1.01;
  drive(*model, qs, MatD<2>::Zero(), 1e-3, 1);
  const double sxx = qs.sigma[0][0], syy = qs.sigma[0][1];
  drive(*model, qs, L, M_PI / 2 / 20000, 20000);
  EXPECT_NEAR(qs.sigma[0][1], sxx, 1e-3 * std::abs(sxx));
  EXPECT_NEAR(qs.sigma[0][0], syy, 1e-3 * std::abs(sxx));
}

TEST(Materials, UniaxialStrainFollowsHooke) {
  // Small uniaxial compression eps_yy = -1e-4 in plane strain: sigma_yy = M eps, sigma_xx = sigma_zz = lambda eps.
  scene::Scene s;
  const double E = 1.0e7, nu = 0.25;
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), M = lambda + E / (1 + nu);
  for (const char* name : {"linear-elastic", "hencky"}) {
    const auto model = make_material<2>(elastic(name), s);
    auto ps = one_particle();
    MatD<2> L = MatD<2>::Zero();
    L(1, 1) = -1e-4;  // 1/s over 1 s
    drive(*model, ps, L, 1e-3, 1000);
    const double eps = std::log(ps.F[0](1, 1));
    EXPECT_NEAR(ps.sigma[0][1], M * eps, 1e-3 * M * std::abs(eps)) << name;
    EXPECT_NEAR(ps.sigma[0][0], lambda * eps, 2e-3 * M * std::abs(eps)) << name;
    EXPECT_NEAR(ps.sigma[0][2], lambda * eps, 2e-3 * M * std::abs(eps)) << name;
  }
}

TEST(TimeFunctions, ExpressionTableAndRamp) {
  scene::TimeFunction tf;
  tf.expression = "40e3*sin(5*pi*t)";
  TimeFunction f(tf);
  EXPECT_NEAR(f(0.1), 40e3 * std::sin(5 * M_PI * 0.1), 1e-9);
  scene::TimeFunction tt;
  tt.table = {{0.0, 0.0}, {1.0, 10.0}, {2.0, 10.0}};
  TimeFunction g(tt);
  EXPECT_DOUBLE_EQ(g(-1.0), 0.0);
  EXPECT_DOUBLE_EQ(g(0.25), 2.5);
  EXPECT_DOUBLE_EQ(g(1.5), 10.0);
  EXPECT_DOUBLE_EQ(g(5.0), 10.0);
  scene::TimeFunction tr;
  tr.ramp = 0.5;
  TimeFunction r(tr);
  EXPECT_DOUBLE_EQ(r(0.25), 0.5);
  EXPECT_DOUBLE_EQ(r(1.0), 1.0);
}

namespace {

/// A cohesionless Mohr–Coulomb sand and a fluid, with an initialisation phase that gives the sand
/// a cohesion of 1 MPa (initialisation.materials).
scene::Scene sand_with_phase_cohesion(bool plasticity) {
  scene::Scene s;
  scene::Material sand;
  sand.name = "sand";
  sand.model = scene::MaterialModel::mohr_coulomb;
  sand.params = {{"youngs_modulus", 1.0e7}, {"poisson_ratio", 0.3}, {"cohesion", 0.0}, {"friction_angle", 30.0},
                 {"dilation_angle", 0.0}, {"density", 2000.0}};
  scene::Material water;
  water.name = "water";
  water.model = scene::MaterialModel::fluid;
  s.materials = {sand, water};
  s.initialisation.duration = 1.0;
  s.initialisation.plasticity = plasticity;
  s.initialisation.materials["sand"] = {{"cohesion", 1.0e6}};
  return s;
}

/// The plastic strain of a fresh particle after a simple shear of 1e-3 from zero stress: any
/// shear yields cohesionless sand at p = 0; with c = 1 MPa it stays elastic (tau = G gamma ~ 4 kPa).
double plastic_strain_of_shear(const MaterialModel<2>& model) {
  auto ps = one_particle();
  MatD<2> L;
  L << 0, 1, 0, 0;  // 1/s
  drive(model, ps, L, 1e-4, 10);
  return ps.eps_p[0];
}

}  // namespace

TEST(Materials, TheInitialisationPhaseSwapsInItsOwnParametersAndBack) {
  const scene::Scene s = sand_with_phase_cohesion(true);
  std::vector<std::unique_ptr<MaterialModel<2>>> models;
  models.push_back(make_material<2>(s.materials[0], s));
  models.push_back(nullptr);  // the fluid has no constitutive model
  PhaseMaterials<2> phase(s);
  EXPECT_GT(plastic_strain_of_shear(*models[0]), 0.0);  // the scene's c = 0
  const MaterialModel<2>* scene_model = models[0].get();
  phase.set(models, &s.initialisation);
  EXPECT_NE(models[0].get(), scene_model);
  EXPECT_EQ(models[1], nullptr);
  EXPECT_EQ(plastic_strain_of_shear(*models[0]), 0.0);  // c = 1 MPa, plastic flow on
  phase.set(models, &s.initialisation);                  // again: nothing changes
  EXPECT_EQ(plastic_strain_of_shear(*models[0]), 0.0);
  phase.set(models, nullptr);
  EXPECT_EQ(models[0].get(), scene_model);  // the scene's own model, as it was
  EXPECT_GT(plastic_strain_of_shear(*models[0]), 0.0);

  // Plastic flow off during the phase: off in both, back on in the scene's model at the end.
  const scene::Scene e = sand_with_phase_cohesion(false);
  std::vector<std::unique_ptr<MaterialModel<2>>> elastic_models;
  elastic_models.push_back(make_material<2>(e.materials[0], e));
  PhaseMaterials<2> elastic_phase(e);
  elastic_phase.set(elastic_models, &e.initialisation);
  EXPECT_EQ(plastic_strain_of_shear(*elastic_models[0]), 0.0);
  elastic_phase.set(elastic_models, nullptr);
  EXPECT_GT(plastic_strain_of_shear(*elastic_models[0]), 0.0);
}
