// Constitutive models behind one small interface. The solver calls each model once per step for
// all of its particles (one virtual call per material per step, none per particle); the loop over
// particles lives inside the model, so the compiler sees the whole kernel.
//
// Contract of update_stress: on entry ps.F[p] is F_{n+1} (already updated from L = ps.L[p] over dt)
// and ps.sigma[p] is sigma_n; on exit ps.sigma[p] is sigma_{n+1} (Cauchy, tension positive). A
// model must not allocate. It returns the smallest particle index whose update failed (J <= 0,
// non-finite stress), or -1. A model with internal variables (needs_material_state) keeps them in
// ps.state[p] and updates them in the same call.
//
// Modified F-bar (seed 001 eqs. 81-83, solver/transfer/fbar.hpp): every model reports the elastic
// logarithmic volumetric strain of its b_e,n (elastic_volumetric_strain), and, when
// ps.ev_shift is allocated, update_stress replaces b_e,n by b̄_e,n = exp(2 ps.ev_shift[p] / 3) b_e,n
// before the trial — eq. 82 with (J̄^e / J^e)^{2/3} = exp(2/3 ln(J̄^e / J^e)). Hypoelastic and
// small-strain models realise the same shift on the stress: σ_n + K ps.ev_shift[p] 1.
#pragma once

#include <algorithm>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "scene/scene.hpp"
#include "solver/particles/particles.hpp"

namespace swmpm {

template <int Dim>
class MaterialModel {
 public:
  virtual ~MaterialModel() = default;
  virtual std::string name() const = 0;
  virtual long update_stress(ParticleSet<Dim>& ps, std::span<const int> ids, double dt) const = 0;
  /// Constrained (P-wave) modulus K + 4G/3 [Pa] at the current state, for the CFL condition.
  virtual double p_wave_modulus() const = 0;
  /// The largest P-wave modulus [Pa] among particles `ids` (pressure-dependent models look at each
  /// particle's stress; the others return p_wave_modulus()). One call per material per step.
  virtual double max_p_wave_modulus(const ParticleSet<Dim>& ps, std::span<const int> ids) const {
    (void)ps, (void)ids;
    return p_wave_modulus();
  }
  /// Plastic flow on (the default) or off: with it off, a plastic model returns its elastic trial
  /// stress and leaves its internal variables alone (the initialisation phase, seed 001 App. B.4).
  /// Called between steps, never per particle; elastic models ignore it.
  virtual void set_plastic(bool on) { (void)on; }
  /// Modified F-bar, step (9)(e): ε_v^e = ln J^e = ln √det b_e,n [-] of each particle p of `ids`
  /// at the start of the step, into ev[p] (ev is indexed by particle): the b_e,n this model
  /// rebuilds from σ_n in update_stress (finite strain: with J_n = det F / det ΔF(L, dt), so it
  /// may be called before or after the F-bar stage rewrites F and L consistently; small strain
  /// and hypoelastic: tr σ_n / 3K). One call per material per step; no allocation.
  virtual void elastic_volumetric_strain(const ParticleSet<Dim>& ps, std::span<const int> ids, double dt,
                                         std::span<double> ev) const = 0;
  /// Stored elastic energy of particle p [J, or J/m in plane strain].
  virtual double strain_energy(const ParticleSet<Dim>& ps, int p) const = 0;
  /// Names of state quantities the model reports beside the stress (Nor-Sand: specific_volume,
  /// state_parameter); empty for models without. For reports (swmpm element), not the time loop.
  virtual std::vector<std::string> report_names() const { return {}; }
  /// Their values at particle p, in the order of report_names() (out.size() == its size).
  virtual void report_values(const ParticleSet<Dim>& ps, int p, std::span<double> out) const {
    (void)ps, (void)p, (void)out;
  }
};

/// The loop every model's update_stress runs: fn(p) for each particle p of `ids` (in parallel,
/// no allocation) returns false when its update failed; afterwards a non-finite stress also
/// counts. Returns the smallest failing particle index, or -1 (the update_stress contract).
template <int Dim, class Fn>
long update_each(ParticleSet<Dim>& ps, std::span<const int> ids, Fn&& fn) {
  constexpr long none = std::numeric_limits<long>::max();
  long bad = none;
  const long n = static_cast<long>(ids.size());
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
  for (long k = 0; k < n; ++k) {
    const int p = ids[k];
    if (!fn(p) || !ps.sigma[p].allFinite()) bad = std::min(bad, static_cast<long>(p));
  }
  return bad == none ? -1 : bad;
}

/// fn(p) for each particle p of `ids`, in parallel (each call writes only particle p's data).
template <class Fn>
void for_each_id(std::span<const int> ids, Fn&& fn) {
  const long n = static_cast<long>(ids.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
  for (long k = 0; k < n; ++k) fn(ids[k]);
}

/// Builds the model a scene material names. Throws std::runtime_error for models this build's
/// formulations cannot run yet.
template <int Dim>
std::unique_ptr<MaterialModel<Dim>> make_material(const scene::Material& m, const scene::Scene& s);

/// True when a material of the scene keeps internal variables in ParticleSet::state (nor-sand):
/// the particle set must then carry them (ParticleSet::add_material_state) before the first step.
bool needs_material_state(const scene::Scene& s);

/// Lamé parameters from Young's modulus and Poisson's ratio.
struct Elastic {
  double E, nu, lambda, mu, K;
  static Elastic from(double E, double nu) {
    return {E, nu, E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))};
  }
  double p_wave() const { return K + 4.0 * mu / 3.0; }
};

}  // namespace swmpm
