// Formulations `semi-implicit-single-point` and `semi-implicit-double-point`: the incremental
// fractional-step two-phase MPM of seed 001 (Xie, Navas, López-Querol 2025, §3-4.5; single-point
// as in Yuan et al. 2023), incompressible constituents, in swmpm's signs (docs/formulations.md,
// "Derivation in swmpm's signs", derives every line below).
//
// Signs: effective stress sigma' tension positive, pore pressure p compression positive (the
// paper's p_w = -p). Units SI; 2D quantities per metre of thickness.
//
// The variants differ only in which points carry the water: single-point maps the water terms
// from the soil points (each carries n, p, v_f, m_f as in explicit-single-point); double-point
// from its own water points (State::fluid), which move with the water velocity, with the nodal
// porosity of the soil (eqs. 46-51).
//
// One step (named, timed stages; numbers are the paper's algorithm steps, §4.5):
//   (0) reorder points into scatter order every 10 steps (memory locality only)
//   (1) shape data of soil (and water) points, active node box, scatter schedules
//   (2) P2G: M_s, M_s v_s, nodal porosity and conductivity (soil-mass weighted, eqs. 44-47),
//       water mass and momentum (eqs. 50-51; double-point: each water point first takes its
//       porosity and volume from the nodal porosity), effective-stress forces; the points'
//       moments of (5a) in the same pass (cell-moment path)
//   (5a)-(5b) L, D_s, D_w (eqs. 61-63, L symmetric: c(n) inside the quadrature), the nodal p^t
//       (linear projection of the points' pressures), free-surface and drained nodes
//   (3)-(4) body forces M b at the nodes; water and soil predictors (eqs. 52-53) with the drag implicit in both velocities (the
//       seed's form, implicit in v_w* only, with solver.drag_integration = semi-implicit) and the
//       pressure force -G p^t of the same gradient operator G as the corrections; BCs
//   (5c) pressure increment: L dp = -(1/dt) [D_s v_s* + D_w v_w*] (eq. 60), p^{t+1} = p_D on
//       free-surface / drained nodes; CHOLMOD
//   (6) corrections v^{t+1} = v* - dt/M (G dp) (eqs. 64-68, G the strong gradient S_K grad S_J);
//       BCs on v^{t+1}; pressure update (incremental, or node-wise remap eq. 77)
//   (7) G2P (FLIP/PIC) of the soil points, positions; MUSL remap of the soil velocity (step 8a)
//   (8) F, V, porosity (1 - n) J = 1 - n0, permeability law; double-point water points: G2P and
//       positions; stress by the material model. The water points' porosity and volume (step 8h
//       with the M_s erratum, eq. 36) come from the next step's nodal porosity, in its water P2G
//       (docs/formulations.md, "Water points' porosity"). (Stage timers: the water points' G2P is
//       in "stress and porosity", the moments in "p2g", since 2026-12-02.)
#include <omp.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <sstream>
#include <type_traits>
#include <utility>

#include "solver/formulation.hpp"
#include "solver/formulations/pressure_poisson.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/loads.hpp"
#include "solver/materials/material.hpp"
#include "solver/transfer/cell_moments.hpp"
#include "solver/transfer/fbar.hpp"
#include "solver/transfer/projection.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {
namespace {

constexpr double g_earth = 9.81;  // m/s^2, in k = rho_w g kappa / mu and in the drag Q = g n M_w / k

/// Water and permeability of one solid material.
struct Permeability {
  enum class Law { constant, kozeny_carman, xie_leo };
  double rho_w = 0.0;  // kg/m^3, density of the pore water
  double k0 = 0.0;     // m/s, hydraulic conductivity at the initial porosity
  Law law = Law::constant;
  /// k at porosity n of a point whose initial porosity was n0:
  ///   kozeny-carman  k = k0 [n^3 / (1 - n)^2] / [n0^3 / (1 - n0)^2]   (step 8g, C1 fixed by (n0, k0))
  ///   xie-leo        k = k0 J^2,  J = (1 - n0) / (1 - n)               (incompressible grains)
  double at(double n, double n0) const {
    switch (law) {
      case Law::constant: return k0;
      case Law::kozeny_carman: return k0 * (n * n * n / ((1 - n) * (1 - n))) / (n0 * n0 * n0 / ((1 - n0) * (1 - n0)));
      case Law::xie_leo: {
        const double J = (1 - n0) / (1 - n);
        return k0 * J * J;
      }
    }
    return k0;
  }
};

/// A node whose support reaches more than this many cells beyond the water is on the free surface
/// (every shape function; see free_surface()).
constexpr double kSurfaceCut = 0.25;

template <int Dim, class Shape>
class SemiImplicit final : public Formulation<Dim> {
  static constexpr int S = Shape::support;
  using Poisson = PressurePoisson<Dim, S - 1>;  // rows of L reach S - 1 nodes per axis
  using DSt = Stencil<Dim, S - 1>;               // so do those of D
  static constexpr int KD = DSt::K;
  static constexpr int NP = Dim == 2 ? S * S : S * S * S;  // nodes per point
  // Stencil slot of the pair (node r, node k) of one point's support (r, k in for_each_node's
  // order, x fastest), the same in D's and L's stencils (both reach S - 1): the offset is
  // d = k - r per axis, so slot(d) = sum_a (d_a + S - 1) W^a = kRowSlot[r] + kColumnSlot[k].
  static_assert(DSt::W == Poisson::W && DSt::K == Poisson::K);
  static constexpr std::array<int, NP> pair_slot_part(bool row) {
    std::array<int, NP> out{};
    for (int r = 0; r < NP; ++r) {
      int slot = 0, mul = 1, rest = r;
      for (int a = 0; a < Dim; ++a, rest /= S, mul *= DSt::W) slot += (row ? S - 1 - rest % S : rest % S) * mul;
      out[r] = slot;
    }
    return out;
  }
  static constexpr std::array<int, NP> kRowSlot = pair_slot_part(true);
  static constexpr std::array<int, NP> kColumnSlot = pair_slot_part(false);
  // 2D with a shape function that is one polynomial per cell (linear, B-splines): the operators are
  // assembled from cell moments (transfer/cell_moments.hpp). GIMP and 3D scatter point by point.
  static constexpr bool kCellMoments = Dim == 2 && (Shape::bspline || std::is_same_v<Shape, shape::Linear>);
  using Moments = transfer::CellMoments<std::conditional_t<kCellMoments, Shape, shape::Linear>>;

 public:
  SemiImplicit(const scene::Scene& s, const State<Dim>& state)
      : double_point_(s.formulation == scene::Formulation::semi_implicit_double_point),
        grid_(make_grid<Dim>(s, Shape::degree, Shape::bspline)),
        bcs_solid_(s, grid_, state.surfaces),
        bcs_fluid_(GridBoundary<Dim>::fluid(s, grid_, state.surfaces)),
        // A prescribed pore pressure is the Dirichlet value of the pressure equation on its face
        // (face_pressure_); the strong gradient G p of the pressure forces holds its boundary term,
        // so it is no load here (docs/formulations.md, "Prescribed pore pressure").
        loads_(s, grid_, state.solid, state.surfaces, /*pore_pressure_forces=*/false),
        flip_(s.solver.flip),
        damping_(s.solver.damping),
        scene_damping_(s.solver.damping),
        materials_(make_materials<Dim>(s)),
        material_particles_(group_by_material(state.solid, s.materials.size())),
        poisson_(grid_),
        fbar_(s, grid_) {
    conservative_ = s.solver.continuity != "non-conservative";  // "" (unset): this formulation's default
    remove_escaped_ = double_point_ && s.solver.escaped_water == "remove";
    implicit_drag_ = s.solver.drag_integration != "semi-implicit";  // "" (unset): the default, implicit
    const auto& st = s.solver.stabilisation;
    if (st.pressure == "node-remap") remap_ = Remap::node;
    else if (st.pressure == "mfvp-linear") remap_ = Remap::linear;
    else if (st.pressure == "none") remap_ = Remap::none;
    else
      throw std::runtime_error("solver.stabilisation.pressure: \"" + st.pressure + "\" is not available in " + name() +
                               " (available: node-remap, mfvp-linear, none)");
    if constexpr (Shape::bspline) {
      // One point per cell and axis under-integrates the B-spline supports (3 or 4 cells wide):
      // B1 diverges within 4-9 steps at every cell size, both variants (bench/results/
      // speed-vs-error-b1-*-2026-12-01.md). Two or more points per cell work.
      const ParticleSet<Dim>& sp = state.solid;
      for (std::size_t p = 0; p < sp.size(); ++p)
        if (2.0 * sp.l[p].maxCoeff() > 0.75 * s.grid.cell_size)
          throw std::runtime_error("bodies/" + std::to_string(sp.body[p]) + "/particles_per_cell: 1 point per cell "
                                   "and axis is not available with " + scene::to_string(s.grid.shape_function) +
                                   " in " + name() + " (it diverges within 10 steps); use 2 or more, or gimp");
    }
    if (!state.solid.two_phase())
      throw std::runtime_error(name() + " needs saturated soil points (porosity in particles/solid.vtu): run swmpm "
                               "preprocess with a body that has a solid and a fluid");
    if (double_point_ && state.fluid.size() == 0)
      throw std::runtime_error(name() + " needs water points (particles/fluid.vtu): run swmpm preprocess again");
    for (std::size_t i = 0; i < s.boundaries.size(); ++i) {
      const auto& b = s.boundaries[i];
      if (!b.fluid || *b.fluid != scene::FluidBc::pressure) continue;
      const std::string where = "boundaries/" + std::to_string(i) + "/fluid";
      const int f = scene::grid_face_index(b.on);
      if (f < 0)
        throw std::runtime_error(where + ": a prescribed pore pressure on a named surface is not implemented in " +
                                 name() + " yet (grid faces only)");
      // The value acts through the face's nodes that carry water: some water must reach the face.
      const ParticleSet<Dim>& wet = double_point_ ? state.fluid : state.solid;
      bool reaches = false;
      for (std::size_t p = 0; p < wet.size() && !reaches; ++p) reaches = domain_ends_on_face(grid_, f, wet.x[p], wet.l[p]);
      if (!reaches)
        throw std::runtime_error(where + ": no water lies on \"" + b.on +
                                 "\", so the prescribed pore pressure would act on nothing");
    }
    // Per grid face: drained (p prescribed, 0 or the face's value) unless the water cannot cross it.
    face_pressure_.fill(0.0);
    face_drained_.fill(true);
    for (const auto& f : bcs_fluid_.faces()) face_drained_[2 * f.axis + f.side] = false;
    for (const auto& b : s.boundaries)
      if (b.fluid && *b.fluid == scene::FluidBc::pressure) face_pressure_[scene::grid_face_index(b.on)] = b.fluid_value;

    perm_.resize(s.materials.size());
    for (std::size_t k = 0; k < s.materials.size(); ++k) {
      const auto& m = s.materials[k];
      if (m.model == scene::MaterialModel::fluid) continue;
      perm_[k].k0 = m.has("hydraulic_conductivity") ? m.at("hydraulic_conductivity") : 0.0;
      perm_[k].law = m.permeability_law == "kozeny-carman" ? Permeability::Law::kozeny_carman
                     : m.permeability_law == "xie-leo"     ? Permeability::Law::xie_leo
                                                           : Permeability::Law::constant;
    }
    const ParticleSet<Dim>& ps = state.solid;
    fluid_of_material_.assign(s.materials.size(), -1);
    for (std::size_t p = 0; p < ps.size(); ++p) {
      const int fm = fluid_material_of(s, ps, static_cast<int>(p));
      if (fm < 0) continue;
      const auto& f = s.materials[fm];
      auto& pm = perm_[ps.material[p]];
      fluid_of_material_[ps.material[p]] = fm;
      pm.rho_w = f.at("density");
      if (pm.k0 == 0.0 && s.materials[ps.material[p]].has("intrinsic_permeability"))
        pm.k0 = s.materials[ps.material[p]].at("intrinsic_permeability") * pm.rho_w * g_earth / f.at("dynamic_viscosity");
      if (!(pm.k0 > 0.0))
        throw std::runtime_error("material \"" + s.materials[ps.material[p]].name +
                                 "\": a saturated skeleton needs hydraulic_conductivity or intrinsic_permeability");
    }
    if (double_point_) {
      rho_w_points_.resize(s.materials.size(), 0.0);
      for (std::size_t k = 0; k < s.materials.size(); ++k)
        if (s.materials[k].model == scene::MaterialModel::fluid) rho_w_points_[k] = s.materials[k].at("density");
    }
    const std::size_t nodes = grid_.num_nodes();
    soil_.resize(nodes);
    water_.resize(nodes);
    node_.assign(nodes, NodeExtra{});
    if (double_point_) water_sums_.assign(nodes, WaterSums{});
    extent_.assign(nodes, Extent{});
    support_.resize(nodes);
    p_node_.assign(nodes, 0.0);
    A_soil_.assign(nodes, Vec<Dim>::Zero());
    A_water_.assign(nodes, Vec<Dim>::Zero());
    for (std::size_t i = 0; i < nodes; ++i) support_[i] = basis_integral(i);
    D_solid_.assign(nodes * KD, Vec<Dim>::Zero());
    D_water_.assign(nodes * KD, Vec<Dim>::Zero());
    if constexpr (kCellMoments) {
      moments_ = std::make_unique<Moments>(grid_);
      double rho_s = 0.0, rho_w = 0.0;
      if (single_densities(state, rho_s, rho_w)) moments_->derive_laplace(rho_s, rho_w);
    }
    d_steps_ = DSt::steps(grid_.nodes_per_axis());
  }

  std::string name() const override {
    return double_point_ ? "semi-implicit-double-point" : "semi-implicit-single-point";
  }

  /// Whether every soil point has the same grain density m / ((1 - n) V) (to 1e-12) and all the
  /// water the same density: then the L weight of every point is (1 - n) V / rho_s + n V / rho_w
  /// (soil_weights, water_weights), a fixed combination of the D^s and D^w weights
  /// (CellMoments::derive_laplace). Both are constant in a run (incompressible constituents).
  bool single_densities(const State<Dim>& st, double& rho_s, double& rho_w) const {
    const ParticleSet<Dim>& ps = st.solid;
    const ParticleSet<Dim>& ws = double_point_ ? st.fluid : st.solid;
    if (ps.size() == 0 || ws.size() == 0) return false;
    // Every value positive, finite and within 1e-12 of the first.
    auto one_value = [](std::size_t n, auto&& value_of, double& first) {
      first = value_of(0);
      for (std::size_t p = 0; p < n; ++p) {
        const double v = value_of(p);
        if (!(v > 0.0) || !std::isfinite(v) || std::abs(v - first) > 1e-12 * first) return false;
      }
      return true;
    };
    return one_value(ps.size(), [&](std::size_t p) { return grain_density(ps, static_cast<int>(p)); }, rho_s) &&
           one_value(ws.size(), [&](std::size_t p) { return water_density(ws, static_cast<int>(p)); }, rho_w);
  }

  void step(State<Dim>& st, const StepContext& ctx) override {
    // The nodal data of the last step are overwritten below: output fields not filled by now stay
    // as they are (a failed step leaves them; a completed one marks them stale again).
    output_fields_stale_ = water_output_stale_ = false;
    ParticleSet<Dim>& ps = st.solid;
    ParticleSet<Dim>& ws = double_point_ ? st.fluid : st.solid;
    const double dt = ctx.dt;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    double t0 = omp_get_wtime();
    auto lap = [&](const char* stage) {
      const double t1 = omp_get_wtime();
      this->times_.add(stage, t1 - t0);
      t0 = t1;
    };

    bool reordered = reorder_for_locality(st, schedule_, reorder_, material_particles_, reorder_interval);
    if (double_point_ && st.step % reorder_interval == 0 && wschedule_.order().size() == ws.size() &&
        !wschedule_.in_order()) {
      wreorder_.apply(ws, wschedule_.order());
      reordered = true;
    }
    if (reordered) lap("reorder");                                                          // (0)

    long bad = -1;                                                                          // (1)
    box_ = transfer::evaluate_shapes<Shape>(grid_, ps, sd_, bad);
    if (bad >= 0) st.health.report(bad, "solid", "left the grid (or position not finite)");
    if (double_point_) {
      // With the cell moments the water points take no gradient (P2G, moments, G2P, projection:
      // weights only); the point-wise D^w and L need them.
      const NodeBox<Dim> wbox = transfer::evaluate_shapes<Shape>(grid_, ws, sdw_, bad);
      if (bad >= 0) st.health.report(bad, "fluid", "water point left the grid (or position not finite)");
      for (int a = 0; a < Dim; ++a) {
        box_.lo[a] = std::min(box_.lo[a], wbox.lo[a]);
        box_.hi[a] = std::max(box_.hi[a], wbox.hi[a]);
      }
      transfer::build_schedule(grid_, sdw_, wschedule_);
    }
    collect_face_forces<Shape>(grid_, loads_, ps, st.index_of_id, ctx.t, box_, face_forces_);
    transfer::build_schedule(grid_, sd_, schedule_);
    clear_nodes();
    lap("shape functions");

    scatter_soil(ps);                                                                       // (2)
    nodal_porosity();
    if (double_point_) {
      bad = scatter_water_points(ws);
      if (bad >= 0) st.health.report(bad, "fluid", "water-point porosity outside (0, 1]");
    }
    for (const auto& ff : face_forces_)  // tractions on the soil (no pore-pressure loads: see loads_)
      for_each_loaded_node(
          grid_, ff, [&](std::size_t i) { return soil_.acc[i].m > transfer::empty_node_mass; },
          [&](std::size_t i, double N) { soil_.acc[i].f += N * ff.f; });
    lap("p2g");

    assemble_pressure(ps, ws);                                                              // (5a)-(5b)
    lap("pressure assembly");

    predict(dt, b);                                                                         // (3)-(4)
    lap("predictor");

    if (!solve_pressure(dt)) {                                                              // (5c)
      st.health.report(0, "fluid",
                       "pressure Poisson system not positive definite (water touching no drained node or free "
                       "surface has an undetermined pressure)");
      return;
    }
    lap("pressure solve");

    correct(ps, ws, dt);                                                                    // (6)
    bad = update_pressure(ws);
    if (bad >= 0) st.health.report(bad, double_point_ ? "fluid" : "solid", "pore pressure not finite");
    lap("correction");

    gather(ps, dt);                                                                         // (7)
    lap("g2p + musl remap");

    bad = update_soil(ps, dt);                                                              // (8)
    if (bad >= 0) st.health.report(bad, "solid", "volume ratio J <= 0 or porosity outside (0, 1)");
    fbar_.apply(grid_, box_, schedule_, sd_, dt, st, materials_, material_particles_);  // (9)(b)-(g), transfer/fbar.hpp
    if (double_point_) update_water_points(ws, dt);
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const long m_bad = materials_[k]->update_stress(ps, material_particles_[k], dt);
      if (m_bad >= 0) st.health.report(m_bad, "solid", "stress update failed (" + materials_[k]->name() + ")");
    }
    if (tie_) tie_water_points(st);
    else if (remove_escaped_) remove_escaped_water(ws);
    lap("stress and porosity");
  }

  double critical_time_step(const State<Dim>& st, std::string& reason) const override {
    // Soil CFL only: the pressure is implicit (incompressible constituents) and the drag
    // semi-implicit, so neither the water's compressibility nor k limits dt. The skeleton's P-wave
    // carries the pore water with it (saturated density).
    const ParticleSet<Dim>& ps = st.solid;
    double c_max = 0.0;
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const double M = materials_[k]->max_p_wave_modulus(ps, material_particles_[k]);
      for (int p : material_particles_[k]) {
        const double rho_sat = (ps.m[p] + ps.n[p] * perm_[k].rho_w * ps.V[p]) / ps.V[p];
        c_max = std::max(c_max, std::sqrt(M / rho_sat));
      }
    }
    double v_max = 0.0;
    for (const ParticleSet<Dim>* set : {&st.solid, &st.fluid}) {
      const long n = static_cast<long>(set->size());
#pragma omp parallel for reduction(max : v_max) if (n > parallel_threshold)
      for (long p = 0; p < n; ++p) v_max = std::max(v_max, set->v[p].norm());
    }
    std::ostringstream os;
    os << "soil P-wave CFL (c = " << c_max << " m/s with the saturated density, |v|max = " << v_max
       << " m/s); the pore pressure is implicit and the drag " << (implicit_drag_ ? "implicit" : "semi-implicit")
       << ", so neither K_w nor k limits dt";
    reason = os.str();
    return grid_.h() / (c_max + v_max);
  }

  double kinetic_energy(const State<Dim>& st) const override {
    const auto& ps = st.solid;
    if (double_point_) {
      const auto& ws = st.fluid;
      return fixed_order_sum(ps.size(), [&](std::size_t p) { return 0.5 * ps.m[p] * ps.v[p].squaredNorm(); }) +
             fixed_order_sum(ws.size(), [&](std::size_t p) { return 0.5 * ws.m[p] * ws.v[p].squaredNorm(); });
    }
    return fixed_order_sum(ps.size(), [&](std::size_t p) {
      return 0.5 * (ps.m[p] * ps.v[p].squaredNorm() + ps.m_f[p] * ps.v_f[p].squaredNorm());
    });
  }
  /// The skeleton's stored energy; incompressible water stores none.
  double strain_energy(const State<Dim>& st) const override {
    const auto& ps = st.solid;
    return fixed_order_sum(ps.size(), [&](std::size_t p) {
      return materials_[ps.material[p]]->strain_energy(ps, static_cast<int>(p));
    });
  }
  double external_power(const State<Dim>& st, const StepContext& ctx) const override {
    const ParticleSet<Dim>& ps = st.solid;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    double power = 0.0;
    if (double_point_) {
      power = fixed_order_sum(ps.size(), [&](std::size_t p) { return b.dot(ps.m[p] * ps.v[p]); }) +
              fixed_order_sum(st.fluid.size(), [&](std::size_t p) { return b.dot(st.fluid.m[p] * st.fluid.v[p]); });
    } else {
      power = fixed_order_sum(ps.size(), [&](std::size_t p) { return b.dot(ps.m[p] * ps.v[p] + ps.m_f[p] * ps.v_f[p]); });
    }
    loads_.for_each_force(ctx.t, st.index_of_id, [&](int p, const Vec<Dim>& f_p, const Vec<Dim>&, bool) {
      power += f_p.dot(ps.v[p]);  // tractions act on the soil (no pore-pressure loads: see loads_)
    });
    return power + pore_pressure_power();
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
      if (!face_drained_[f] || face_pressure_[f] == 0.0) continue;
      const int axis = f / 2, j = f % 2 == 0 ? 0 : nn[axis] - 1;
      const double outward = f % 2 == 0 ? -1.0 : 1.0;
      NodeBox<Dim> face = box_;
      face.lo[axis] = face.hi[axis] = j;
      if (face.empty() || box_.lo[axis] > j || box_.hi[axis] < j) continue;
      grid_.for_each_node(face, [&](std::size_t i, const auto&) {  // serial: fixed summation order
        if (!(water_.acc[i].m > transfer::empty_node_mass)) return;
        const double n = node_[i].n;
        const double qn = (1.0 - n) * soil_.v[i][axis] + n * water_.v[i][axis];
        power -= face_pressure_[f] * outward * qn * basis_integral(i, axis);
      });
    }
    return power;
  }
  void set_initialisation(State<Dim>& st, const scene::Initialisation* phase) override {
    set_plastic(materials_, phase == nullptr || phase->plasticity);
    damping_ = phase_damping(phase, scene_damping_);
    if (scene_perm_.empty()) scene_perm_ = perm_;
    perm_ = scene_perm_;
    if (phase && phase->hydraulic_conductivity) {
      for (auto& pm : perm_) {
        pm.k0 = *phase->hydraulic_conductivity;
        pm.law = Permeability::Law::constant;
      }
      fast_drainage_ = true;
    }
    if (phase == nullptr && fast_drainage_) {
      // The phase's seepage velocities belong to its permeability, not the scene's (the pressure
      // field of steady seepage does not depend on k, the flow is proportional to it): the pore
      // water restarts at the soil's velocity and the drag brings it to the scene's Darcy flow
      // within k / (n g).
      if (!partner_.empty()) restart_water_with_soil(st);
      if (!double_point_) st.solid.v_f = st.solid.v;
      fast_drainage_ = false;
    }
    tie_ = double_point_ && phase && phase->tie_water;
    if ((tie_ || (double_point_ && phase && phase->hydraulic_conductivity)) && partner_.empty())
      partner_ = coincident_soil_points(st);
  }
  std::size_t active_cells(const State<Dim>& st) const override { return count_active_cells(grid_, st.solid); }
  // Restart: what a step carries to the next beyond the particles — the schedule orders the next
  // reordering reads, the pressure solver's equations and reused factor, the initialisation's
  // water-point partners, and the escaped-water totals. The output-only fields are complete in a
  // checkpoint (the loop completes them first), so nothing is stale after a restore.
  void save(Checkpoint& c) const override {
    save_order(c, "formulation/schedule_order", schedule_);
    save_order(c, "formulation/water_schedule_order", wschedule_);
    c.put("formulation/partner", partner_);
    c.header["formulation_state"] = {{"escaped_points", escaped_points_}, {"escaped_mass", escaped_mass_}};
    poisson_.save(c, "formulation/poisson");
  }
  void restore(const Checkpoint& c, State<Dim>& st) override {
    regroup_by_material(st.solid, material_particles_);  // the checkpoint's particle order
    restore_order(c, "formulation/schedule_order", schedule_);
    restore_order(c, "formulation/water_schedule_order", wschedule_);
    c.get("formulation/partner", partner_);
    escaped_points_ = c.header.at("formulation_state").at("escaped_points");
    escaped_mass_ = c.header.at("formulation_state").at("escaped_mass");
    output_fields_stale_ = water_output_stale_ = false;
    poisson_.restore(c, "formulation/poisson");
  }

 private:
  enum class Remap { none, node, linear };

  /// Double-point water P2G sums of one node in register pairs: {sum S m, sum S rho_w V} and, in
  /// 2D, sum S m v (3D: water_.acc's mv), one packed multiply-add each per point and node; copied
  /// into water_.acc and node_ after the pass. (With sum S m v as an Eigen vector here instead:
  /// 18 more instructions per point-step, callgrind B4 6².)
  struct WaterSums {
    Pair m_raw{0.0, 0.0};
    Pair mv{0.0, 0.0};
  };

  /// Per-node quantities besides the two phases' momenta and forces.
  struct NodeExtra {
    double mn = 0.0;        // sum S m_s n (nodal porosity x M_s, eq. 46)
    double mk = 0.0;        // sum S m_s k (eq. 47)
    double w_raw = 0.0;     // double-point: sum S rho_w V (M_w = n_I w_raw, eq. 50)
    double n = 1.0, k = 0.0;            // nodal porosity and conductivity
    double soil_volume = 0.0;           // sum S V of the soil points (only with escaped_water = remove)
    double drag = 0.0;                  // Q_I dt (kg)
  };

  static int fluid_material_of(const scene::Scene& s, const ParticleSet<Dim>& ps, int p) {
    if (!ps.fluid_material.empty() && ps.fluid_material[p] >= 0) return ps.fluid_material[p];
    const auto& body = s.bodies[ps.body[p]];
    return body.fluid.empty() ? -1 : static_cast<int>(s.material_index(body.fluid));
  }

  /// Integral of node i's basis function over the grid [m^Dim]: linear/GIMP h (h/2 on a grid
  /// face); clamped B-splines of degree q (t_{i+q+1} - t_i) / (q + 1) from the open knot vector.
  /// except_axis >= 0: over the grid face normal to that axis [m^(Dim-1)] (the other axes' factors).
  double basis_integral(std::size_t i, int except_axis = -1) const {
    double v = 1.0;
    for (int a = 0; a < Dim; ++a) {
      const auto& ax = grid_.axis(a);
      const int j = static_cast<int>(i % static_cast<std::size_t>(ax.nodes));
      i /= static_cast<std::size_t>(ax.nodes);
      if (a == except_axis) continue;
      if constexpr (Shape::bspline) {
        const int q = Shape::degree;
        auto knot = [&](int t) { return std::clamp(t - q, 0, ax.cells) * ax.h; };
        v *= (knot(j + q + 1) - knot(j)) / (q + 1);
      } else {
        v *= (j == 0 || j == ax.nodes - 1) ? 0.5 * ax.h : ax.h;
      }
    }
    return v;
  }

  void clear_nodes() {
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      soil_.acc[i] = {Vec<Dim>::Zero(), Vec<Dim>::Zero(), 0.0};
      water_.acc[i] = {Vec<Dim>::Zero(), Vec<Dim>::Zero(), 0.0};
      node_[i] = NodeExtra{};
      extent_[i] = Extent{};
    });
  }

  /// Extent of the water: min / max of x -/+ l per axis (the points' domains) over water points,
  /// for the free surface (surface_cut). kBaseExtent: every node of a point's support has S > 0
  /// (off the cell faces), so the points are collected per first node of their support (base)
  /// and a node's extent is the union over the bases whose supports hold it (water_extent): one
  /// update per point instead of one per node. Otherwise (GIMP: a far node's S may vanish) per
  /// node over its points with S > 0.
  static constexpr bool kBaseExtent = Shape::bspline || std::is_same_v<Shape, shape::Linear>;
  struct Extent {
    Vec<Dim> lo = Vec<Dim>::Constant(std::numeric_limits<double>::infinity());
    Vec<Dim> hi = Vec<Dim>::Constant(-std::numeric_limits<double>::infinity());
    void add(const Vec<Dim>& x_lo, const Vec<Dim>& x_hi) {
      lo = lo.cwiseMin(x_lo);
      hi = hi.cwiseMax(x_hi);
    }
  };
  /// A water point's domain [x_lo, x_hi] = [x - l, x + l] joins the extent (through the scatter
  /// schedule): kBaseExtent at its support's first node, here; otherwise at each node with
  /// S > 0, in the P2G's node loop (add_node_extent).
  template <bool G>
  void add_base_extent(const shape::ShapeData<Dim, S, G>& sd, const Vec<Dim>& x_lo, const Vec<Dim>& x_hi) {
    if constexpr (kBaseExtent) extent_[grid_.index(sd.base)].add(x_lo, x_hi);
  }
  void add_node_extent(std::size_t i, double N, const Vec<Dim>& x_lo, const Vec<Dim>& x_hi) {
    if constexpr (!kBaseExtent)
      if (N > 0.0) extent_[i].add(x_lo, x_hi);
  }
  /// The extent of the water inside node i's support.
  Extent water_extent(std::size_t i, const std::array<int, Dim>& ijk) const {
    if constexpr (!kBaseExtent) {
      return extent_[i];
    } else {
      // Bases b with b <= ijk <= b + S - 1 per axis, inside this step's box (cleared entries).
      std::array<int, Dim> lo, n;
      for (int a = 0; a < Dim; ++a) {
        lo[a] = std::max(ijk[a] - (S - 1), box_.lo[a]);
        n[a] = ijk[a] - lo[a] + 1;
      }
      Extent e;
      std::array<int, Dim> b = lo;
      for (;;) {
        const Extent& c = extent_[grid_.index(b)];
        e.add(c.lo, c.hi);
        int a = 0;
        for (; a < Dim; ++a) {
          if (++b[a] < lo[a] + n[a]) break;
          b[a] = lo[a];
        }
        if (a == Dim) break;
      }
      return e;
    }
  }

  /// (2) Soil points: M_s, M_s v_s, sum S m n, sum S m k (eqs. 44-47) and the soil's internal force
  ///   f_s = -sum_sp V sigma' . grad S   (the body force sum S m_s b = M_s b is added at the node, (3)),
  /// and, single-point, the water carried on the same points (and its extent, free surface):
  ///   M_w = sum S m_f, M_w v_w = sum S m_f v_f (body force M_w b at the node).
  /// The pressure forces (-n grad p on the water, -(1 - n) grad p on the soil: eqs. 55-57 with
  /// p_w = -p) are added at the nodes by the predictor, from the nodal p^t.
  void scatter_soil(const ParticleSet<Dim>& ps) {
    const bool sp = !double_point_;
    const bool track_soil_volume = remove_escaped_;  // for remove_escaped_water
    const bool laplace_derived = kCellMoments && moments_->laplace_derived();
    schedule_.run([&](int p) __attribute__((always_inline)) {
      const double V = ps.V[p], n = ps.n[p], m = ps.m[p];
      const double n0 = 1.0 - (1.0 - n) * V / ps.V0[p];
      const double k = perm_[ps.material[p]].at(n, n0);
      const Mat3 sig = to_matrix(ps.sigma[p]);
      const MatD<Dim> A = V * sig.template topLeftCorner<Dim, Dim>();
      const Vec<Dim> mv = m * ps.v[p];
      const double mf = sp ? ps.m_f[p] : 0.0;
      const Vec<Dim> mfv = sp ? Vec<Dim>(mf * ps.v_f[p]) : Vec<Dim>::Zero();
      const bool wet = sp && mf > 0.0;  // carries water: joins the free surface's extent
      const Vec<Dim> x_lo = ps.x[p] - ps.l[p], x_hi = ps.x[p] + ps.l[p];
      if (wet) add_base_extent(sd_[p], x_lo, x_hi);
      if constexpr (kCellMoments) {  // (5a)'s moments in the same pass (assemble_operators_from_moments)
        const Weights c = soil_weights(ps, p, laplace_derived);
        if (sp) moments_->template add<true, true>(grid_, sd_[p].base, ps.x[p], c.s, c.w, c.l);
        else moments_->template add<true, false>(grid_, sd_[p].base, ps.x[p], c.s, 0.0, c.l);
      }
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>& dN) {
        auto& s = soil_.acc[i];
        s.m += N * m;
        s.mv += N * mv;
        s.f -= A * dN;
        auto& e = node_[i];
        e.mn += N * m * n;
        e.mk += N * m * k;
        if (track_soil_volume) e.soil_volume += N * V;
        if (sp) {
          auto& w = water_.acc[i];
          w.m += N * mf;
          w.mv += N * mfv;
          if (wet) add_node_extent(i, N, x_lo, x_hi);
        }
      });
    });
  }

  /// (2) Nodal porosity and conductivity of the soil, n_I = sum S m n / M_s and k_I = sum S m k /
  /// M_s (eqs. 46-47; 1 and 0 where no soil), for the water points' P2G, the drag and the
  /// continuity.
  void nodal_porosity() {
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      auto& e = node_[i];
      const double Ms = soil_.acc[i].m;
      e.n = porosity_at_node(e.mn, Ms);
      e.k = Ms > transfer::empty_node_mass ? e.mk / Ms : 0.0;
    });
  }
  /// n_I = sum S m n / M_s of the soil at a node, 1 where there is none (eq. 46, step 8h erratum).
  static double porosity_at_node(double mn, double Ms) { return Ms > transfer::empty_node_mass ? mn / Ms : 1.0; }
  /// A water point's porosity n_p and volume V = m / (n_p rho_w) (eq. 36: n V = n0 V0); returns V.
  double set_water_porosity(ParticleSet<Dim>& ws, std::size_t p, double np) const {
    ws.n[p] = np;
    return ws.V[p] = ws.m[p] / (np * rho_w_points_[ws.material[p]]);
  }

  /// (2) Water points (double-point, eqs. 50-51, 56), in one pass per point:
  ///   (8h)-(8i) of the previous step: the porosity at the point, n_p = sum S n_I (n_I of this
  ///   step's soil points, nodal_porosity()), and its volume V = m / (n_p rho_w) (eq. 36:
  ///   n V = n0 V0);
  ///   P2G: sum S rho_w V, sum S m v, sum S m (the velocity weights of eq. 51), from which the node
  ///   pass forms M_w and the body force n_I (sum S rho_w V) b; the points' extent for the free
  ///   surface (add_base_extent, add_node_extent).
  /// The seed maps the soil's porosity with the shape functions of the step that updated it
  /// (step 8h); here the next step's soil P2G maps it, with the points where they now are, and no
  /// pass of its own (docs/formulations.md, "Water points' porosity"). Returns the first point
  /// whose porosity is outside (0, 1], or -1.
  long scatter_water_points(ParticleSet<Dim>& ws) {
    const bool laplace_derived = kCellMoments && moments_->laplace_derived();
    long bad = transfer::no_particle;
    wschedule_.run([&](int p) __attribute__((always_inline)) {
      double np = 0.0;
      shape::for_each_node(grid_, sdw_[p], [&](std::size_t i, double N, const auto&) { np += N * node_[i].n; });
      if (!(np > 0.0 && np <= 1.0 + 1e-12)) {
#pragma omp critical(swmpm_water_porosity)
        bad = std::min(bad, static_cast<long>(p));
      }
      const double m = ws.m[p], rhoV = rho_w_points_[ws.material[p]] * set_water_porosity(ws, p, np);
      const Vec<Dim> mv = m * ws.v[p];
      const Vec<Dim> x_lo = ws.x[p] - ws.l[p], x_hi = ws.x[p] + ws.l[p];
      add_base_extent(sdw_[p], x_lo, x_hi);
      if constexpr (kCellMoments) {
        const Weights c = water_weights(ws, p, laplace_derived);
        moments_->template add<false, true>(grid_, sdw_[p].base, ws.x[p], 0.0, c.w, c.l);
      }
      const Pair m_rhoV{m, rhoV}, mv_pair{mv[0], mv[1]};
      shape::for_each_node(grid_, sdw_[p], [&](std::size_t i, double N, const auto&) {
        WaterSums& w = water_sums_[i];
        w.m_raw += N * m_rhoV;
        if constexpr (Dim == 2) w.mv += N * mv_pair;
        else water_.acc[i].mv += N * mv;
        add_node_extent(i, N, x_lo, x_hi);
      });
    });
    // Into the node fields the rest of the step reads (and zero for the next step's points).
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      WaterSums& w = water_sums_[i];
      auto& a = water_.acc[i];
      a.m = w.m_raw[0];
      if constexpr (Dim == 2) a.mv = Vec<Dim>(w.mv[0], w.mv[1]);
      node_[i].w_raw = w.m_raw[1];
      w = WaterSums{};
    });
    return bad == transfer::no_particle ? -1 : bad;
  }

  /// (3)-(4) per node, with v^t = M v / M and Q = g n M_w / k (eq. 58), a = dt Q,
  /// A_w = M_w v_w^t + dt (f_w - G^w p^t), A_s = M_s v_s^t + dt (f_s - G^s p^t):
  ///   semi-implicit (seed 001 eqs. 52-53): (M_w + a) v_w* = A_w + a v_s^t,
  ///                                        M_s v_s* = A_s + a (v_w* - v_s^t);
  ///   implicit (default):  (M_w + a) v_w* - a v_s* = A_w,  (M_s + a) v_s* - a v_w* = A_s,
  ///     det = M_w M_s + a (M_w + M_s), v_w* = ((M_s + a) A_w + a A_s) / det,
  ///     v_s* = ((M_w + a) A_s + a A_w) / det.
  /// Both conserve the mixture's momentum. Without forces the seed's form maps the relative velocity
  /// r = v_w - v_s to r M_w (1 - a / M_s) / (M_w + a), |.| -> M_w / M_s for a stiff drag: it
  /// diverges at nodes with much more water than soil (free water over soil, a seepage exit);
  /// the implicit form maps r to r / (1 + a / M_w + a / M_s) (docs/formulations.md, "Implicit drag").
  /// Then the velocity boundary conditions of each phase on v*. The pressure force is the strong
  /// form -sum_p c V S_K grad p^t(x_p) of the nodal p^t (eqs. 55, 57 integrated by parts), i.e.
  /// the operator G of the corrections (6): see docs/formulations.md, "B-splines", for why the
  /// weak form sum_p c V p_p grad S_K of the paper is unstable with B-splines.
  void predict(double dt, const Vec<Dim>& b) {
    const double alpha = damping_;
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto& ijk) {
      auto& s = soil_.acc[i];
      auto& w = water_.acc[i];
      auto& e = node_[i];
      const bool has_s = s.m > transfer::empty_node_mass;
      Vec<Dim> vw = Vec<Dim>::Zero();
      if (double_point_) {
        vw = w.m > transfer::empty_node_mass ? Vec<Dim>(w.mv / w.m) : Vec<Dim>::Zero();
        // M_w = n_I sum S rho_w V (eq. 50); its body force M_w b (eq. 56) below (w.f is zero here:
        // no load acts on the water).
        w.m = e.n * e.w_raw;
      } else if (w.m > transfer::empty_node_mass) {
        vw = w.mv / w.m;
      }
      s.f += s.m * b;  // body forces sum S m b = M b of both phases (eqs. 55-56)
      w.f += w.m * b;
      add_pressure_force(i, ijk, p_node_, s.f, w.f);  // -G p^t: eqs. 55, 57 in the strong form
      const bool has_w = w.m > transfer::empty_node_mass;
      const Vec<Dim> vs = has_s ? Vec<Dim>(s.mv / s.m) : Vec<Dim>::Zero();
      soil_.vL[i] = vs;
      water_.vL[i] = vw;
      e.drag = has_s && has_w && e.k > 0.0 ? dt * g_earth * e.n * w.m / e.k : 0.0;  // Q dt
      const Vec<Dim> fs = local_damping<Dim>(s.f, vs, alpha);
      if (implicit_drag_ && e.drag > 0.0) {
        const double a = e.drag, det = w.m * s.m + a * (w.m + s.m);
        const Vec<Dim> Aw = w.m * vw + dt * w.f, As = s.m * vs + dt * fs;
        water_.v[i] = ((s.m + a) * Aw + a * As) / det;
        soil_.v[i] = ((w.m + a) * As + a * Aw) / det;
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

  /// (5) eqs. 60-63 in swmpm's signs (docs/formulations.md):
  ///   dt sum_J L_IJ dp_J = -(D^s v_s* + D^w v_w*)_I
  ///   D^s_IK = sum_sp (1 - n) V S_I grad S_K,  D^w_IK = sum_wp n V S_I grad S_K   (eqs. 62-63)
  ///   L_IJ = sum_p V c_p grad S_I . grad S_J,  c = (1 - n)/rho_s (soil points) + n/rho_w (water)
  /// (eq. 61 with c inside the quadrature: L symmetric, CHOLMOD). The pressure forces of (3)-(4)
  /// and the corrections (6) use G = D read as (velocity node, pressure node): the strong
  /// gradient of eq. 67-68. The exact projection D M^-1 D^T in place of L was tried (with the
  /// weak gradient D^T): stable, but its two-cell stencil decouples the pressure (Terzaghi on
  /// GIMP 30 % RMS error instead of 0.09 %).
  /// Prescribed nodes: grid faces the water drains through (p = 0, or the face's value) and the
  /// free surface (free_surface()); dp_D = p_D - p^t(x_D), with p^t at the node from the linear
  /// projection of the points' pressures (exact for a hydrostatic field).
  void assemble_pressure(const ParticleSet<Dim>& ps, const ParticleSet<Dim>& ws) {
    auto fit = [&](const auto& sdw, const StripeSchedule& wsched) {
      linear_.fit(grid_, box_, wsched, sdw, ws.x, [&](int p) { return ws.V[p]; }, [&](int p) { return ws.p[p]; });
    };
    if (double_point_) fit(sdw_, wschedule_);
    else fit(sd_, schedule_);
    // A node whose water lies in a strip of its support (free surface) has an ill-posed linear fit
    // (leverage > NodeProjection::kMaxLeverage): it takes the gradient of the nearest well-posed node inward
    // along its cut and fits only its value (docs/formulations.md, "Free-surface nodes whose fit
    // is ill-posed"). Reads well-posed nodes only, writes its own: independent of the node order.
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto& ijk) {
      if (!linear_.has(i) || linear_.well_posed(i)) return;
      const std::size_t src = inward_well_posed(i, ijk);
      if (src != i) linear_.impose_gradient(grid_, i, linear_.gradient_at_node(grid_, src));
    });
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) { p_node_[i] = linear_.at_node(i); });
    poisson_.clear(grid_, box_);
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      std::fill_n(D_solid_.data() + i * KD, KD, Vec<Dim>::Zero());
      std::fill_n(D_water_.data() + i * KD, KD, Vec<Dim>::Zero());
    });
    const auto& nn = grid_.nodes_per_axis();
    grid_.for_each_node(box_, [&](std::size_t i, const auto& ijk) {
      if (!(water_.acc[i].m > transfer::empty_node_mass)) return;
      // A node on several drained faces (a corner) takes a `pressure` face's value over p = 0,
      // whatever the order of the boundaries; of two `pressure` faces the first in x, y, z order.
      int face = -1;
      for (int a = 0; a < Dim; ++a)
        for (int side = 0; side < 2; ++side) {
          const int f = 2 * a + side;
          if (ijk[a] != (side ? nn[a] - 1 : 0) || !face_drained_[f]) continue;
          if (face < 0 || (face_pressure_[face] == 0.0 && face_pressure_[f] != 0.0)) face = f;
        }
      double p_surface = 0.0;
      const bool surface = face < 0 && free_surface(i, ijk, p_surface);
      if (face >= 0 || surface) {
        const double p_bar = face >= 0 ? face_pressure_[face] : p_surface;
        poisson_.prescribe(i, p_bar - p_node_[i]);
      } else {
        poisson_.set_unknown(i);
      }
    });
    // Soil points: D^s; single-point also D^w from the same points.
    if constexpr (kCellMoments) {
      assemble_operators_from_moments();
    } else {
      schedule_.run([&](int p) {
        const Weights c = soil_weights(ps, p);
        if (double_point_) scatter_operators<true, false>(sd_[p], c.s, 0.0, c.l);
        else scatter_operators<true, true>(sd_[p], c.s, c.w, c.l);
      });
      if (double_point_)
        wschedule_.run([&](int p) {
          const Weights c = water_weights(ws, p);
          scatter_operators<false, true>(sdw_[p], 0.0, c.w, c.l);
        });
    }
  }

  /// A point's weights in the operators of (5a): D^s gets s = (1 - n) V, D^w gets w = n V, L gets
  /// l = c V with c = (1 - n)/rho_s + n/rho_w. Single-point: a soil point carries both phases;
  /// double-point: a soil point only the soil's share of s and l (w unused), a water point only
  /// the water's (water_weights).
  struct Weights {
    double s, w, l;
  };
  /// without_l: l is not needed (CellMoments::derive_laplace) and left 0.
  Weights soil_weights(const ParticleSet<Dim>& ps, int p, bool without_l = false) const {
    const double V = ps.V[p], n = ps.n[p];
    if (without_l) return {(1.0 - n) * V, double_point_ ? 0.0 : n * V, 0.0};
    const double rho_s = grain_density(ps, p);
    if (double_point_) return {(1.0 - n) * V, 0.0, V * (1.0 - n) / rho_s};
    const double c = (1.0 - n) / rho_s + n / water_density(ps, p);
    return {(1.0 - n) * V, n * V, V * c};
  }
  Weights water_weights(const ParticleSet<Dim>& ws, int p, bool without_l = false) const {
    const double nV = ws.n[p] * ws.V[p];
    return {0.0, nV, without_l ? 0.0 : nV / water_density(ws, p)};
  }
  /// rho_s = m / ((1 - n) V) of a soil point (kg/m^3).
  static double grain_density(const ParticleSet<Dim>& ps, int p) { return ps.m[p] / ((1.0 - ps.n[p]) * ps.V[p]); }
  /// rho_w of a point's water: a water point's material (double-point), a soil point's pore fluid
  /// (single-point).
  double water_density(const ParticleSet<Dim>& ws, int p) const {
    return double_point_ ? rho_w_points_[ws.material[p]] : perm_[ws.material[p]].rho_w;
  }

  /// (5a) by cell moments: the same weights as scatter_operators() below, summed per cell as
  /// moments of the points' local coordinates, then each cell's node pairs (exact for shape
  /// functions that are one polynomial per cell; transfer/cell_moments.hpp). B4 6^2: the
  /// point-wise scatter took 1443 instructions per point-step (single-point), 950 per pass
  /// (double-point).
  void assemble_operators_from_moments() {
    if constexpr (kCellMoments) {
      // The points' moments were added by the P2G passes (scatter_soil, scatter_water_points),
      // soil points first, in schedule order.
      Moments& cm = *moments_;
      const std::size_t nx = static_cast<std::size_t>(grid_.nodes_per_axis()[0]);
      cm.reduce(box_, [&](std::size_t first, const typename Moments::CellOperators& op) {
        for (int r = 0; r < NP; ++r) {
          const std::size_t node = first + static_cast<std::size_t>(r / S) * nx + r % S;
          double* lrow = poisson_.row(node) + kRowSlot[r];
          Vec<Dim>* srow = D_solid_.data() + node * KD + kRowSlot[r];
          Vec<Dim>* wrow = D_water_.data() + node * KD + kRowSlot[r];
          for (int k = r; k < NP; ++k) lrow[kColumnSlot[k]] += op.l(r, k);  // lower triangle, as the rows store
          for (int k = 0; k < NP; ++k) {
            srow[kColumnSlot[k]] += op.ds(r, k);
            wrow[kColumnSlot[k]] += op.dw(r, k);
          }
        }
      });
    }
  }

  /// (5c) right-hand side and the CHOLMOD solve. The continuity is the mixture's volume balance
  /// in conservation form, div[(1 - n) v_s + n v_w] = 0 (the sum of the phases' mass balances with
  /// incompressible constituents), tested with S_I, with the flux interpolated from the nodal fluxes
  /// q_K = (1 - n_K) v_sK + n_K v_wK (n_K of eq. 46):
  ///   rhs_I = -(1/dt) sum_K D0_IK . q_K,   D0_IK = sum_p V_p S_I grad S_K = (D^s + D^w)_IK
  /// (soil points carry (1 - n) V, water points n V: together the mixture volume). Expanded,
  ///   div q = (1 - n) div v_s + n div v_w + (v_w - v_s) . grad n,
  /// the paper's eq. 60 right-hand side -(1/dt)(D^s v_s* + D^w v_w*) without the last term. That
  /// term is the water leaving a compacting zone; without it B2 consolidates 15 % too fast
  /// (docs/formulations.md, "Continuity in conservation form"). With uniform porosity both agree.
  /// The pressure forces keep the strong gradient with the points' porosity (G = D^s, D^w read
  /// transposed).
  bool solve_pressure(double dt) {
    const double inv_dt = 1.0 / dt;
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto& ijk) {
      if (poisson_.role(i) == Poisson::inactive) return;
      // Right-hand side -(1/dt)(D^s v_s* + D^w v_w*)_I.
      const Vec<Dim>* Ds_i = D_solid_.data() + i * KD;
      const Vec<Dim>* Dw_i = D_water_.data() + i * KD;
      double div = 0.0;
      for (int kk = 0; kk < KD; ++kk) {
        if (!inside(ijk, DSt::offset(kk))) continue;
        const std::size_t Kn = i + d_steps_[kk];
        if (conservative_) {
          const double nK = node_[Kn].n;
          div += (Ds_i[kk] + Dw_i[kk]).dot((1.0 - nK) * soil_.v[Kn] + nK * water_.v[Kn]);
        } else {
          div += Ds_i[kk].dot(soil_.v[Kn]) + Dw_i[kk].dot(water_.v[Kn]);
        }
      }
      poisson_.rhs(i) = -inv_dt * div;
    });
    return poisson_.solve(grid_, box_);
  }

  /// (5b) Whether node i (with water) is on the free surface, and its prescribed pressure p_D:
  /// the water inside its support stops more than kSurfaceCut cells short of the support's end
  /// along some axis (a grid face is not a cut: the support is clipped to the grid; Kularathna &
  /// Soga 2017, seed-notes seed 001 item 7, took a support less than 60 % full, which misses the
  /// surface between nodes of the B-splines: docs/formulations.md). With B-splines such a node lies
  /// up to about a cell inside or outside the surface, so p_D = 0 there would move the surface;
  /// p_D is instead the value at the node of the linear fit of the points' pressures shifted to
  /// vanish on the surface x_s (the water's extent along the axis of the largest cut):
  /// p_D = -dp/dx_a (x_s - x_Ia). Exact for a hydrostatic or any linear field (and p_D = 0 for
  /// linear/GIMP with a surface through a node row).
  bool free_surface(std::size_t i, const std::array<int, Dim>& ijk, double& p_D) const {
    p_D = 0.0;
    double x_s = 0.0;
    int axis = -1;
    bool hi_cut = false;
    const double cut = surface_cut(i, ijk, axis, hi_cut, x_s);
    if (cut <= kSurfaceCut * grid_.h()) return false;
    p_D = -linear_.gradient_at_node(grid_, i)[axis] * (x_s - grid_.axis(axis).node_x[ijk[axis]]);
    return true;
  }
  /// The nearest node with a well-posed linear fit from node i inward (towards the water) along
  /// the axis of its largest support cut, within S - 1 steps (the nodes that share points with
  /// i); i itself if there is none (no cut, or a sheet of water thinner than the supports: the
  /// node keeps the Order-0 fit, p_D = 0 at a surface node).
  std::size_t inward_well_posed(std::size_t i, const std::array<int, Dim>& ijk) const {
    int axis = -1;
    bool hi_cut = false;
    double x_s = 0.0;
    surface_cut(i, ijk, axis, hi_cut, x_s);
    if (axis < 0) return i;
    const auto& nn = grid_.nodes_per_axis();
    std::size_t stride = 1;
    for (int a = 0; a < axis; ++a) stride *= static_cast<std::size_t>(nn[a]);
    std::size_t k = i;
    for (int j = ijk[axis], step = 1; step < S; ++step) {
      j += hi_cut ? -1 : 1;
      if (j < 0 || j >= nn[axis]) break;
      k = hi_cut ? k - stride : k + stride;
      if (linear_.well_posed(k)) return k;
    }
    return i;
  }
  /// The largest cut of node i's support by the water's extent (water_extent): its length [m],
  /// axis, side (hi_cut: the water stops short of the support's upper end) and the extent x_s.
  double surface_cut(std::size_t i, const std::array<int, Dim>& ijk, int& axis, bool& hi_cut, double& x_s) const {
    const Extent e = water_extent(i, ijk);
    double cut = 0.0;
    axis = -1;
    for (int a = 0; a < Dim; ++a) {
      const auto [s_lo, s_hi] = support_range(a, ijk[a]);
      if (s_hi - e.hi[a] > cut) cut = s_hi - e.hi[a], x_s = e.hi[a], axis = a, hi_cut = true;
      if (e.lo[a] - s_lo > cut) cut = e.lo[a] - s_lo, x_s = e.lo[a], axis = a, hi_cut = false;
    }
    return cut;
  }
  /// Support of basis j along axis a, clipped to the grid [m]: B-splines [t_j, t_{j+q+1}] on the
  /// clamped knot vector; linear and GIMP the hat's [x_j - h, x_j + h] (GIMP's wider reach of
  /// l_p belongs to the points' domains, which the water extent already includes).
  std::pair<double, double> support_range(int a, int j) const {
    const auto& ax = grid_.axis(a);
    if constexpr (Shape::bspline) {
      const int q = Shape::degree;
      auto knot = [&](int t) { return ax.origin + std::clamp(t - q, 0, ax.cells) * ax.h; };
      return {knot(j), knot(j + q + 1)};
    } else {
      return {std::max(ax.node_x[j] - ax.h, ax.origin), std::min(ax.node_x[j] + ax.h, ax.origin + ax.cells * ax.h)};
    }
  }

  /// f_s -= sum_J G^s_KJ q_J, f_w -= sum_J G^w_KJ q_J at node K: the pressure force of a nodal
  /// field q in the strong form of eqs. 67-68, G^s_KJ = sum_sp (1 - n) V S_K grad S_J =
  /// D^s_KJ (equal-order pressure and velocity shapes: G is D read with the roles of I and J
  /// swapped), i.e. f_s = -sum_sp (1 - n) V S_K grad q(x_sp).
  void add_pressure_force(std::size_t k, const std::array<int, Dim>& ijk, const std::vector<double>& q, Vec<Dim>& fs,
                          Vec<Dim>& fw) const {
    const Vec<Dim>* Ds_k = D_solid_.data() + k * KD;
    const Vec<Dim>* Dw_k = D_water_.data() + k * KD;
    Vec<Dim> gs = Vec<Dim>::Zero(), gw = Vec<Dim>::Zero();
    for (int kk = 0; kk < KD; ++kk) {
      if (!inside(ijk, DSt::offset(kk))) continue;
      const double qJ = q[k + d_steps_[kk]];
      gs += qJ * Ds_k[kk];
      gw += qJ * Dw_k[kk];
    }
    fs -= gs;
    fw -= gw;
  }

  /// Whether node ijk + d lies in this step's active box (rows outside it hold stale values).
  bool inside(const std::array<int, Dim>& ijk, const std::array<int, Dim>& d) const {
    for (int a = 0; a < Dim; ++a)
      if (ijk[a] + d[a] < box_.lo[a] || ijk[a] + d[a] > box_.hi[a]) return false;
    return true;
  }

  /// One point's share of the operators of (5a), through the stripe schedule:
  ///   D^s_IK += cs S_I grad S_K,  D^w_IK += cw S_I grad S_K   (eqs. 62-63; cs = (1 - n) V, cw = n V)
  ///   L_IJ += cl grad S_I . grad S_J                            (eq. 61, cl = c V inside the quadrature)
  /// The node pairs are visited once for all three (a phase with c = 0 is skipped at compile time).
  template <bool kSoil, bool kWater>
  void scatter_operators(const shape::ShapeData<Dim, S>& sd, double cs, double cw, double cl) {
    std::array<std::size_t, NP> node;
    std::array<double, NP> N;
    std::array<Vec<Dim>, NP> grad;
    int a = 0;
    shape::for_each_node(grid_, sd, [&](std::size_t i, double w, const Vec<Dim>& dN) {
      node[a] = i;
      N[a] = w;
      grad[a] = dN;
      ++a;
    });
    // Row r's pairs. Slots are compile-time (kRowSlot, kColumnSlot); with r a constant too (2D,
    // below) both inner loops unroll completely and every entry is a constant offset from its
    // row's start (B4 6^2: scatter 2433 -> 1588 instructions per point-step, results bitwise equal).
    auto pairs_of_row = [&](int r) __attribute__((always_inline)) {
      double* lrow = poisson_.row(node[r]) + kRowSlot[r];
      const Vec<Dim> g = cl * grad[r];
      // L is symmetric: only the pairs k >= r (node k at or after node r in flat index: the
      // lower triangle, which the Poisson rows store), 45 of the 81 in 2D.
#pragma GCC unroll 64
      for (int k = r; k < NP; ++k) lrow[kColumnSlot[k]] += g.dot(grad[k]);
      if (N[r] == 0.0) return;
      Vec<Dim>* srow = D_solid_.data() + node[r] * KD + kRowSlot[r];
      Vec<Dim>* wrow = D_water_.data() + node[r] * KD + kRowSlot[r];
      const double sN = cs * N[r], wN = cw * N[r];
#pragma GCC unroll 64
      for (int k = 0; k < NP; ++k) {
        if constexpr (kSoil) srow[kColumnSlot[k]] += sN * grad[k];
        if constexpr (kWater) wrow[kColumnSlot[k]] += wN * grad[k];
      }
    };
    if constexpr (NP <= 16) {  // 2D: every row unrolled (3D's 27-64 rows stay a loop: code size)
      [&]<int... R>(std::integer_sequence<int, R...>) { (pairs_of_row(R), ...); }(std::make_integer_sequence<int, NP>{});
    } else {
      for (int r = 0; r < NP; ++r) pairs_of_row(r);
    }
  }

  /// (6) eqs. 64-68 with the strong gradient G (eqs. 67-68):
  ///   M_sK (v_sK^{t+1} - v_sK*) = -dt sum_J G^s_KJ dp_J,   M_wK (v_wK^{t+1} - v_wK*) = -dt sum_J G^w_KJ dp_J
  /// (= -dt sum_p (1 - n) V S_K grad dp(x_p)), then the boundary conditions on v^{t+1} (step 6d
  /// erratum: on v^{t+1}, not v*). The velocity change at a node is a weighted mean of grad dp
  /// over the points it touches, however little mass it has.
  void correct(const ParticleSet<Dim>&, const ParticleSet<Dim>&, double dt) {
    const auto& dp = poisson_.dp();
    grid_.parallel_for_each_node(box_, [&](std::size_t k, const auto& ijk) {
      Vec<Dim> js = Vec<Dim>::Zero(), jw = Vec<Dim>::Zero();
      add_pressure_force(k, ijk, dp, js, jw);
      const double Ms = soil_.acc[k].m, Mw = water_.acc[k].m;
      if (Ms > transfer::empty_node_mass) soil_.v[k] += (dt / Ms) * js;
      if (Mw > transfer::empty_node_mass) water_.v[k] += (dt / Mw) * jw;
    });
    bcs_solid_.apply(grid_, box_, soil_.v, true);
    bcs_fluid_.apply(grid_, box_, water_.v, false);
  }

  /// (6)-(7c) p^{t+1} at the water points: `none` p += sum S dp (incremental); `node-remap`
  /// p = sum S (pbar_I + dp_I) with pbar_I the water-mass-weighted nodal average (eq. 77);
  /// `mfvp-linear` the same with the linear projection (reproduces linear fields). Double-point:
  /// the soil points' p^{t+1} (output only) is filled when read, complete_output_fields().
  long update_pressure(ParticleSet<Dim>& ws) {
    if (remap_ == Remap::node) {
      if (double_point_)
        constant_.fit(grid_, box_, wschedule_, sdw_, ws.x, [&](int p) { return ws.m[p]; }, [&](int p) { return ws.p[p]; });
      else
        constant_.fit(grid_, box_, schedule_, sd_, ws.x, [&](int p) { return ws.m_f[p]; }, [&](int p) { return ws.p[p]; });
    }
    output_fields_stale_ = water_output_stale_ = double_point_;
    // p^{t+1} = remapped p^t at the point + sum S dp, in one visit of its nodes.
    auto update = [&](const auto& sdw) {
      return with_remap([&](auto visit, auto remapped) {
        constexpr bool kRemapped = decltype(remapped)::value;
        const auto& dp = poisson_.dp();
        const long n = static_cast<long>(ws.size());
        long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
        for (long p = 0; p < n; ++p) {
          double inc = 0.0, value = 0.0;
          visit(sdw[p], ws.x[p], [&](std::size_t i, double N, double pbar) {
            inc += N * dp[i];
            if constexpr (kRemapped) value += N * pbar;
          });
          ws.p[p] = (kRemapped ? value : ws.p[p]) + inc;
          if (!std::isfinite(ws.p[p])) bad = std::min(bad, p);
        }
        return bad == transfer::no_particle ? -1 : bad;
      });
    };
    return double_point_ ? update(sdw_) : update(sd_);
  }
  /// Calls body(visit, remapped) with the remap's visitor: visit(sd, x, fn) calls fn(i, N, pbar_I)
  /// at each node of a point (for_each_node's order), pbar_I the nodal term of the remapped
  /// p^t at the point (NodeProjection::for_each_node_value; 0 without remap: remapped is
  /// std::false_type, p^t stays the point's own). One visit gathers the increment too.
  template <class Body>
  auto with_remap(Body&& body) const {
    switch (remap_) {
      case Remap::node:
        return body([&](const auto& sd, const Vec<Dim>& x, auto&& fn)
                        __attribute__((always_inline)) { constant_.for_each_node_value(grid_, sd, x, fn); },
                    std::true_type{});
      case Remap::linear:
        return body([&](const auto& sd, const Vec<Dim>& x, auto&& fn)
                        __attribute__((always_inline)) { linear_.for_each_node_value(grid_, sd, x, fn); },
                    std::true_type{});
      case Remap::none:
        break;
    }
    return body(
        [&](const auto& sd, const Vec<Dim>&, auto&& fn) __attribute__((always_inline)) {
          shape::for_each_node(grid_, sd, [&](std::size_t i, double N, const auto&) { fn(i, N, 0.0); });
        },
        std::false_type{});
  }

  /// Double-point: the soil points' pore pressure, p^{t+1} interpolated from the nodes (the
  /// projected p^t plus the increment, with the step's shape data), and the water velocity v_w^{t+1}
  /// at them, for output and monitors only; the time loop asks for them when it writes
  /// (Formulation::complete_output_fields).
  void complete_output_fields(State<Dim>& st, bool water_points) override {
    if (water_points && water_output_stale_) {
      water_output_stale_ = false;
      complete_water_porosity(st.solid, st.fluid);
    }
    if (!output_fields_stale_) return;
    output_fields_stale_ = false;
    ParticleSet<Dim>& ps = st.solid;
    const auto& dp = poisson_.dp();
    const long m = static_cast<long>(ps.size());
#pragma omp parallel for schedule(static) if (m > parallel_threshold)
    for (long p = 0; p < m; ++p) {
      double value = 0.0;
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>&) {
        value += N * (linear_.at_node(i) + dp[i]);
      });
      ps.p[p] = value;
      ps.v_f[p] = water_velocity_at(sd_[p]);
    }
  }
  /// Double-point: v_w^{t+1} interpolated with a soil point's shape data (the water velocity at it).
  Vec<Dim> water_velocity_at(const shape::ShapeData<Dim, S>& sd) const {
    Vec<Dim> vw = Vec<Dim>::Zero();
    shape::for_each_node(grid_, sd, [&](std::size_t i, double N, const Vec<Dim>&) { vw += N * water_.v[i]; });
    return vw;
  }

  /// (7) the soil points (kPoreWater: single-point, the same points carry the pore water's
  /// velocity too). Double-point soil points keep no water velocity in the step: the water
  /// velocity at them is filled for output (complete_output_fields).
  template <bool kPoreWater>
  void gather_soil(ParticleSet<Dim>& ps, double dt) {
    schedule_.run([&](int p) __attribute__((always_inline)) {
      Vec<Dim> vs = Vec<Dim>::Zero(), vs_old = Vec<Dim>::Zero(), vw = Vec<Dim>::Zero(), vw_old = Vec<Dim>::Zero();
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>&) {
        vs += N * soil_.v[i];
        vs_old += N * soil_.vL[i];
        if constexpr (kPoreWater) {
          vw += N * water_.v[i];
          vw_old += N * water_.vL[i];
        }
      });
      ps.v[p] = flip_ * (ps.v[p] + vs - vs_old) + (1.0 - flip_) * vs;
      if constexpr (kPoreWater) ps.v_f[p] = flip_ * (ps.v_f[p] + vw - vw_old) + (1.0 - flip_) * vw;
      ps.x[p] += dt * vs;
      const Vec<Dim> mv = ps.m[p] * ps.v[p];
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>&) { soil_.acc[i].mv += N * mv; });
    });
  }

  /// (7) FLIP/PIC for the soil points (single-point: and their pore water), soil positions with
  /// v_s^{t+1}, and the MUSL remap of the soil momentum (step 8a) before the strain increment.
  /// Double-point water points: update_water_points().
  void gather(ParticleSet<Dim>& ps, double dt) {
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) { soil_.acc[i].mv.setZero(); });
    if (double_point_) gather_soil<false>(ps, dt);
    else gather_soil<true>(ps, dt);
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      const auto& s = soil_.acc[i];
      soil_.v[i] = s.m > transfer::empty_node_mass ? Vec<Dim>(s.mv / s.m) : Vec<Dim>::Zero();
    });
    bcs_solid_.apply(grid_, box_, soil_.v, false);
  }

  /// (8) L_s = sum v_s (x) grad S with the remapped velocities; F, V; porosity from
  /// (1 - n) J = 1 - n0 (step 8f); single-point pore-water mass n rho_w V.
  long update_soil(ParticleSet<Dim>& ps, double dt) {
    const long n = static_cast<long>(ps.size());
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      MatD<Dim> L = MatD<Dim>::Zero();
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double, const Vec<Dim>& dN) {
        L.noalias() += soil_.v[i] * dN.transpose();
      });
      ps.L[p] = L;
      Mat3& F = ps.F[p];
      transfer::apply_increment<Dim>(transfer::deformation_increment<Dim>(L, dt), F);  // F_{n+1} = dF F_n
      const double V_old = ps.V[p];
      const double J = F.determinant();
      ps.V[p] = J * ps.V0[p];
      ps.n[p] = 1.0 - (1.0 - ps.n[p]) * V_old / ps.V[p];
      ps.m_f[p] = ps.n[p] * perm_[ps.material[p]].rho_w * ps.V[p];
      if (!(J > 0.0) || !(ps.n[p] > 0.0 && ps.n[p] < 1.0)) bad = std::min(bad, p);
    }
    return bad == transfer::no_particle ? -1 : bad;
  }

  /// For each water-point id, the id of the soil point seeded at the same place (preprocess seeds
  /// the water of a saturated body on the soil's lattice), -1 for free water.
  static std::vector<std::int64_t> coincident_soil_points(const State<Dim>& st) {
    const ParticleSet<Dim>& ps = st.solid;
    const ParticleSet<Dim>& ws = st.fluid;
    auto less = [](const Vec<Dim>& a, const Vec<Dim>& b) {
      return std::lexicographical_compare(a.data(), a.data() + Dim, b.data(), b.data() + Dim);
    };
    std::vector<int> order(ps.size());
    for (std::size_t p = 0; p < ps.size(); ++p) order[p] = static_cast<int>(p);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return less(ps.x0[a], ps.x0[b]); });
    std::int64_t max_id = -1;
    for (auto id : ws.id) max_id = std::max(max_id, id);
    std::vector<std::int64_t> out(static_cast<std::size_t>(max_id + 1), -1);
    for (std::size_t w = 0; w < ws.size(); ++w) {
      const auto it = std::lower_bound(order.begin(), order.end(), ws.x0[w],
                                       [&](int q, const Vec<Dim>& x) { return less(ps.x0[q], x); });
      if (it != order.end() && ps.x0[*it] == ws.x0[w]) out[ws.id[w]] = ps.id[*it];
    }
    return out;
  }

  /// Initialisation phase (seed 001 §5.4): each water point takes the position of its coincident
  /// soil point, so the points do not seep while gravity grows. Their velocities stay their own:
  /// the grid still solves the Darcy flow that drains the excess pressure (resetting them to the
  /// soil's each step would hold the water still and keep the layer undrained).
  void tie_water_points(State<Dim>& st) const {
    ParticleSet<Dim>& ws = st.fluid;
    const ParticleSet<Dim>& ps = st.solid;
    const long n = static_cast<long>(ws.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      const std::int64_t sid = partner_[ws.id[p]];
      if (sid < 0) continue;
      const int q = st.index_of_id[sid];
      ws.x[p] = ps.x[q];
    }
  }

  /// End of an initialisation phase with its own permeability (double-point): each water point with
  /// a coincident soil point takes that point's velocity.
  void restart_water_with_soil(State<Dim>& st) const {
    ParticleSet<Dim>& ws = st.fluid;
    const ParticleSet<Dim>& ps = st.solid;
    for (std::size_t p = 0; p < ws.size(); ++p) {
      const std::int64_t sid = partner_[ws.id[p]];
      if (sid >= 0) ws.v[p] = ps.v[st.index_of_id[sid]];
    }
  }

  /// (7) double-point water points: FLIP/PIC velocity and position with v_w^{t+1}, shape data of
  /// the start of the step. Their porosity and volume (8h)-(8i) follow in the next step's P2G
  /// (scatter_water_points), or for output in complete_output_fields.
  void update_water_points(ParticleSet<Dim>& ws, double dt) {
    const long n = static_cast<long>(ws.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      Vec<Dim> vw = Vec<Dim>::Zero(), vw_old = Vec<Dim>::Zero();
      shape::for_each_node(grid_, sdw_[p], [&](std::size_t i, double N, const auto&) {
        vw += N * water_.v[i];
        vw_old += N * water_.vL[i];
      });
      ws.v[p] = flip_ * (ws.v[p] + vw - vw_old) + (1.0 - flip_) * vw;
      ws.x[p] += dt * vw;
    }
  }

  /// Double-point, output only: the water points' porosity and volume where the points are now,
  /// as the next step's P2G will find them (scatter_water_points): the soil's porosity mapped to
  /// the nodes with the soil points' current shape functions, n_I = sum S m n / sum S m (1 where
  /// no soil), interpolated at each water point, V = m / (n rho_w). The soil's sums go in one
  /// thread in point order (the same numbers with any number of threads); frames are rare.
  void complete_water_porosity(const ParticleSet<Dim>& ps, ParticleSet<Dim>& ws) {
    long bad = -1;
    transfer::evaluate_shapes<Shape>(grid_, ps, out_sd_, bad);
    transfer::evaluate_shapes<Shape>(grid_, ws, out_sdw_, bad);
    out_m_.assign(grid_.num_nodes(), 0.0);
    out_mn_.assign(grid_.num_nodes(), 0.0);
    for (std::size_t p = 0; p < ps.size(); ++p) {
      const double m = ps.m[p], mn = m * ps.n[p];
      shape::for_each_node(grid_, out_sd_[p], [&](std::size_t i, double N, const auto&) {
        out_m_[i] += N * m;
        out_mn_[i] += N * mn;
      });
    }
    const long n = static_cast<long>(ws.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      double np = 0.0;
      shape::for_each_node(grid_, out_sdw_[p], [&](std::size_t i, double N, const auto&) {
        np += N * porosity_at_node(out_mn_[i], out_m_[i]);
      });
      set_water_porosity(ws, static_cast<std::size_t>(p), np);
    }
  }

  /// solver.escaped_water = remove (double-point): the water points outside the soil leave the
  /// run — an outflow through the drained free surface into a reservoir that is not modelled
  /// (B2: the water squeezed out of the top would otherwise float above the soil as a sheet
  /// thinner than a cell, whose surface nodes take p = 0 and cut the soil off its drained top).
  /// "Outside": the soil's volume fraction interpolated at the point,
  ///   phi(x_w) = sum_I S_I(x_w) min(1, sum_sp S_I V_sp / int S_I dx),
  /// is below one half (the soil's surface is where phi = 1/2). Shape data and nodal sums of the
  /// start of the step; removal keeps the order of the remaining points (thread-independent).
  void remove_escaped_water(ParticleSet<Dim>& ws) {
    const long n = static_cast<long>(ws.size());
    escaped_.resize(ws.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      double phi = 0.0;
      shape::for_each_node(grid_, sdw_[p], [&](std::size_t i, double N, const auto&) {
        phi += N * std::min(1.0, node_[i].soil_volume / support_[i]);
      });
      escaped_[p] = phi < 0.5;
    }
    const std::size_t n0 = ws.size();
    std::size_t removed = 0;
    for (std::size_t p = 0; p < n0; ++p)
      if (escaped_[p]) ++removed, escaped_mass_ += ws.m[p];
    if (removed == 0) return;
    escaped_points_ += static_cast<long>(removed);
    ws.for_each_field([&](auto& f) {
      if (f.size() != n0) return;  // fields the water points do not use
      std::size_t k = 0;
      for (std::size_t p = 0; p < n0; ++p)
        if (!escaped_[p]) f[k++] = f[p];
      f.resize(k);
    });
  }

 public:
  std::vector<typename Formulation<Dim>::Counter> counters() const override {
    // The pressure solver's work (pressure_poisson.hpp): how often the unknown node set changed
    // (new pattern and symbolic analysis), numeric factorisations, and CG iterations preconditioned
    // by an older factor on the other steps.
    std::vector<typename Formulation<Dim>::Counter> c = {
        {"pressure_pattern_builds", static_cast<double>(poisson_.pattern_builds()),
         "new sparsity patterns of L (the set of unknown nodes changed)"},
        {"pressure_factorisations", static_cast<double>(poisson_.factorisations()), "CHOLMOD numeric factorisations"},
        {"pressure_cg_iterations", static_cast<double>(poisson_.cg_iterations()),
         "conjugate-gradient iterations preconditioned by an older factor"}};
    if (remove_escaped_) {
      c.push_back({"escaped_water_points", static_cast<double>(escaped_points_), "water points removed (solver.escaped_water)"});
      c.push_back({"escaped_water_mass", escaped_mass_, "kg (per metre in 2D)"});
    }
    return c;
  }

 private:
  bool double_point_;
  Grid<Dim> grid_;
  GridBoundary<Dim> bcs_solid_, bcs_fluid_;
  ParticleLoads<Dim> loads_;
  double flip_, damping_, scene_damping_;
  Remap remap_ = Remap::node;
  std::vector<std::unique_ptr<MaterialModel<Dim>>> materials_;
  std::vector<std::vector<int>> material_particles_;
  std::vector<Permeability> perm_;          // per solid material (the initialisation phase's while it runs)
  std::vector<Permeability> scene_perm_;    // per solid material, as the scene gives it
  bool tie_ = false;                        // initialisation: water points follow their soil points
  bool conservative_ = false;               // solver.continuity = conservative (solve_pressure)
  bool implicit_drag_ = true;               // solver.drag_integration (predictor)
  bool remove_escaped_ = false;             // solver.escaped_water = remove (double-point)
  std::vector<char> escaped_;               // per water point, this step (reused)
  long escaped_points_ = 0;                 // removed so far
  double escaped_mass_ = 0.0;               // kg (per metre in 2D), removed so far
  bool fast_drainage_ = false;              // initialisation with its own permeability is running
  std::vector<std::int64_t> partner_;       // per water-point id: the coincident soil point's id (-1: none)
  std::vector<int> fluid_of_material_;      // per solid material: its pore water's material
  std::vector<double> rho_w_points_;        // per fluid material (double-point water points)
  std::array<bool, 6> face_drained_{};
  std::array<double, 6> face_pressure_{};   // Pa, prescribed p on drained faces (0 unless `pressure`)
  NodeFields<Dim> soil_, water_;
  std::vector<NodeExtra> node_;
  std::vector<WaterSums> water_sums_;  // double-point: zero between steps (scatter_water_points)
  std::vector<Extent> extent_;   // per node: water extent (kBaseExtent: of the points whose support starts there)
  std::vector<double> support_;  // per node: integral of its basis function over the grid
  std::vector<double> p_node_;   // Pa, per node: p^t from the linear projection of the points' pressures
  std::vector<Vec<Dim>> A_soil_, A_water_;  // per node: M v^t + dt f of each phase (implicit drag)
  Poisson poisson_;
  std::vector<Vec<Dim>> D_solid_, D_water_;  // per node: row I of D^s, D^w over the D stencil
  std::unique_ptr<Moments> moments_;         // kCellMoments only
  std::array<long, KD> d_steps_{};
  NodeProjection<Dim, S, 1> linear_;
  NodeProjection<Dim, S, 0> constant_;
  NodeBox<Dim> box_;
  std::vector<shape::ShapeData<Dim, S>> sd_;
  std::vector<shape::ShapeData<Dim, S, !kCellMoments>> sdw_;  // weights only with the cell moments
  std::vector<shape::ShapeData<Dim, S, false>> out_sd_, out_sdw_;  // complete_water_porosity (output only)
  std::vector<double> out_m_, out_mn_;                               // per node, complete_water_porosity
  bool output_fields_stale_ = false;  // double-point: ps.p and ps.v_f lag the last step (complete_output_fields)
  bool water_output_stale_ = false;   // double-point: the water points' n and V lag the last step
  std::vector<FaceForce<Dim, S>> face_forces_;
  StripeSchedule schedule_, wschedule_;
  Reorder<Dim> reorder_, wreorder_;
  FBar<Dim, S> fbar_;
  static constexpr long reorder_interval = 10;  // steps
};

}  // namespace

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_semi_implicit(const scene::Scene& s, const State<Dim>& state) {
  return make_for_shape<SemiImplicit, Dim>(s, state);
}

template std::unique_ptr<Formulation<2>> make_semi_implicit<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_semi_implicit<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
