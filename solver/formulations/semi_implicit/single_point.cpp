// Formulation `semi-implicit-single-point`: seed 001's incremental fractional-step two-phase MPM
// (Xie, Navas, López-Querol 2025, §3-4.5) with the water carried by the soil points, as in Yuan
// et al. 2023: each point carries n, p, v_f and m_f, as in explicit-single-point. The stages
// common to both variants are core.hpp's and pressure.hpp's (docs/formulations.md derives them).
//
// One step (numbers are the paper's algorithm steps, §4.5):
//   (0) reorder points into scatter order every 10 steps (memory locality only)
//   (1) shape data, active node box, scatter schedule
//   (2) P2G of the soil points and their water: M_s, M_s v_s, nodal porosity and conductivity
//       (soil-mass weighted, eqs. 44-47), M_w and M_w v_w, effective-stress forces; the points'
//       moments of (5a) in the same pass (cell moments)
//   (5a)-(5b) L, D_s, D_w (eqs. 61-63), the nodal p^t, free-surface and drained nodes
//   (3)-(4) body forces; water and soil predictors (eqs. 52-53) with the drag implicit and the
//       pressure force -G p^t; BCs
//   (5c) pressure increment: L dp = -(1/dt) div q* (eq. 60, conservation form); CHOLMOD
//   (6) corrections v^{t+1} = v* - dt/M (G dp) (eqs. 64-68); BCs; p^{t+1} at the points
//   (7) G2P (FLIP/PIC) of both phases, positions; MUSL remap of the soil velocity (step 8a)
//   (8)-(9) F, V, porosity (1 - n) J = 1 - n0, pore-water mass; F-bar; stress
#include "solver/formulations/semi_implicit/core.hpp"

namespace swmpm {
namespace {

using semi_implicit::Weights;

template <int Dim, class Shape>
class SemiImplicitSinglePoint final : public semi_implicit::Core<Dim, Shape> {
  using Core = semi_implicit::Core<Dim, Shape>;
  using Core::kCellMoments, Core::reorder_interval;
  using Core::schedule_, Core::reorder_, Core::material_particles_, Core::sd_, Core::pressure_, Core::water_,
      Core::pore_;

 public:
  SemiImplicitSinglePoint(const scene::Scene& s, const State<Dim>& state)
      : Core(s, state, state.solid, "semi-implicit-single-point") {
    const ParticleSet<Dim>& ps = state.solid;
    this->derive_laplace_if_single_densities(ps, ps, [&](int p) { return pore_[ps.material[p]].rho_w; });
  }
  std::string name() const override { return "semi-implicit-single-point"; }

  void step(State<Dim>& st, const StepContext& ctx) override {
    ParticleSet<Dim>& ps = st.solid;  // the soil points, which carry the pore water
    const double dt = ctx.dt;
    StageClock lap(this->times_);

    if (reorder_for_locality(st, schedule_, reorder_, material_particles_, reorder_interval, &this->domain_))
      lap("reorder");  // (0)

    this->evaluate_soil_shapes(st);                                                         // (1)
    this->prepare_nodes(st, ctx);
    lap("shape functions");

    this->template scatter_soil<true, false>(ps, [&](int p, bool without_l) { return weights(ps, p, without_l); });  // (2)
    this->nodal_porosity();
    this->add_face_forces();
    lap("p2g");

    assemble_pressure(ps);                                                                  // (5a)-(5b)
    lap("pressure assembly");

    this->nodal_water_velocity();                                                           // (3)-(4)
    this->predict(dt, Core::gravity(ctx));
    lap("predictor");

    if (!this->solve_pressure(st, dt)) return;                                              // (5c)
    lap("pressure solve");

    this->correct(dt);                                                                      // (6)
    const long bad = pressure_.update_points(schedule_, sd_, ps, [&](int p) { return ps.m_f[p]; });  // dry: p = 0
    if (bad >= 0) st.health.report(bad, "solid", "pore pressure not finite");
    lap("correction");

    this->template gather_soil<true>(ps, dt);                                               // (7)
    lap("g2p + musl remap");

    this->update_soil(st, dt);                                                              // (8)-(9)
    lap("stress and porosity");
  }

  double kinetic_energy(const State<Dim>& st) const override {
    const auto& ps = st.solid;
    return fixed_order_sum(ps.size(), [&](std::size_t p) {
      return 0.5 * (ps.m[p] * ps.v[p].squaredNorm() + ps.m_f[p] * ps.v_f[p].squaredNorm());
    });
  }
  double external_power(const State<Dim>& st, const StepContext& ctx) const override {
    const auto& ps = st.solid;
    const Vec<Dim> b = Core::gravity(ctx);
    const double gravity = fixed_order_sum(ps.size(), [&](std::size_t p) {
      return b.dot(ps.m[p] * ps.v[p] + ps.m_f[p] * ps.v_f[p]);
    });
    return Core::external_power(gravity, st, ctx);
  }
  void set_initialisation(State<Dim>& st, const scene::Initialisation* phase) override {
    // The phase's seepage velocities belong to its permeability, not the scene's (the pressure
    // field of steady seepage does not depend on k, the flow is proportional to it): the pore
    // water restarts at the soil's velocity and the drag brings it to the scene's Darcy flow
    // within k / (n g).
    if (this->set_phase(phase)) st.solid.v_f = st.solid.v;
  }
  void save(Checkpoint& c) const override { this->save_core(c); }
  void restore(const Checkpoint& c, State<Dim>& st) override { this->restore_core(c, st); }

 private:
  /// (5a)-(5b) the nodal p^t from the points' pressures, the nodes' roles, then D^s and D^w and L
  /// from the same points (by cell moments, or point by point).
  void assemble_pressure(const ParticleSet<Dim>& ps) {
    pressure_.fit(schedule_, sd_, ps, [&](int p) { return this->dry(ps, p) ? 0.0 : ps.V[p]; });  // the water's points
    pressure_.set_node_roles(water_);
    if constexpr (kCellMoments) {
      pressure_.assemble_from_moments(schedule_);
    } else {
      pressure_.run_operators(schedule_, [&](int p) { pressure_.template add_operators<true, true>(sd_[p], weights(ps, p)); });
    }
  }
  /// A point carries both phases: s = (1 - n) V, w = n V, l = V [(1 - n)/rho_s + n/rho_w]
  /// (without_l: l is derived from the others, CellMoments::derive_laplace, and left 0). A dry
  /// point carries the soil's shares only, w = 0 and l = V (1 - n)/rho_s, as a double-point soil
  /// point: its empty pores hold no water for the pressure to move.
  Weights weights(const ParticleSet<Dim>& ps, int p, bool without_l = false) const {
    const double V = ps.V[p], n = ps.n[p];
    const bool dry = this->dry(ps, p);
    const double w = dry ? 0.0 : n * V;
    if (without_l) return {(1.0 - n) * V, w, 0.0};
    const double c = (1.0 - n) / Core::grain_density(ps, p) + (dry ? 0.0 : n / pore_[ps.material[p]].rho_w);
    return {(1.0 - n) * V, w, V * c};
  }
};

}  // namespace

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_semi_implicit_single_point(const scene::Scene& s, const State<Dim>& state) {
  return make_for_shape<SemiImplicitSinglePoint, Dim>(s, state);
}

template std::unique_ptr<Formulation<2>> make_semi_implicit_single_point<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_semi_implicit_single_point<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
