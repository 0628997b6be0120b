// Mohr-Coulomb (solver/materials/mohr_coulomb.{hpp,cpp}):
//  - the return mapping against states whose exact return is known by construction: a point s* on
//    the main plane, an edge, the apex or the tension cut-off, plus a positive combination of the
//    elastic images D m of the flow vectors active there (trial = s* + Σ Δγ_i D m_i), must come
//    back to s* with Δε^p = Σ Δγ_i m_i — for associated (ψ = φ) and non-associated flow;
//  - 20 000 random trial states: returned state on the surface (Φ = 0 to 1e-10 of the stress
//    scale), inside the cut-off, principal order kept, elastic states bit-identical, the plastic
//    strain of a main-plane return along m = (1 + sin ψ, 0, −1 + sin ψ), every region visited;
//  - the model in a step: a geostatic initial stress is unchanged by a zero increment (the Hencky
//    law is inverted exactly); a rigid rotation rotates the stress and keeps its principal values
//    without plastic strain; elastic states match `hencky` (finite strain) and `linear-elastic`
//    (small strain); plane strain in 3D equals Dim 2;
//  - strength reduction: the plane-strain pure-shear limit (σ_xx − σ_yy)/2 = c_f cos φ_f − σ_m sin φ_f
//    and the triaxial compression limit q/p′ = 6 sin φ_f / (3 − sin φ_f) (c = 0) with SRF 1 and 2.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include "scene/scene.hpp"
#include "solver/materials/material.hpp"
#include "solver/materials/mohr_coulomb.hpp"
#include "solver/transfer/transfer.hpp"
#include "support/material_point.hpp"

using namespace swmpm;
namespace mc = swmpm::mohr_coulomb;
using mc::Principal;

namespace {

constexpr double E = 1.0e7, nu = 0.3;  // Pa, -
const double deg = M_PI / 180.0;

mc::Params params(double c, double phi, double psi, double srf = 1.0, double T = 1.0e30) {
  return mc::Params::from(Elastic::from(E, nu), c, phi, psi, srf, T);
}

scene::Material mc_material(double c, double phi, double psi, double srf = 1.0, double T = 0.0) {
  scene::Material m;
  m.name = "soil";
  m.model = scene::MaterialModel::mohr_coulomb;
  m.params = {{"youngs_modulus", E},   {"poisson_ratio", nu}, {"density", 2000.0},
              {"cohesion", c},         {"friction_angle", phi}, {"dilation_angle", psi},
              {"strength_reduction_factor", srf}, {"tension_cutoff", T}};
  return m;
}

scene::Scene kinematics(const std::string& k) {
  scene::Scene s;
  s.solver.kinematics = k;
  return s;
}

using swmpm::testing::drive;
using swmpm::testing::one_particle;

Principal D(const mc::Params& m, const Principal& v) { return m.stiffness(v); }

void expect_principal_near(const Principal& a, const Principal& b, double tol, const char* what) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(a[i], b[i], tol) << what << " component " << i;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The return mapping alone.

TEST(MohrCoulomb, ElasticTrialIsUnchanged) {
  const auto m = params(10e3, 30, 10, 1.0, 0.0);
  const Principal s(-40e3, -100e3, -60e3);  // Φ = 60e3 - 140e3 * 0.5 - 17.3e3 < 0, mean < 0 = T
  const auto r = mc::return_map(m, s);
  EXPECT_EQ(r.region, mc::Region::elastic);
  EXPECT_EQ(r.s, s);
  EXPECT_EQ(r.deps_p, Principal::Zero());
  EXPECT_LT(mc::yield_function(m, s), 0.0);
}

TEST(MohrCoulomb, MainPlaneReturnByConstruction) {
  for (double psi : {30.0, 10.0, 0.0}) {  // associated, non-associated, no dilatancy
    const auto m = params(10e3, 30, psi);
    const double sf = m.sin_phi, sp = m.sin_psi, k = m.k();
    // s* on the main plane with distinct principal values: σ3 = (σ1 (1 + sin φ) − 2c cos φ) / (1 − sin φ).
    const double s1 = -50e3, s2 = -100e3, s3 = (s1 * (1 + sf) - k) / (1 - sf);  // s3 = -184.6 kPa
    const Principal star(s1, s2, s3), ma(1 + sp, 0, sp - 1);
    ASSERT_NEAR(mc::yield_function(m, star), 0.0, 1e-9);
    const double dg = 2e-3;
    const Principal trial = star + dg * D(m, ma);
    // In another order: the return must come back in the trial's order.
    const Principal shuffled(trial[2], trial[0], trial[1]);
    const auto r = mc::return_map(m, shuffled);
    EXPECT_EQ(r.region, mc::Region::plane) << psi;
    expect_principal_near(r.s, Principal(s3, s1, s2), 1e-10 * 184.6e3, "main plane");
    expect_principal_near(r.deps_p, dg * Principal(ma[2], ma[0], ma[1]), 1e-12, "main plane flow");
    EXPECT_NEAR(mc::yield_function(m, r.s), 0.0, 1e-10 * 184.6e3);
  }
}

TEST(MohrCoulomb, EdgeReturnsByConstruction) {
  for (double psi : {30.0, 10.0}) {
    const auto m = params(10e3, 30, psi);
    const double sf = m.sin_phi, sp = m.sin_psi, k = m.k();
    const Principal ma(1 + sp, 0, sp - 1), mb(0, 1 + sp, sp - 1), mcv(1 + sp, sp - 1, 0);
    {  // edge σ1 = σ2 (triaxial compression): s* = (A, A, B), B = (A (1 + sin φ) − k) / (1 − sin φ)
      const double A = -50e3, B = (A * (1 + sf) - k) / (1 - sf);
      const Principal star(A, A, B);
      const double ga = 2e-3, gb = 0.7e-3;
      const Principal trial = star + ga * D(m, ma) + gb * D(m, mb);
      const auto r = mc::return_map(m, trial);
      EXPECT_EQ(r.region, mc::Region::edge_12) << psi;
      expect_principal_near(r.s, star, 1e-10 * std::abs(B), "edge 12");
      expect_principal_near(r.deps_p, ga * ma + gb * mb, 1e-12, "edge 12 flow");
      EXPECT_NEAR(mc::yield_function(m, r.s), 0.0, 1e-10 * std::abs(B));
    }
    {  // edge σ2 = σ3 (triaxial extension): s* = (A, B, B), A = (k + B (1 − sin φ)) / (1 + sin φ)
      const double B = -100e3, A = (k + B * (1 - sf)) / (1 + sf);
      const Principal star(A, B, B);
      const double ga = 1.5e-3, gc = 1.0e-3;
      const Principal trial = star + ga * D(m, ma) + gc * D(m, mcv);
      const auto r = mc::return_map(m, trial);
      EXPECT_EQ(r.region, mc::Region::edge_23) << psi;
      expect_principal_near(r.s, star, 1e-10 * std::abs(B), "edge 23");
      expect_principal_near(r.deps_p, ga * ma + gc * mcv, 1e-12, "edge 23 flow");
      EXPECT_NEAR(mc::yield_function(m, r.s), 0.0, 1e-10 * std::abs(B));
    }
  }
}

TEST(MohrCoulomb, ApexReturn) {
  for (double psi : {30.0, 15.0}) {
    const auto m = params(10e3, 30, psi);  // no cut-off: apex c cot φ = 17.32 kPa
    const double apex = 10e3 / std::tan(30 * deg);
    EXPECT_NEAR(m.apex, apex, 1e-9);
    const double sp = m.sin_psi;
    // Three flow vectors: strictly inside the apex's cone of returns (two would land on an edge
    // line through the apex, which the edge return already finds).
    const Principal ma(1 + sp, 0, sp - 1), mb(0, 1 + sp, sp - 1), mcv(1 + sp, sp - 1, 0);
    const Principal trial = Principal::Constant(apex) + 1e-3 * D(m, ma) + 2e-3 * D(m, mb) + 0.5e-3 * D(m, mcv);
    const auto r = mc::return_map(m, trial);
    EXPECT_EQ(r.region, mc::Region::apex) << psi;
    expect_principal_near(r.s, Principal::Constant(apex), 1e-9, "apex");
    expect_principal_near(r.deps_p, 1e-3 * ma + 2e-3 * mb + 0.5e-3 * mcv, 1e-12, "apex flow");
  }
}

TEST(MohrCoulomb, TensionCutoffReturns) {
  const double T = 5e3;  // below the apex 17.32 kPa
  const auto m = params(10e3, 30, 10, 1.0, T);
  ASSERT_TRUE(m.cutoff);
  const double sf = m.sin_phi, k = m.k();
  {  // small deviator: pure volumetric shift to mean = T
    const Principal trial(T + 21e3, T + 20e3, T + 19e3);
    const auto r = mc::return_map(m, trial);
    EXPECT_EQ(r.region, mc::Region::cutoff);
    expect_principal_near(r.s, Principal(T + 1e3, T, T - 1e3), 1e-9, "cut-off");
    expect_principal_near(r.deps_p, Principal::Constant(20e3 / (3 * m.K)), 1e-15, "cut-off flow");
  }
  {  // the cut-off plane with the main plane: s* = (T + u, T, T − u), u = (2c cos φ − 2T sin φ)/2,
     // trial = s* + Δγ_t K 1 + Δγ 2G dev(m) (deviatoric part along dev m = (1 + sinψ/3, −2 sinψ/3, −1 + sinψ/3))
    const double u = 0.5 * (k - 2 * T * sf);  // 6.16 kPa
    const Principal star(T + u, T, T - u);
    const double sp = m.sin_psi;
    const Principal dev_m(1 + sp / 3, -2 * sp / 3, -1 + sp / 3);
    const Principal trial = star + Principal::Constant(40e3) + 2 * m.G * 1e-3 * dev_m;
    const auto r = mc::return_map(m, trial);
    EXPECT_EQ(r.region, mc::Region::cutoff_plane);
    expect_principal_near(r.s, star, 1e-9, "cut-off plane");
    EXPECT_NEAR(r.s.sum() / 3, T, 1e-9);
    EXPECT_NEAR(mc::yield_function(m, r.s), 0.0, 1e-9);
  }
  {  // corner with the edge σ1 = σ2: (T + x, T + x, T − 2x), x = (2c cos φ − 2T sin φ)/(3 − sin φ)
    const double x = (k - 2 * T * sf) / (3 - sf);  // 5.774 kPa
    const Principal corner(T + x, T + x, T - 2 * x);
    const double sp = m.sin_psi;
    const Principal ma(1 + sp, 0, sp - 1), mb(0, 1 + sp, sp - 1);
    auto dev = [](Principal v) { return Principal(v.array() - v.sum() / 3); };
    const Principal trial = corner + Principal::Constant(30e3) + 2 * m.G * (1e-3 * dev(ma) + 0.5e-3 * dev(mb));
    const auto r = mc::return_map(m, trial);
    EXPECT_EQ(r.region, mc::Region::cutoff_edge_12);
    expect_principal_near(r.s, corner, 1e-9, "cut-off corner 12");
  }
  {  // corner with the edge σ2 = σ3: (T + 2y, T − y, T − y), y = (2c cos φ − 2T sin φ)/(3 + sin φ)
    const double y = (k - 2 * T * sf) / (3 + sf);
    const Principal corner(T + 2 * y, T - y, T - y);
    const double sp = m.sin_psi;
    const Principal ma(1 + sp, 0, sp - 1), mcv(1 + sp, sp - 1, 0);
    auto dev = [](Principal v) { return Principal(v.array() - v.sum() / 3); };
    const Principal trial = corner + Principal::Constant(30e3) + 2 * m.G * (1e-3 * dev(ma) + 0.5e-3 * dev(mcv));
    const auto r = mc::return_map(m, trial);
    EXPECT_EQ(r.region, mc::Region::cutoff_edge_23);
    expect_principal_near(r.s, corner, 1e-9, "cut-off corner 23");
  }
  {  // T above the apex: the cut-off never acts, the cone's apex does.
    const auto m2 = params(10e3, 30, 10, 1.0, 50e3);
    EXPECT_FALSE(m2.cutoff);
    const auto r = mc::return_map(m2, Principal(60e3, 50e3, 40e3));
    EXPECT_EQ(r.region, mc::Region::apex);
  }
}

TEST(MohrCoulomb, RandomTrialsLandOnTheSurface) {
  // Deterministic LCG; parameter sets cover c = 0, ψ = 0, ψ = φ, cut-off active and not, SRF.
  std::uint64_t state = 12345;
  auto uniform = [&](double a, double b) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return a + (b - a) * static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  struct Set {
    double c, phi, psi, srf, T;
  };
  const std::vector<Set> sets{{10e3, 30, 0, 1, 0},    {0, 35, 35, 1, 0},      {20e3, 30, 0, 2, 1e30},
                              {5e3, 20, 10, 1, 2e3},  {30e3, 40, 20, 1.5, 1e30}, {15e3, 0.0, 0, 1, 0}};
  std::map<mc::Region, int> visits;
  double worst_phi = 0.0, worst_order = 0.0;
  for (const auto& st : sets) {
    const auto m = params(st.c, st.phi, st.psi, st.srf, st.T);
    for (int n = 0; n < 20000 / static_cast<int>(sets.size()); ++n) {
      const Principal trial(uniform(-300e3, 60e3), uniform(-300e3, 60e3), uniform(-300e3, 60e3));
      const auto r = mc::return_map(m, trial);
      ++visits[r.region];
      const double scale = std::max(trial.cwiseAbs().maxCoeff(), st.c);
      const double f = mc::yield_function(m, r.s);
      if (r.region == mc::Region::elastic) {
        ASSERT_EQ(r.s, trial);
        ASSERT_LE(f, 0.0);
        continue;
      }
      // Admissible: Φ <= 0 and mean <= T; plastic cone regions sit on Φ = 0.
      const bool on_cutoff = r.region == mc::Region::cutoff || r.region == mc::Region::cutoff_plane ||
                             r.region == mc::Region::cutoff_edge_12 || r.region == mc::Region::cutoff_edge_23;
      if (r.region != mc::Region::cutoff) worst_phi = std::max(worst_phi, std::abs(f) / scale);
      ASSERT_LE(f, 1e-10 * scale);
      if (on_cutoff) {
        ASSERT_NEAR(r.s.sum() / 3, st.T, 1e-10 * scale);
      }
      if (m.cutoff) {
        ASSERT_LE(r.s.sum() / 3, st.T + 1e-10 * scale);
      }
      // Isotropic return: the principal order of the trial is kept.
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          if (trial[i] > trial[j]) worst_order = std::max(worst_order, (r.s[j] - r.s[i]) / scale);
      ASSERT_LE((m.compliance(trial - r.s) - r.deps_p).norm(), 1e-15);
      if (r.region == mc::Region::plane) {
        int i0 = 0, i2 = 0;
        for (int i = 1; i < 3; ++i) {
          if (trial[i] > trial[i0]) i0 = i;
          if (trial[i] < trial[i2]) i2 = i;
        }
        const int i1 = 3 - i0 - i2;
        const double g = r.deps_p[i0] / (1 + m.sin_psi);
        ASSERT_GT(g, 0.0);
        const double eps_round = 1e-15 * scale / m.G;  // rounding of C⁻¹ (trial − s)
        ASSERT_NEAR(r.deps_p[i1], 0.0, eps_round);
        ASSERT_NEAR(r.deps_p[i2], g * (m.sin_psi - 1), eps_round + 1e-12 * g);
      }
    }
  }
  // Measured: worst |Φ| 3.0e-15 of the stress scale, principal order never reversed.
  std::printf("random returns: worst |Phi|/scale %.2e, worst order violation %.2e\n", worst_phi, worst_order);
  EXPECT_LT(worst_phi, 1e-12);
  EXPECT_LE(worst_order, 1e-12);
  for (auto region : {mc::Region::elastic, mc::Region::plane, mc::Region::edge_12, mc::Region::edge_23,
                      mc::Region::apex, mc::Region::cutoff, mc::Region::cutoff_plane, mc::Region::cutoff_edge_12,
                      mc::Region::cutoff_edge_23})
    EXPECT_GT(visits[region], 0) << "region " << static_cast<int>(region) << " never visited";
}

// ---------------------------------------------------------------------------------------------
// The model in a step.

template <int Dim>
void geostatic_state_is_in_equilibrium(const std::string& kin) {
  // σ0 with K0 = 0.6 and a shear, inside the surface; no deformation: σ must not move.
  const auto model = make_material<Dim>(mc_material(5e3, 30, 0), kinematics(kin));
  Sym s0;
  s0 << -60e3, -100e3, -60e3, -8e3, 0, 0;
  auto ps = one_particle<Dim>(s0);
  drive<Dim>(*model, ps, MatD<Dim>::Zero(), 1e-3, 10);
  std::printf("geostatic %s Dim %d: |sigma - sigma0| = %.2e Pa after 10 steps\n", kin.c_str(), Dim,
              (ps.sigma[0] - s0).norm());
  EXPECT_LT((ps.sigma[0] - s0).norm(), 1e-10 * 100e3) << kin << " Dim " << Dim;
  EXPECT_EQ(ps.eps_p[0], 0.0);
}

TEST(MohrCoulomb, InitialStressIsInEquilibrium) {
  geostatic_state_is_in_equilibrium<2>("finite-strain");
  geostatic_state_is_in_equilibrium<3>("finite-strain");
  geostatic_state_is_in_equilibrium<2>("small-strain");
  geostatic_state_is_in_equilibrium<3>("small-strain");
}

template <int Dim>
void elastic_states_match(const MatD<Dim>& L, int steps, double tol_finite) {
  // No yield (c huge, no cut-off): finite strain is Hencky, small strain is the Jaumann update.
  scene::Material strong = mc_material(1e12, 30, 0, 1.0, 1e13);
  scene::Material hencky = strong, linear = strong;
  hencky.model = scene::MaterialModel::hencky;
  linear.model = scene::MaterialModel::linear_elastic;
  for (const char* kin : {"finite-strain", "small-strain"}) {
    const bool finite = std::string(kin) == "finite-strain";
    const auto model = make_material<Dim>(strong, kinematics(kin));
    const auto ref = make_material<Dim>(finite ? hencky : linear, kinematics(kin));
    auto a = one_particle<Dim>(), b = one_particle<Dim>();
    drive<Dim>(*model, a, L, 1e-3, steps);
    drive<Dim>(*ref, b, L, 1e-3, steps);
    const double err = (a.sigma[0] - b.sigma[0]).norm() / b.sigma[0].norm();
    std::printf("elastic %s Dim %d, |ln V| %.3f: |sigma - reference| / |reference| = %.2e (|reference| %.3g Pa)\n",
                kin, Dim, std::abs(std::log(a.F[0].determinant())), err, b.sigma[0].norm());
    EXPECT_LT(err, finite ? tol_finite : 1e-11) << kin << " Dim " << Dim;
    EXPECT_EQ(a.eps_p[0], 0.0);
  }
}

TEST(MohrCoulomb, ElasticStatesMatchHenckyAndLinearElastic) {
  // 2D: stretch, shear and spin over 0.5 s (about 10 % strain). 3D: 0.4 s of a general L (40 %
  // logarithmic strains, |2 dev ε_e| > 1/8: exp(2 ε_e) then needs the scaling and squaring of sym_exp).
  // Measured: finite strain 2.6e-14 (2D), 1.1e-14 (3D) of |σ| against hencky; small strain
  // 1.6e-15 / 1.5e-14 against linear-elastic.
  MatD<2> L2;
  L2 << -0.2, 0.15, 0.05, 0.1;
  elastic_states_match<2>(L2, 500, 1e-11);
  MatD<3> L3;
  L3 << -1.0, 0.3, 0.1, 0.2, 0.5, -0.4, 0.0, 0.6, 0.2;
  elastic_states_match<3>(L3, 400, 1e-11);
}

template <int Dim>
void rotation_keeps_principal_stresses(const std::string& kin) {
  // Load into plasticity by compression + shear from an isotropic state, then rotate rigidly.
  const auto model = make_material<Dim>(mc_material(5e3, 30, 5), kinematics(kin));
  Sym s0;
  s0 << -100e3, -100e3, -100e3, 0, 0, 0;
  auto ps = one_particle<Dim>(s0);
  MatD<Dim> Ld = MatD<Dim>::Zero();
  Ld(0, 0) = 0.5, Ld(1, 1) = -1.0, Ld(0, 1) = 0.3;
  drive<Dim>(*model, ps, Ld, 1e-4, 500);  // 5 % strain: plastic
  ASSERT_GT(ps.eps_p[0], 1e-4);
  const double eps_p0 = ps.eps_p[0];
  const Mat3 s_before = to_matrix(ps.sigma[0]);
  // Rigid rotation by 90 degrees about z.
  MatD<Dim> W = MatD<Dim>::Zero();
  W(0, 1) = -1.0, W(1, 0) = 1.0;
  const bool finite = kin == "finite-strain";
  const int steps = finite ? 1 : 20000;  // finite strain: exact in one step of any size
  const double dt = (finite ? 2.0 * std::tan(M_PI / 4) : M_PI / 2) / steps;  // Cayley: tan(θ/2) = ω dt/2
  drive<Dim>(*model, ps, W, dt, steps);
  Mat3 R = Mat3::Identity();
  R.topLeftCorner<2, 2>() << 0, -1, 1, 0;
  const Mat3 expected = R * s_before * R.transpose();
  const Mat3 got = to_matrix(ps.sigma[0]);
  Eigen::SelfAdjointEigenSolver<Mat3> e1(s_before), e2(got);
  const double tol = finite ? 1e-10 : 1e-3;  // small strain: Jaumann forward Euler, error O(ω dt)
  // Measured: finite strain 1.0e-15 (2D) and 1.6e-15 (3D) relative; small strain 2.4e-5.
  EXPECT_LT((got - expected).norm(), tol * s_before.norm()) << kin << " Dim " << Dim;
  EXPECT_LT((e1.eigenvalues() - e2.eigenvalues()).norm(), tol * s_before.norm()) << kin;
  std::printf("rotation %s Dim %d: |sigma - R sigma0 R^T| / |sigma0| = %.2e, plastic strain added %.2e\n", kin.c_str(),
              Dim, (got - expected).norm() / s_before.norm(), ps.eps_p[0] - eps_p0);
  // No plastic strain from a rotation. Small strain: the forward-Euler Jaumann update grows |σ| by
  // (ω Δt)² per step, which the return takes back as a little plastic strain (measured 6.2e-6).
  EXPECT_LT(ps.eps_p[0] - eps_p0, finite ? 1e-14 : 2e-5) << kin;
}

TEST(MohrCoulomb, RigidRotationRotatesTheStress) {
  rotation_keeps_principal_stresses<2>("finite-strain");
  rotation_keeps_principal_stresses<3>("finite-strain");
  rotation_keeps_principal_stresses<2>("small-strain");
  rotation_keeps_principal_stresses<3>("small-strain");
}

TEST(MohrCoulomb, PlaneStrainIn3DEqualsDim2) {
  // A plastic plane-strain path (compression, shear, spin) gives the same stress in Dim 2 (2x2
  // closed-form spectral decomposition) and Dim 3 (Eigen computeDirect).
  for (const char* kin : {"finite-strain", "small-strain"}) {
    const auto m2 = make_material<2>(mc_material(5e3, 30, 10, 1.0, 0.0), kinematics(kin));
    const auto m3 = make_material<3>(mc_material(5e3, 30, 10, 1.0, 0.0), kinematics(kin));
    Sym s0;
    s0 << -50e3, -100e3, -50e3, 0, 0, 0;
    const auto [a, b] = swmpm::testing::plane_strain_path(*m2, *m3, s0);
    ASSERT_GT(a.eps_p[0], 0.01);
    std::printf("plane strain %s: |sigma_2D - sigma_3D| / |sigma| = %.2e, plastic strain %.4f\n", kin,
                (a.sigma[0] - b.sigma[0]).norm() / a.sigma[0].norm(), a.eps_p[0]);
    // Measured: 6.2e-14 (finite), 6.0e-15 (small) of |σ|, plastic strain 0.0254.
    EXPECT_LT((a.sigma[0] - b.sigma[0]).norm(), 1e-11 * a.sigma[0].norm()) << kin;
    EXPECT_NEAR(a.eps_p[0], b.eps_p[0], 1e-10 * a.eps_p[0]) << kin;
  }
}

// ---------------------------------------------------------------------------------------------
// Strength reduction on stress paths with closed-form limits.

TEST(MohrCoulomb, StrengthReductionPlaneStrainPureShear) {
  // Plane-strain pure shear L = diag(ε̇, −ε̇) from σ = −100 kPa I, ψ = 0: isochoric, principal axes
  // fixed, σ_zz = σ_m stays −100 kPa, so the limit is (σ_xx − σ_yy)/2 = c_f cos φ_f − σ_m sin φ_f.
  const double c = 20e3, phi = 30, sm = -100e3;
  for (double srf : {1.0, 2.0}) {
    const double tf = std::tan(phi * deg) / srf, phif = std::atan(tf), cf = c / srf;
    const double limit = cf * std::cos(phif) - sm * std::sin(phif);  // SRF 1: 67.32 kPa, SRF 2: 37.34 kPa
    for (const char* kin : {"finite-strain", "small-strain"}) {
      const auto model = make_material<2>(mc_material(c, phi, 0, srf), kinematics(kin));
      Sym s0;
      s0 << sm, sm, sm, 0, 0, 0;
      auto ps = one_particle<2>(s0);
      MatD<2> L = MatD<2>::Zero();
      L(0, 0) = 1.0, L(1, 1) = -1.0;
      drive<2>(*model, ps, L, 1e-5, 2000);  // 2 % strain: yields at 0.87 % (SRF 1)
      const double half_diff = 0.5 * (ps.sigma[0][0] - ps.sigma[0][1]);
      std::printf("pure shear %s SRF %g: (sxx - syy)/2 = %.6g Pa, closed form %.6g Pa\n", kin, srf, half_diff, limit);
      EXPECT_NEAR(half_diff, limit, 1e-9 * limit) << kin << " SRF " << srf;
      EXPECT_NEAR(ps.sigma[0][2], sm, 1e-9 * limit) << kin;
      EXPECT_GT(ps.eps_p[0], 1e-3);
    }
  }
}

TEST(MohrCoulomb, StrengthReductionTriaxialCompression) {
  // Isochoric axisymmetric compression in 3D, L = diag(ε̇/2, −ε̇, ε̇/2) from σ = −p I, ψ = 0:
  // the state stays on the σ1 = σ2 edge with p fixed; failure at q = 3x,
  // x = (2 c_f cos φ_f + 2 p sin φ_f)/(3 − sin φ_f); with c = 0, q/p′ = 6 sin φ_f / (3 − sin φ_f).
  const double p = 100e3, phi = 35;
  for (double c : {0.0, 10e3}) {
    for (double srf : {1.0, 2.0}) {
      const double phif = std::atan(std::tan(phi * deg) / srf), sf = std::sin(phif), cf = c / srf;
      const double q_limit = 3 * (2 * cf * std::cos(phif) + 2 * p * sf) / (3 - sf);
      if (c == 0.0) {
        EXPECT_NEAR(q_limit / p, 6 * sf / (3 - sf), 1e-14);  // SRF 1: 1.4183, SRF 2: 0.7427 (φ = 35°)
      }
      for (const char* kin : {"finite-strain", "small-strain"}) {
        const auto model = make_material<3>(mc_material(c, phi, 0, srf), kinematics(kin));
        Sym s0;
        s0 << -p, -p, -p, 0, 0, 0;
        auto ps = one_particle<3>(s0);
        MatD<3> L = MatD<3>::Zero();
        L(0, 0) = 0.5, L(1, 1) = -1.0, L(2, 2) = 0.5;
        drive<3>(*model, ps, L, 1e-5, 4000);  // 4 % axial strain: yields below 1.5 %
        std::printf("triaxial %s c %g SRF %g: q/p' = %.6f, closed form %.6f\n", kin, c, srf,
                    deviatoric_stress(ps.sigma[0]) / mean_stress(ps.sigma[0]), q_limit / p);
        EXPECT_NEAR(deviatoric_stress(ps.sigma[0]), q_limit, 1e-9 * q_limit) << kin << " SRF " << srf;
        EXPECT_NEAR(mean_stress(ps.sigma[0]), p, 1e-9 * p) << kin;
        EXPECT_NEAR(ps.sigma[0][0], ps.sigma[0][2], 1e-9 * p);  // on the edge σ1 = σ2
        EXPECT_GT(ps.eps_p[0], 1e-3);
      }
    }
  }
}

TEST(MohrCoulomb, StrainEnergyIsTheElasticEnergy) {
  // Uniaxial elastic compression: energy ½ σ:C⁻¹:σ V equals ½ M ε² V0 (small) and Hencky's ψ V0.
  scene::Material strong = mc_material(1e12, 30, 0, 1.0, 1e13);
  scene::Material hencky = strong;
  hencky.model = scene::MaterialModel::hencky;
  MatD<2> L = MatD<2>::Zero();
  L(1, 1) = -0.1;
  const auto model = make_material<2>(strong, kinematics("finite-strain"));
  const auto ref = make_material<2>(hencky, kinematics("finite-strain"));
  auto a = one_particle<2>(), b = one_particle<2>();
  drive<2>(*model, a, L, 1e-3, 1000);  // 10 % log strain
  drive<2>(*ref, b, L, 1e-3, 1000);
  std::printf("strain energy: %.12g J vs hencky %.12g J\n", model->strain_energy(a, 0), ref->strain_energy(b, 0));
  EXPECT_NEAR(model->strain_energy(a, 0), ref->strain_energy(b, 0), 1e-9 * ref->strain_energy(b, 0));
}

TEST(MohrCoulomb, PlasticFlowSwitchedOffIsTheElasticModel) {
  // The initialisation phase (set_plastic(false)): a weak soil driven far beyond yield responds as
  // its elastic part (hencky / linear-elastic) with no plastic strain; switched on again, the next
  // step returns the stress to the surface.
  scene::Material weak = mc_material(1e3, 30, 0, 1.0, 1e13), hencky = weak, linear = weak;
  hencky.model = scene::MaterialModel::hencky;
  linear.model = scene::MaterialModel::linear_elastic;
  MatD<2> L;
  L << -0.2, 0.15, 0.05, 0.1;
  for (const char* kin : {"finite-strain", "small-strain"}) {
    const bool finite = std::string(kin) == "finite-strain";
    auto model = make_material<2>(weak, kinematics(kin));
    const auto ref = make_material<2>(finite ? hencky : linear, kinematics(kin));
    model->set_plastic(false);
    auto a = one_particle<2>(), b = one_particle<2>();
    drive<2>(*model, a, L, 1e-3, 200);
    drive<2>(*ref, b, L, 1e-3, 200);
    const double err = (a.sigma[0] - b.sigma[0]).norm() / b.sigma[0].norm();
    EXPECT_LT(err, 1e-11) << kin;
    EXPECT_EQ(a.eps_p[0], 0.0) << kin;
    model->set_plastic(true);
    drive<2>(*model, a, L, 1e-3, 1);
    const mc::Params m = params(1e3, 30, 0);
    Eigen::SelfAdjointEigenSolver<Mat3> e(to_matrix(a.sigma[0]));
    const double J = finite ? a.F[0].determinant() : 1.0;  // the surface is in Kirchhoff stress
    std::printf("plasticity off for 200 steps (%s): |sigma - elastic| / |elastic| = %.1e; on: eps_p %.3g, "
                "yield function %.2e of |sigma|\n", kin, err, a.eps_p[0],
                mc::yield_function(m, J * Principal(e.eigenvalues())) / a.sigma[0].norm());
    EXPECT_GT(a.eps_p[0], 1e-3) << kin;
    EXPECT_LT(std::abs(mc::yield_function(m, J * Principal(e.eigenvalues()))), 1e-8 * J * a.sigma[0].norm()) << kin;
  }
}
