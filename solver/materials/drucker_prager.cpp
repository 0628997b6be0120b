// `drucker-prager`: Drucker-Prager perfect plasticity (seed 004 eqs. 15-19), non-associated
// (dilation angle ψ), with strength reduction and a tension cut-off, in finite strain. The return
// mapping is in drucker_prager.hpp; the equations are in docs/formulations.md, "Drucker-Prager
// (materials/drucker_prager.cpp)".
//
// Kinematics as `mohr-coulomb` in finite strain: multiplicative elastoplasticity with Hencky
// elasticity (seed 004 eq. 16; de Souza Neto et al. 2008, §14.5). b_e,n is not stored but rebuilt
// each step from σ_n and J_n (b_e = exp(2 C⁻¹ : τ), τ_n = J_n σ_n; materials/hencky_trial.hpp), the
// trial is b_tr = ΔF b_e,n ΔFᵀ, ε_tr = ½ ln b_tr in principal values, τ_tr = D ε_tr; the return is
// on the principal Kirchhoff stresses with the principal directions fixed; σ = τ / J.
#include "solver/materials/drucker_prager.hpp"

#include <stdexcept>

#include "solver/materials/hencky_trial.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {
namespace {

namespace dp = drucker_prager;
using dp::Principal;

template <int Dim>
class DruckerPrager final : public MaterialModel<Dim> {
 public:
  DruckerPrager(Elastic e, dp::Params p) : e_(e), p_(p) {}
  std::string name() const override { return "drucker-prager"; }
  double p_wave_modulus() const override { return e_.p_wave(); }
  void set_plastic(bool on) override { plastic_ = on; }

  /// b_e,n from σ_n and J_n (shifted by ps.ev_shift under the modified F-bar); b_tr = ΔF b_e,n ΔFᵀ;
  /// ε_tr = ½ ln b_tr; τ_tr = D ε_tr; return; σ = τ / J.
  long update_stress(ParticleSet<Dim>& ps, std::span<const int> ids, double dt) const override {
    return update_each(ps, ids, [&](int p) {
      const MatD<Dim> dF = transfer::deformation_increment<Dim>(ps.L[p], dt);
      const double J = ps.F[p].determinant();
      if (!(J > 0.0)) return false;
      hencky::Trial<Dim> t;
      if (!hencky::trial<Dim>(e_, ps.sigma[p], J / dF.determinant(), dF, ps.ev_shift.empty() ? 0.0 : ps.ev_shift[p], t))
        return false;
      const dp::Return r = admissible(hencky::stress(e_, t.eps));
      ps.sigma[p] = hencky::cauchy<Dim>(t, r.s, J);
      if (r.region != dp::Region::elastic) ps.eps_p[p] += dp::equivalent_plastic_increment(r.deps_p);
      return true;
    });
  }

  /// ε_v^e of b_e,n: tr τ_n / 3K, τ_n = J_n σ_n.
  void elastic_volumetric_strain(const ParticleSet<Dim>& ps, std::span<const int> ids, double dt,
                                 std::span<double> ev) const override {
    for_each_id(ids, [&](int p) {
      const double Jn = ps.F[p].determinant() / transfer::deformation_jacobian<Dim>(ps.L[p], dt);
      ev[p] = hencky::volumetric_strain(e_, ps.sigma[p], Jn);
    });
  }

  /// Stored elastic energy ½ τ : C⁻¹ : τ per reference volume times V0 (= ψ of Hencky elasticity,
  /// seed 004 eq. 16, in the elastic logarithmic strain), τ = J σ.
  double strain_energy(const ParticleSet<Dim>& ps, int p) const override {
    const double J = ps.F[p].determinant();
    return hencky::complementary_energy_density(e_, ps.sigma[p]) * J * J * ps.V0[p];
  }

 private:
  /// The return mapping, or the elastic trial itself while plastic flow is off.
  dp::Return admissible(const Principal& trial) const {
    if (plastic_) return dp::return_map(p_, trial);
    return dp::Return{trial, Principal::Zero(), dp::Region::elastic};
  }

  Elastic e_;
  dp::Params p_;
  bool plastic_ = true;
};

}  // namespace

template <int Dim>
std::unique_ptr<MaterialModel<Dim>> make_drucker_prager(const scene::Material& m, const scene::Scene& s) {
  if (s.solver.kinematics != "finite-strain")
    throw std::runtime_error("material \"" + m.name + "\": drucker-prager is a finite-strain model (Hencky "
                             "elasticity, seed 004); solver.kinematics \"" + s.solver.kinematics +
                             "\" is not supported (use finite-strain)");
  const Elastic e = Elastic::from(m.at("youngs_modulus"), m.at("poisson_ratio"));
  const auto opt = [&](const char* key, double def) { return m.has(key) ? m.at(key) : def; };
  return std::make_unique<DruckerPrager<Dim>>(
      e, dp::Params::from(e, opt("cohesion", 0.0), m.at("friction_angle"), opt("dilation_angle", 0.0),
                          opt("strength_reduction_factor", 1.0), opt("tension_cutoff", 0.0)));
}

template std::unique_ptr<MaterialModel<2>> make_drucker_prager<2>(const scene::Material&, const scene::Scene&);
template std::unique_ptr<MaterialModel<3>> make_drucker_prager<3>(const scene::Material&, const scene::Scene&);

}  // namespace swmpm
