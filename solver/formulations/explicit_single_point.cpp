// Formulation `explicit-single-point`: stabilised explicit two-phase MPM on one set of points
// carrying the soil skeleton and its pore fluid (seed 000, Tang et al., §3.3 and Fig. 3), with the
// errata of shared/spec/seed-notes.md resolved (docs/formulations.md derives each line).
//
// Signs: effective stress sigma' tension positive, pore pressure p compression positive;
// total stress sigma = sigma' - p I. Units SI; 2D quantities per metre of thickness.
//
// One step (named, timed stages; numbers are the paper's sub-steps):
//   (0) reorder particles into scatter order every 10 steps (memory locality only)
//   (2) P2G of both phases: masses, momenta, internal forces (eqs. 21, 23), body forces (eq. 22
//       and the fluid-mass erratum), nodal Darcy drag coefficient (eq. 12), tractions on the solid
//   (3) nodal accelerations of both phases with the drag integrated implicitly per node (a 2x2
//       solve per component: no drag time-step limit), boundary conditions for each phase
//   (4) G2P of both phases (FLIP/PIC blend), positions move with the solid; (5) MUSL remap
//   (6) strain rates of both phases; cell-average (mass-weighted) volumetric rates (eqs. 26-27)
//   (8) F, V, porosity (eq. 4 integrated: (1 - n) V is constant), fluid mass n rho_f V — done
//       before (7) because material models take F_{n+1} on entry; then F-bar (transfer/fbar.hpp)
//       when solver.stabilisation.fbar is set (after the strain smoothing, which it smooths again)
//   (7) effective stress (material model), pore pressure rate (eq. 9 with the n div v_f erratum)
//       through the node-based multi-field variational step with Q = [1], linear or quadratic
//       (eqs. 33-34)
//   (9) physical bounds: a suction beyond cavitation and beyond twice the scene's stress scale
//       stops the run, naming the remedy (issue 27; docs/formulations.md, "Pore pressure bound")
#include <omp.h>

#include <limits>
#include <sstream>

#include "solver/formulation.hpp"
#include "solver/formulations/explicit_single_point/cells.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/loads.hpp"
#include "solver/materials/material.hpp"
#include "solver/parallel/particles.hpp"
#include "solver/porous/drag.hpp"
#include "solver/porous/permeability.hpp"
#include "solver/porous/points.hpp"
#include "solver/porous/porosity.hpp"
#include "solver/transfer/fbar.hpp"
#include "solver/transfer/projection.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {
namespace {

/// Fluid and permeability of one solid material in a saturated body.
struct PoreFluid {
  double rho_f = 0.0;  // kg/m^3, fluid density
  double K_f = 0.0;    // Pa, fluid bulk modulus
  porous::Permeability perm;        // of the skeleton (the initialisation phase's while it runs)
  porous::Permeability scene_perm;  // the material's own
};

template <int Dim, class Shape>
class ExplicitSinglePoint final : public Formulation<Dim> {
  static constexpr int S = Shape::support;

 public:
  ExplicitSinglePoint(const scene::Scene& s, const State<Dim>& state)
      : grid_(make_grid<Dim>(s, Shape::degree, Shape::bspline)),
        bcs_solid_(s, grid_, state.surfaces),
        bcs_fluid_(GridBoundary<Dim>::fluid(s, grid_, state.surfaces)),
        loads_(s, grid_, state.solid, state.surfaces),
        flip_(s.solver.flip),
        damping_(s.solver.damping),
        scene_damping_(s.solver.damping),
        smoothing_(s.solver.stabilisation.strain_smoothing),
        mfvp_order_(mfvp_order(s.solver.stabilisation.pressure)),
        smoothing_stage_(grid_),
        materials_(make_materials<Dim>(s)),
        phase_materials_(s),
        material_particles_(group_by_material(state.solid, s.materials.size())),
        fbar_(s, grid_) {
    const auto& pressure = s.solver.stabilisation.pressure;
    if (pressure == "node-remap")
      throw std::runtime_error("solver.stabilisation.pressure: \"node-remap\" belongs to the semi-implicit "
                               "formulations (available here: none, mfvp-constant, mfvp-linear, mfvp-quadratic, "
                               "cell-constant)");
    cell_pressure_ = pressure == "cell-constant";
    conservative_ = s.solver.continuity == "conservative";
    if (!state.solid.two_phase())
      throw std::runtime_error("explicit-single-point needs saturated particles (pore_pressure, porosity, fluid_mass "
                               "in particles/solid.vtu): run swmpm preprocess with a body that has a solid and a fluid");
    pore_.resize(s.materials.size());
    // The fluid of each solid material: its first point's that has one (none: a dry body in a
    // saturated scene), over every rank's points.
    const std::vector<int> fluid_of = material_value_over_ranks(
        state.solid, s.materials.size(), /*last=*/false, [&](int p) { return state.solid.fluid_material[p]; });
    for (std::size_t k = 0; k < s.materials.size(); ++k) {
      const int fm = fluid_of[k];
      if (fm < 0) continue;
      const auto& f = s.materials[fm];
      auto& pf = pore_[k];
      pf.rho_f = f.at("density");
      pf.K_f = f.at("bulk_modulus");
      pf.perm = pf.scene_perm = porous::permeability_of(s.materials[k], f);
    }
    solid_.resize(grid_.num_nodes());
    fluid_.resize(grid_.num_nodes());
    drag_.resize(grid_.num_nodes());  // zero (NodeArray)
    if (conservative_) porosity_.resize(grid_.num_nodes());
    stress_scale0_ = initial_stress_scale(s, state.solid);
  }

  std::string name() const override { return "explicit-single-point"; }

  void step(State<Dim>& st, const StepContext& ctx) override {
    ParticleSet<Dim>& ps = st.solid;
    const double dt = ctx.dt;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    StageClock lap(this->times_);

    if (reorder_for_locality(st, schedule_, reorder_, material_particles_, reorder_interval, &domain_))
      lap("reorder");  // (0)

    long bad = -1;
    box_ = transfer::evaluate_shapes<Shape>(grid_, ps, sd_, bad);
    // Under mpirun: particles that crossed a cut move to their rank; the rank's node box.
    if (parallel::own_particles<Shape>(domain_, grid_, st, schedule_, sd_, box_, bad))
      regroup_by_material(ps, material_particles_);
    if (bad >= 0) st.health.report(bad, "solid", "left the grid (or position not finite)");
    collect_face_forces<Shape>(grid_, loads_, ps, st.index_of_id, ctx.t, box_, face_forces_);
    parallel::share_face_forces<Shape>(domain_, grid_, face_forces_, box_);  // mpirun: every rank's, in order
    transfer::build_schedule(grid_, sd_, schedule_);
    clear_nodes();
    lap("shape functions");

    if (cell_pressure_) cells_.project(grid_, box_, schedule_, ps, [&](int p) { return pore_[ps.material[p]].K_f; });  // (1b)
    if (conservative_) nodal_porosity(ps);                                               // (1c)
    if (cell_pressure_ || conservative_) lap("cell pressure and nodal porosity");

    scatter_both_phases(ps, b);                                                          // (2)
    const auto loaded = carries_mass(solid_);
    parallel::weigh_face_forces(domain_, grid_, face_forces_, loaded);
    for (const auto& ff : face_forces_) {
      // A prescribed pore pressure (split) loads both phases, (1 - n) and n of -p A n.
      const double to_fluid = ff.split ? ff.n : 0.0;
      for_each_loaded_node(
          grid_, ff, loaded,
          [&](std::size_t i, double N) {
            solid_.acc[i].f += (N * (1.0 - to_fluid)) * ff.f;
            fluid_.acc[i].f += (N * to_fluid) * ff.f;
          });
    }
    lap("p2g");

    update_grid(dt);                                                                     // (3)
    lap("grid update");

    // (4)-(5) FLIP/PIC of both phases, positions with the solid, MUSL remap of both momenta
    porous::gather_soil_points</*kPoreWater=*/true, /*kRemapWater=*/true>(grid_, box_, schedule_, sd_, flip_, dt, ps,
                                                                         solid_, fluid_);
    bcs_solid_.apply(grid_, box_, solid_.v, false);
    bcs_fluid_.apply(grid_, box_, fluid_.v, false);
    lap("g2p + musl remap");

    strain_rates(ps);                                                                    // (6)
    if (smoothing_) smoothing_stage_.apply(grid_, box_, schedule_, ps, div_f_);         // eqs. 26-27
    lap("strain rates");

    bad = update_volumes(ps, dt);                                                        // (8)
    if (bad >= 0) st.health.report(bad, "solid", "volume ratio J <= 0 or porosity outside (0, 1)");
    lap("volume and porosity");
    if (fbar_.apply(grid_, box_, schedule_, sd_, dt, st, materials_, material_particles_)) lap("f-bar");  // (8b), after smoothing

    // (7) after (8): the material contract wants F_{n+1} on entry (Hencky reads it).
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const long m_bad = materials_[k]->update_stress(ps, material_particles_[k], dt);
      if (m_bad >= 0) st.health.report(m_bad, "solid", "stress update failed (" + materials_[k]->name() + ")");
    }
    bad = update_pore_pressure(ps, dt);
    if (bad >= 0) st.health.report(bad, "solid", "pore pressure not finite");
    check_suction(st, ctx.t);                                                            // (9)
    lap("stress and pressure");
  }

  double critical_time_step(const State<Dim>& st, std::string& reason) const override {
    // Undrained P-wave speed c = sqrt((K' + 4G/3 + K_f / n) / rho_sat) (seed-notes, seed 000);
    // the drag is implicit at the nodes, so it sets no limit.
    const ParticleSet<Dim>& ps = st.solid;
    double c_max = 0.0;
    const std::vector<double> moduli = max_p_wave_moduli(materials_, ps, material_particles_);
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const double M_s = moduli[k];
      for (int p : material_particles_[k]) {
        const double rho_sat = (ps.m[p] + ps.m_f[p]) / ps.V[p];
        const double M = M_s + (ps.fluid_material[p] >= 0 ? pore_[k].K_f / ps.n[p] : 0.0);
        c_max = std::max(c_max, std::sqrt(M / rho_sat));
      }
    }
    double v_max = 0.0;
    const long n = static_cast<long>(ps.size());
#pragma omp parallel for reduction(max : v_max) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) v_max = std::max(v_max, std::max(ps.v[p].norm(), ps.v_f[p].norm()));
    c_max = parallel::max(c_max);  // over all ranks (mpirun)
    v_max = parallel::max(v_max);
    std::ostringstream os;
    os << "undrained P-wave CFL (c = " << c_max << " m/s incl. K_f/n, |v|max = " << v_max
       << " m/s); Darcy drag is implicit per node and sets no limit";
    reason = os.str();
    return grid_.h() / (c_max + v_max);
  }

  double kinetic_energy(const State<Dim>& st) const override {
    const auto& ps = st.solid;
    return fixed_order_sum(ps.size(), [&](std::size_t p) {
      return 0.5 * (ps.m[p] * ps.v[p].squaredNorm() + ps.m_f[p] * ps.v_f[p].squaredNorm());
    });
  }
  /// Stored energy: the skeleton's elastic energy plus the pore fluid's, n p^2 / (2 K_f) V (the
  /// mixture's storage modulus K_f / n of eq. 9).
  double strain_energy(const State<Dim>& st) const override {
    const auto& ps = st.solid;
    return fixed_order_sum(ps.size(), [&](std::size_t p) {
      const double fluid = ps.fluid_material[p] >= 0
                               ? ps.n[p] * ps.p[p] * ps.p[p] / (2.0 * pore_[ps.material[p]].K_f) * ps.V[p]
                               : 0.0;
      return materials_[ps.material[p]]->strain_energy(ps, static_cast<int>(p)) + fluid;
    });
  }
  double external_power(const State<Dim>& st, const StepContext& ctx) const override {
    const ParticleSet<Dim>& ps = st.solid;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    double power = fixed_order_sum(ps.size(), [&](std::size_t p) { return b.dot(ps.m[p] * ps.v[p] + ps.m_f[p] * ps.v_f[p]); });
    loads_.for_each_force(ctx.t, st.index_of_id, [&](int p, const Vec<Dim>& f_p, const Vec<Dim>&, bool split) {
      const double n = split ? ps.n[p] : 0.0;
      power += f_p.dot((1.0 - n) * ps.v[p] + n * ps.v_f[p]);
    });
    return power;
  }
  void set_initialisation(State<Dim>& st, const scene::Initialisation* phase) override {
    phase_materials_.set(materials_, phase);  // the phase's parameters and plastic flag (materials/material.hpp)
    damping_ = phase_damping(phase, scene_damping_);
    for (auto& pf : pore_)
      pf.perm = phase && phase->hydraulic_conductivity
                    ? porous::Permeability{.law = porous::Permeability::Law::constant, .k0 = *phase->hydraulic_conductivity}
                    : pf.scene_perm;
    // The phase's seepage velocities belong to its permeability: the pore water restarts at the
    // skeleton's velocity and the drag brings it to the scene's Darcy flow (as semi_implicit/single_point.cpp).
    if (phase) fast_drainage_ = phase->hydraulic_conductivity.has_value();
    else if (fast_drainage_) st.solid.v_f = st.solid.v, fast_drainage_ = false;
  }
  std::size_t active_cells(const State<Dim>& st) const override { return count_active_cells(grid_, st.solid); }
  std::string on_several_ranks(const scene::Scene&) const override { return {}; }  // every option runs on several ranks
  std::vector<typename Formulation<Dim>::Counter> counters() const override {
    return parallel::counters<typename Formulation<Dim>::Counter>(domain_);
  }
  void distribute(State<Dim>& st) override {
    parallel::distribute<Shape>(domain_, grid_, st, schedule_, material_particles_);
    fbar_.distribute(domain_);
  }
  // Restart: the last step's schedule order, which the next step's reordering (0) reads; every
  // other field is rebuilt by each step from the particles.
  // The largest load so far and the steps beyond the suction bound (9) so far are carried too.
  void save(Checkpoint& c) const override {
    save_order(c, "formulation/schedule_order", schedule_);
    c.put_global("formulation/load_scale", std::vector<double>{load_scale_, static_cast<double>(suction_steps_)});
  }
  void restore(const Checkpoint& c, State<Dim>& st) override {
    regroup_by_material(st.solid, material_particles_);  // the checkpoint's particle order
    restore_order(c, "formulation/schedule_order", schedule_);
    if (c.has("formulation/load_scale")) {  // absent in checkpoints written before it existed
      std::vector<double> v;
      c.get("formulation/load_scale", v);
      if (v.size() == 2) load_scale_ = v[0], suction_steps_ = static_cast<long>(v[1]);
    }
  }

 private:
  void clear_nodes() {
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      solid_.acc[i] = {Vec<Dim>::Zero(), Vec<Dim>::Zero(), 0.0};
      fluid_.acc[i] = {Vec<Dim>::Zero(), Vec<Dim>::Zero(), 0.0};
      drag_[i] = 0.0;
      if (conservative_) porosity_[i] = {0.0, 0.0};
    });
  }

  /// (2) eqs. 20-23: m_sI, m_fI, momenta, and
  ///   f_s = sum_p [ (1 - n_p) p_p V_p grad N - V_p sigma'_p grad N + N m_sp b ]
  ///   f_f = sum_p [ n_p p_p V_p grad N + N m_fp b ]                   (erratum: fluid mass)
  ///   D_I = sum_p N n_p^2 rho_f g / k_p V_p   (drag f_d = D (v_s - v_f) per node, eq. 12)
  void scatter_both_phases(const ParticleSet<Dim>& ps, const Vec<Dim>& b) {
    schedule_.run([&](int p) {
      const auto& sp = sd_[p];
      const PoreFluid& pf = pore_[ps.material[p]];
      const double V = ps.V[p], n = ps.n[p];
      const bool wet = ps.fluid_material[p] >= 0;  // dry points (no pore fluid) carry no drag
      if (conservative_) {
        const auto np = porous::porosity_at_point(grid_, sp, porosity_);
        nhat_[p] = np.n;
        grad_n_[p] = np.grad;
      }
      // The pressure the forces see: the point's own, or its cell's (cell-constant pressure); the
      // porosity: the point's own, or (conservative) n^ interpolated from the nodal porosity, whose
      // gradient adds the interaction force p grad n^ (fluid +, soil -).
      const double pp = cell_pressure_ ? (wet ? cells_.at_point(p) : 0.0) : ps.p[p];
      const double nn = conservative_ ? nhat_[p] : n;
      const double ps_solid = (1.0 - nn) * pp * V, ps_fluid = nn * pp * V;  // N m (N in 2D per m)
      // f_s = N (m_s b - p V grad n^) - A grad N with A = V sigma' - (1 - n) p V I;
      // f_f = N (m_f b + p V grad n^) + n p V grad N
      const Mat3 s = to_matrix(ps.sigma[p]);
      const MatD<Dim> A = V * s.template topLeftCorner<Dim, Dim>() - ps_solid * MatD<Dim>::Identity();
      const double m_s = ps.m[p], m_f = ps.m_f[p];
      const Vec<Dim> mv_s = m_s * ps.v[p], mv_f = m_f * ps.v_f[p];
      const Vec<Dim> interaction = conservative_ ? Vec<Dim>((pp * V) * grad_n_[p]) : Vec<Dim>::Zero();
      const Vec<Dim> mb_s = m_s * b - interaction, mb_f = m_f * b + interaction;
      // eq. 12: the Darcy drag n^2 rho_f g / k of the point's permeability (the scene's law).
      const double drag = wet ? porous::darcy_drag(n, pf.rho_f, pf.perm.at_point(n, V, ps.V0[p])) * V : 0.0;
      // Row-factored (shape::for_each_row): grad N = (dwx[a] w_r, wx[a] g_r).
      shape::for_each_row(grid_, sp, [&](std::size_t row, double w_r, const Vec<Dim - 1>& g_r) {
        const Vec<Dim> fs_w = w_r * mb_s - A.template rightCols<Dim - 1>() * g_r, fs_dw = -w_r * A.col(0);
        Vec<Dim> ff_w = w_r * mb_f;
        ff_w.template tail<Dim - 1>() += ps_fluid * g_r;
        const double ff_dw = w_r * ps_fluid;  // along x only
        const double ms_r = w_r * m_s, mf_r = w_r * m_f, d_r = w_r * drag;
        const Vec<Dim> mvs_r = w_r * mv_s, mvf_r = w_r * mv_f;
        for (int a = 0; a < S; ++a) {
          const std::size_t i = row + a;
          const double wx = sp.w[0][a], dwx = sp.dw[0][a];
          auto& ns = solid_.acc[i];
          auto& nf = fluid_.acc[i];
          ns.m += wx * ms_r;
          ns.mv += wx * mvs_r;
          ns.f += wx * fs_w + dwx * fs_dw;
          nf.m += wx * mf_r;
          nf.mv += wx * mvf_r;
          nf.f += wx * ff_w;
          nf.f[0] += dwx * ff_dw;
          drag_[i] += wx * d_r;
        }
      });
    }, solid_.acc, fluid_.acc, drag_);
  }

  /// (3) Per node and component, with u = velocities at the end of the step:
  ///   m_s (u_s - vL_s) = dt F_s - dt D (u_s - u_f),   m_f (u_f - vL_f) = dt F_f + dt D (u_s - u_f)
  /// solved exactly (porous::solve_drag); local damping acts on each phase's unbalanced force. A
  /// node with one phase only moves it without drag.
  void update_grid(double dt) {
    const double alpha = damping_;
    auto damp = [alpha](const Vec<Dim>& f, const Vec<Dim>& v) { return local_damping<Dim>(f, v, alpha); };
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      const auto& ns = solid_.acc[i];
      const auto& nf = fluid_.acc[i];
      const double ms = ns.m, mf = nf.m;
      const bool has_s = ms > transfer::empty_node_mass, has_f = mf > transfer::empty_node_mass;
      const Vec<Dim> vLs = has_s ? Vec<Dim>(ns.mv / ms) : Vec<Dim>::Zero();
      const Vec<Dim> vLf = has_f ? Vec<Dim>(nf.mv / mf) : Vec<Dim>::Zero();
      solid_.vL[i] = vLs;
      fluid_.vL[i] = vLf;
      if (!has_s && !has_f) {
        solid_.v[i].setZero();
        fluid_.v[i].setZero();
        return;
      }
      const Vec<Dim> rs = ms * vLs + dt * damp(ns.f, vLs);
      const Vec<Dim> rf = mf * vLf + dt * damp(nf.f, vLf);
      if (has_s && has_f) {
        const auto u = porous::solve_drag<Dim>(ms, mf, dt * drag_[i], rs, rf);
        solid_.v[i] = u.v_s;
        fluid_.v[i] = u.v_w;
      } else {
        solid_.v[i] = has_s ? Vec<Dim>(rs / ms) : Vec<Dim>::Zero();
        fluid_.v[i] = has_f ? Vec<Dim>(rf / mf) : Vec<Dim>::Zero();
      }
    });
    bcs_solid_.apply(grid_, box_, solid_.v, true);
    bcs_fluid_.apply(grid_, box_, fluid_.v, false);
  }

  /// (6) L_s = sum v_s (x) grad N (into ps.L) and div v_f = sum v_f . grad N (eqs. 24-25).
  /// With the conservative continuity, also grad n^ . (v_f - v_s) at the point (velocities
  /// interpolated from the nodes); with the cell-constant pressure, the point's rate of change of
  /// pore-water volume before any smoothing,
  ///   r_p = V_p [ (1 - n) div v_s + n div v_f (+ grad n^ . (v_f - v_s)) ],
  /// the exact transpose of the pressure forces of (2) (docs/formulations.md, "Cell-constant pressure").
  void strain_rates(ParticleSet<Dim>& ps) {
    const long n = static_cast<long>(ps.size());
    div_f_.resize(ps.size());
    const bool keep_flux = conservative_ && !cell_pressure_;  // read by pressure_rate; r_p holds it otherwise
    if (keep_flux) flux_.resize(ps.size());
    if (cell_pressure_) vol_rate_.resize(ps.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      MatD<Dim> L = MatD<Dim>::Zero();
      double div_f = 0.0;
      Vec<Dim> w = Vec<Dim>::Zero();  // v_f - v_s at the point
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>& dN) {
        L.noalias() += solid_.v[i] * dN.transpose();
        div_f += fluid_.v[i].dot(dN);
        if (conservative_) w += N * (fluid_.v[i] - solid_.v[i]);
      });
      ps.L[p] = L;
      div_f_[p] = div_f;
      const double flux = conservative_ ? grad_n_[p].dot(w) : 0.0;
      if (keep_flux) flux_[p] = flux;
      if (cell_pressure_) {
        const double nn = conservative_ ? nhat_[p] : ps.n[p];
        vol_rate_[p] = ps.fluid_material[p] >= 0 ? ps.V[p] * ((1.0 - nn) * L.trace() + nn * div_f + flux) : 0.0;
      }
    }
  }

  /// (1c) Nodal porosity n_I = sum N m_s n / sum N m_s (soil-mass weighted, as seed 001 step 2c).
  /// The points' n^ = sum N_I n_I and grad n^ = sum grad N_I n_I (porous::porosity_at_point), which
  /// the interaction force and the conservative continuity share, are gathered in the force
  /// scatter of (2).
  void nodal_porosity(const ParticleSet<Dim>& ps) {
    porous::nodal_porosity(grid_, box_, schedule_, sd_, ps, porous::PorosityWeight::mass, 0.0, porosity_);
    nhat_.resize(ps.size());
    grad_n_.resize(ps.size());
  }

  static int mfvp_order(const std::string& pressure) {
    if (pressure == "mfvp-constant") return 0;
    if (pressure == "mfvp-linear") return 1;
    if (pressure == "mfvp-quadratic") return 2;
    return -1;
  }

  /// (7) eq. 9: pdot_p = -(K_f / n)[(1 - n) div v_s + n div v_f], then the node-based multi-field
  /// variational step (eqs. 33-34) with the basis Q of `mfvp_order_`.
  long update_pore_pressure(ParticleSet<Dim>& ps, double dt) {
    if (cell_pressure_) return cells_.update(schedule_, ps, vol_rate_, dt);
    // With a multi-field variational step the rate is computed inside its scatter and the
    // pressure updated inside its gather (two passes over the particles fewer).
    if (mfvp_order_ == 0) return mfvp(mfvp0_, ps, dt);
    if (mfvp_order_ == 1) return mfvp(mfvp1_, ps, dt);
    if (mfvp_order_ == 2) return mfvp(mfvp2_, ps, dt);
    const long n = static_cast<long>(ps.size());
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      ps.p[p] += dt * pressure_rate(ps, static_cast<int>(p));
      if (!std::isfinite(ps.p[p])) bad = std::min(bad, p);
    }
    return bad == transfer::no_particle ? -1 : bad;
  }

  /// eq. 9 at particle p (0 for a dry point in a saturated scene); with the conservative
  /// continuity the mixture's volume balance (n/K_f) dp/dt = -div[(1 - n^) v_s + n^ v_f], i.e. eq. 9
  /// with n^ and the term grad n^ . (v_f - v_s).
  double pressure_rate(const ParticleSet<Dim>& ps, int p) const {
    if (ps.fluid_material[p] < 0) return 0.0;
    const double np = ps.n[p], K_f = pore_[ps.material[p]].K_f;
    if (conservative_) {
      const double nn = nhat_[p];
      return -(K_f / np) * ((1.0 - nn) * div_s_[p] + nn * div_f_[p] + flux_[p]);
    }
    return -(K_f / np) * ((1.0 - np) * div_s_[p] + np * div_f_[p]);
  }

  /// eqs. 33-34, node-based: H_I = sum_p Q Q^T N V, a_I = H_I^-1 sum_p N Q pdot_p V (the sign of
  /// eq. 33 folded into pdot_p), pdot_p = sum_I N_Ip Q_p^T a_I, Q centred at node I
  /// (transfer/projection.hpp, without its leverage limit: a node whose H_I is singular, too few
  /// particles for the basis, falls back to the constant basis). For Order 0 the positions are
  /// immaterial; for higher orders the current positions serve as the quadrature points.
  /// Dry points (fluid_material -1) take no part: weight 0 in the fit, and their p stays 0.
  template <class Projection>
  long mfvp(Projection& projection, ParticleSet<Dim>& ps, double dt) {
    projection.fit(grid_, box_, schedule_, sd_, ps.x, [&](int p) { return ps.fluid_material[p] < 0 ? 0.0 : ps.V[p]; },
                   [&](int p) { return pressure_rate(ps, p); });
    const long n = static_cast<long>(ps.size());
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      if (ps.fluid_material[p] < 0) continue;
      ps.p[p] += dt * projection.at_point(grid_, sd_[p], ps.x[p]);
      if (!std::isfinite(ps.p[p])) bad = std::min(bad, p);
    }
    return bad == transfer::no_particle ? -1 : bad;
  }

  /// The stress scale S0 of the initial state (Pa), for the suction bound (9): the largest of
  ///   |p| and |sigma'_ij| at any point (an initial or geostatic state),
  ///   rho_sat g H (the weight of the particles' full height H, gravity unramped),
  ///   sqrt(M rho_sat) |v|max (the water-hammer pressure rho c v of the initial velocities against
  ///   a rigid wall, c the undrained P-wave speed, M = K' + 4G/3 + K_f/n).
  /// The loads' stresses are added as the run goes (loads_.stress_scale).
  double initial_stress_scale(const scene::Scene& s, const ParticleSet<Dim>& ps) const {
    double scale = 0.0, rho_max = 0.0, rho_c = 0.0, v_max = 0.0;
    double y_lo = std::numeric_limits<double>::infinity(), y_hi = -y_lo;
    const std::vector<double> moduli = max_p_wave_moduli(materials_, ps, material_particles_);  // over the ranks
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const double M_s = moduli[k];
      for (int p : material_particles_[k]) {
        const bool wet = ps.fluid_material[p] >= 0;
        if (wet) scale = std::max(scale, std::abs(ps.p[p]));
        for (int c = 0; c < 6; ++c) scale = std::max(scale, std::abs(ps.sigma[p][c]));
        const double rho = (ps.m[p] + ps.m_f[p]) / ps.V[p];
        rho_max = std::max(rho_max, rho);
        rho_c = std::max(rho_c, std::sqrt((M_s + (wet ? pore_[k].K_f / ps.n[p] : 0.0)) * rho));
        v_max = std::max(v_max, std::max(ps.v[p].norm(), ps.v_f[p].norm()));
        y_lo = std::min(y_lo, ps.x[p][1] - ps.l[p][1]);
        y_hi = std::max(y_hi, ps.x[p][1] + ps.l[p][1]);
      }
    }
    std::array<double, 6> most{scale, rho_max, rho_c, v_max, -y_lo, y_hi};  // over every rank's points
    parallel::max(std::span<double>(most));
    scale = most[0], rho_max = most[1], rho_c = most[2], v_max = most[3], y_lo = -most[4], y_hi = most[5];
    const double g = std::sqrt(s.gravity[0] * s.gravity[0] + s.gravity[1] * s.gravity[1] + s.gravity[2] * s.gravity[2]);
    if (y_hi > y_lo) scale = std::max(scale, rho_max * g * (y_hi - y_lo));
    return std::max(scale, rho_c * v_max);
  }

  /// (9) Physical bounds of the pore pressure. The formulation models a saturated skeleton whose
  /// pore water carries any tension; real water cavitates when its absolute pressure nears zero,
  /// i.e. at a gauge pressure of about -100 kPa, and the soil then desaturates, which is not
  /// modelled. Beyond that, a suction is still a solution of the model when the loads produce it
  /// (undrained unloading takes at most the whole change of total stress, B <= 1). A sudden load
  /// or release at most doubles a linear response. So a point is out of bounds when
  ///   p < -2 max(p_cav, S),   p_cav = 100 kPa,  S = max(S0, the largest load stress so far),
  /// S0 from initial_stress_scale, for `persistent_steps` steps in a row: a wave or an impact
  /// passes a point within a few steps (it moves cfl cells per step), whereas the seed's scheme at
  /// large strain holds its pore-pressure mode (p of several q of either sign between particle rows,
  /// examples/large-strain-consolidation/README.md) for the rest of the run. Measured 2026-12-05:
  /// the longest streak beyond the bound is 32 steps on A5 at cfl 0.9 (a spike to -809 kPa), 16 on
  /// the unstabilised A3 small reading; 9068 on A5 without stabilisation (-2.5 MPa), about 1.8e5
  /// on the large-strain columns. The run then stops (status diverged) and names the remedy.
  void check_suction(State<Dim>& st, double t) {
    const ParticleSet<Dim>& ps = st.solid;
    load_scale_ = std::max(load_scale_, loads_.stress_scale(t));
    const double scale = std::max(stress_scale0_, load_scale_);        // Pa, S
    const double limit = 2.0 * std::max(cavitation_suction, scale);  // Pa
    const long n = static_cast<long>(ps.size());
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p)
      if (ps.fluid_material[p] >= 0 && ps.p[p] < -limit) bad = std::min(bad, p);
    suction_steps_ = parallel::any(bad != transfer::no_particle) ? suction_steps_ + 1 : 0;  // anywhere in the body
    if (suction_steps_ < persistent_steps || bad == transfer::no_particle) return;
    std::ostringstream what, remedy;
    what << "has pore pressure " << ps.p[bad] << " Pa, below -" << limit
         << " Pa (twice the larger of water's cavitation suction, about 100 kPa, and the largest stress the scene "
            "applies, "
         << scale << " Pa), somewhere in the body for " << suction_steps_
         << " steps in a row: a suction a saturated skeleton cannot hold (this formulation models no desaturation)";
    if (!(cell_pressure_ && conservative_))
      remedy << "At large strain this is the pore-pressure mode of the seed's scheme (the mfvp pressure step "
                "with eq. 9); use \"solver\": {\"continuity\": \"conservative\", \"stabilisation\": "
                "{\"pressure\": \"cell-constant\"}} (docs/formulations.md, \"Cell-constant pressure and "
                "conservative continuity\").";
    else
      remedy << "Try a smaller dt (or cfl), or check the loads and the boundary conditions.";
    st.health.report(bad, "solid", what.str(), remedy.str());
  }

  /// (8) F_{n+1} = dF F_n, V = det F V0; porosity from (1 - n) V = const (eq. 4, incompressible
  /// grains); fluid mass n rho_f V.
  long update_volumes(ParticleSet<Dim>& ps, double dt) {
    const long n = static_cast<long>(ps.size());
    long bad = transfer::no_particle;
    div_s_.resize(ps.size());
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      div_s_[p] = ps.L[p].trace();  // eq. 9 takes the (smoothed) rate of (6): F-bar acts on the skeleton only
      const double J = porous::update_skeleton<Dim>(ps.L[p], dt, ps.F[p], ps.V[p], ps.V0[p], ps.n[p]);
      const bool wet = ps.fluid_material[p] >= 0;
      if (wet) ps.m_f[p] = ps.n[p] * pore_[ps.material[p]].rho_f * ps.V[p];
      if (!(J > 0.0) || !(ps.n[p] >= 0.0 && ps.n[p] < 1.0) || (wet && !(ps.n[p] > 0.0))) bad = std::min(bad, p);
    }
    return bad == transfer::no_particle ? -1 : bad;
  }

  Grid<Dim> grid_;
  GridBoundary<Dim> bcs_solid_, bcs_fluid_;
  ParticleLoads<Dim> loads_;
  double flip_, damping_, scene_damping_;
  bool fast_drainage_ = false;  // an initialisation phase with its own permeability is running
  bool smoothing_;
  int mfvp_order_;  // -1 none, 0 constant, 1 linear, 2 quadratic basis Q
  bool cell_pressure_ = false;  // solver.stabilisation.pressure = cell-constant
  bool conservative_ = false;   // solver.continuity = conservative
  explicit_single_point::CellPressure<Dim> cells_;  // (1b), (7) with the cell-constant pressure
  explicit_single_point::StrainSmoothing<Dim> smoothing_stage_;  // (6), eqs. 26-27
  std::vector<double> vol_rate_;                     // per particle: r_p
  NodeArray<std::array<double, 2>> porosity_;        // per node: sum N m n -> n_I, sum N m
  std::vector<double> nhat_, flux_;                  // per particle: n^, grad n^ . (v_f - v_s)
  std::vector<Vec<Dim>> grad_n_;                     // per particle: grad n^
  std::vector<std::unique_ptr<MaterialModel<Dim>>> materials_;
  PhaseMaterials<Dim> phase_materials_;  // initialisation.materials: swapped in by set_initialisation
  std::vector<std::vector<int>> material_particles_;
  std::vector<PoreFluid> pore_;  // per solid material
  NodeFields<Dim> solid_, fluid_;
  NodeArray<double> drag_;                           // per node
  // The multi-field variational step of each basis order (only the scene's is used).
  NodeProjection<Dim, S, 0, LeverageLimit::off> mfvp0_;
  NodeProjection<Dim, S, 1, LeverageLimit::off> mfvp1_;
  NodeProjection<Dim, S, 2, LeverageLimit::off> mfvp2_;
  std::vector<double> div_f_;                        // per particle
  std::vector<double> div_s_;                        // per particle: tr L_s of (6), before F-bar
  NodeBox<Dim> box_;
  std::vector<shape::ShapeData<Dim, S>> sd_;
  std::vector<FaceForce<Dim, S>> face_forces_;
  StripeSchedule schedule_;
  Reorder<Dim> reorder_;
  FBar<Dim, S> fbar_;
  parallel::Domain<Dim> domain_;  // mpirun: this rank's stripes and particles
  static constexpr long reorder_interval = 10;  // steps
  static constexpr double cavitation_suction = 1.0e5;  // Pa, gauge: water's absolute pressure near zero
  double stress_scale0_ = 0.0;  // Pa, S0 of the suction bound (9)
  double load_scale_ = 0.0;     // Pa, the largest load stress so far
  long suction_steps_ = 0;      // consecutive steps with a point beyond the bound
  static constexpr long persistent_steps = 100;
};

}  // namespace

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_explicit_single_point(const scene::Scene& s, const State<Dim>& state) {
  return make_for_shape<ExplicitSinglePoint, Dim>(s, state);
}

template std::unique_ptr<Formulation<2>> make_explicit_single_point<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_explicit_single_point<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
