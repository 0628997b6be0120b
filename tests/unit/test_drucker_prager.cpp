// Drucker-Prager (solver/materials/drucker_prager.{hpp,cpp}):
//  - below yield the model is Hencky elasticity (= the `hencky` model, 2D and 3D);
//  - closed forms: one isochoric (pure deviatoric) step beyond yield from an isotropic state
//    returns radially onto Φ = 0 with √J2 = ξ c + η p (ψ = 0; ψ > 0: Δγ = Φ^tr / (G + K η η̄));
//    a pure volumetric tension beyond the apex returns to σ_m = ξ c / η (no cut-off) or to the
//    cut-off σ_m = T;
//  - 20 000 random trial states per parameter set: Φ(σ) <= 1e-9 of the stress scale after every
//    return (= 0 on the cone, the apex and the cut-off circle), σ_m <= T, elastic states
//    bit-identical, the cone's plastic strain along ∂Ψ/∂σ (ψ = 0: no volumetric plastic strain);
//  - objectivity: a rigid rotation R (one Cayley step of a spin) gives R σ R^T;
//  - an isochoric triaxial compression at constant p reaches q/p = √3 η (c = 0), with SRF 1 and 2;
//    the drained triaxial of `swmpm element` (constant lateral stress) fails at q/p = √3 η too.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <stdexcept>
#include <vector>

#include "scene/scene.hpp"
#include "solver/element.hpp"
#include "solver/materials/drucker_prager.hpp"
#include "solver/materials/material.hpp"
#include "solver/transfer/transfer.hpp"
#include "support/material_point.hpp"

using namespace swmpm;
namespace dp = swmpm::drucker_prager;
using dp::Principal;

namespace {

constexpr double E = 1.0e7, nu = 0.3;  // Pa, -
const double deg = M_PI / 180.0;

dp::Params params(double c, double phi, double psi, double srf = 1.0, double T = 1.0e30) {
  return dp::Params::from(Elastic::from(E, nu), c, phi, psi, srf, T);
}

scene::Material dp_material(double c, double phi, double psi, double srf = 1.0, double T = 0.0) {
  scene::Material m;
  m.name = "soil";
  m.model = scene::MaterialModel::drucker_prager;
  m.params = {{"youngs_modulus", E},   {"poisson_ratio", nu}, {"density", 2000.0},
              {"cohesion", c},         {"friction_angle", phi}, {"dilation_angle", psi},
              {"strength_reduction_factor", srf}, {"tension_cutoff", T}};
  return m;
}

scene::Scene finite_strain() {
  scene::Scene s;
  s.solver.kinematics = "finite-strain";
  return s;
}

using swmpm::testing::drive;
using swmpm::testing::one_particle;

Principal principal_of(const Sym& s) {
  Eigen::SelfAdjointEigenSolver<Mat3> e(to_matrix(s));
  return e.eigenvalues();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Constants and the model's construction.

TEST(DruckerPrager, PlaneStrainMatchConstants) {
  // Seed 004 eqs. 18-19 at φ = 30°: tan φ = 0.57735, 9 + 12 tan² φ = 13, η = 0.48038, ξ = 0.83205.
  const auto m = params(10e3, 30, 0);
  EXPECT_NEAR(m.eta, 3 * std::tan(30 * deg) / std::sqrt(13.0), 1e-15);
  EXPECT_NEAR(m.xi, 3 / std::sqrt(13.0), 1e-15);
  EXPECT_EQ(m.eta_bar, 0.0);
  EXPECT_NEAR(m.apex, 10e3 / std::tan(30 * deg), 1e-9);  // ξ c / η = c cot φ for this match
  EXPECT_FALSE(m.cutoff);
  // Strength reduction: tan φ_f = tan φ / SRF, c_f = c / SRF (as mohr-coulomb).
  const auto r = params(10e3, 30, 0, 2.0);
  EXPECT_NEAR(r.eta, dp::eta_of(std::tan(30 * deg) / 2), 1e-15);
  EXPECT_NEAR(r.c, 5e3, 1e-12);
}

TEST(DruckerPrager, SmallStrainKinematicsIsRefused) {
  scene::Scene s;
  s.solver.kinematics = "small-strain";
  EXPECT_THROW(make_material<2>(dp_material(1e3, 30, 0), s), std::runtime_error);
  EXPECT_EQ(make_material<2>(dp_material(1e3, 30, 0), finite_strain())->name(), "drucker-prager");
}

// ---------------------------------------------------------------------------------------------
// (1) Below yield: Hencky elasticity.

template <int Dim>
void elastic_equals_hencky() {
  scene::Material strong = dp_material(1e12, 30, 0, 1.0, 1e13), hencky = strong;
  hencky.model = scene::MaterialModel::hencky;
  const auto model = make_material<Dim>(strong, finite_strain());
  const auto ref = make_material<Dim>(hencky, finite_strain());
  MatD<Dim> L = MatD<Dim>::Zero();
  L(0, 0) = -0.2, L(0, 1) = 0.15, L(1, 0) = 0.05, L(1, 1) = 0.1;
  if constexpr (Dim == 3) L(2, 2) = -0.05, L(0, 2) = 0.1, L(2, 1) = -0.07;
  auto a = one_particle<Dim>(), b = one_particle<Dim>();
  drive<Dim>(*model, a, L, 1e-3, 500);  // ~10 % strain, with rotation
  drive<Dim>(*ref, b, L, 1e-3, 500);
  const double err = (a.sigma[0] - b.sigma[0]).norm() / b.sigma[0].norm();
  std::printf("elastic Dim %d: |sigma - hencky| / |hencky| = %.2e (|sigma| = %.4g Pa)\n", Dim, err, b.sigma[0].norm());
  EXPECT_LT(err, 1e-11);
  EXPECT_EQ(a.eps_p[0], 0.0);
  EXPECT_NEAR(model->strain_energy(a, 0), ref->strain_energy(b, 0), 1e-9 * ref->strain_energy(b, 0));
}

TEST(DruckerPrager, ElasticStatesMatchHencky) {
  elastic_equals_hencky<2>();
  elastic_equals_hencky<3>();
}

// ---------------------------------------------------------------------------------------------
// (2) Closed forms.

template <int Dim>
void isochoric_step_closed_form(double psi) {
  // One step L = diag(a, −a, 0) from σ0 = −p0 1 (J = 1): ΔF = diag(d, 1/d, 1) (midpoint rule), so
  // the trial Kirchhoff stress is τ^tr = −p0 1 + 2G (e, −e, 0), e = ln d: √J2^tr = 2G e, σ_m^tr = −p0.
  const double c = 10e3, phi = 30, p0 = 100e3, a = 2.0, dt = 0.01;
  const auto m = params(c, phi, psi, 1.0, 0.0);
  const auto model = make_material<Dim>(dp_material(c, phi, psi, 1.0, 0.0), finite_strain());
  Sym s0;
  s0 << -p0, -p0, -p0, 0, 0, 0;
  auto ps = one_particle<Dim>(s0);
  MatD<Dim> L = MatD<Dim>::Zero();
  L(0, 0) = a, L(1, 1) = -a;
  drive<Dim>(*model, ps, L, dt, 1);
  const double d = (1 + a * dt / 2) / (1 - a * dt / 2), e = std::log(d), G = m.G, K = m.K;
  const double q_tr = 2 * G * e;
  const double phi_tr = q_tr - m.eta * p0 - m.xi * c;  // Φ^tr = 97.5 kPa: well beyond yield
  ASSERT_GT(phi_tr, 0.0);
  // Box 8.8 (i): Δγ = Φ^tr / (G + K η η̄), √J2 = √J2^tr − G Δγ, σ_m = σ_m^tr − K η̄ Δγ.
  const double dgamma = phi_tr / (G + K * m.eta * m.eta_bar);
  const double r = q_tr - G * dgamma, sm = -p0 - K * m.eta_bar * dgamma;
  if (psi == 0.0) {
    EXPECT_NEAR(r, m.xi * c + m.eta * p0, 1e-9 * r);  // √J2 = ξ c + η p (p compression positive)
  }
  // Radial: dev σ = (r / √J2^tr) dev τ^tr = (r, −r, 0).
  const Sym& s = ps.sigma[0];
  std::printf("isochoric step Dim %d psi %g: sxx - sm = %.9g (closed form %.9g), sm = %.9g (%.9g) Pa\n", Dim, psi,
              s[0] - sm, r, (s[0] + s[1] + s[2]) / 3, sm);
  EXPECT_NEAR(s[0], sm + r, 1e-9 * p0);
  EXPECT_NEAR(s[1], sm - r, 1e-9 * p0);
  EXPECT_NEAR(s[2], sm, 1e-9 * p0);
  EXPECT_NEAR(s[3], 0.0, 1e-9 * p0);
  EXPECT_NEAR(dp::yield_function(m, principal_of(s)), 0.0, 1e-9 * p0);
  // Δε^p = Δγ ∂Ψ/∂σ = Δγ ((1/2, −1/2, 0) + η̄/3 1) (s/(2√J2) with s = (r, −r, 0)).
  const Principal deps = dgamma * (Principal(0.5, -0.5, 0.0) + Principal::Constant(m.eta_bar / 3));
  EXPECT_NEAR(ps.eps_p[0], dp::equivalent_plastic_increment(deps), 1e-9 * ps.eps_p[0]);
}

TEST(DruckerPrager, IsochoricStepReturnsRadially) {
  for (double psi : {0.0, 10.0}) {
    isochoric_step_closed_form<2>(psi);
    isochoric_step_closed_form<3>(psi);
  }
}

TEST(DruckerPrager, VolumetricTensionBeyondTheApex) {
  // One step L = a 1 from σ = 0: ΔF = d 1, trial τ = 3K ln d 1 (σ_m^tr = 25 kPa > apex 3.46 kPa),
  // no deviator, so the radial return crosses the axis at once. No cut-off (T = 1e30): the apex
  // σ_m = ξ c / η (Kirchhoff), σ = apex / J 1 with J = d³; cut-off T = 1 kPa < apex: σ_m = T / J.
  const double c = 2e3, phi = 30, a = 1.0, dt = 0.001;
  for (double T : {1e30, 1e3}) {
    const auto m = params(c, phi, 0, 1.0, T);
    const auto model = make_material<3>(dp_material(c, phi, 0, 1.0, T), finite_strain());
    auto ps = one_particle<3>();
    MatD<3> L = MatD<3>::Identity() * a;
    drive<3>(*model, ps, L, dt, 1);
    const double d = (1 + a * dt / 2) / (1 - a * dt / 2), J = d * d * d;
    const double sm_tr = 3 * m.K * std::log(d);
    const double target = std::min(m.apex, T);
    ASSERT_GT(sm_tr, m.apex);
    const Sym& s = ps.sigma[0];
    std::printf("volumetric tension T %g: sigma_m J = %.9g Pa (apex %.9g, trial %.9g), shear %.1e\n", T,
                J * (s[0] + s[1] + s[2]) / 3, m.apex, sm_tr, s.tail<3>().norm());
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(J * s[i], target, 1e-9 * sm_tr);
    EXPECT_LT(s.tail<3>().norm(), 1e-12 * sm_tr);
    // Δε^p = (σ_m^tr − target)/(3K) 1: ε̄^p = √(2/3 · 3) (σ_m^tr − target)/(3K).
    EXPECT_NEAR(ps.eps_p[0], std::sqrt(2.0) * (sm_tr - target) / (3 * m.K), 1e-9 * ps.eps_p[0]);
  }
  // The return map: a trial beyond the apex with a deviator small enough that the radial return
  // would cross the axis (√J2^tr < G Δγ) goes to the apex; with ψ = 0 the cone region would
  // give no volumetric flow, the apex takes it all.
  const auto m = params(2e3, 30, 0);
  const auto r = dp::return_map(m, Principal(10e3, 9e3, 8e3));
  EXPECT_EQ(r.region, dp::Region::apex);
  EXPECT_EQ(r.s, Principal::Constant(m.apex));
  EXPECT_NEAR(r.deps_p.sum(), (9e3 - m.apex) / m.K, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// (3) Consistency of every return region on random trials.

TEST(DruckerPrager, RandomTrialsLandOnTheSurface) {
  struct Case {
    double c, phi, psi, T;
    std::vector<dp::Region> regions;  // the regions this case must visit
  };
  using R = dp::Region;
  const std::vector<Case> cases{
      {10e3, 30, 0, 1e30, {R::elastic, R::cone, R::apex}},
      {10e3, 35, 15, 1e30, {R::elastic, R::cone, R::apex}},
      {10e3, 30, 10, 5e3, {R::elastic, R::cone, R::cutoff, R::cutoff_cone}},
      {5e3, 0, 0, 2e3, {R::elastic, R::cone, R::cutoff, R::cutoff_cone}},  // φ = 0: von Mises cylinder
  };
  std::mt19937_64 rng(20261204);
  // Trials σ_m 1 + q x̂: σ_m in [−200, 60] kPa, a deviator of random direction and size up to 100 kPa.
  std::uniform_real_distribution<double> u_sm(-200e3, 60e3), u_q(0.0, 100e3), u_x(-1.0, 1.0);
  for (const auto& cs : cases) {
    const auto m = params(cs.c, cs.phi, cs.psi, 1.0, cs.T);
    std::map<R, int> seen;
    double worst_phi = 0.0, worst_flow = 0.0, worst_vol = 0.0;
    for (int k = 0; k < 20000; ++k) {
      Principal x(u_x(rng), u_x(rng), u_x(rng));
      x -= Principal::Constant(x.sum() / 3);
      const Principal tr = Principal::Constant(u_sm(rng)) + u_q(rng) * x;
      const auto r = dp::return_map(m, tr);
      ++seen[r.region];
      const double scale = std::max(tr.cwiseAbs().maxCoeff(), m.xi * m.c);
      const double f = dp::yield_function(m, r.s);
      ASSERT_LE(f, 1e-9 * scale) << "trial " << tr.transpose();
      ASSERT_LE(r.s.sum() / 3, m.tension + 1e-12 * scale);
      if (r.region == R::elastic) {
        ASSERT_EQ(r.s, tr);
        continue;
      }
      if (r.region != R::cutoff) {  // on the cone (smooth part, apex or circle): Φ = 0
        worst_phi = std::max(worst_phi, std::abs(f) / scale);
        ASSERT_LE(std::abs(f), 1e-9 * scale) << "region " << static_cast<int>(r.region);
      }
      if (r.region == R::cone) {
        // Δε^p = Δγ ∂Ψ/∂σ at σ_{n+1}, ∂Ψ/∂σ = s / (2√J2) + η̄/3 1, Δγ = (√J2^tr − √J2) / G.
        const double q = dp::sqrt_J2(r.s);
        const Principal n = (r.s - Principal::Constant(r.s.sum() / 3)) / (2 * q) + Principal::Constant(m.eta_bar / 3);
        const double dgamma = (dp::sqrt_J2(tr) - q) / m.G;
        // Round-off floor: strains of 1e-13 of the stress scale (tiny returns have tiny Δε^p).
        const double floor = 1e-13 * scale / m.G;
        const double flow = (r.deps_p - dgamma * n).norm();
        worst_flow = std::max(worst_flow, flow / r.deps_p.norm());
        ASSERT_LT(flow, 1e-9 * r.deps_p.norm() + floor);
        if (cs.psi == 0.0) {
          worst_vol = std::max(worst_vol, std::abs(r.deps_p.sum()) / r.deps_p.norm());
          ASSERT_LT(std::abs(r.deps_p.sum()), 1e-12 * r.deps_p.norm() + floor);
        }
      }
      if (r.region == R::cutoff || r.region == R::cutoff_cone) {
        ASSERT_NEAR(r.s.sum() / 3, m.tension, 1e-12 * scale);
      }
    }
    std::printf("random c %g phi %g psi %g T %g: elastic %d cone %d apex %d cutoff %d cutoff_cone %d; "
                "max |Phi|/scale %.1e, flow direction %.1e, volumetric %.1e\n",
                cs.c, cs.phi, cs.psi, cs.T, seen[R::elastic], seen[R::cone], seen[R::apex], seen[R::cutoff],
                seen[R::cutoff_cone], worst_phi, worst_flow, worst_vol);
    for (R reg : cs.regions) EXPECT_GT(seen[reg], 0) << "region " << static_cast<int>(reg) << " not visited";
  }
}

// ---------------------------------------------------------------------------------------------
// (4) Objectivity.

template <int Dim>
void rigid_rotation(const MatD<Dim>& W) {
  const auto model = make_material<Dim>(dp_material(5e3, 30, 5), finite_strain());
  Sym s0;
  s0 << -100e3, -100e3, -100e3, 0, 0, 0;
  auto ps = one_particle<Dim>(s0);
  MatD<Dim> Ld = MatD<Dim>::Zero();
  Ld(0, 0) = 0.5, Ld(1, 1) = -1.0, Ld(0, 1) = 0.3;
  drive<Dim>(*model, ps, Ld, 1e-4, 500);  // 5 % strain: plastic
  ASSERT_GT(ps.eps_p[0], 1e-4);
  const double eps_p0 = ps.eps_p[0];
  const Mat3 before = to_matrix(ps.sigma[0]);
  // One step of the spin W: ΔF = (I − W/2)⁻¹ (I + W/2) (dt = 1) is a rotation R exactly (Cayley).
  Mat3 R = Mat3::Identity();
  R.topLeftCorner<Dim, Dim>() = transfer::deformation_increment<Dim>(W, 1.0);
  ASSERT_LT((R * R.transpose() - Mat3::Identity()).norm(), 1e-14);
  drive<Dim>(*model, ps, W, 1.0, 1);
  const Mat3 expected = R * before * R.transpose();
  const double err = (to_matrix(ps.sigma[0]) - expected).norm() / before.norm();
  std::printf("rotation Dim %d: |sigma - R sigma0 R^T| / |sigma0| = %.2e, plastic strain added %.1e\n", Dim, err,
              ps.eps_p[0] - eps_p0);
  EXPECT_LT(err, 1e-10);
  EXPECT_LT(ps.eps_p[0] - eps_p0, 1e-14);
}

TEST(DruckerPrager, RigidRotationRotatesTheStress) {
  MatD<2> W2;
  W2 << 0, -2, 2, 0;  // 90° about z
  rigid_rotation<2>(W2);
  MatD<3> W3;
  W3 << 0, -0.9, 0.4, 0.9, 0, -1.3, -0.4, 1.3, 0;  // about (1.3, 0.4, 0.9)
  rigid_rotation<3>(W3);
}

TEST(DruckerPrager, PlaneStrainIn3DEqualsDim2) {
  const auto m2 = make_material<2>(dp_material(5e3, 30, 10, 1.0, 0.0), finite_strain());
  const auto m3 = make_material<3>(dp_material(5e3, 30, 10, 1.0, 0.0), finite_strain());
  Sym s0;
  s0 << -50e3, -100e3, -50e3, 0, 0, 0;
  const auto [a, b] = swmpm::testing::plane_strain_path(*m2, *m3, s0);
  ASSERT_GT(a.eps_p[0], 0.01);
  std::printf("plane strain: |sigma_2D - sigma_3D| / |sigma| = %.2e, plastic strain %.4f\n",
              (a.sigma[0] - b.sigma[0]).norm() / a.sigma[0].norm(), a.eps_p[0]);
  EXPECT_LT((a.sigma[0] - b.sigma[0]).norm(), 1e-11 * a.sigma[0].norm());
  EXPECT_NEAR(a.eps_p[0], b.eps_p[0], 1e-10 * a.eps_p[0]);
}

// ---------------------------------------------------------------------------------------------
// (5) Triaxial compression to the Drucker-Prager limit.

TEST(DruckerPrager, TriaxialCompressionReachesTheLimitRatio) {
  // Isochoric axisymmetric compression, L = diag(ε̇/2, −ε̇, ε̇/2) from σ = −p I (the drained
  // constant-p path; strain controlled): with q = √(3 J2) the cone reads q = √3 (ξ c_f + η_f p), so
  // with c = 0, q/p = √3 η_f (φ = 35°: 0.9431 at SRF 1, 0.5622 at SRF 2). ψ = 0 keeps p fixed;
  // ψ = 10° makes the isochoric path dilate against elasticity: p rises and the state climbs the
  // cone, still at q/p = √3 η.
  const double p = 100e3, phi = 35;
  for (double psi : {0.0, 10.0}) {
    for (double c : {0.0, 10e3}) {
      if (psi > 0 && c > 0) continue;
      for (double srf : {1.0, 2.0}) {
        const auto m = params(c, phi, psi, srf);
        const auto model = make_material<3>(dp_material(c, phi, psi, srf, 1e30), finite_strain());
        Sym s0;
        s0 << -p, -p, -p, 0, 0, 0;
        auto ps = one_particle<3>(s0);
        MatD<3> L = MatD<3>::Zero();
        L(0, 0) = 0.5, L(1, 1) = -1.0, L(2, 2) = 0.5;
        drive<3>(*model, ps, L, 1e-5, 4000);  // 4 % axial strain
        const double J = ps.F[0].determinant();  // 1 to round-off (isochoric)
        const double pe = mean_stress(ps.sigma[0]), q = deviatoric_stress(ps.sigma[0]);
        const double q_limit = std::sqrt(3.0) * (m.xi * m.c + m.eta * J * pe) / J;
        std::printf("triaxial psi %g c %g SRF %g: p = %.6g Pa, q/p = %.6f, closed form %.6f (sqrt3 eta = %.6f), "
                    "|q - closed form| / q %.1e, |sxx - szz| / p %.1e\n", psi, c, srf, pe, q / pe, q_limit / pe,
                    std::sqrt(3.0) * m.eta, std::abs(q - q_limit) / q_limit,
                    std::abs(ps.sigma[0][0] - ps.sigma[0][2]) / p);
        EXPECT_NEAR(q, q_limit, 1e-9 * q_limit) << "psi " << psi << " c " << c << " SRF " << srf;
        if (psi == 0.0) {
          EXPECT_NEAR(pe, p, 1e-9 * p);
        } else {
          EXPECT_GT(pe, 1.01 * p);
        }
        // Axisymmetry is not imposed (the cone has no edge to snap to): σ_xx = σ_zz holds to the
        // round-off of 4000 decompositions of a b_e^tr with a double eigenvalue (measured ≤ 6.4e-9 p).
        EXPECT_NEAR(ps.sigma[0][0], ps.sigma[0][2], 2e-8 * p);
        EXPECT_GT(ps.eps_p[0], 1e-3);
      }
    }
  }
}

TEST(DruckerPrager, DrainedTriaxialReachesTheLimitRatio) {
  // The conventional drained triaxial of `swmpm element` (solver/element.cpp: lateral stress held
  // at p0 by a Newton iteration on the lateral stretch, Δq = 3Δp), c = 0, φ = 30°, ψ = 0, from
  // p0 = 100 kPa to 5 % axial strain: failure at q/p = √3 η = 0.83205, i.e. (Δq = 3Δp)
  // p_f = p0 / (1 − η/√3) = 138.38 kPa; past it ψ = 0 keeps the volume constant.
  const double p0 = 100e3, phi = 30;
  scene::Scene s = finite_strain();
  s.materials.push_back(dp_material(0.0, phi, 0.0, 1.0, 0.0));
  const auto r = run_element(s, "soil", ElementTest::drained_triaxial, p0, 0.05, 200);
  const auto m = params(0.0, phi, 0.0);
  const double ratio = std::sqrt(3.0) * m.eta, p_f = p0 / (1 - m.eta / std::sqrt(3.0));
  const std::size_t n = r.size();
  std::printf("drained triaxial: q/p end = %.8f (sqrt3 eta = %.8f, rel. %.1e), p end = %.2f Pa (closed form %.2f, "
              "rel. %.1e), radial %.1e, eps_v last steps %.6e -> %.6e\n", r.q.back() / r.p.back(), ratio,
              std::abs(r.q.back() / r.p.back() / ratio - 1), r.p.back(), p_f, std::abs(r.p.back() / p_f - 1),
              std::abs(r.radial_stress.back() / p0 - 1), r.volumetric_strain[n - 2], r.volumetric_strain[n - 1]);
  EXPECT_NEAR(r.q.back() / r.p.back(), ratio, 1e-6 * ratio);
  EXPECT_NEAR(r.p.back(), p_f, 1e-6 * p_f);
  EXPECT_NEAR(r.radial_stress.back(), p0, 1e-6 * p0);
  EXPECT_NEAR(r.volumetric_strain[n - 1], r.volumetric_strain[n - 2], 1e-9);
}

TEST(DruckerPrager, PlasticFlowSwitchedOffIsTheElasticModel) {
  scene::Material weak = dp_material(1e3, 30, 0, 1.0, 1e13), hencky = weak;
  hencky.model = scene::MaterialModel::hencky;
  MatD<2> L;
  L << -0.2, 0.15, 0.05, 0.1;
  auto model = make_material<2>(weak, finite_strain());
  const auto ref = make_material<2>(hencky, finite_strain());
  model->set_plastic(false);
  auto a = one_particle<2>(), b = one_particle<2>();
  drive<2>(*model, a, L, 1e-3, 200);
  drive<2>(*ref, b, L, 1e-3, 200);
  EXPECT_LT((a.sigma[0] - b.sigma[0]).norm(), 1e-11 * b.sigma[0].norm());
  EXPECT_EQ(a.eps_p[0], 0.0);
  model->set_plastic(true);
  drive<2>(*model, a, L, 1e-3, 1);
  const double J = a.F[0].determinant();  // the surface is in Kirchhoff stress
  const double f = dp::yield_function(params(1e3, 30, 0, 1.0, 1e13), J * principal_of(a.sigma[0]));
  EXPECT_GT(a.eps_p[0], 1e-3);
  EXPECT_LT(std::abs(f), 1e-8 * J * a.sigma[0].norm());
}
