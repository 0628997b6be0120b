// What the two semi-implicit formulations share: the incremental fractional-step two-phase MPM
// of seed 001 (Xie, Navas, López-Querol 2025, §3-4.5), incompressible constituents, in swmpm's
// signs (docs/formulations.md, "Derivation in swmpm's signs", derives every line below).
//
// Signs: effective stress sigma' tension positive, pore pressure p compression positive (the
// paper's p_w = -p). Units SI; 2D quantities per metre of thickness.
//
// The stages here are those of the soil and of the grid; the variants (single_point.cpp,
// double_point.cpp) differ only in which points carry the water, and each writes its own step()
// from these stages and its own water stages. The pressure step is pressure.hpp's.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "solver/formulation.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/formulations/semi_implicit/pressure.hpp"
#include "solver/loads.hpp"
#include "solver/materials/material.hpp"
#include "solver/parallel/particles.hpp"
#include "solver/porous/drag.hpp"
#include "solver/porous/permeability.hpp"
#include "solver/porous/points.hpp"
#include "solver/porous/porosity.hpp"
#include "solver/transfer/fbar.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::semi_implicit {

/// The pore water of one solid material: its density and the skeleton's permeability law.
struct PoreWater {
  double rho_w = 0.0;  // kg/m^3
  porous::Permeability perm;
};

/// Per-node quantities besides the two phases' momenta and forces.
struct NodeExtra {
  double mn = 0.0;           // sum S m_s n (nodal porosity x M_s, eq. 46)
  double mk = 0.0;           // sum S m_s k (eq. 47)
  double w_raw = 0.0;        // double-point: sum S rho_w V (M_w = n_I w_raw, eq. 50)
  double n = 1.0, k = 0.0;   // nodal porosity and conductivity
  double soil_volume = 0.0;  // sum S V of the soil points (double-point with escaped_water = remove)
  double drag = 0.0;         // Q_I dt (kg)
};

template <int Dim, class Shape>
class Core : public Formulation<Dim> {
 protected:
  static constexpr int S = Shape::support;
  using Pressure = PressureStep<Dim, Shape>;
  static constexpr bool kCellMoments = Pressure::kCellMoments;
  static constexpr long reorder_interval = 10;  // steps

  /// wet: the points that carry the water (the soil points, or the water points).
  Core(const scene::Scene& s, const State<Dim>& state, const ParticleSet<Dim>& wet, const std::string& name)
      : grid_(make_grid<Dim>(s, Shape::degree, Shape::bspline)),
        bcs_solid_(s, grid_, state.surfaces),
        bcs_fluid_(GridBoundary<Dim>::fluid(s, grid_, state.surfaces)),
        // A prescribed pore pressure is the Dirichlet value of the pressure equation on its face;
        // the strong gradient G p of the pressure forces holds its boundary term, so it is no load
        // here (docs/formulations.md, "Prescribed pore pressure").
        loads_(s, grid_, state.solid, state.surfaces, /*pore_pressure_forces=*/false),
        flip_(s.solver.flip),
        damping_(s.solver.damping),
        scene_damping_(s.solver.damping),
        materials_(make_materials<Dim>(s)),
        phase_materials_(s),
        material_particles_(group_by_material(state.solid, s.materials.size())),
        pressure_(grid_, box_, reach_, remap_of(s, name), drained_faces(), face_pressures(s)),
        fbar_(s, grid_) {
    conservative_ = s.solver.continuity != "non-conservative";  // "" (unset): this formulation's default
    implicit_drag_ = s.solver.drag_integration != "semi-implicit";  // "" (unset): the default, implicit
    // One point per cell with B-splines and a pore pressure on a named surface are refused by the
    // formulation's row (scene/formulations.cpp) before anything is written.
    if (!state.solid.two_phase())
      throw std::runtime_error(name + " needs saturated soil points (porosity in particles/solid.vtu): run swmpm "
                               "preprocess with a body that has a solid and a fluid");
    if (parallel::sum(static_cast<long>(wet.size())) == 0)  // over every rank's points
      throw std::runtime_error(name + " needs water points (particles/fluid.vtu): run swmpm preprocess again");
    for (std::size_t i = 0; i < s.boundaries.size(); ++i) {
      const auto& b = s.boundaries[i];
      if (!b.fluid || *b.fluid != scene::FluidBc::pressure) continue;
      const std::string where = "boundaries/" + std::to_string(i) + "/fluid";
      const int f = scene::grid_face_index(b.on);  // a grid face: the row refuses named surfaces
      // The value acts through the face's nodes that carry water: some water must reach the face.
      bool reaches = false;
      for (std::size_t p = 0; p < wet.size() && !reaches; ++p) reaches = domain_ends_on_face(grid_, f, wet.x[p], wet.l[p]);
      if (!parallel::any(reaches))  // over every rank's points
        throw std::runtime_error(where + ": no water lies on \"" + b.on +
                                 "\", so the prescribed pore pressure would act on nothing");
    }
    // The pore water of each solid material (its points' pore fluid) and its permeability law.
    pore_.resize(s.materials.size());
    for (std::size_t k = 0; k < s.materials.size(); ++k) {
      const auto& m = s.materials[k];
      if (m.model == scene::MaterialModel::fluid) continue;
      pore_[k].perm.k0 = m.has("hydraulic_conductivity") ? m.at("hydraulic_conductivity") : 0.0;
      pore_[k].perm.law = porous::law_of(m.permeability_law);
    }
    const ParticleSet<Dim>& ps = state.solid;
    pore_water_on_soil_ = &wet == &state.solid;
    // The water of each solid material: its last point's (none: dry), over every rank's points.
    const std::vector<int> water_of = material_value_over_ranks(
        ps, s.materials.size(), /*last=*/true, [&](int p) { return fluid_material_of(s, ps, p); });
    for (std::size_t k = 0; k < s.materials.size(); ++k) {
      const int fm = water_of[k];
      if (fm < 0) continue;
      auto& pw = pore_[k];
      pw.rho_w = s.materials[fm].at("density");
      pw.perm = porous::permeability_of(s.materials[k], s.materials[fm]);
    }
    const std::size_t nodes = grid_.num_nodes();
    soil_.resize(nodes);
    water_.resize(nodes);
    node_.assign(nodes, NodeExtra{});
    A_soil_.resize(nodes);  // zero (NodeArray)
    A_water_.resize(nodes);
  }

  // ---- the stages of a step ------------------------------------------------------------------

  /// (1) Shape data of the soil points and the active node box; failures reported. Under mpirun
  /// the soil points that crossed a cut move to their rank first (parallel::own_particles).
  void evaluate_soil_shapes(State<Dim>& st) {
    long bad = -1;
    box_ = transfer::evaluate_shapes<Shape>(grid_, st.solid, sd_, bad);
    if (parallel::own_particles<Shape>(domain_, grid_, st, schedule_, sd_, box_, bad))
      regroup_by_material(st.solid, material_particles_);
    if (bad >= 0) st.health.report(bad, "solid", "left the grid (or position not finite)");
  }
  /// (1) The soil's scatter schedule, the tractions' face points (mpirun: every rank's), the
  /// nodes the step may read (reach_), and the box's nodes cleared.
  void prepare_nodes(State<Dim>& st, const StepContext& ctx) {
    collect_face_forces<Shape>(grid_, loads_, st.solid, st.index_of_id, ctx.t, box_, face_forces_);
    parallel::share_face_forces<Shape>(domain_, grid_, face_forces_, box_);
    reach_ = box_;
    if (domain_.active()) {  // the rank's own node columns and kGhost either side
      const int a = domain_.axis();
      const auto [lo, hi] = domain_.owned_columns();
      reach_.lo[a] = std::max(0, lo - Pressure::kGhost);
      reach_.hi[a] = std::min(grid_.nodes_per_axis()[a] - 1, hi + Pressure::kGhost - 1);
    }
    transfer::build_schedule(grid_, sd_, schedule_);
    auto& surface = pressure_.surface();
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      soil_.acc[i] = {Vec<Dim>::Zero(), Vec<Dim>::Zero(), 0.0};
      water_.acc[i] = {Vec<Dim>::Zero(), Vec<Dim>::Zero(), 0.0};
      node_[i] = NodeExtra{};
      surface.clear(i);
    });
  }

  /// (2) Soil points: M_s, M_s v_s, sum S m n, sum S m k (eqs. 44-47) and the soil's internal force
  ///   f_s = -sum_sp V sigma' . grad S   (the body force sum S m_s b = M_s b is added at the node, (3)),
  /// and, kPoreWater (single-point), the water carried on the same points (and its extent for the
  /// free surface): M_w = sum S m_f, M_w v_w = sum S m_f v_f. kSoilVolume: sum S V too (escaped
  /// water). weights(p, laplace_derived): the point's share of (5a), whose moments go in the same
  /// pass (cell moments). The pressure forces (-n grad p on the water, -(1 - n) grad p on the soil:
  /// eqs. 55-57 with p_w = -p) are added at the nodes by the predictor, from the nodal p^t.
  template <bool kPoreWater, bool kSoilVolume, class SoilWeights>
  void scatter_soil(const ParticleSet<Dim>& ps, SoilWeights&& weights) {
    const bool laplace_derived = pressure_.laplace_derived();
    auto& surface = pressure_.surface();
    auto scatter = [&](int p) __attribute__((always_inline)) {
      const double V = ps.V[p], n = ps.n[p], m = ps.m[p];
      const double k = pore_[ps.material[p]].perm.at_point(n, V, ps.V0[p]);
      const Mat3 sig = to_matrix(ps.sigma[p]);
      const MatD<Dim> A = V * sig.template topLeftCorner<Dim, Dim>();
      const Vec<Dim> mv = m * ps.v[p];
      const double mf = kPoreWater ? ps.m_f[p] : 0.0;
      const Vec<Dim> mfv = kPoreWater ? Vec<Dim>(mf * ps.v_f[p]) : Vec<Dim>::Zero();
      const bool wet = kPoreWater && mf > 0.0;  // carries water: joins the free surface's extent
      const Vec<Dim> x_lo = ps.x[p] - ps.l[p], x_hi = ps.x[p] + ps.l[p];
      if (wet) surface.add_at_base(grid_, sd_[p], x_lo, x_hi);
      if constexpr (kCellMoments) {
        const Weights c = weights(p, laplace_derived);
        pressure_.moments().template add<true, kPoreWater>(grid_, sd_[p].base, ps.x[p], c.s, c.w, c.l);
      }
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>& dN) {
        auto& s = soil_.acc[i];
        s.m += N * m;
        s.mv += N * mv;
        s.f -= A * dN;
        auto& e = node_[i];
        e.mn += N * m * n;
        e.mk += N * m * k;
        if constexpr (kSoilVolume) e.soil_volume += N * V;
        if constexpr (kPoreWater) {
          auto& w = water_.acc[i];
          w.m += N * mf;
          w.mv += N * mfv;
          if (wet) surface.add_at_node(i, N, x_lo, x_hi);
        }
      });
    };
    // Under mpirun the scattered node arrays are exchanged at the cuts (StripeSchedule::run); the
    // cell moments go to the points' own cells, which the rank owns.
    if constexpr (kPoreWater) schedule_.run(scatter, soil_.acc, node_, water_.acc, surface.extents());
    else schedule_.run(scatter, soil_.acc, node_);
    // The free surface's test at a node reads the extents of the supports starting up to S - 1
    // columns below it (kBaseExtent): the ghost columns' too.
    if constexpr (kPoreWater && porous::SupportCut<Dim, Shape>::kBaseExtent) pressure_.fill_ghosts(surface.extents());
  }

  /// (2) Nodal porosity and conductivity of the soil, n_I = sum S m n / M_s and k_I = sum S m k /
  /// M_s (eqs. 46-47; 1 and 0 where no soil), for the water points' P2G, the drag and the
  /// continuity.
  void nodal_porosity() {
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      auto& e = node_[i];
      const double Ms = soil_.acc[i].m;
      e.n = porous::porosity_at_node(e.mn, Ms, 1.0);
      e.k = Ms > transfer::empty_node_mass ? e.mk / Ms : 0.0;
    });
    pressure_.fill_ghosts(node_);  // mpirun: the continuity's n_K, R columns beyond the rank's
  }
  /// (3) Tractions on the soil (no pore-pressure loads: see loads_).
  void add_face_forces() {
    parallel::weigh_face_forces(domain_, grid_, face_forces_, carries_mass(soil_));  // one rank: weigh_face_forces
    add_weighed_face_forces(grid_, face_forces_, soil_);
  }
  /// (3) The water's nodal velocity v_w^t = M_w v_w / M_w from the scattered sums (0 where none).
  void nodal_water_velocity() {
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      const auto& w = water_.acc[i];
      water_.vL[i] = w.m > transfer::empty_node_mass ? Vec<Dim>(w.mv / w.m) : Vec<Dim>::Zero();
    });
  }

  /// (3)-(4) per node, with v^t = M v / M, Q = g n M_w / k (eq. 58), a = dt Q (porous::
  /// darcy_drag_impulse), A_w = M_w v_w^t + dt (f_w - G^w p^t), A_s = M_s v_s^t + dt (f_s - G^s p^t):
  ///   semi-implicit (seed 001 eqs. 52-53): (M_w + a) v_w* = A_w + a v_s^t,
  ///                                        M_s v_s* = A_s + a (v_w* - v_s^t);
  ///   implicit (default): porous::solve_drag, (M_w + a) v_w* - a v_s* = A_w,
  ///                                           (M_s + a) v_s* - a v_w* = A_s.
  /// Both conserve the mixture's momentum. Without forces the seed's form maps the relative velocity
  /// r = v_w - v_s to r M_w (1 - a / M_s) / (M_w + a), |.| -> M_w / M_s for a stiff drag: it
  /// diverges at nodes with much more water than soil (free water over soil, a seepage exit);
  /// the implicit form maps r to r / (1 + a / M_w + a / M_s) (docs/formulations.md, "Implicit drag").
  /// Then the velocity boundary conditions of each phase on v*. The pressure force is the strong
  /// form -sum_p c V S_K grad p^t(x_p) of the nodal p^t (eqs. 55, 57 integrated by parts), i.e.
  /// the operator G of the corrections (6): see docs/formulations.md, "B-splines", for why the
  /// weak form sum_p c V p_p grad S_K of the paper is unstable with B-splines. Reads v_w^t from
  /// water_.vL (nodal_water_velocity).
  void predict(double dt, const Vec<Dim>& b) {
    const double alpha = damping_;
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto& ijk) {
      auto& s = soil_.acc[i];
      auto& w = water_.acc[i];
      auto& e = node_[i];
      const bool has_s = s.m > transfer::empty_node_mass;
      const Vec<Dim> vw = water_.vL[i];
      s.f += s.m * b;  // body forces sum S m b = M b of both phases (eqs. 55-56)
      w.f += w.m * b;
      pressure_.add_pressure_force(i, ijk, pressure_.p_node(), s.f, w.f);  // -G p^t: eqs. 55, 57 in the strong form
      const bool has_w = w.m > transfer::empty_node_mass;
      const Vec<Dim> vs = has_s ? Vec<Dim>(s.mv / s.m) : Vec<Dim>::Zero();
      soil_.vL[i] = vs;
      e.drag = has_s && has_w && e.k > 0.0 ? porous::darcy_drag_impulse(dt, e.n, w.m, e.k) : 0.0;
      const Vec<Dim> fs = local_damping<Dim>(s.f, vs, alpha);
      if (implicit_drag_ && e.drag > 0.0) {
        const Vec<Dim> Aw = w.m * vw + dt * w.f, As = s.m * vs + dt * fs;
        const auto u = porous::solve_drag<Dim>(s.m, w.m, e.drag, As, Aw);
        water_.v[i] = u.v_w;
        soil_.v[i] = u.v_s;
        A_water_[i] = Aw;
        A_soil_[i] = As;
      } else {
        const Vec<Dim> vw_star =
            has_w ? Vec<Dim>((w.m * vw + dt * w.f + e.drag * vs) / (w.m + e.drag)) : Vec<Dim>::Zero();
        soil_.v[i] = has_s ? Vec<Dim>(vs + (dt * fs + e.drag * (vw_star - vs)) / s.m) : Vec<Dim>::Zero();
        water_.v[i] = vw_star;
      }
    });
    bcs_solid_.apply(grid_, box_, soil_.v, false);
    if (implicit_drag_) {
      // A constrained component is known: the other phase takes it from its own equation,
      // (M_w + a) v_w* = A_w + a v_s*, then (M_s + a) v_s* = A_s + a v_w* (both identities of the
      // coupled solution where nothing is constrained), each followed by its phase's conditions.
      grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
        const double a = node_[i].drag;
        if (a > 0.0) water_.v[i] = (A_water_[i] + a * soil_.v[i]) / (water_.acc[i].m + a);
      });
      bcs_fluid_.apply(grid_, box_, water_.v, false);
      grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
        const double a = node_[i].drag;
        if (a > 0.0) soil_.v[i] = (A_soil_[i] + a * water_.v[i]) / (soil_.acc[i].m + a);
      });
      bcs_solid_.apply(grid_, box_, soil_.v, false);
    } else {
      bcs_fluid_.apply(grid_, box_, water_.v, false);
    }
  }

  /// (5c) The pressure increment; false (reported) if the system is not positive definite.
  bool solve_pressure(State<Dim>& st, double dt) {
    pressure_.fill_ghosts(soil_.v);  // mpirun: the divergence reads R columns beyond the rank's
    pressure_.fill_ghosts(water_.v);
    auto n_of = [&](std::size_t K) { return node_[K].n; };
    const bool ok = conservative_ ? pressure_.template solve<true>(dt, soil_, water_, n_of)
                                  : pressure_.template solve<false>(dt, soil_, water_, n_of);
    if (!ok)
      st.health.report(0, "fluid",
                       "pressure Poisson system not positive definite (water touching no drained node or free "
                       "surface has an undetermined pressure)");
    return ok;
  }

  /// (6) eqs. 64-68 with the strong gradient G (eqs. 67-68):
  ///   M_sK (v_sK^{t+1} - v_sK*) = -dt sum_J G^s_KJ dp_J,   M_wK (v_wK^{t+1} - v_wK*) = -dt sum_J G^w_KJ dp_J
  /// (= -dt sum_p (1 - n) V S_K grad dp(x_p)), then the boundary conditions on v^{t+1} (step 6d
  /// erratum: on v^{t+1}, not v*). The velocity change at a node is a weighted mean of grad dp
  /// over the points it touches, however little mass it has.
  void correct(double dt) {
    const auto& dp = pressure_.dp();
    grid_.parallel_for_each_node(box_, [&](std::size_t k, const auto& ijk) {
      Vec<Dim> js = Vec<Dim>::Zero(), jw = Vec<Dim>::Zero();
      pressure_.add_pressure_force(k, ijk, dp, js, jw);
      const double Ms = soil_.acc[k].m, Mw = water_.acc[k].m;
      if (Ms > transfer::empty_node_mass) soil_.v[k] += (dt / Ms) * js;
      if (Mw > transfer::empty_node_mass) water_.v[k] += (dt / Mw) * jw;
    });
    bcs_solid_.apply(grid_, box_, soil_.v, true);
    bcs_fluid_.apply(grid_, box_, water_.v, false);
  }

  /// (7) FLIP/PIC for the soil points (kPoreWater, single-point: and their pore water), soil
  /// positions with v_s^{t+1}, and the MUSL remap of the soil momentum (step 8a) before the strain
  /// increment (porous::gather_soil_points).
  template <bool kPoreWater>
  void gather_soil(ParticleSet<Dim>& ps, double dt) {
    porous::gather_soil_points<kPoreWater, false>(grid_, box_, schedule_, sd_, flip_, dt, ps, soil_, water_);
    bcs_solid_.apply(grid_, box_, soil_.v, false);
  }

  /// (8) L_s = sum v_s (x) grad S with the remapped velocities; F, V and the porosity from
  /// (1 - n) J = 1 - n0 (step 8f, porous::update_skeleton); the pore-water mass n rho_w V (0 at a
  /// dry single-point point: it stays dry); then F-bar (9)(b)-(g) and the stress by each material
  /// model. Failures reported.
  void update_soil(State<Dim>& st, double dt) {
    ParticleSet<Dim>& ps = st.solid;
    const long n = static_cast<long>(ps.size());
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      MatD<Dim> L = MatD<Dim>::Zero();
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double, const Vec<Dim>& dN) {
        L.noalias() += soil_.v[i] * dN.transpose();
      });
      ps.L[p] = L;
      const double J = porous::update_skeleton<Dim>(L, dt, ps.F[p], ps.V[p], ps.V0[p], ps.n[p]);
      ps.m_f[p] = dry(ps, p) ? 0.0 : ps.n[p] * pore_[ps.material[p]].rho_w * ps.V[p];
      if (!(J > 0.0) || !(ps.n[p] > 0.0 && ps.n[p] < 1.0)) bad = std::min(bad, p);
    }
    if (bad != transfer::no_particle) st.health.report(bad, "solid", "volume ratio J <= 0 or porosity outside (0, 1)");
    fbar_.apply(grid_, box_, schedule_, sd_, dt, st, materials_, material_particles_);  // transfer/fbar.hpp
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const long m_bad = materials_[k]->update_stress(ps, material_particles_[k], dt);
      if (m_bad >= 0) st.health.report(m_bad, "solid", "stress update failed (" + materials_[k]->name() + ")");
    }
  }

  // ---- what the loop asks of both variants ---------------------------------------------------

 public:
  double critical_time_step(const State<Dim>& st, std::string& reason) const override {
    // Soil CFL only: the pressure is implicit (incompressible constituents) and the drag
    // semi-implicit, so neither the water's compressibility nor k limits dt. The skeleton's P-wave
    // carries the pore water with it (saturated density; a dry point's own, which is faster).
    const ParticleSet<Dim>& ps = st.solid;
    double c_max = 0.0;
    const std::vector<double> moduli = max_p_wave_moduli(materials_, ps, material_particles_);
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const double M = moduli[k];
      for (int p : material_particles_[k]) {
        const double rho = (ps.m[p] + (dry(ps, p) ? 0.0 : ps.n[p] * pore_[k].rho_w * ps.V[p])) / ps.V[p];
        c_max = std::max(c_max, std::sqrt(M / rho));
      }
    }
    double v_max = 0.0;
    for (const ParticleSet<Dim>* set : {&st.solid, &st.fluid}) {
      const long n = static_cast<long>(set->size());
#pragma omp parallel for reduction(max : v_max) if (n > parallel_threshold)
      for (long p = 0; p < n; ++p) v_max = std::max(v_max, set->v[p].norm());
    }
    c_max = parallel::max(c_max);  // over all ranks (mpirun)
    v_max = parallel::max(v_max);
    std::ostringstream os;
    os << "soil P-wave CFL (c = " << c_max << " m/s with the saturated density, |v|max = " << v_max
       << " m/s); the pore pressure is implicit and the drag " << (implicit_drag_ ? "implicit" : "semi-implicit")
       << ", so neither K_w nor k limits dt";
    reason = os.str();
    return grid_.h() / (c_max + v_max);
  }
  /// The skeleton's stored energy; incompressible water stores none.
  double strain_energy(const State<Dim>& st) const override {
    const auto& ps = st.solid;
    return fixed_order_sum(ps.size(), [&](std::size_t p) {
      return materials_[ps.material[p]]->strain_energy(ps, static_cast<int>(p));
    });
  }
  std::size_t active_cells(const State<Dim>& st) const override { return count_active_cells(grid_, st.solid); }
  std::vector<typename Formulation<Dim>::Counter> counters() const override {
    auto c = pressure_.template counters<typename Formulation<Dim>::Counter>();
    domain_.add_counters(c);
    return c;
  }
  std::string on_several_ranks(const scene::Scene&) const override { return {}; }  // every option runs on several ranks
  void distribute(State<Dim>& st) override {
    parallel::distribute<Shape>(domain_, grid_, st, schedule_, material_particles_);
    pressure_.distribute(domain_);
    fbar_.distribute(domain_);
  }

 protected:
  /// The external power: that of gravity on both phases (gravity_power, the variant's sum), then
  /// of the tractions on the soil and of the prescribed pore pressures.
  double external_power(double gravity_power, const State<Dim>& st, const StepContext& ctx) const {
    double power = gravity_power;
    loads_.for_each_force(ctx.t, st.index_of_id, [&](int p, const Vec<Dim>& f_p, const Vec<Dim>&, bool) {
      power += f_p.dot(st.solid.v[p]);  // tractions act on the soil (no pore-pressure loads: see loads_)
    });
    return power + pore_pressure_power();
  }
  static Vec<Dim> gravity(const StepContext& ctx) {
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    return b;
  }
  /// Power of the prescribed pore pressures p_bar on their faces [W or W/m]: the traction -p_bar n
  /// on the mixture, whose boundary term the strong gradient holds, times the mixture's volume flux
  /// q = (1 - n) v_s + n v_w, at the face nodes with water of the last step:
  ///   P = sum_K -p_bar (n . q_K) int_face S_K dA.
  /// Without it the energy check counted no work for a flow that p_bar drives.
  double pore_pressure_power() const {
    double power = 0.0;
    const auto& nn = grid_.nodes_per_axis();
    for (int f = 0; f < 2 * Dim; ++f) {
      if (!pressure_.drained(f) || pressure_.face_pressure(f) == 0.0) continue;
      const int axis = f / 2, j = f % 2 == 0 ? 0 : nn[axis] - 1;
      const double outward = f % 2 == 0 ? -1.0 : 1.0;
      NodeBox<Dim> face = box_;
      face.lo[axis] = face.hi[axis] = j;
      if (domain_.active()) {  // mpirun: each rank its own columns (the run sums the ranks' powers)
        const auto [lo, hi] = domain_.owned_columns();
        face.lo[domain_.axis()] = std::max(face.lo[domain_.axis()], lo);
        face.hi[domain_.axis()] = std::min(face.hi[domain_.axis()], hi - 1);
      }
      if (face.empty() || box_.lo[axis] > j || box_.hi[axis] < j) continue;
      grid_.for_each_node(face, [&](std::size_t i, const auto&) {  // serial: fixed summation order
        if (!(water_.acc[i].m > transfer::empty_node_mass)) return;
        const double n = node_[i].n;
        const double qn = (1.0 - n) * soil_.v[i][axis] + n * water_.v[i][axis];
        power -= pressure_.face_pressure(f) * outward * qn * porous::basis_integral<Shape>(grid_, i, axis);
      });
    }
    return power;
  }
  /// The initialisation phase's plasticity, damping and permeability (its hydraulic_conductivity
  /// for every material while it runs). True when a phase with its own permeability has just ended.
  bool set_phase(const scene::Initialisation* phase) {
    phase_materials_.set(materials_, phase);  // the phase's parameters and plastic flag (materials/material.hpp)
    damping_ = phase_damping(phase, scene_damping_);
    if (scene_pore_.empty()) scene_pore_ = pore_;
    pore_ = scene_pore_;
    if (phase && phase->hydraulic_conductivity) {
      for (auto& pw : pore_) pw.perm = porous::Permeability{porous::Permeability::Law::constant, *phase->hydraulic_conductivity};
      fast_drainage_ = true;
    }
    const bool ended = phase == nullptr && fast_drainage_;
    if (ended) fast_drainage_ = false;
    return ended;
  }
  /// Restart: the schedule order the next step's reordering reads, and the pressure solver's
  /// equations and reused factor.
  void save_core(Checkpoint& c) const {
    save_order(c, "formulation/schedule_order", schedule_);
    pressure_.save(c);
  }
  void restore_core(const Checkpoint& c, State<Dim>& st) {
    regroup_by_material(st.solid, material_particles_);  // the checkpoint's particle order
    restore_order(c, "formulation/schedule_order", schedule_);
    pressure_.restore(c);
  }
  /// The box of the soil's and another set's nodes (double-point: the water points').
  void join_box(const NodeBox<Dim>& other) {
    for (int a = 0; a < Dim; ++a) {
      box_.lo[a] = std::min(box_.lo[a], other.lo[a]);
      box_.hi[a] = std::max(box_.hi[a], other.hi[a]);
    }
  }
  /// rho_s = m / ((1 - n) V) of a soil point (kg/m^3).
  static double grain_density(const ParticleSet<Dim>& ps, int p) { return ps.m[p] / ((1.0 - ps.n[p]) * ps.V[p]); }
  /// Single-point: the soil point carries no pore water (fluid_material -1: a dry body in a
  /// saturated scene, or soil above a hydrostatic body's water table). Double-point soil points
  /// never carry water (theirs is on the water points).
  bool dry(const ParticleSet<Dim>& ps, long p) const { return pore_water_on_soil_ && ps.fluid_material[p] < 0; }
  /// Cell moments: when every soil point has the same grain density m / ((1 - n) V) (to 1e-12)
  /// and all the water the same density (water_density(p) of the water's points ws), the L weight
  /// of every point is (1 - n) V / rho_s + n V / rho_w, a fixed combination of the D^s and D^w
  /// weights (CellMoments::derive_laplace). Both are constant in a run (incompressible constituents).
  template <class WaterDensity>
  void derive_laplace_if_single_densities(const ParticleSet<Dim>& ps, const ParticleSet<Dim>& ws,
                                          WaterDensity&& water_density) {
    if constexpr (kCellMoments) {
      if (parallel::sum(static_cast<long>(ps.size())) == 0 || parallel::sum(static_cast<long>(ws.size())) == 0) return;
      // Every value positive, finite and within 1e-12 of the first (the first point of the
      // one-rank order: the lowest key under mpirun), over every rank's points.
      auto one_value = [](const ParticleSet<Dim>& set, auto&& value_of, double& first) {
        const std::size_t n = set.size();
        constexpr long unplaced = std::numeric_limits<long>::max();
        first = parallel::value_at_lowest(n ? static_cast<long>(set.place(0)) : unplaced, n ? value_of(0) : 0.0,
                                          -std::numeric_limits<double>::infinity(), unplaced);
        bool ok = true;
        for (std::size_t p = 0; p < n && ok; ++p) {
          const double v = value_of(p);
          ok = v > 0.0 && std::isfinite(v) && std::abs(v - first) <= 1e-12 * first;
        }
        return !parallel::any(!ok);
      };
      double rho_s = 0.0, rho_w = 0.0;
      const bool single_soil = one_value(ps, [&](std::size_t p) { return grain_density(ps, static_cast<int>(p)); }, rho_s);
      const bool single_water = one_value(ws, [&](std::size_t p) { return water_density(static_cast<int>(p)); }, rho_w);
      if (single_soil && single_water) pressure_.moments().derive_laplace(rho_s, rho_w);
    }
  }

  Grid<Dim> grid_;
  GridBoundary<Dim> bcs_solid_, bcs_fluid_;
  ParticleLoads<Dim> loads_;
  double flip_, damping_, scene_damping_;
  std::vector<std::unique_ptr<MaterialModel<Dim>>> materials_;
  PhaseMaterials<Dim> phase_materials_;  // initialisation.materials: swapped in by set_initialisation
  std::vector<std::vector<int>> material_particles_;
  std::vector<PoreWater> pore_;        // per solid material (the initialisation phase's while it runs)
  std::vector<PoreWater> scene_pore_;  // per solid material, as the scene gives it
  bool conservative_ = true;           // solver.continuity = conservative (solve_pressure)
  bool implicit_drag_ = true;          // solver.drag_integration (predictor)
  bool fast_drainage_ = false;         // an initialisation with its own permeability is running
  bool pore_water_on_soil_ = false;    // single-point: the soil points carry the water (fluid_material per point)
  NodeBox<Dim> box_;
  NodeBox<Dim> reach_;  // the nodes the per-node stages may read: box_ (mpirun: and the ghost columns)
  parallel::Domain<Dim> domain_;  // mpirun: this rank's stripes and soil points (inactive at one rank)
  NodeFields<Dim> soil_, water_;
  std::vector<NodeExtra> node_;
  NodeArray<Vec<Dim>> A_soil_, A_water_;  // per node: M v^t + dt f of each phase (implicit drag)
  Pressure pressure_;
  std::vector<shape::ShapeData<Dim, S>> sd_;
  std::vector<FaceForce<Dim, S>> face_forces_;
  StripeSchedule schedule_;
  Reorder<Dim> reorder_;
  FBar<Dim, S> fbar_;

 private:
  /// The pore water of soil point p: single-point, the point's own fluid_material (-1: dry, also
  /// in a body with a fluid, above its water table); double-point (fluid_material -1 throughout),
  /// the fluid of the point's body.
  int fluid_material_of(const scene::Scene& s, const ParticleSet<Dim>& ps, int p) const {
    if (pore_water_on_soil_) return ps.fluid_material[p];
    const auto& body = s.bodies[ps.body[p]];
    return body.fluid.empty() ? -1 : static_cast<int>(s.material_index(body.fluid));
  }
  static Remap remap_of(const scene::Scene& s, const std::string& name) {
    const auto& pressure = s.solver.stabilisation.pressure;
    if (pressure == "node-remap") return Remap::node;
    if (pressure == "mfvp-linear") return Remap::linear;
    if (pressure == "none") return Remap::none;
    throw std::runtime_error("solver.stabilisation.pressure: \"" + pressure + "\" is not available in " + name +
                             " (available: node-remap, mfvp-linear, none)");
  }
  /// Per grid face: drained (p prescribed, 0 or the face's value) unless the water cannot cross it.
  std::array<bool, 6> drained_faces() const {
    std::array<bool, 6> drained;
    drained.fill(true);
    for (const auto& f : bcs_fluid_.faces()) drained[2 * f.axis + f.side] = false;
    return drained;
  }
  static std::array<double, 6> face_pressures(const scene::Scene& s) {
    std::array<double, 6> value;
    value.fill(0.0);
    for (const auto& b : s.boundaries) {
      const int f = scene::grid_face_index(b.on);  // a named surface is refused by the constructor
      if (b.fluid && *b.fluid == scene::FluidBc::pressure && f >= 0) value[f] = b.fluid_value;
    }
    return value;
  }
};

}  // namespace swmpm::semi_implicit
