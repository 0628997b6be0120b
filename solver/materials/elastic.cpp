// Elastic models: `linear-elastic` (hypoelastic, Jaumann rate — small strains, objective under
// rotation) and `hencky` (hyperelastic, logarithmic strain — finite strains).
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "solver/materials/drucker_prager.hpp"
#include "solver/materials/hencky_trial.hpp"
#include "solver/materials/material.hpp"
#include "solver/materials/mohr_coulomb.hpp"
#include "solver/materials/nor_sand.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {
namespace {


template <int Dim>
class LinearElastic final : public MaterialModel<Dim> {
 public:
  explicit LinearElastic(Elastic e) : e_(e) {}
  std::string name() const override { return "linear-elastic"; }
  double p_wave_modulus() const override { return e_.p_wave(); }

  /// Under the modified F-bar σ_n is first shifted by K ps.ev_shift[p] 1 (the hypoelastic b̄_e:
  /// the elastic volumetric strain tr σ / 3K moves by the shift).
  long update_stress(ParticleSet<Dim>& ps, std::span<const int> ids, double dt) const override {
    return update_each(ps, ids, [&](int p) {
      Sym& s = ps.sigma[p];
      if (!ps.ev_shift.empty()) s.template head<3>().array() += e_.K * ps.ev_shift[p];
      if constexpr (Dim == 2) {
        // Plane strain written out: D in-plane, W = [[0, w], [-w, 0]], w = (L_xy - L_yx)/2.
        const auto& L = ps.L[p];
        const double dxx = L(0, 0), dyy = L(1, 1), dxy = 0.5 * (L(0, 1) + L(1, 0)), w = 0.5 * (L(0, 1) - L(1, 0));
        const double lam_tr = e_.lambda * (dxx + dyy), two_mu = 2.0 * e_.mu;
        const double sxx = s[0], syy = s[1], sxy = s[3];
        s[0] += dt * (lam_tr + two_mu * dxx + 2.0 * w * sxy);
        s[1] += dt * (lam_tr + two_mu * dyy - 2.0 * w * sxy);
        s[2] += dt * lam_tr;
        s[3] += dt * (two_mu * dxy + w * (syy - sxx));
      } else {
        const Mat3 L = embed<Dim>(ps.L[p]);
        const Mat3 D = 0.5 * (L + L.transpose());  // rate of deformation
        const Mat3 W = 0.5 * (L - L.transpose());  // spin
        const Mat3 sm = to_matrix(s);
        // Jaumann rate: sigma_dot = C : D + W sigma - sigma W
        const Mat3 rate = e_.lambda * D.trace() * Mat3::Identity() + 2.0 * e_.mu * D + W * sm - sm * W;
        s = to_voigt(sm + dt * rate);
      }
      return true;
    });
  }

  /// ε_v^e = tr σ_n / 3K.
  void elastic_volumetric_strain(const ParticleSet<Dim>& ps, std::span<const int> ids, double,
                                 std::span<double> ev) const override {
    for_each_id(ids, [&](int p) { ev[p] = hencky::volumetric_strain(e_, ps.sigma[p], 1.0); });
  }

  /// Complementary energy 1/2 sigma : C^-1 : sigma V (exact for linear elasticity).
  double strain_energy(const ParticleSet<Dim>& ps, int p) const override {
    const Sym& s = ps.sigma[p];
    const double tr = s[0] + s[1] + s[2];
    const double ss = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] +
                      2.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]);
    return 0.5 * ((1.0 + e_.nu) / e_.E * ss - e_.nu / e_.E * tr * tr) * ps.V[p];
  }

 private:
  Elastic e_;
};

template <int Dim>
class Hencky final : public MaterialModel<Dim> {
 public:
  explicit Hencky(Elastic e) : e_(e) {}
  std::string name() const override { return "hencky"; }
  double p_wave_modulus() const override { return e_.p_wave(); }

  /// Total form from F_{n+1}; under the modified F-bar (ps.ev_shift allocated) the incremental form
  /// of materials/hencky_trial.hpp instead: b_e,n rebuilt from σ_n and shifted, b_tr = ΔF b̄_e,n ΔFᵀ.
  /// Without a shift the two agree to round-off (an elastic model has b_e,n = F_n F_nᵀ), but the
  /// incremental one keeps an initial stress and the shifts of earlier steps.
  long update_stress(ParticleSet<Dim>& ps, std::span<const int> ids, double dt) const override {
    if (!ps.ev_shift.empty())
      return update_each(ps, ids, [&](int p) {
        const MatD<Dim> dF = transfer::deformation_increment<Dim>(ps.L[p], dt);
        const double J = ps.F[p].determinant();
        if (!(J > 0.0)) return false;
        hencky::Trial<Dim> t;
        if (!hencky::trial<Dim>(e_, ps.sigma[p], J / dF.determinant(), dF, ps.ev_shift[p], t)) return false;
        ps.sigma[p] = hencky::cauchy<Dim>(t, hencky::stress(e_, t.eps), J);
        return true;
      });
    return update_each(ps, ids, [&](int p) {
      const Mat3& F = ps.F[p];
      const double J = F.determinant();
      if (!(J > 0.0)) return false;
      // Kirchhoff stress tau = lambda tr(eps) I + 2 mu eps, eps = 1/2 ln(F F^T); sigma = tau / J.
      Eigen::SelfAdjointEigenSolver<Mat3> eig;
      eig.computeDirect(F * F.transpose());
      const Eigen::Vector3d eps = 0.5 * eig.eigenvalues().array().log();
      const double tr = eps.sum();
      const Eigen::Vector3d tau = e_.lambda * tr * Eigen::Vector3d::Ones() + 2.0 * e_.mu * eps;
      const Mat3& Q = eig.eigenvectors();
      ps.sigma[p] = to_voigt(Q * (tau / J).asDiagonal() * Q.transpose());
      return true;
    });
  }

  /// ε_v^e = tr τ_n / 3K, τ_n = J_n σ_n (= ln J_n in the total form, where b_e,n = F_n F_nᵀ).
  void elastic_volumetric_strain(const ParticleSet<Dim>& ps, std::span<const int> ids, double dt,
                                 std::span<double> ev) const override {
    for_each_id(ids, [&](int p) {
      const double Jn = ps.F[p].determinant() / transfer::deformation_jacobian<Dim>(ps.L[p], dt);
      ev[p] = hencky::volumetric_strain(e_, ps.sigma[p], Jn);
    });
  }

  /// Stored energy psi = mu eps:eps + lambda/2 tr(eps)^2 per reference volume, times V0.
  double strain_energy(const ParticleSet<Dim>& ps, int p) const override {
    Eigen::SelfAdjointEigenSolver<Mat3> eig;
    eig.computeDirect(ps.F[p] * ps.F[p].transpose());
    const Eigen::Vector3d eps = 0.5 * eig.eigenvalues().array().log();
    const double tr = eps.sum();
    return (e_.mu * eps.squaredNorm() + 0.5 * e_.lambda * tr * tr) * ps.V0[p];
  }

 private:
  Elastic e_;
};

}  // namespace

template <int Dim>
std::unique_ptr<MaterialModel<Dim>> make_material(const scene::Material& m, const scene::Scene& s) {
  using scene::MaterialModel;
  switch (m.model) {
    case MaterialModel::linear_elastic:
      return std::make_unique<LinearElastic<Dim>>(Elastic::from(m.at("youngs_modulus"), m.at("poisson_ratio")));
    case MaterialModel::hencky:
      return std::make_unique<Hencky<Dim>>(Elastic::from(m.at("youngs_modulus"), m.at("poisson_ratio")));
    case MaterialModel::mohr_coulomb:
      return make_mohr_coulomb<Dim>(m, s);  // materials/mohr_coulomb.cpp
    case MaterialModel::drucker_prager:
      return make_drucker_prager<Dim>(m, s);  // materials/drucker_prager.cpp
    case MaterialModel::nor_sand:
      return make_nor_sand<Dim>(m, s);  // materials/nor_sand.cpp
    default:
      throw std::runtime_error("material \"" + m.name + "\": model \"" + scene::to_string(m.model) +
                               "\" is not implemented yet in this version (available: linear-elastic, hencky, "
                               "mohr-coulomb, drucker-prager, nor-sand)");
  }
}

bool needs_material_state(const scene::Scene& s) {
  for (const auto& m : s.materials)
    if (m.model == scene::MaterialModel::nor_sand) return true;
  return false;
}

template std::unique_ptr<MaterialModel<2>> make_material<2>(const scene::Material&, const scene::Scene&);
template std::unique_ptr<MaterialModel<3>> make_material<3>(const scene::Material&, const scene::Scene&);

}  // namespace swmpm
