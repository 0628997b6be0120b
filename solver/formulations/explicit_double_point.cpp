// Formulation `explicit-double-point`: seed 003's 2-phase double-point MPM (Ceccato, Yerro,
// Martinelli; the scheme of Martinelli 2016 and Anura3D): solid points (State::solid) carry the
// skeleton, liquid points (State::fluid) the water, each with its own velocity and constant mass;
// both momentum balances (eqs. 6-7) are explicit at the nodes, the drag (eq. 9) implicit per node.
// docs/formulations.md, "Explicit double-point", derives each line and states the choices.
//
// Signs: effective stress sigma' tension positive, liquid pressure p compression positive
// (sigma_L = -p I + tau, tau the viscous deviatoric stress). Units SI; 2D quantities per metre.
// n is the porosity (the seed's n_L), 1 - n the solid fraction (n_S).
//
// One step (the seed's §3 steps in brackets):
//   (0) both sets in scatter order every 10 steps (memory locality only)
//   (1) shape data of both sets, the active box, schedules
//   (2a) liquid P2G: M_L, M_L v_L, sum N m p (nodal p), sum N V (occupied volume, free surface)
//   (2b) solid P2G: M_s, M_s v_s, the effective-stress force and weight, the drag coefficient
//        D_I = sum N V c(n, kappa, |v_L - v_S|) with each solid point's own porosity; the nodal
//        porosity n_I = 1 - (solid volume) / (volume the support holds), 1 where no solid
//   (2c) liquid forces: the liquid's weight and its pressure's force on both phases (eqs. 6-7 with
//        the sigma_L . grad n part of eq. 9), integrated over the liquid points with n^ = sum N n_I
//   (3) [1-2] per node: both momenta with the drag implicit (porous::solve_drag); BCs per phase
//   (4) [3-4, 7] G2P of both sets (FLIP/PIC), positions with each set's own velocity; MUSL remap
//   (5) [5] solid: L, F, V, n; liquefied points (n > n_max) get sigma' = 0, the others the
//       material model; liquid: p += -(K_L / n^) [n^ div v_L + (1 - n^) div v_S +
//       grad n^ . (v_L - v_S)] dt (eq. 8) through the multi-field variational step, the cavitation
//       bound, the viscous deviatoric stress
//   (6) [6] liquid points on the free surface (volume fraction below kFreeSurfaceFraction) get p = 0
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>

#include "solver/formulation.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/loads.hpp"
#include "solver/materials/material.hpp"
#include "solver/parallel/particles.hpp"
#include "solver/porous/drag.hpp"
#include "solver/porous/free_surface.hpp"
#include "solver/porous/permeability.hpp"
#include "solver/porous/points.hpp"
#include "solver/porous/porosity.hpp"
#include "solver/porous/tie.hpp"
#include "solver/transfer/fbar.hpp"
#include "solver/transfer/projection.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {
namespace {

/// A liquid point whose support is less than this full of liquid lies on the free surface (the
/// liquid's volume fraction interpolated at the point, porous::volume_fraction_at_point: 5/8 on
/// the top row of a flat surface with 2 points per cell, 7/8 on the row below, 1 inside).
constexpr double kFreeSurfaceFraction = 0.5;
/// A mixture's solid fraction is capped at this share of the packing 1 - n_max in the
/// Krieger–Dougherty viscosity (the law diverges at the packing).
constexpr double kViscosityPackingCap = 0.95;
/// The nodal porosity 1 - theta_I is kept above this (points clustering in a support can give
/// theta_I > 1).
constexpr double kMinNodalPorosity = 0.01;
/// A node whose support holds solid points of at least this share of its volume is inside soil.
constexpr double kFullSupport = 0.98;
/// Intrinsic viscosity [eta] of rigid spheres (Einstein), the exponent's factor of Krieger–Dougherty.
constexpr double kIntrinsicViscosity = 2.5;

/// The liquid of one fluid material.
struct Liquid {
  double rho = 0.0;         // kg/m^3
  double K = 0.0;           // Pa, bulk modulus (weakly compressible)
  double mu = 0.0;          // Pa s, dynamic viscosity
  double cavitation = 0.0;  // Pa, the largest tension carried (p >= -cavitation)
};

/// The skeleton of one solid material with the liquid in its pores.
struct Skeleton {
  porous::Permeability perm;        // k [m/s] (the initialisation phase's while it runs)
  porous::Permeability scene_perm;  // the material's own
  double rho_L = 0.0, mu = 0.0;     // the pore liquid's density and viscosity (drag)
  double n_max = 1.0;               // liquefied above (1: never)
};

template <int Dim, class Shape>
class ExplicitDoublePoint final : public Formulation<Dim> {
  static constexpr int S = Shape::support;
  static constexpr long reorder_interval = 10;  // steps

 public:
  ExplicitDoublePoint(const scene::Scene& s, const State<Dim>& state)
      : grid_(make_grid<Dim>(s, Shape::degree, Shape::bspline)),
        bcs_solid_(s, grid_, state.surfaces),
        bcs_liquid_(GridBoundary<Dim>::fluid(s, grid_, state.surfaces)),
        loads_(s, grid_, state.solid, state.surfaces, /*pore_pressure_forces=*/false),
        flip_(s.solver.flip),
        damping_(s.solver.damping),
        scene_damping_(s.solver.damping),
        materials_(make_materials<Dim>(s)),
        phase_materials_(s),
        material_particles_(group_by_material(state.solid, s.materials.size())),
        fbar_(s, grid_) {
    if (parallel::sum(static_cast<long>(state.fluid.size())) == 0)  // over every rank's points
      throw std::runtime_error("explicit-double-point needs liquid points (particles/fluid.vtu): give a body a "
                               "\"fluid\", then run swmpm preprocess again");
    drag_.kind = s.solver.drag == "darcy" ? porous::DragLaw::Kind::darcy : porous::DragLaw::Kind::ergun;
    const auto& pressure = s.solver.stabilisation.pressure;
    mfvp_order_ = pressure == "none" ? -1 : pressure == "mfvp-constant" ? 0 : 1;
    liquid_.resize(s.materials.size());
    int first_fluid = -1;
    for (std::size_t k = 0; k < s.materials.size(); ++k) {
      const auto& m = s.materials[k];
      if (m.model != scene::MaterialModel::fluid) continue;
      if (first_fluid < 0) first_fluid = static_cast<int>(k);
      liquid_[k] = {m.at("density"), m.at("bulk_modulus"), m.has("dynamic_viscosity") ? m.at("dynamic_viscosity") : 1e-3,
                    m.has("cavitation_threshold") ? m.at("cavitation_threshold") : 0.0};
    }
    // The pore liquid of each solid material: its bodies' fluid, else the scene's first fluid (dry
    // soil that liquid reaches).
    skeleton_.resize(s.materials.size());
    const std::vector<char> present = materials_present(material_particles_);  // over every rank's points
    for (std::size_t k = 0; k < s.materials.size(); ++k) {
      const auto& m = s.materials[k];
      if (m.model == scene::MaterialModel::fluid) continue;
      int fm = first_fluid;
      for (const auto& b : s.bodies)
        if (b.solid == m.name && !b.fluid.empty()) {
          fm = static_cast<int>(s.material_index(b.fluid));
          break;
        }
      Skeleton& sk = skeleton_[k];
      sk.n_max = m.has("maximum_porosity") ? m.at("maximum_porosity") : 1.0;
      n_max_ = std::min(n_max_, sk.n_max);
      sk.rho_L = liquid_[fm].rho;
      sk.mu = liquid_[fm].mu;
      if (m.has("hydraulic_conductivity") || m.has("intrinsic_permeability") || m.has("grain_diameter"))
        sk.perm = sk.scene_perm = porous::permeability_of(m, s.materials[fm]);
      else if (present[k])
        throw std::runtime_error("material \"" + m.name + "\": explicit-double-point needs the permeability of every "
                                 "skeleton (hydraulic_conductivity, intrinsic_permeability or grain_diameter): liquid "
                                 "may reach dry soil");
      if (m.has("ergun_a")) drag_.A = m.at("ergun_a");
      if (m.has("ergun_b")) drag_.B = m.at("ergun_b");
    }
    const std::size_t nodes = grid_.num_nodes();
    solid_.resize(nodes);
    liquid_nodes_.resize(nodes);
    node_.assign(nodes, NodeSums{});
    support_.resize(nodes);
    for (std::size_t i = 0; i < nodes; ++i) support_[i] = porous::basis_integral<Shape>(grid_, i);
  }

  std::string name() const override { return "explicit-double-point"; }

  void step(State<Dim>& st, const StepContext& ctx) override {
    ParticleSet<Dim>& ps = st.solid;
    ParticleSet<Dim>& ws = st.fluid;
    const double dt = ctx.dt;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    StageClock lap(this->times_);

    if (reorder(st)) lap("reorder");                                                         // (0)

    evaluate_shapes(st, ctx);                                                                // (1)
    lap("shape functions");

    scatter_liquid_mass(ws);                                                                 // (2a)
    scatter_solid(ps, b);                                                                    // (2b)
    nodal_porosity();
    scatter_liquid_forces(ws, b);                                                            // (2c)
    parallel::weigh_face_forces(domain_, grid_, face_forces_, carries_mass(solid_));
    add_weighed_face_forces(grid_, face_forces_, solid_);
    lap("p2g");

    update_grid(dt);                                                                         // (3)
    lap("grid update");

    // (4) the solid points also take the liquid's velocity (v_f: the relative speed of the
    // Ergun term in the next step's drag), the liquid points move with the liquid.
    porous::gather_soil_points</*kPoreWater=*/true, /*kRemapWater=*/false>(grid_, box_, schedule_, sd_, flip_, dt, ps,
                                                                          solid_, liquid_nodes_);
    porous::gather_soil_points<false, false>(grid_, box_, wschedule_, sdw_, flip_, dt, ws, liquid_nodes_, liquid_nodes_);
    bcs_solid_.apply(grid_, box_, solid_.v, false);
    bcs_liquid_.apply(grid_, box_, liquid_nodes_.v, false);
    stop_at_grid_faces(ps);
    stop_at_grid_faces(ws);
    if (tie_) report_untied(st, porous::tie_positions(ps, st.index_of_id, partner_, ws));
    lap("g2p + musl remap");

    long bad = update_solid(st, dt);                                                         // (5)
    if (bad >= 0) st.health.report(bad, "solid", "volume ratio J <= 0 or porosity outside (0, 1)");
    lap("stress and porosity");
    bad = update_liquid(ws, dt);                                                             // (5)-(6)
    if (bad >= 0) st.health.report(bad, "fluid", "liquid pressure not finite");
    lap("liquid pressure");
  }

  double critical_time_step(const State<Dim>& st, std::string& reason) const override {
    // Solid points: the P-wave of the skeleton on its partial density plus the liquid's storage
    // acting on both phases without drag, c^2 = M / rho_s' + K_L [(1 - n) / (n rho_S) + 1 / rho_L];
    // free liquid: c = sqrt(K_L / rho_L); the viscous limit dt < rho_L h^2 / (2 Dim mu); the drag
    // is implicit per node and sets no limit.
    const ParticleSet<Dim>& ps = st.solid;
    const ParticleSet<Dim>& ws = st.fluid;
    double c_solid = 0.0, c_liquid = 0.0, nu_max = 0.0;
    for (std::size_t k = 0; k < liquid_.size(); ++k)
      if (liquid_[k].rho > 0.0) {
        c_liquid = std::max(c_liquid, std::sqrt(liquid_[k].K / liquid_[k].rho));
        nu_max = std::max(nu_max, liquid_[k].mu * viscosity_factor_max() / liquid_[k].rho);
      }
    const double K_L = max_liquid_modulus(), rho_L = min_liquid_density();
    // Called every step with dt "auto": the per-point maxima in parallel (a max does not depend on
    // the order), of the squares, with one square root each.
    double c2_solid = 0.0;
    const std::vector<double> moduli = max_p_wave_moduli(materials_, ps, material_particles_);
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const double M_s = moduli[k];
      const auto& ids = material_particles_[k];
      const long m = static_cast<long>(ids.size());
#pragma omp parallel for schedule(static) reduction(max : c2_solid) if (m > parallel_threshold)
      for (long j = 0; j < m; ++j) {
        const int p = ids[j];
        const double n = ps.n[p], rho_bar = ps.m[p] / ps.V[p], rho_S = rho_bar / (1.0 - n);
        c2_solid = std::max(c2_solid, M_s / rho_bar + K_L * ((1.0 - n) / (n * rho_S) + 1.0 / rho_L));
      }
    }
    double v2_max = 0.0;
    for (const ParticleSet<Dim>* set : {&ps, &ws}) {
      const long m = static_cast<long>(set->size());
#pragma omp parallel for schedule(static) reduction(max : v2_max) if (m > parallel_threshold)
      for (long p = 0; p < m; ++p) v2_max = std::max(v2_max, set->v[p].squaredNorm());
    }
    std::array<double, 2> maxima{c2_solid, v2_max};
    parallel::max(std::span<double>(maxima));  // over all ranks (mpirun)
    c2_solid = maxima[0], v2_max = maxima[1];
    c_solid = std::sqrt(c2_solid);
    const double v_max = std::sqrt(v2_max);
    const double h = grid_.h();
    const double dt_wave = h / (std::max(c_solid, c_liquid) + v_max);
    const double dt_visc = nu_max > 0.0 ? h * h / (2.0 * Dim * nu_max) : std::numeric_limits<double>::infinity();
    std::ostringstream os;
    if (dt_visc < dt_wave) {
      os << "viscous limit of the liquid (nu = " << nu_max << " m^2/s incl. the liquefied mixture's)";
      reason = os.str();
      return dt_visc;
    }
    os << (c_solid > c_liquid ? "solid points' P-wave CFL with the liquid's storage (c = " : "liquid's P-wave CFL (c = ")
       << std::max(c_solid, c_liquid) << " m/s; solid " << c_solid << ", free liquid " << c_liquid
       << " m/s; |v|max = " << v_max << " m/s); the drag is implicit per node and sets no limit";
    reason = os.str();
    return dt_wave;
  }

  double kinetic_energy(const State<Dim>& st) const override {
    const auto &ps = st.solid, &ws = st.fluid;
    return fixed_order_sum(ps.size(), [&](std::size_t p) { return 0.5 * ps.m[p] * ps.v[p].squaredNorm(); }) +
           fixed_order_sum(ws.size(), [&](std::size_t p) { return 0.5 * ws.m[p] * ws.v[p].squaredNorm(); });
  }
  /// The skeleton's elastic energy (liquefied points none) plus the liquid's, p^2 / (2 K_L) m / rho_L.
  double strain_energy(const State<Dim>& st) const override {
    const auto &ps = st.solid, &ws = st.fluid;
    return fixed_order_sum(ps.size(), [&](std::size_t p) {
             return liquefied(ps, static_cast<int>(p)) ? 0.0
                                                       : materials_[ps.material[p]]->strain_energy(ps, static_cast<int>(p));
           }) +
           fixed_order_sum(ws.size(), [&](std::size_t p) {
             const Liquid& l = liquid_[ws.material[p]];
             return ws.p[p] * ws.p[p] / (2.0 * l.K) * ws.m[p] / l.rho;
           });
  }
  double external_power(const State<Dim>& st, const StepContext& ctx) const override {
    const auto &ps = st.solid, &ws = st.fluid;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    double power = fixed_order_sum(ps.size(), [&](std::size_t p) { return b.dot(ps.m[p] * ps.v[p]); }) +
                   fixed_order_sum(ws.size(), [&](std::size_t p) { return b.dot(ws.m[p] * ws.v[p]); });
    loads_.for_each_force(ctx.t, st.index_of_id,
                          [&](int p, const Vec<Dim>& f_p, const Vec<Dim>&, bool) { power += f_p.dot(ps.v[p]); });
    return power;
  }
  void set_initialisation(State<Dim>& st, const scene::Initialisation* phase) override {
    phase_materials_.set(materials_, phase);  // the phase's parameters and plastic flag (materials/material.hpp)
    damping_ = phase_damping(phase, scene_damping_);
    for (auto& sk : skeleton_)
      sk.perm = phase && phase->hydraulic_conductivity
                    ? porous::Permeability{.law = porous::Permeability::Law::constant, .k0 = *phase->hydraulic_conductivity}
                    : sk.scene_perm;
    const bool was_tied = tie_;
    tie_ = phase && phase->tie_water;
    if ((tie_ || (phase && phase->hydraulic_conductivity)) && partner_.empty())
      partner_ = parallel::coincident_points(domain_, st.solid, st.fluid);  // over every rank's points (mpirun)
    // The phase's seepage velocities belong to its permeability, not the scene's: each liquid
    // point with a coincident solid point restarts at that point's velocity.
    if (!phase && (was_tied || fast_drainage_) && !partner_.empty())
      report_untied(st, porous::tie_velocities(st.solid, st.index_of_id, partner_, st.fluid));
    fast_drainage_ = phase && phase->hydraulic_conductivity.has_value();
  }
  std::size_t active_cells(const State<Dim>& st) const override {
    return std::max(count_active_cells(grid_, st.solid), count_active_cells(grid_, st.fluid));
  }
  std::string on_several_ranks(const scene::Scene&) const override { return {}; }  // every option runs on several ranks
  std::vector<typename Formulation<Dim>::Counter> counters() const override {
    return parallel::counters<typename Formulation<Dim>::Counter>(domain_);
  }
  /// mpirun: both sets over the ranks, the cuts balanced on their particles together.
  void distribute(State<Dim>& st) override {
    parallel::distribute<Shape>(domain_, grid_, st, schedule_, &wschedule_);
    regroup_by_material(st.solid, material_particles_);
    fbar_.distribute(domain_);
  }
  /// Restart: both sets' schedule orders (the next reordering reads them) and the
  /// initialisation's partners (per water-point id: the same table on every rank); every nodal
  /// field is rebuilt by each step from the points.
  void save(Checkpoint& c) const override {
    save_order(c, "formulation/schedule_order", schedule_);
    save_order(c, "formulation/water_schedule_order", wschedule_, "fluid");
    c.put_global("formulation/partner", partner_);
  }
  void restore(const Checkpoint& c, State<Dim>& st) override {
    regroup_by_material(st.solid, material_particles_);
    restore_order(c, "formulation/schedule_order", schedule_);
    restore_order(c, "formulation/water_schedule_order", wschedule_);
    c.get("formulation/partner", partner_);
    free_surface_.clear();  // recomputed by the next step
  }
  /// liquefied (0/1) on the solid points, free_surface (0/1) on the liquid points (as detected by
  /// the last step; 0 before the first).
  void add_point_fields(const State<Dim>& st, scene::PointCloud& solid, scene::PointCloud& fluid) const override {
    auto& liq = solid.add("liquefied", 1);
    for (std::size_t p = 0; p < st.solid.size(); ++p) liq.values[p] = liquefied(st.solid, static_cast<int>(p)) ? 1.0 : 0.0;
    auto& fs = fluid.add("free_surface", 1);
    if (free_surface_.size() == st.fluid.size())
      for (std::size_t p = 0; p < st.fluid.size(); ++p) fs.values[p] = free_surface_[p];
  }

 private:
  /// Per-node sums besides the two phases' momenta and forces.
  struct NodeSums {
    double Vs = 0.0, V = 0.0;  // sum N (1 - n) V, sum N V of the solid points
    double Vw = 0.0;           // sum N m / rho_L(p) of the liquid points: the liquid's own volume
    double drag = 0.0;         // D_I = sum N V c [kg/s per (m/s)]: the drag force is D_I (v_L - v_S)
    double mp = 0.0;           // sum N m p of the liquid points -> p_I = mp / M_L (output)
    double V_L = 0.0;          // sum N V of the liquid points (mixture volume): free-surface test
    double n = 1.0;            // n_I: the solid points' porosity, 1 where there is no solid
  };

  bool liquefied(const ParticleSet<Dim>& ps, int p) const { return ps.n[p] > skeleton_[ps.material[p]].n_max; }

  /// A tied water point whose soil point this rank does not hold (tie_positions; mpirun only: a
  /// tied pair shares its position and so its stripe).
  static void report_untied(State<Dim>& st, long w) {
    if (w >= 0)
      st.health.report(w, "fluid", "tied water point whose soil point another rank holds (the pair's supports differ)");
  }

  /// (0) Both sets in last step's schedule order every reorder_interval steps.
  bool reorder(State<Dim>& st) {
    const bool solid = reorder_for_locality(st, schedule_, reorder_, material_particles_, reorder_interval, &domain_);
    return reorder_set(st.fluid, st.step, wschedule_, wreorder_, reorder_interval, &domain_) || solid;
  }

  /// (1) Shape data of both sets, the active node box (both sets'), the schedules, the solid's
  /// face forces, and the box's nodes cleared. Under mpirun the points that crossed a cut move to
  /// their rank first, and the box is the rank's (parallel::migrate_sets).
  void evaluate_shapes(State<Dim>& st, const StepContext& ctx) {
    long bad = -1, wbad = -1;
    box_ = transfer::evaluate_shapes<Shape>(grid_, st.solid, sd_, bad);
    NodeBox<Dim> wbox = transfer::evaluate_shapes<Shape>(grid_, st.fluid, sdw_, wbad);
    parallel::own_both_sets<Shape>(domain_, grid_, st, material_particles_, parallel::StepSet{st.solid, schedule_, sd_, box_, bad},
                                   parallel::StepSet{st.fluid, wschedule_, sdw_, wbox, wbad});
    if (bad >= 0) st.health.report(bad, "solid", "left the grid (or position not finite)");
    if (wbad >= 0) st.health.report(wbad, "fluid", "liquid point left the grid (or position not finite)");
    for (int a = 0; a < Dim; ++a) {
      box_.lo[a] = std::min(box_.lo[a], wbox.lo[a]);
      box_.hi[a] = std::max(box_.hi[a], wbox.hi[a]);
    }
    box_ = domain_.node_box(box_);
    collect_face_forces<Shape>(grid_, loads_, st.solid, st.index_of_id, ctx.t, box_, face_forces_);
    parallel::share_face_forces<Shape>(domain_, grid_, face_forces_, box_);  // mpirun: every rank's, in order
    transfer::build_schedule(grid_, sd_, schedule_);
    transfer::build_schedule(grid_, sdw_, wschedule_);
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      solid_.acc[i] = {Vec<Dim>::Zero(), Vec<Dim>::Zero(), 0.0};
      liquid_nodes_.acc[i] = {Vec<Dim>::Zero(), Vec<Dim>::Zero(), 0.0};
      node_[i] = NodeSums{};
    });
  }

  /// (2b) Solid points (eq. 6 without the liquid's pressure, which (2c) adds):
  ///   M_s = sum N m_s,  f_s = sum [ N m_s b - V sigma' grad N ],
  ///   D_I = sum N V c_p, c_p = n^2 mu / kappa (+ beta n^3 rho_L |v_L - v_S| with Ergun, eqs. 9-10),
  /// kappa = k mu / (rho_L g) of the point's permeability law at its own porosity (eq. 11 with
  /// grains), |v_L - v_S| from the velocities the last step left at the point. A liquefied point
  /// carries sigma' = 0, which its stress holds already.
  void scatter_solid(const ParticleSet<Dim>& ps, const Vec<Dim>& b) {
    schedule_.run([&](int p) __attribute__((always_inline)) {
      const auto& sp = sd_[p];
      const Skeleton& sk = skeleton_[ps.material[p]];
      const double V = ps.V[p], n = ps.n[p], m = ps.m[p];
      const double k = sk.perm.at_point(n, V, ps.V0[p]);
      const double kappa = k * sk.mu / (sk.rho_L * porous::g_earth);  // m^2
      // A non-porous solid (n = 0) takes no liquid and no drag.
      const double c = n > 0.0 ? drag_.coefficient(n, kappa, sk.mu, sk.rho_L, (ps.v_f[p] - ps.v[p]).norm()) : 0.0;
      const double d = c * V, Vs = (1.0 - n) * V;
      const MatD<Dim> A = V * to_matrix(ps.sigma[p]).template topLeftCorner<Dim, Dim>();
      const Vec<Dim> mv = m * ps.v[p], mb = m * b;
      shape::for_each_node(grid_, sp, [&](std::size_t i, double N, const Vec<Dim>& dN) {
        auto& a = solid_.acc[i];
        a.m += N * m;
        a.mv += N * mv;
        a.f.noalias() += N * mb - A * dN;
        NodeSums& s = node_[i];
        s.Vs += N * Vs;
        s.V += N * V;
        s.drag += N * d;
      });
    }, solid_.acc, node_);
  }

  /// (2a) Liquid points' P2G: M_L = sum N m, sum N m v, sum N m p (the nodal p_I = sum N m p / M_L
  /// of the solid points' output) and sum N V (V = m / (n^ rho_L), the mixture volume the point
  /// stood for in the last step: the nodal porosity's occupied volume and the free-surface test).
  void scatter_liquid_mass(const ParticleSet<Dim>& ws) {
    wschedule_.run([&](int p) __attribute__((always_inline)) {
      const double m = ws.m[p], mp = m * ws.p[p], V = ws.V[p], Vw = liquid_volume(ws, p);
      const Vec<Dim> mv = m * ws.v[p];
      shape::for_each_node(grid_, sdw_[p], [&](std::size_t i, double N, const Vec<Dim>&) {
        auto& a = liquid_nodes_.acc[i];
        a.m += N * m;
        a.mv += N * mv;
        NodeSums& s = node_[i];
        s.mp += N * mp;
        s.V_L += N * V;
        s.Vw += N * Vw;
      });
    }, liquid_nodes_.acc, node_);
  }
  /// The nodal porosity at the nodes with solid, the liquid's share of the mixture volume its
  /// points stand for, n_I = sum N V_w / sum N V (V_w = m / rho_L(p) a liquid point's own volume, V
  /// its mixture volume, (5)); 1 at the nodes without solid. With the liquid points' own volumes
  /// as quadrature weights the porosity steps from the soil's to 1 within the cell a
  /// soil–free-water interface cuts, and the pressure forces of (2c) hold a bed under free water
  /// hydrostatic (docs/formulations.md, "Explicit double-point": the solid points' porosity
  /// averaged to the nodes, with V = m / (n^ rho_L), put the pressure in the interface cells
  /// 50 % off).
  void nodal_porosity() {
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      NodeSums& s = node_[i];
      s.n = solid_.acc[i].m > transfer::empty_node_mass && s.V_L > 0.0 ? std::clamp(s.Vw / s.V_L, kMinNodalPorosity, 1.0)
                                                                        : 1.0;
    });
  }
  /// The liquid's own volume at a liquid point, m / rho_L(p) with rho_L(p) = rho_L (1 + p / K_L)
  /// to first order (weakly compressible).
  double liquid_volume(const ParticleSet<Dim>& ws, int p) const {
    const Liquid& l = liquid_[ws.material[p]];
    return ws.m[p] / l.rho * (1.0 - ws.p[p] / l.K);
  }

  /// (2c) Liquid points: n^ = sum N n_I and grad n^, the mixture volume V = m / (n^ rho_L); the
  /// liquid's weight and its pressure on both phases, integrated over the liquid points (where
  /// the liquid is):
  ///   f_L += N m b + V [ p (n^ grad N + N grad n^) - n^ tau grad N ]  (eq. 7 with the sigma_L . grad n
  ///                                                                    part of eq. 9: -n grad p)
  ///   f_S += V p [ (1 - n^) grad N - N grad n^ ]                    (eq. 6: -(1 - n) grad p)
  /// One quadrature for both, so the interaction p grad n^ acts on the two phases equal and
  /// opposite and the sum is the mixture's V p grad N; the operator is the transpose of the
  /// pressure rate of (5), so the pressure's work is its stored energy's change (docs/formulations.md).
  void scatter_liquid_forces(ParticleSet<Dim>& ws, const Vec<Dim>& b) {
    wschedule_.run([&](int p) __attribute__((always_inline)) {
      const auto& sp = sdw_[p];
      double nh = 0.0;
      Vec<Dim> grad_n = Vec<Dim>::Zero();
      shape::for_each_node(grid_, sp, [&](std::size_t i, double N, const Vec<Dim>& dN) {
        nh += N * node_[i].n;
        grad_n += node_[i].n * dN;
      });
      ws.n[p] = nh;  // the porosity the liquid's update (5) reads, with these shape data
      const double m = ws.m[p], pp = ws.p[p], V = ws.V[p];
      const double pV = pp * V, lq = nh * pV, sq = pV - lq;
      const MatD<Dim> T = (nh * V) * to_matrix(ws.sigma[p]).template topLeftCorner<Dim, Dim>();
      const Vec<Dim> inter = pV * grad_n, mb = m * b + inter;
      shape::for_each_node(grid_, sp, [&](std::size_t i, double N, const Vec<Dim>& dN) {
        liquid_nodes_.acc[i].f.noalias() += N * mb + lq * dN - T * dN;
        solid_.acc[i].f += sq * dN - N * inter;
      });
    }, liquid_nodes_.acc, solid_.acc);
  }

  /// (3) Per node and component, u the velocities at the end of the step:
  ///   M_s (u_s - vL_s) = dt f_s + dt D (u_L - u_s),   M_L (u_L - vL_L) = dt f_L - dt D (u_L - u_s)
  /// solved exactly (porous::solve_drag): the drag never limits dt. Local damping acts on each
  /// phase's unbalanced force. A node with one phase moves it alone.
  void update_grid(double dt) {
    const double alpha = damping_;
    auto damp = [alpha](const Vec<Dim>& f, const Vec<Dim>& v) { return local_damping<Dim>(f, v, alpha); };
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      const auto& ns = solid_.acc[i];
      const auto& nl = liquid_nodes_.acc[i];
      const double ms = ns.m, ml = nl.m;
      const bool has_s = ms > transfer::empty_node_mass, has_l = ml > transfer::empty_node_mass;
      const Vec<Dim> vLs = has_s ? Vec<Dim>(ns.mv / ms) : Vec<Dim>::Zero();
      const Vec<Dim> vLl = has_l ? Vec<Dim>(nl.mv / ml) : Vec<Dim>::Zero();
      solid_.vL[i] = vLs;
      liquid_nodes_.vL[i] = vLl;
      const Vec<Dim> rs = ms * vLs + dt * damp(ns.f, vLs);
      const Vec<Dim> rl = ml * vLl + dt * damp(nl.f, vLl);
      if (has_s && has_l) {
        const auto u = porous::solve_drag<Dim>(ms, ml, dt * node_[i].drag, rs, rl);
        solid_.v[i] = u.v_s;
        liquid_nodes_.v[i] = u.v_w;
      } else {
        solid_.v[i] = has_s ? Vec<Dim>(rs / ms) : Vec<Dim>::Zero();
        liquid_nodes_.v[i] = has_l ? Vec<Dim>(rl / ml) : Vec<Dim>::Zero();
      }
    });
    bcs_solid_.apply(grid_, box_, solid_.v, true);
    bcs_liquid_.apply(grid_, box_, liquid_nodes_.v, false);
  }

  /// (4) The grid's faces are walls: a point that the G2P carried past one (GIMP's domain reaches
  /// past the wall's nodes, so a thin free-surface flow along a floor can cross it) stops on it,
  /// its velocity into the wall zeroed.
  void stop_at_grid_faces(ParticleSet<Dim>& set) const {
    const Vec<Dim> lo = grid_.min(), hi = grid_.max();
    const long n = static_cast<long>(set.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p)
      for (int a = 0; a < Dim; ++a) {
        double& x = set.x[p][a];
        if (x < lo[a]) x = lo[a], set.v[p][a] = std::max(set.v[p][a], 0.0);
        else if (x > hi[a]) x = hi[a], set.v[p][a] = std::min(set.v[p][a], 0.0);
      }
  }

  /// (5) Solid points: L = sum v_s (x) grad N; F, V, porosity ((1 - n) V constant); F-bar when
  /// the scene asks; then the effective stress: zero where n > n_max (liquefied, seed 003 §3),
  /// the material model elsewhere. A point whose porosity falls back below n_max restarts from
  /// sigma' = 0 (sedimentation: the grains touch again, unloaded).
  long update_solid(State<Dim>& st, double dt) {
    ParticleSet<Dim>& ps = st.solid;
    const long n = static_cast<long>(ps.size());
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      MatD<Dim> L = MatD<Dim>::Zero();
      double ph = 0.0;  // the liquid's pressure at the point, p_I = sum N m p / M_L (output, monitors)
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>& dN) {
        L.noalias() += solid_.v[i] * dN.transpose();
        const double M_L = liquid_nodes_.acc[i].m;
        if (M_L > transfer::empty_node_mass) ph += N * node_[i].mp / M_L;
      });
      ps.L[p] = L;
      ps.p[p] = ph;
    }
    fbar_.apply(grid_, box_, schedule_, sd_, dt, st, materials_, material_particles_);
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      const double J = porous::update_skeleton<Dim>(ps.L[p], dt, ps.F[p], ps.V[p], ps.V0[p], ps.n[p]);
      if (!(J > 0.0) || !(ps.n[p] >= 0.0 && ps.n[p] < 1.0)) bad = std::min(bad, p);
    }
    // Liquefied points leave their material's list for this step (their stress is zero).
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const auto& all = material_particles_[k];
      auto& active = active_[k];
      active.clear();
      const double n_max = skeleton_[k].n_max;
      for (int p : all) {
        if (ps.n[p] > n_max) ps.sigma[p] = Sym::Zero();
        else active.push_back(p);
      }
      const long m_bad = materials_[k]->update_stress(ps, active, dt);
      if (m_bad >= 0) st.health.report(m_bad, "solid", "stress update failed (" + materials_[k]->name() + ")");
    }
    return bad == transfer::no_particle ? -1 : bad;
  }

  /// (5) Liquid points, with the step's shape data and the remapped nodal velocities:
  ///   dp = -(K_L / n^) dt [ n^ div v_L + (1 - n^) div v_S + grad n^ . (v_L - v_S) ]
  /// (eq. 8, the mixture's volume balance; the divergences from the nodal velocities, v_L - v_S
  /// interpolated: the transpose of (2b)'s forces); p >= -cavitation; the
  /// viscous deviatoric stress tau = 2 mu_eff dev D_L where the mixture is liquid-like
  /// (n^ > n_max: Krieger–Dougherty on the solid fraction 1 - n^; free water: mu_L; elsewhere 0);
  /// (6) the free surface: phi = sum N min(1, V_I / int N_I) < kFreeSurfaceFraction gives p = 0, tau = 0.
  long update_liquid(ParticleSet<Dim>& ws, double dt) {
    const long n = static_cast<long>(ws.size());
    free_surface_.resize(ws.size());
    rate_.resize(ws.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      const Liquid& l = liquid_[ws.material[p]];
      const double nh = ws.n[p];  // n^ of (2c), the same shape data and nodal porosity
      const double mu = effective_viscosity(l.mu, nh);
      double div_s = 0.0, div_l = 0.0, phi = 0.0, soil = 0.0, n_soil = 0.0;
      bool inside = true;  // every node of the support is full of solid
      Vec<Dim> w = Vec<Dim>::Zero(), grad_n = Vec<Dim>::Zero();
      MatD<Dim> L = MatD<Dim>::Zero();
      shape::for_each_node(grid_, sdw_[p], [&](std::size_t i, double N, const Vec<Dim>& dN) {
        const NodeSums& s = node_[i];
        const Vec<Dim>& vs = solid_.v[i];
        const Vec<Dim>& vl = liquid_nodes_.v[i];
        div_s += vs.dot(dN);
        div_l += vl.dot(dN);
        w += N * (vl - vs);
        grad_n += s.n * dN;
        phi += N * std::min(1.0, s.V_L / support_[i]);
        if (s.V > 0.0) soil += N, n_soil += N * (1.0 - s.Vs / s.V);
        inside = inside && s.V >= kFullSupport * support_[i];
        if (mu > 0.0) L.noalias() += vl * dN.transpose();
      });
      // eq. 8: the transpose of (2c)'s pressure forces
      const double div_q = nh * div_l + (1.0 - nh) * div_s + grad_n.dot(w);
      rate_[p] = -l.K / nh * div_q;
      // The mixture volume the point stands for: where its support is full of soil, its liquid
      // volume over the solid points' porosity there (n_I = sum N V n / sum N V); in free liquid
      // (no solid in the support), its own volume; between, within a cell of the soil's surface,
      // it follows the liquid, V *= 1 + dt div v_L (seepage into soil stretches it by 1 / n), so
      // that the porosity steps where the liquid points' volumes step, not smeared over the
      // support. (Switching at the soil's half volume fraction instead: seepage 9 % low at
      // h = 25 mm and 19 % at 12.5 mm; this: 13 % and 4 %.)
      const double Vw = liquid_volume(ws, static_cast<int>(p));
      // Following the liquid, V stays between the two: the liquid's own volume (free) and its
      // volume over the soil's porosity (in the soil) — a drift beyond (a dilating shear zone
      // at the soil's edge) made n^ tiny and K_L / n^ unstable (the d = 7 mm Darcy collapse).
      const double V_soil = soil > 0.0 ? Vw * soil / n_soil : Vw;
      ws.V[p] = inside ? V_soil : soil == 0.0 ? Vw : std::clamp(ws.V[p] * (1.0 + dt * div_l), Vw, std::max(Vw, V_soil));
      const bool surface = phi < kFreeSurfaceFraction;
      free_surface_[p] = surface ? 1 : 0;
      Sym tau = Sym::Zero();
      if (!surface && mu > 0.0) {
        const MatD<Dim> D = 0.5 * (L + L.transpose());
        const MatD<Dim> dev = D - (D.trace() / 3.0) * MatD<Dim>::Identity();  // 3D trace (plane strain: D_zz = 0)
        Mat3 t = Mat3::Zero();
        t.template topLeftCorner<Dim, Dim>() = 2.0 * mu * dev;
        if constexpr (Dim == 2) t(2, 2) = 2.0 * mu * (-D.trace() / 3.0);
        tau = to_voigt(t);
      }
      ws.sigma[p] = tau;
    }
    // The pressure rate through the node-based multi-field variational step (seed 000 eqs. 33-34,
    // as explicit-single-point: a_I = H_I^-1 sum N Q rate V, rate(x) = sum N Q^T a_I), which
    // removes the point-to-point checkerboard of a pressure updated point by point.
    if (mfvp_order_ == 0) mfvp0_.fit(grid_, box_, wschedule_, sdw_, ws.x, [&](int p) { return ws.V[p]; }, [&](int p) { return rate_[p]; });
    if (mfvp_order_ == 1) mfvp1_.fit(grid_, box_, wschedule_, sdw_, ws.x, [&](int p) { return ws.V[p]; }, [&](int p) { return rate_[p]; });
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      const Liquid& l = liquid_[ws.material[p]];
      const double rate = mfvp_order_ == 0   ? mfvp0_.at_point(grid_, sdw_[p], ws.x[p])
                          : mfvp_order_ == 1 ? mfvp1_.at_point(grid_, sdw_[p], ws.x[p])
                                             : rate_[p];
      double pp = std::max(ws.p[p] + dt * rate, -l.cavitation);
      if (free_surface_[p]) pp = 0.0;
      ws.p[p] = pp;
      if (!std::isfinite(pp)) bad = std::min(bad, p);
    }
    return bad == transfer::no_particle ? -1 : bad;
  }

  /// Viscosity of the liquid at porosity n^: 0 in soil below n_max (solid-like, seed 003 §3), the
  /// Krieger–Dougherty mixture mu_L (1 - phi / phi_m)^(-[eta] phi_m) above it (phi = 1 - n^ the
  /// solid fraction, phi_m = 1 - n_max the packing where the grains touch; Krieger & Dougherty
  /// 1959), mu_L in free water (phi = 0).
  double effective_viscosity(double mu_L, double nh) const {
    if (!(nh > n_max_)) return 0.0;
    const double phi_m = 1.0 - n_max_;
    if (phi_m <= 0.0) return mu_L;
    const double phi = std::min(1.0 - nh, kViscosityPackingCap * phi_m);
    return mu_L * std::pow(1.0 - phi / phi_m, -kIntrinsicViscosity * phi_m);
  }
  double viscosity_factor_max() const {
    const double phi_m = 1.0 - n_max_;
    return phi_m <= 0.0 ? 1.0 : std::pow(1.0 - kViscosityPackingCap, -kIntrinsicViscosity * phi_m);
  }
  double max_liquid_modulus() const {
    double K = 0.0;
    for (const auto& l : liquid_) K = std::max(K, l.K);
    return K;
  }
  double min_liquid_density() const {
    double rho = std::numeric_limits<double>::infinity();
    for (const auto& l : liquid_)
      if (l.rho > 0.0) rho = std::min(rho, l.rho);
    return rho;
  }

  Grid<Dim> grid_;
  GridBoundary<Dim> bcs_solid_, bcs_liquid_;
  ParticleLoads<Dim> loads_;
  double flip_, damping_, scene_damping_;
  porous::DragLaw drag_;
  double n_max_ = 1.0;  // the smallest maximum_porosity of the scene's skeletons (liquid viscosity)
  std::vector<std::unique_ptr<MaterialModel<Dim>>> materials_;
  PhaseMaterials<Dim> phase_materials_;  // initialisation.materials: swapped in by set_initialisation
  std::vector<std::vector<int>> material_particles_;
  std::vector<std::vector<int>> active_ = std::vector<std::vector<int>>(material_particles_.size());
  std::vector<Liquid> liquid_;      // per material (fluid materials)
  std::vector<Skeleton> skeleton_;  // per material (solid materials)
  NodeFields<Dim> solid_, liquid_nodes_;
  std::vector<NodeSums> node_;
  std::vector<double> support_;       // per node: int N_I dx (the free-surface test's full volume)
  std::vector<std::uint8_t> free_surface_;  // per liquid point, the last step's detection
  std::vector<double> rate_;                 // per liquid point: dp/dt before the projection
  int mfvp_order_ = 1;  // solver.stabilisation.pressure: -1 none, 0 mfvp-constant, 1 mfvp-linear
  NodeProjection<Dim, S, 0, LeverageLimit::off> mfvp0_;
  NodeProjection<Dim, S, 1, LeverageLimit::off> mfvp1_;
  std::vector<std::int64_t> partner_;  // per liquid-point id: the coincident solid point's id (tie)
  bool tie_ = false, fast_drainage_ = false;
  NodeBox<Dim> box_;
  std::vector<shape::ShapeData<Dim, S>> sd_, sdw_;
  std::vector<FaceForce<Dim, S>> face_forces_;
  StripeSchedule schedule_, wschedule_;
  Reorder<Dim> reorder_, wreorder_;
  FBar<Dim, S> fbar_;
  parallel::Domain<Dim> domain_;  // mpirun: this rank's stripes and both sets' points
};

}  // namespace

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_explicit_double_point(const scene::Scene& s, const State<Dim>& state) {
  return make_for_shape<ExplicitDoublePoint, Dim>(s, state);
}

template std::unique_ptr<Formulation<2>> make_explicit_double_point<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_explicit_double_point<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
