// Constitutive models on one particle: objectivity under rigid rotation (Jaumann-rate linear
// elasticity and Hencky), a uniaxial-strain stress against Hooke's law, and time functions.
#include <gtest/gtest.h>

#include <cmath>
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
