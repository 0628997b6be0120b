// `mohr-coulomb`: Mohr-Coulomb perfect plasticity, non-associated (dilation angle ψ), with
// strength reduction and a tension cut-off, in finite strain (default) or small strain
// (`solver.kinematics`). The return mapping is in mohr_coulomb.hpp; the equations are in
// docs/formulations.md, "Mohr-Coulomb (materials/mohr_coulomb.cpp)".
//
// Finite strain: multiplicative elastoplasticity with Hencky elasticity (de Souza Neto et al. 2008,
// §14.5). The elastic left Cauchy-Green tensor b_e is not stored: isotropic Hencky elasticity makes
// it a function of the Kirchhoff stress, b_e = exp(2 C⁻¹ : τ) (coaxial with τ), and τ_n = J_n σ_n
// with J_n = det F_n = det F_{n+1} / det ΔF. So each step rebuilds b_e,n from σ_n: nothing to carry
// through reordering, snapshots or restarts, and an initial (geostatic) stress is an elastic state
// in equilibrium at step 0.
#include "solver/materials/mohr_coulomb.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "solver/materials/hencky_trial.hpp"
#include "solver/materials/spectral.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {
namespace {

namespace mc = mohr_coulomb;
using mc::Principal;
using spectral::eig2;
using spectral::Eig2;
using spectral::rebuild;
using spectral::Sym2;

template <int Dim>
class MohrCoulomb final : public MaterialModel<Dim> {
 public:
  MohrCoulomb(Elastic e, mc::Params p, bool finite) : e_(e), p_(p), finite_(finite) {}
  std::string name() const override { return "mohr-coulomb"; }
  double p_wave_modulus() const override { return e_.p_wave(); }
  void set_plastic(bool on) override { plastic_ = on; }

  long update_stress(ParticleSet<Dim>& ps, std::span<const int> ids, double dt) const override {
    return update_each(ps, ids, [&](int p) { return finite_ ? finite_strain(ps, p, dt) : small_strain(ps, p, dt); });
  }

  /// ε_v^e of b_e,n: tr τ_n / 3K (finite strain, τ_n = J_n σ_n) or tr σ_n / 3K (small strain).
  void elastic_volumetric_strain(const ParticleSet<Dim>& ps, std::span<const int> ids, double dt,
                                 std::span<double> ev) const override {
    for_each_id(ids, [&](int p) {
      const double Jn = finite_ ? ps.F[p].determinant() / transfer::deformation_jacobian<Dim>(ps.L[p], dt)
                                : 1.0;
      ev[p] = hencky::volumetric_strain(e_, ps.sigma[p], Jn);
    });
  }

  /// Stored elastic energy. Finite strain: ½ τ : C⁻¹ : τ per reference volume times V0 (= ψ of
  /// Hencky elasticity in the elastic logarithmic strain); small strain: ½ σ : C⁻¹ : σ V.
  double strain_energy(const ParticleSet<Dim>& ps, int p) const override {
    const double J = finite_ ? ps.F[p].determinant() : 1.0;
    const double w = hencky::complementary_energy_density(e_, ps.sigma[p]);
    return finite_ ? w * J * J * ps.V0[p] : w * ps.V[p];
  }

 private:
  /// The return mapping, or the elastic trial itself while plastic flow is off.
  mc::Return admissible(const Principal& trial) const {
    if (plastic_) return mc::return_map(p_, trial);
    return mc::Return{trial, Principal::Zero(), mc::Region::elastic};
  }

  void add_plastic(ParticleSet<Dim>& ps, int p, const mc::Return& r) const {
    if (r.region != mc::Region::elastic) ps.eps_p[p] += mc::equivalent_plastic_increment(r.deps_p);
  }

  /// b_e,n from σ_n and J_n (shifted by ps.ev_shift under the modified F-bar); b_tr = ΔF b_e,n ΔFᵀ;
  /// ε_tr = ½ ln b_tr; τ_tr = D ε_tr; return; σ = τ / J (materials/hencky_trial.hpp).
  bool finite_strain(ParticleSet<Dim>& ps, int p, double dt) const {
    const MatD<Dim> dF = transfer::deformation_increment<Dim>(ps.L[p], dt);
    const double J = ps.F[p].determinant();
    if (!(J > 0.0)) return false;
    const double Jn = J / dF.determinant();
    hencky::Trial<Dim> t;
    if (!hencky::trial<Dim>(e_, ps.sigma[p], Jn, dF, ps.ev_shift.empty() ? 0.0 : ps.ev_shift[p], t)) return false;
    const mc::Return r = admissible(p_.stiffness(t.eps));
    ps.sigma[p] = hencky::cauchy<Dim>(t, r.s, J);
    add_plastic(ps, p, r);
    return true;
  }

  /// Trial σ_tr = σ_n + Δt (λ tr D I + 2G D + W σ − σ W) (Jaumann, as linear-elastic); return.
  /// Under the modified F-bar σ_n is first shifted by K ps.ev_shift[p] 1 (the small-strain b̄_e).
  bool small_strain(ParticleSet<Dim>& ps, int p, double dt) const {
    Sym& s = ps.sigma[p];
    if (!ps.ev_shift.empty()) s.template head<3>().array() += e_.K * ps.ev_shift[p];
    const double G = e_.mu;
    if constexpr (Dim == 2) {
      const auto& L = ps.L[p];
      const double dxx = L(0, 0), dyy = L(1, 1), dxy = 0.5 * (L(0, 1) + L(1, 0)), w = 0.5 * (L(0, 1) - L(1, 0));
      const double lam_tr = e_.lambda * (dxx + dyy);
      const double sxx = s[0] + dt * (lam_tr + 2.0 * G * dxx + 2.0 * w * s[3]);
      const double syy = s[1] + dt * (lam_tr + 2.0 * G * dyy - 2.0 * w * s[3]);
      const double szz = s[2] + dt * lam_tr;
      const double sxy = s[3] + dt * (2.0 * G * dxy + w * (s[1] - s[0]));
      const Eig2 e = eig2(sxx, syy, sxy);
      const mc::Return r = admissible(Principal(e.l1, e.l2, szz));
      const Sym2 t = rebuild(e, r.s[0], r.s[1]);
      s << t.xx, t.yy, r.s[2], t.xy, 0.0, 0.0;
      add_plastic(ps, p, r);
    } else {
      const Mat3 L = embed<Dim>(ps.L[p]);
      const Mat3 D = 0.5 * (L + L.transpose()), W = 0.5 * (L - L.transpose());
      const Mat3 sm = to_matrix(s);
      const Mat3 tr = sm + dt * (e_.lambda * D.trace() * Mat3::Identity() + 2.0 * G * D + W * sm - sm * W);
      Eigen::SelfAdjointEigenSolver<Mat3> eig;
      eig.computeDirect(0.5 * (tr + tr.transpose()));
      const mc::Return r = admissible(eig.eigenvalues());
      const Mat3& Q = eig.eigenvectors();
      s = to_voigt(Q * r.s.asDiagonal() * Q.transpose());
      add_plastic(ps, p, r);
    }
    return true;
  }

  Elastic e_;
  mc::Params p_;
  bool finite_;
  bool plastic_ = true;
};

}  // namespace

template <int Dim>
std::unique_ptr<MaterialModel<Dim>> make_mohr_coulomb(const scene::Material& m, const scene::Scene& s) {
  const Elastic e = Elastic::from(m.at("youngs_modulus"), m.at("poisson_ratio"));
  const auto opt = [&](const char* key, double def) { return m.has(key) ? m.at(key) : def; };
  const mc::Params p = mc::Params::from(e, opt("cohesion", 0.0), m.at("friction_angle"), opt("dilation_angle", 0.0),
                                        opt("strength_reduction_factor", 1.0), opt("tension_cutoff", 0.0));
  if (s.solver.kinematics != "finite-strain" && s.solver.kinematics != "small-strain")
    throw std::runtime_error("material \"" + m.name + "\": solver.kinematics \"" + s.solver.kinematics +
                             "\" is not one of small-strain, finite-strain");
  return std::make_unique<MohrCoulomb<Dim>>(e, p, s.solver.kinematics == "finite-strain");
}

template std::unique_ptr<MaterialModel<2>> make_mohr_coulomb<2>(const scene::Material&, const scene::Scene&);
template std::unique_ptr<MaterialModel<3>> make_mohr_coulomb<3>(const scene::Material&, const scene::Scene&);

}  // namespace swmpm
