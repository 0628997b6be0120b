// `nor-sand`: Borja & Andrade (2006) Nor-Sand in finite deformation, with seed 001's dilatancy
// cut-off and gas-like state (App. B). The return mapping is in nor_sand.hpp; the equations are in
// docs/formulations.md, "Nor-Sand (materials/nor_sand.cpp)".
//
// Kinematics as `mohr-coulomb` in finite strain: multiplicative elastoplasticity, b_e not stored
// but rebuilt each step from σ_n (the hyperelastic law is isotropic, so ε_e is coaxial with τ and
// a function of it, ε_e = A 1 + B τ, NS4), trial b_e^tr = ΔF b_e,n ΔFᵀ, return in its principal
// logarithmic strains, σ = τ / J. The internal variables (π_i, Ē_d^p, ψ_start) live in
// ParticleSet::state. A zero stress (a point that never had one, or a gas-like one) is read as
// zero elastic strain, ε_e,n = 0 (seed 001 after eq. 93: b_e ≈ I).
//
// Specific volume v = J v0 (seed 001 eq. 95) with J = det F of the particle. With F-bar on, this is
// the stabilised J̄ (eqs. 96–97): the F-bar stage (transfer/fbar.hpp) leaves F̄ (det F̄ = J̄) in ps.F
// before the stress update, and this model reads it unchanged. Under the modified F-bar b_e,n is
// shifted by ps.ev_shift (eq. 82) before the trial.
#include "solver/materials/nor_sand.hpp"

#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "solver/materials/spectral.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {

nor_sand::Params nor_sand::Params::from(const scene::Material& m) {
  Params p;
  p.mu0 = m.at("shear_modulus");
  p.alpha0 = m.at("shear_modulus_coupling");
  p.kappa = m.at("swelling_index");
  p.p_ref = m.at("reference_pressure");
  p.eps_v0 = m.at("reference_elastic_volumetric_strain");
  p.lambda = m.at("compression_index");
  p.v_c0 = m.at("reference_specific_volume");
  p.p_csl = m.at("csl_reference_pressure");
  p.M = m.at("critical_state_ratio");
  p.N = m.at("yield_coefficient");
  p.N_bar = m.at("potential_coefficient");
  p.h = m.at("hardening_modulus");
  p.alpha = m.at("dilatancy_multiplier");
  p.v0 = m.at("initial_specific_volume");
  p.ocr = m.at("overconsolidation_ratio");
  p.cutoff_start = m.at("dilatancy_cutoff_start");
  p.cutoff_end = m.at("dilatancy_cutoff_end");
  p.gas_ratio = m.at("gas_specific_volume_ratio");
  return p;
}

namespace {

namespace ns = nor_sand;
using ns::Principal;
using spectral::eig2;
using spectral::Eig2;
using spectral::rebuild;
using spectral::Sym2;

template <int Dim>
class NorSand final : public MaterialModel<Dim> {
 public:
  explicit NorSand(ns::Params p) : p_(p) {}
  std::string name() const override { return "nor-sand"; }
  /// Off: the hyperelastic trial (NS2) is the stress and π_i stays unset, so that the first plastic
  /// step takes it from the stress then (App. B.4: p0, ε_v0^e from the end of elastic loading), by
  /// eq. 113 as printed: π_i = OCR p0 (1 − N)^{(1−N)/N} from the mean stress alone, so a point with
  /// a deviator starts outside the surface and yields at once (the landslides of §5.4 start so).
  /// Without an elastic phase (a geostatic initial stress, say), π_i puts the stress point itself
  /// on the surface (eq. 113 generalised to q > 0): the initial state is in equilibrium at step 0.
  void set_plastic(bool on) override {
    plastic_ = on;
    if (!on) after_elastic_phase_ = true;
  }

  /// K + 4G/3 at zero elastic strain: K = p̂(0)/κ̃ (formulations ask max_p_wave_modulus instead).
  double p_wave_modulus() const override { return modulus_at(p_.p_unstrained()); }
  /// Tangent K = p/κ̃ (NS3 at ε_s = 0) and μ_e = μ0 + α0 p at the largest Kirchhoff pressure.
  double max_p_wave_modulus(const ParticleSet<Dim>& ps, std::span<const int> ids) const override {
    double p_max = p_.p_unstrained();
    for (int p : ids) p_max = std::max(p_max, mean_stress(ps.sigma[p]) * ps.F[p].determinant());
    return modulus_at(p_max);
  }

  long update_stress(ParticleSet<Dim>& ps, std::span<const int> ids, double dt) const override {
    if (ps.state.size() != ps.size())
      throw std::logic_error("nor-sand: the particle set carries no material state (add_material_state)");
    return update_each(ps, ids, [&](int p) { return update(ps, p, dt); });
  }

  /// ε_v^e of b_e,n by NS4 from τ_n = J_n σ_n: ε_v = 3 (A − p B); 0 for a point without compression
  /// (read as zero elastic strain, as update_stress does).
  void elastic_volumetric_strain(const ParticleSet<Dim>& ps, std::span<const int> ids, double dt,
                                 std::span<double> ev) const override {
    for_each_id(ids, [&](int p) {
      const double Jn = ps.F[p].determinant() / transfer::deformation_jacobian<Dim>(ps.L[p], dt);
      const double pk = Jn * mean_stress(ps.sigma[p]);
      if (!(pk > 0.0)) {
        ev[p] = 0.0;
        return;
      }
      const ns::Coaxial c = ns::elastic_strain_of(p_, pk, Jn * deviatoric_stress(ps.sigma[p]));
      ev[p] = 3.0 * (c.A - pk * c.B);
    });
  }

  /// Ψ (NS1) of the elastic strain rebuilt from σ, per reference volume, times V0.
  double strain_energy(const ParticleSet<Dim>& ps, int p) const override {
    const double J = ps.F[p].determinant();
    const double pk = J * mean_stress(ps.sigma[p]);
    if (!(pk > 0.0)) return 0.0;
    const double qk = J * deviatoric_stress(ps.sigma[p]);
    const ns::Coaxial c = ns::elastic_strain_of(p_, pk, qk);
    const double mu = 1.0 / (2.0 * c.B);
    // NS4: B = 1/2μ_e, A = ε_v/3 + p B, so ε_v = 3 (A − p B); ε_s = q / 3μ_e.
    ns::Elastic el;
    el.eps_v = 3.0 * (c.A - pk * c.B);
    el.eps_s = qk / (3.0 * mu);
    el.p_hat = p_.p_ref * std::exp(-(el.eps_v - p_.eps_v0) / p_.kappa);
    el.mu = mu;
    return ns::stored_energy(p_, el) * ps.V0[p];
  }

  std::vector<std::string> report_names() const override {
    return {"specific_volume", "state_parameter", "image_pressure"};
  }
  /// v = J v0, ψ = v − v_c(p) with the Kirchhoff p = J p_σ (NS6; NaN when p <= 0: gas-like) and
  /// π_i [Pa] (NaN while unset: before the first plastic step).
  void report_values(const ParticleSet<Dim>& ps, int p, std::span<double> out) const override {
    const double J = ps.F[p].determinant(), v = J * p_.v0, pk = J * mean_stress(ps.sigma[p]);
    out[0] = v;
    out[1] = pk > 0.0 ? v - p_.v_csl(pk) : std::nan("");
    const double pi = ps.state.size() == ps.size() ? ns::State::load(ps.state[p]).pi : 0.0;
    out[2] = pi > 0.0 ? pi : std::nan("");
  }

 private:
  double modulus_at(double p) const { return p / p_.kappa + 4.0 / 3.0 * (p_.mu0 + p_.alpha0 * p); }

  /// One particle. When the return mapping does not converge (a trial far outside the surface:
  /// a velocity-gradient spike at a free surface gave q/p ≈ 300 in one step of B5), the step is
  /// repeated in 64 or 256 equal sub-steps of the same velocity gradient (F_n → F_{n+1} through
  /// ΔF(L, dt/m)^k), each a full return; the modified F-bar shift applies to the first only.
  bool update(ParticleSet<Dim>& ps, int p, double dt) const {
    const double shift = ps.ev_shift.empty() ? 0.0 : ps.ev_shift[p];
    if (update_once(ps, p, dt, shift)) return true;
    // update_once writes σ, the state and ε_p only on success: they still hold step n here.
    const Sym sigma_n = ps.sigma[p];
    const MaterialState state_n = ps.state[p];
    const double eps_p_n = ps.eps_p[p];
    const Mat3 F_end = ps.F[p];
    Mat3 dF = Mat3::Identity();
    dF.template topLeftCorner<Dim, Dim>() = transfer::deformation_increment<Dim>(ps.L[p], dt);
    const Mat3 F_n = dF.inverse() * F_end;
    for (int m : {64, 256}) {
      ps.sigma[p] = sigma_n, ps.state[p] = state_n, ps.eps_p[p] = eps_p_n, ps.F[p] = F_n;
      Mat3 dF_sub = Mat3::Identity();
      dF_sub.template topLeftCorner<Dim, Dim>() = transfer::deformation_increment<Dim>(ps.L[p], dt / m);
      bool ok = true;
      for (int k = 0; k < m && ok; ++k) {
        ps.F[p] = k + 1 == m ? F_end : Mat3(dF_sub * ps.F[p]);
        ok = update_once(ps, p, dt / m, k == 0 ? shift : 0.0);
      }
      if (ok) return true;
    }
    ps.F[p] = F_end;
    return false;
  }

  /// One step: gas-like check (eq. 93), b_e,n from σ_n (shifted by the modified F-bar's ln(J̄^e/J^e)),
  /// trial, return (NS10–11), σ = τ / J.
  bool update_once(ParticleSet<Dim>& ps, int p, double dt, double shift) const {
    const MatD<Dim> dF = transfer::deformation_increment<Dim>(ps.L[p], dt);
    const double J = ps.F[p].determinant();
    if (!(J > 0.0)) return false;
    const double Jn = J / dF.determinant(), v = J * p_.v0;
    Sym& s = ps.sigma[p];
    if (v > p_.v_crit()) {  // gas-like: no stress, the internal variables wait (eq. 93)
      s.setZero();
      return true;
    }
    ns::State st = ns::State::load(ps.state[p]);
    ns::Return r;
    if constexpr (Dim == 2) {
      // Plane strain: in-plane 2x2 and zz apart (σ_xz = σ_yz = 0); ΔF_zz = 1 keeps ε_zz of step n.
      const Eig2 en = eig2(s[0], s[1], s[3]);
      const Principal tau_n = Jn * Principal(en.l1, en.l2, s[2]);
      const ns::Coaxial c = coaxial(tau_n, st);
      const Principal eps_n = Principal::Constant(c.A + shift / 3.0) + c.B * tau_n;
      Eig2 et;
      if (!spectral::plane_strain_trial(en, eps_n[0], eps_n[1], dF, et)) return false;
      r = admissible(Principal(0.5 * std::log(et.l1), 0.5 * std::log(et.l2), eps_n[2]), v, st);
      if (!r.converged) return false;
      const Sym2 t = rebuild(et, r.tau[0], r.tau[1]);
      s << t.xx / J, t.yy / J, r.tau[2] / J, t.xy / J, 0.0, 0.0;
    } else {
      const Mat3 tau_n = Jn * to_matrix(s);
      const double pk = -tau_n.trace() / 3.0;
      const ns::Coaxial c = coaxial_pq(pk, std::sqrt(1.5) * (tau_n + pk * Mat3::Identity()).norm(), st);
      const Mat3 B = spectral::sym_exp(2.0 * ((c.A + shift / 3.0) * Mat3::Identity() + c.B * tau_n));
      const Mat3 Bt = dF * B * dF.transpose();
      Eigen::SelfAdjointEigenSolver<Mat3> eig;
      eig.computeDirect(0.5 * (Bt + Bt.transpose()));
      const Principal beta = eig.eigenvalues();
      if (!(beta.minCoeff() > 0.0)) return false;
      r = admissible(0.5 * beta.array().log().matrix(), v, st);
      if (!r.converged) return false;
      const Mat3& Q = eig.eigenvectors();
      s = to_voigt(Q * (r.tau / J).asDiagonal() * Q.transpose());
    }
    if (!plastic_) return true;  // elastic phase: the internal variables wait (π_i unset)
    // Internal variables: π_i, Ē_d^p, and ψ_i frozen where Ē_d^p passes the cut-off start (eq. 92).
    if (st.Ed <= p_.cutoff_start && st.Ed + r.dEd > p_.cutoff_start) st.psi_start = r.psi_i;
    st.Ed += r.dEd;
    st.pi = r.pi;
    st.store(ps.state[p]);
    ps.eps_p[p] += r.dEp;
    return true;
  }

  /// The return mapping, or the elastic trial (NS2) while plastic flow is off.
  ns::Return admissible(const Principal& eps_tr, double v, const ns::State& st) const {
    if (plastic_) return ns::return_map(p_, eps_tr, v, st);
    ns::Return r;
    r.tau = ns::elastic(p_, eps_tr).tau;
    r.eps_e = eps_tr;
    r.pi = st.pi;
    return r;
  }

  /// NS4 for principal Kirchhoff stresses; ε_e = 0 (A = B = 0) for a point without compression.
  /// Sets π_i of a point that has none yet (NS5 with OCR: seed 001 eq. 113 after an elastic phase,
  /// eq. 113 generalised to the stress point otherwise; see set_plastic).
  ns::Coaxial coaxial(const Principal& tau, ns::State& st) const {
    const double pk = -tau.sum() / 3.0;
    const Principal dev = tau + Principal::Constant(pk);
    return coaxial_pq(pk, std::sqrt(1.5) * dev.norm(), st);
  }
  ns::Coaxial coaxial_pq(double pk, double qk, ns::State& st) const {
    const bool stressed = pk > 0.0;
    if (!(st.pi > 0.0))
      st.pi = stressed ? ns::initial_image_pressure(p_, pk, after_elastic_phase_ ? 0.0 : qk)
                       : ns::initial_image_pressure(p_, p_.p_unstrained(), 0.0);
    return stressed ? ns::elastic_strain_of(p_, pk, qk) : ns::Coaxial{};
  }

  ns::Params p_;
  bool plastic_ = true;
  bool after_elastic_phase_ = false;  // π_i by eq. 113 from p alone (App. B.4)
};

}  // namespace

template <int Dim>
std::unique_ptr<MaterialModel<Dim>> make_nor_sand(const scene::Material& m, const scene::Scene& s) {
  if (s.solver.kinematics != "finite-strain")
    throw std::runtime_error("material \"" + m.name + "\": nor-sand is a finite-strain model (Borja & Andrade 2006); "
                             "solver.kinematics \"" + s.solver.kinematics + "\" is not supported (use finite-strain)");
  return std::make_unique<NorSand<Dim>>(nor_sand::Params::from(m));
}

template std::unique_ptr<MaterialModel<2>> make_nor_sand<2>(const scene::Material&, const scene::Scene&);
template std::unique_ptr<MaterialModel<3>> make_nor_sand<3>(const scene::Material&, const scene::Scene&);

}  // namespace swmpm
