// Formulation `mpm-fem`: seed 004's hybrid (Pan, Yamaguchi, Moriguchi & Terada): the soil
// skeleton by MPM on the grid's B-splines (MUSL), the pore and free water (and the air above
// it) by a stabilised Eulerian finite-element method on the same grid and basis
// (solver/fem/fluid.hpp), the free surface by an Allen–Cahn phase field (solver/fem/phase_field.hpp).
// docs/formulations.md, "mpm-fem", derives each line and states the choices.
//
// Signs: effective stress sigma' tension positive, pore pressure p compression positive. Units SI;
// 2D quantities per metre. n the porosity, theta the soil's volume fraction at a node.
//
// One step, the seed's §"Numerical algorithm" (i)-(vii):
//   (0) soil points in scatter order every 10 steps (memory locality only)
//   (i) soil P2G: M_s (eq. 53), M_s v_s (eq. 77), the effective-stress force and weight (eqs.
//       54-55), tractions; theta_I = sum N V / Omega_I (eq. 79), n_I = 1 - sum N (1 - n) V /
//       Omega_I (eq. 81, volume-based), k_I = sum N m k / sum N m (eq. 78), Omega_I = int N_I
//   (ii) the fluid's n, theta, k at its Gauss points from those nodal values (eq. 51)
//   (iii) the fluid's v^{L+1}, p^{L+1} (eqs. 67-68, one linear system)
//   (iv) the phase field phi^{L+1} (eq. 106); rho, mu blended by phi (eqs. 89-90)
//   (v) the soil's nodal velocity (eq. 69): the fluid's pressure on the skeleton,
//       int ((1 - n) grad N - N grad n) p (eq. 54), and the drag Q (v_f - v_s), Q_I = int N c
//       lumped, implicit in the soil's own velocity (the seed: explicit; see below)
//   (vi) G2P (FLIP/PIC), MUSL remap, F, V, n (eqs. 73-75, n <= 0.99), k (eq. 76), the stress
//   (vii) the grid is cleared by the next step's P2G
//
// The drag on the soil: v_s^{L+1} = (M v_s^L + dt (F + Q v_f^{L+1})) / (M + dt Q) per node. The
// seed's explicit drag (theta = 0) limits dt to about M / Q, which fine soils make tiny; implicit
// in the soil's own velocity, it sets no limit and costs nothing.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>

#include "solver/fem/fluid.hpp"
#include "solver/fem/phase_field.hpp"
#include "solver/formulation.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/loads.hpp"
#include "solver/materials/material.hpp"
#include "solver/parallel/particles.hpp"
#include "solver/porous/free_surface.hpp"
#include "solver/porous/permeability.hpp"
#include "solver/porous/points.hpp"
#include "solver/transfer/fbar.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {
namespace {

/// The porosity of a soil point is capped here (seed §"Time integration": "the upper limit value
/// of the solid porosity ... set at 0.99").
constexpr double kMaxPointPorosity = 0.99;
/// The nodal porosity is kept above this (points clustering in a support can give theta_I > 1).
constexpr double kMinNodalPorosity = 0.01;

/// The soil's nodal sums of (i).
struct SoilSums {
  double V = 0.0;   // m^3: sum N V
  double Vs = 0.0;  // m^3: sum N (1 - n) V, the grains' volume
  double mk = 0.0;  // kg m^2: sum N m k (k the intrinsic permeability)
};

template <int Dim, class Shape>
class MpmFem final : public Formulation<Dim> {
  static constexpr int S = Shape::support;
  static constexpr long reorder_interval = 10;  // steps
  using Basis = fem::CellBasis<Dim, Shape>;

 public:
  MpmFem(const scene::Scene& s, const State<Dim>& state)
      : grid_(make_grid<Dim>(s, Shape::degree, Shape::bspline)),
        bcs_solid_(s, grid_, state.surfaces),
        loads_(s, grid_, state.solid, state.surfaces, /*pore_pressure_forces=*/false),
        flip_(s.solver.flip),
        damping_(s.solver.damping),
        scene_damping_(s.solver.damping),
        materials_(make_materials<Dim>(s)),
        material_particles_(group_by_material(state.solid, s.materials.size())),
        phase_materials_(s),
        fbar_(s, grid_) {
    if constexpr (!Shape::bspline)
      throw std::runtime_error("mpm-fem needs grid.shape_function \"bspline2\" or \"bspline3\"");
    // Water: the scene's first fluid material.
    fem::FluidProperties props;
    int water = -1;
    for (std::size_t k = 0; k < s.materials.size(); ++k)
      if (s.materials[k].model == scene::MaterialModel::fluid) {
        water = static_cast<int>(k);
        break;
      }
    if (water < 0) throw std::runtime_error("mpm-fem needs a fluid material (the water)");
    const auto& wm = s.materials[water];
    props.rho_w = wm.at("density");
    props.mu_w = wm.has("dynamic_viscosity") ? wm.at("dynamic_viscosity") : 1e-3;
    props.rho_a = s.solver.air.density;
    props.mu_a = s.solver.air.dynamic_viscosity;
    // The skeletons' permeability (hydraulic conductivity k_h [m/s]; intrinsic k = k_h mu / (rho g)).
    perm_.resize(s.materials.size());
    const std::vector<char> present = materials_present(material_particles_);  // over every rank's points
    to_intrinsic_ = props.mu_w / (props.rho_w * porous::g_earth);
    for (std::size_t k = 0; k < s.materials.size(); ++k) {
      const auto& m = s.materials[k];
      if (m.model == scene::MaterialModel::fluid || !present[k]) continue;
      if (m.has("hydraulic_conductivity") || m.has("intrinsic_permeability") || m.has("grain_diameter"))
        perm_[k] = porous::permeability_of(m, wm);
      else
        throw std::runtime_error("material \"" + m.name + "\": mpm-fem needs the permeability of every soil "
                                 "(hydraulic_conductivity, intrinsic_permeability or grain_diameter)");
      if (m.has("ergun_a")) props.kozeny = m.at("ergun_a");
      if (m.has("ergun_b")) props.forchheimer = m.at("ergun_b");
    }
    props_ = props;
    face_conditions(s);
    const auto& pspg = s.solver.stabilisation.pressure;
    fluid_.pspg = pspg == "pspg-increment" ? fem::Fluid<Dim, Shape>::Pspg::increment : fem::Fluid<Dim, Shape>::Pspg::residual;
    fluid_.implicit_drag = s.solver.drag_integration != "explicit";
    // PSPG's time step at least sqrt(h / |g|) / 40 (fluid.hpp, pspg_time_floor; none without gravity).
    double g2 = 0.0;
    for (double ga : s.gravity) g2 += ga * ga;
    fluid_.pspg_time_floor = g2 > 0.0 ? std::sqrt(grid_.h() / std::sqrt(g2)) / 40.0 : 0.0;
    // The fluid's nodal state on the whole grid (the solve works on the active region's copy).
    const std::size_t nodes = grid_.num_nodes();
    v_.assign(nodes, Vec<Dim>::Zero());
    v_old_.assign(nodes, Vec<Dim>::Zero());
    p_.assign(nodes, 0.0);
    phi_.assign(nodes, 1.0);
    // The phase field: preprocess's nodal phi (particles/phase_field.vtu).
    if (state.phase_field.points.size() == nodes) {
      const auto* phi = state.phase_field.find("phi");
      if (!phi) throw std::runtime_error("particles/phase_field.vtu has no array \"phi\"");
      for (std::size_t i = 0; i < nodes; ++i) phi_[i] = phi->values[i];
      // The water's initial velocity (bodies' initial.velocity; older runs have none: at rest).
      if (const auto* v = state.phase_field.find("velocity"))
        for (std::size_t i = 0; i < nodes; ++i)
          for (int a = 0; a < Dim; ++a) v_[i][a] = v_old_[i][a] = v->values[3 * i + a];
    } else if (!state.phase_field.points.empty()) {
      throw std::runtime_error("particles/phase_field.vtu holds " + std::to_string(state.phase_field.points.size()) +
                               " nodes, the grid " + std::to_string(grid_.num_nodes()) + ": run swmpm preprocess again");
    }
    fem::PhaseFieldParameters pf;
    pf.width = s.solver.phase_field.interface_width.value_or(kDefaultWidthCells * grid_.h());
    pf.mobility = s.solver.phase_field.mobility.value_or(kDefaultMobility);
    pf.volume_correction = s.solver.phase_field.volume_correction;
    pf.lsic = s.solver.phase_field.lsic;
    phase_prm_ = pf;
    phase_mobility_ = pf.mobility;
    substeps_ = std::max(1, s.solver.soil_substeps);
    solid_.resize(nodes);
    sums_.assign(nodes, SoilSums{});
    soil_.resize(nodes);
    soil_force_.assign(nodes, Vec<Dim>::Zero());
    drag_.assign(nodes, 0.0);
    support_.resize(nodes);
    for (std::size_t i = 0; i < nodes; ++i) support_[i] = porous::basis_integral<Shape>(grid_, i);
    basis_.build(grid_);
    soil_box_ = empty_box();
    has_soil_ = parallel::sum(static_cast<long>(state.solid.size())) > 0;  // over every rank's points
    whole_grid_ = s.solver.air.whole_grid;
    set_region(whole_grid_ ? all_cells() : wanted_region(points_node_box_over_ranks(state.solid), empty_box(), 1));
    if (initial_hydrostatic_pressure(s)) set_region(region_, /*count=*/false);  // p copied onto the region
  }

  std::string name() const override { return "mpm-fem"; }

  void step(State<Dim>& st, const StepContext& ctx) override {
    ParticleSet<Dim>& ps = st.solid;
    const double dt = ctx.dt;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    StageClock lap(this->times_);

    if (has_soil_ && reorder_for_locality(st, schedule_, reorder_, material_particles_, reorder_interval, &domain_))
      lap("reorder");                                                                          // (0)
    soil_to_grid(st, ctx, b);                                                                  // (i)-(ii)
    lap("soil p2g");

    // Multi-rate (solver.soil_substeps = k): the fluid and the phase field advance at the first of
    // every k soil steps, to the time the soil reaches after the k steps; the soil takes their
    // pressure and velocity meanwhile (the seed's staggering, steps iii-v, with a longer fluid
    // step). k = 1 is the seed's scheme: the fluid's step is the soil's.
    if (substep_ == 0) {
      // The active region follows the water and the soil (a new pattern when it grows), and the
      // soil's nodal fields are copied onto its nodes.
      if (!whole_grid_ && !region_holds_content(soil_nodes())) set_region(wanted_region(soil_nodes(), region_, 2));
      gather_soil();
      if (water_volume0_ < 0.0) water_target_ = water_volume0_ = phase_.volume(fluid_.phi, fsoil_.n);  // int n phi at t = 0
      lap("fluid region");
      const double dt_f = substeps_ == 1 ? dt : soil_time_ + substeps_ * dt - fluid_time_;
      fluid_time_ = soil_time_ + (substeps_ == 1 ? dt : substeps_ * dt);
      const double a0 = fluid_.seconds_assemble, f0 = fluid_.seconds_factorise, s0 = fluid_.seconds_solve;
      if (!fluid_.step(fsoil_, b, dt_f)) {                                                        // (iii)
        const std::string why = fluid_.failure().empty() ? "the solve failed" : fluid_.failure();
        st.health.report_node(0, {0, 0, 0}, "fluid", "the fluid's system could not be solved: " + why);
        return;
      }
      this->times_.add("fluid assembly", fluid_.seconds_assemble - a0);
      this->times_.add("fluid factorisation", fluid_.seconds_factorise - f0);
      this->times_.add("fluid solve", fluid_.seconds_solve - s0);
      lap.restart();
      check_fluid(st);
      // The water's volume: what it was, less what flowed out through open faces this step
      // (sum over their nodes of n phi v.n_out int N dGamma).
      for (const auto& o : fluid_.conditions().open)
        water_target_ -= dt_f * fsoil_.n[o.node] * std::clamp(fluid_.phi[o.node], 0.0, 1.0) * o.sign * fluid_.v[o.node][o.axis] * o.area;
      if (phase_.step(fluid_.phi, fluid_.v, fsoil_.n, dt_f, water_target_) < 0)                 // (iv)
        st.health.report_node(0, {0, 0, 0}, "fluid", "the phase field's solve did not converge");
      water_corrected_ += phase_.last_corrected_volume;
      scatter_fluid();
      lap("phase field");
    }
    substep_ = (substep_ + 1) % substeps_;
    soil_time_ += dt;

    if (!has_soil_) return;
    fluid_on_soil(dt);                                                                         // (v)
    update_soil_grid(dt);
    lap("soil grid update");
    transfer::gather_velocity_position_remap(grid_, schedule_, box_, sd_, dt, flip_, ps, solid_);  // (vi)
    bcs_solid_.apply(grid_, box_, solid_.v, false);
    lap("g2p + musl remap");
    const long bad = update_soil(st, dt);
    if (bad >= 0) st.health.report(bad, "solid", "volume ratio J <= 0 or porosity outside (0, 1)");
    lap("stress and porosity");
  }

  double critical_time_step(const State<Dim>& st, std::string& reason) const override {
    // The soil's P-wave CFL on its partial density (the water is incompressible: no storage term),
    // and the fluid's advective CFL h / |v_f|max (the Adams–Bashforth advection velocity is explicit).
    const ParticleSet<Dim>& ps = st.solid;
    double c2 = 0.0;
    const std::vector<double> moduli = max_p_wave_moduli(materials_, ps, material_particles_);
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const double M = moduli[k];
      for (int p : material_particles_[k]) c2 = std::max(c2, M * ps.V[p] / ps.m[p]);
    }
    // The coupling: the soil takes the fluid's pressure of the step it moved in (the seed's
    // staggered algorithm, steps iii and v), and a soil velocity forces a pressure that pushes it
    // back by about dt c / (n rho_s') times itself, c = n^2 mu / k the Darcy drag coefficient and
    // rho_s' = m / V the soil's partial density: stable for dt below about n rho_s' / c (measured on
    // the through-flow example's 0.1 mm bed: diverged at 0.8 n rho_s' / c, ran at 0.4; D1 runs at
    // 0.25), so the limit reported is 0.5 n rho_s' / c, scaled by time.cfl like the others.
    double dt_couple = std::numeric_limits<double>::infinity();
    const auto& pr = fluid_.properties();
    for (std::size_t p = 0; p < ps.size(); ++p) {
      const double n = ps.n[p], k = to_intrinsic_ * perm_[ps.material[p]].at_point(n, ps.V[p], ps.V0[p]);
      if (k > 0.0) dt_couple = std::min(dt_couple, 0.5 * n * (ps.m[p] / ps.V[p]) / (n * n * pr.mu_w / k));
    }
    double v2 = 0.0, vf2 = 0.0;
    for (std::size_t p = 0; p < ps.size(); ++p) v2 = std::max(v2, ps.v[p].squaredNorm());
    for (const auto& v : fluid_.v) vf2 = std::max(vf2, v.squaredNorm());
    std::array<double, 3> maxima{c2, v2, -dt_couple};  // over all ranks (mpirun; the fluid's are every rank's)
    parallel::max(std::span<double>(maxima));
    c2 = maxima[0], v2 = maxima[1], dt_couple = -maxima[2];
    const double h = grid_.h(), c = std::sqrt(c2), vs = std::sqrt(v2), vf = std::sqrt(vf2);
    const double dt_soil = c > 0.0 ? h / (c + vs) : std::numeric_limits<double>::infinity();
    const double dt_fluid = vf > 0.0 ? h / vf : std::numeric_limits<double>::infinity();
    // The phase field's reaction 4 M phi (1 - phi)(phi - 1/2) is explicit (eq. 106): its rate at
    // phi = 0 and 1 is 2 M, forward Euler is stable below dt = 1 / M.
    const double dt_phase = 1.0 / phase_mobility_;
    std::ostringstream os;
    // With k soil substeps the fluid's limits hold for its step k dt.
    const double k = substeps_;
    const double dt = std::min({dt_soil, dt_fluid / k, dt_couple / k, dt_phase / k});
    const std::string per_k = substeps_ > 1 ? " / soil_substeps " + std::to_string(substeps_) : "";
    if (dt == dt_phase / k) os << "the phase field's explicit reaction (1 / M_phi = " << dt_phase << " s" << per_k << ")";
    else if (dt == dt_couple / k) os << "soil-fluid coupling (0.5 n rho_s' k / (n^2 mu) = " << dt_couple << " s, the least permeable soil" << per_k << ")";
    else if (dt == dt_soil) os << "soil P-wave CFL (c = " << c << " m/s, |v_s|max = " << vs << " m/s)";
    else os << "fluid advective CFL (|v_f|max = " << vf << " m/s" << per_k << ")";
    os << "; the water is incompressible";
    reason = os.str();
    return std::isfinite(dt) ? dt : kMaxStep;
  }

  double kinetic_energy(const State<Dim>& st) const override {
    const auto& ps = st.solid;
    // mpirun: this rank's soil points; the fluid's on rank 0 (fluid_integral is 0 elsewhere).
    return fixed_order_sum(ps.size(), [&](std::size_t p) { return 0.5 * ps.m[p] * ps.v[p].squaredNorm(); }) +
           fluid_integral([&](const fem::FluidPoint<Dim>& f) { return 0.5 * f.n * f.rho * f.v.squaredNorm(); });
  }
  double strain_energy(const State<Dim>& st) const override {
    return fixed_order_sum(st.solid.size(), [&](std::size_t p) {
      return materials_[st.solid.material[p]]->strain_energy(st.solid, static_cast<int>(p));
    });
  }
  double external_power(const State<Dim>& st, const StepContext& ctx) const override {
    const ParticleSet<Dim>& ps = st.solid;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    double power = fixed_order_sum(ps.size(), [&](std::size_t p) { return ps.m[p] * b.dot(ps.v[p]); });
    power += fluid_integral([&](const fem::FluidPoint<Dim>& f) { return f.n * f.rho * b.dot(f.v); });
    // A prescribed pressure on a grid face works on the fluid crossing it: -p int v.n_out dGamma,
    // int N_I dGamma the face's basis integral (B-splines: the face row's N is 1 on the face).
    if (parallel::rank() == 0) {  // mpirun: on rank 0, as the fluid's integrals
      for (const auto& pf : pressure_faces_) {
        NodeBox<Dim> face = grid_.all_nodes();
        face.lo[pf.axis] = face.hi[pf.axis] = pf.side == 0 ? 0 : grid_.nodes_per_axis()[pf.axis] - 1;
        const double sign = pf.side == 0 ? -1.0 : 1.0;
        grid_.for_each_node(face, [&](std::size_t i, const auto&) {
          power -= pf.value * sign * v_[i][pf.axis] * porous::basis_integral<Shape>(grid_, i, pf.axis);
        });
      }
    }
    loads_.for_each_force(ctx.t, st.index_of_id, [&](int p, const Vec<Dim>& f_p, const Vec<Dim>&, bool) { power += f_p.dot(ps.v[p]); });
    return power;
  }
  void set_initialisation(State<Dim>&, const scene::Initialisation* phase) override {
    phase_materials_.set(materials_, phase);  // the phase's parameters and plastic flag (materials/material.hpp)
    damping_ = phase_damping(phase, scene_damping_);
  }
  std::size_t active_cells(const State<Dim>& st) const override { return count_active_cells(grid_, st.solid); }
  /// mpirun: the soil points over the ranks (parallel::Domain); the fluid's and phase field's
  /// systems assembled per rank and solved over the ranks, their nodal state whole on every rank
  /// (the soil's nodal fields shared first): see step and fem/assembly.hpp's RankShare.
  std::string on_several_ranks(const scene::Scene&) const override { return {}; }  // every option runs on several ranks
  void distribute(State<Dim>& st) override {
    parallel::distribute<Shape>(domain_, grid_, st, schedule_, material_particles_);
    fbar_.distribute(domain_);
  }

  void complete_output_fields(State<Dim>& st, bool) override {
    // The pore pressure and the fluid's velocity at the soil points, from the nodal solution.
    ParticleSet<Dim>& ps = st.solid;
    if (ps.size() == 0 || sd_.size() != ps.size()) return;
    const bool has_vf = !ps.v_f.empty();
    for (std::size_t p = 0; p < ps.size(); ++p) {
      double pp = 0.0;
      Vec<Dim> vf = Vec<Dim>::Zero();
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>&) {
        pp += N * p_[i];
        vf += N * v_[i];
      });
      ps.p[p] = pp;
      if (has_vf) ps.v_f[p] = vf;
    }
  }

  GridFields grid_fields(const State<Dim>&) const override {
    GridFields gf;
    if (parallel::rank() != 0) return gf;  // mpirun: every rank holds the whole grid; rank 0 writes it
    const auto& nn = grid_.nodes_per_axis();
    for (int a = 0; a < Dim; ++a) gf.nodes[a] = nn[a];
    const std::size_t n = grid_.num_nodes();
    gf.cloud.points.resize(n);
    grid_.for_each_node(grid_.all_nodes(), [&](std::size_t i, const std::array<int, Dim>& ijk) {
      const Vec<Dim> x = grid_.node_position(ijk);
      gf.cloud.points[i] = {x[0], x[1], Dim == 3 ? x[Dim - 1] : 0.0};
    });
    auto& v = gf.cloud.add("fluid_velocity", 3).values;
    auto& p = gf.cloud.add("pressure", 1).values;
    auto& phi = gf.cloud.add("phase_field", 1).values;
    auto& por = gf.cloud.add("porosity", 1).values;
    auto& th = gf.cloud.add("solid_fraction", 1).values;
    v.resize(3 * n, 0.0);
    p.resize(n);
    phi.resize(n);
    por.resize(n);
    th.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      for (int a = 0; a < Dim; ++a) v[3 * i + a] = v_[i][a];
      p[i] = p_[i];
      phi[i] = phi_[i];
      por[i] = soil_.n[i];
      th[i] = soil_.theta[i];
    }
    return gf;
  }

  bool fluid_on_grid() const override { return true; }
  std::size_t fluid_nodes() const override { return fgrid_.num_nodes(); }
  double grid_value(const std::array<double, 3>& x, GridQuantity q) const override {
    Vec<Dim> xp;
    for (int a = 0; a < Dim; ++a) xp[a] = x[a];
    if (!inside(xp)) return std::numeric_limits<double>::quiet_NaN();
    double out = 0.0;
    interpolate(xp, [&](std::size_t i, double N) {
      switch (q) {
        case GridQuantity::pressure: out += N * p_[i]; break;
        case GridQuantity::velocity_x: out += N * v_[i][0]; break;
        case GridQuantity::velocity_y: out += N * v_[i][1]; break;
        case GridQuantity::velocity_z: out += Dim == 3 ? N * v_[i][Dim - 1] : 0.0; break;
        case GridQuantity::phase: out += N * phi_[i]; break;
      }
    });
    return out;
  }
  /// Scans down the vertical line (x, y, z) from the grid's top in steps of h/16 for the first
  /// point with phi >= 1/2, then places the crossing by linear interpolation between the samples.
  double grid_water_level(double x, double z) const override {
    const double h = grid_.h(), top = grid_.max()[1], bottom = grid_.min()[1];
    std::array<double, 3> pt{x, top, z};
    double phi_above = grid_value(pt, GridQuantity::phase);
    if (std::isnan(phi_above)) return phi_above;
    for (double y = top - h / 16; y >= bottom - 1e-12; y -= h / 16) {
      pt[1] = std::max(y, bottom);
      const double phi = grid_value(pt, GridQuantity::phase);
      if (phi >= 0.5) return phi_above < 0.5 ? pt[1] + (phi - 0.5) / (phi - phi_above) * (h / 16) : top;
      phi_above = phi;
    }
    return std::numeric_limits<double>::quiet_NaN();
  }

  std::vector<typename Formulation<Dim>::Counter> counters() const override {
    const double V = phase_.volume(fluid_.phi, fsoil_.n);
    std::vector<typename Formulation<Dim>::Counter> c = {{"fluid steps", static_cast<double>(fluid_.solves), ""},
            {"fluid nodes (active region)", static_cast<double>(fgrid_.num_nodes()), ""},
            {"fluid region changes", static_cast<double>(region_changes_), ""},
            {"fluid factorisations", static_cast<double>(fluid_.factorisations()), ""},
            {"fluid Krylov iterations per step",
             fluid_.solves > 0 ? static_cast<double>(fluid_.krylov_iterations) / static_cast<double>(fluid_.solves) : 0.0, ""},
            {"water volume change", water_volume0_ > 0.0 ? (V - water_target_) / water_volume0_ * 100.0 : 0.0, "%"},
            {"water volume corrected", water_volume0_ > 0.0 ? water_corrected_ / water_volume0_ * 100.0 : 0.0, "%"},
            {"water outflow", water_volume0_ > 0.0 ? (water_volume0_ - water_target_) / water_volume0_ * 100.0 : 0.0, "%"}};
    domain_.add_counters(c);
    return c;
  }

  // Restart: the fluid's nodal state (v^L, v^{L-1}, p, phi) and the schedule order. The LU factor
  // is not saved: a restored run factorises afresh at its first step, and so does a saving run at
  // its next step (refactorise_), so that both continue with the same factor, bit for bit. Under
  // mpirun every rank holds the same fluid state (global arrays).
  void save(Checkpoint& c) const override {
    save_order(c, "formulation/schedule_order", schedule_);
    c.put_global("formulation/fluid_v", v_);
    c.put_global("formulation/fluid_v_old", v_old_);
    c.put_global("formulation/fluid_p", p_);
    c.put_global("formulation/phi", phi_);
    std::vector<double> region;
    for (int a = 0; a < Dim; ++a) region.insert(region.end(), {static_cast<double>(region_.lo[a]), static_cast<double>(region_.hi[a])});
    region.push_back(static_cast<double>(region_changes_));
    c.put_global("formulation/fluid_region", region);
    c.put_global("formulation/water_volume0", std::vector<double>{water_volume0_, water_target_, water_corrected_});
    c.put_global("formulation/multirate", std::vector<double>{static_cast<double>(substep_), soil_time_, fluid_time_});
    fluid_.refactorise();
  }
  void restore(const Checkpoint& c, State<Dim>& st) override {
    regroup_by_material(st.solid, material_particles_);
    restore_order(c, "formulation/schedule_order", schedule_);
    c.get("formulation/fluid_v", v_);
    c.get("formulation/fluid_v_old", v_old_);
    c.get("formulation/fluid_p", p_);
    c.get("formulation/phi", phi_);
    NodeBox<Dim> region = all_cells();  // checkpoints before the active region: the whole grid
    if (c.has("formulation/fluid_region")) {
      std::vector<double> r;
      c.get("formulation/fluid_region", r);
      for (int a = 0; a < Dim; ++a) region.lo[a] = static_cast<int>(r.at(2 * a)), region.hi[a] = static_cast<int>(r.at(2 * a + 1));
      region_changes_ = static_cast<long>(r.at(2 * Dim));
    }
    set_region(region, /*count=*/false);
    std::vector<double> v0;
    c.get("formulation/water_volume0", v0);
    water_volume0_ = v0.empty() ? -1.0 : v0[0];
    water_target_ = v0.size() > 1 ? v0[1] : water_volume0_;
    water_corrected_ = v0.size() > 2 ? v0[2] : 0.0;
    if (c.has("formulation/multirate")) {
      std::vector<double> m;
      c.get("formulation/multirate", m);
      substep_ = static_cast<int>(m.at(0));
      soil_time_ = m.at(1);
      fluid_time_ = m.at(2);
    }
    fluid_.refactorise();
  }

 private:
  static constexpr double kDefaultWidthCells = 3.0;  // interface 5 %-95 % width, cells
  static constexpr double kDefaultMobility = 200.0;   // 1/s, the interface's relaxation rate M W
  static constexpr double kMaxStep = 1e-3;            // s, dt auto with nothing moving

  /// The fluid's conditions on the grid faces (boundaries[].on = x_min ... z_max): impermeable
  /// stops the normal velocity, and with a fixed solid every component (no-slip); drained gives
  /// p = 0, pressure p = value. Faces without a `fluid` entry are impermeable where the solid is
  /// fixed, roller or friction, drained where it is free; faces not listed are drained (as the
  /// other formulations, loads.hpp GridBoundary::fluid).
  void face_conditions(const scene::Scene& s) {
    static const char* names[6] = {"x_min", "x_max", "y_min", "y_max", "z_min", "z_max"};
    for (int f = 0; f < 2 * Dim; ++f) {
      const int axis = f / 2, side = f % 2;
      FaceCondition& fc = faces_[f];
      fc.bits = 1u << Dim;  // drained (not listed)
      fc.value = 0.0;
      for (const auto& b : s.boundaries) {
        if (b.on != names[f]) continue;
        const bool impermeable = b.fluid ? *b.fluid == scene::FluidBc::impermeable : b.solid != scene::SolidBc::free;
        if (impermeable) {
          fc.bits = b.solid == scene::SolidBc::fixed ? static_cast<std::uint8_t>((1u << Dim) - 1) : static_cast<std::uint8_t>(1u << axis);
        } else {
          fc.bits = 1u << Dim;
          if (b.fluid && *b.fluid == scene::FluidBc::pressure) fc.value = b.fluid_value;
        }
      }
      if (fc.value != 0.0) pressure_faces_.push_back({axis, side, fc.value});
    }
  }

  /// The Dirichlet conditions of the fluid's grid (the active region): a face of the region on
  /// a face of the grid takes the grid face's condition, a face inside the grid is open (p = 0,
  /// drained: the air beyond is at rest at the atmosphere's pressure).
  typename fem::Fluid<Dim, Shape>::Conditions region_conditions(const NodeBox<Dim>& region) const {
    typename fem::Fluid<Dim, Shape>::Conditions bc;
    const Grid<Dim>& g = fgrid_;
    const std::size_t n = g.num_nodes();
    bc.fixed.assign(n, 0);
    bc.p_value.assign(n, 0.0);
    bc.face_load.assign(n, Vec<Dim>::Zero());
    const auto& nn = g.nodes_per_axis();
    for (int f = 0; f < 2 * Dim; ++f) {
      const int axis = f / 2, side = f % 2;
      const bool on_grid_face = side == 0 ? region.lo[axis] == 0 : region.hi[axis] == grid_.axis(axis).cells - 1;
      const std::uint8_t bits = on_grid_face ? faces_[f].bits : static_cast<std::uint8_t>(1u << Dim);
      const double value = on_grid_face ? faces_[f].value : 0.0;
      NodeBox<Dim> face = g.all_nodes();
      face.lo[axis] = face.hi[axis] = side == 0 ? 0 : nn[axis] - 1;
      g.for_each_node(face, [&](std::size_t i, const auto&) {
        bc.fixed[i] |= bits;
        if (bits >> Dim & 1) bc.p_value[i] = value;
      });
      if (bits >> Dim & 1)  // an open face: the backflow term (fluid.hpp) at its nodes
        g.for_each_node(face, [&](std::size_t i, const auto&) {
          bc.open.push_back({i, axis, side == 0 ? -1.0 : 1.0, porous::basis_integral<Shape>(g, i, axis)});
        });
      // A prescribed p != 0 pushes on the fluid through the face: the boundary term of the
      // pressure's integration by parts, -int N_I n p n_out dGamma (eq. 20's right-hand side).
      if (value != 0.0)
        g.for_each_node(face, [&](std::size_t i, const auto&) {
          bc.face_load[i][axis] -= value * (side == 0 ? -1.0 : 1.0) * porous::basis_integral<Shape>(g, i, axis);
        });
    }
    return bc;
  }

  // ---- The active region (docs/formulations.md, "mpm-fem", "Active region") ----
  // The fluid is solved on a box of cells that holds the water (a node with phi > kWetPhase) and
  // the soil, widened by kHalo cells. The box is a grid of its own, with the clamped B-splines at
  // its faces (fgrid_): where a face of the box is a face of the grid it takes the scene's
  // condition, elsewhere it is open (p = 0), and the air beyond is taken at rest. kHalo = p + 1
  // keeps the soil's nodes off the box's p boundary rows, whose clamped functions differ from the
  // grid's: there the box's nodes are the grid's, function for function, and the soil and the
  // fluid exchange nodal values by index. The box grows (never shrinks) when the water or the
  // soil comes within p cells of a face inside the grid, to 2 kHalo cells beyond them.
  static constexpr int kHalo = Shape::degree + 1;  // cells
  static constexpr double kWetPhase = 0.01;

  NodeBox<Dim> all_cells() const {
    NodeBox<Dim> b;
    for (int a = 0; a < Dim; ++a) b.lo[a] = 0, b.hi[a] = grid_.axis(a).cells - 1;
    return b;
  }

  static NodeBox<Dim> empty_box() {
    NodeBox<Dim> b;
    for (int a = 0; a < Dim; ++a) b.lo[a] = 0, b.hi[a] = -1;
    return b;
  }
  /// The nodes the soil's points reach this step (empty without soil; under mpirun every rank's
  /// points: soil_extent_).
  NodeBox<Dim> soil_nodes() const { return has_soil_ ? soil_extent_ : empty_box(); }
  /// The nodes points at these positions reach (before the first step's shape functions).
  NodeBox<Dim> points_node_box(const ParticleSet<Dim>& ps) const {
    if (ps.size() == 0) return empty_box();
    NodeBox<Dim> b;
    for (int a = 0; a < Dim; ++a) b.lo[a] = std::numeric_limits<int>::max(), b.hi[a] = -1;
    for (std::size_t q = 0; q < ps.size(); ++q)
      for (int a = 0; a < Dim; ++a) {
        const int c = std::clamp(static_cast<int>(std::floor((ps.x[q][a] - grid_.min()[a]) / grid_.h())), 0, grid_.axis(a).cells - 1);
        b.lo[a] = std::min(b.lo[a], c);
        b.hi[a] = std::max(b.hi[a], c + Shape::degree);  // a point in cell c reaches nodes c ... c + p
      }
    return b;
  }

  /// points_node_box of every rank's points (under mpirun each rank holds a slice of them). Collective.
  NodeBox<Dim> points_node_box_over_ranks(const ParticleSet<Dim>& ps) const {
    NodeBox<Dim> b = points_node_box(ps);
    if (ps.size() == 0)
      for (int a = 0; a < Dim; ++a) b.lo[a] = std::numeric_limits<int>::max();  // nothing to the union
    b = domain_.union_box(b);
    return has_soil_ ? b : empty_box();
  }

  /// The cells of the water and the soil: those in the support of a node with phi > kWetPhase
  /// (scanned within the cells `within`, or the whole grid when it is empty), and those that
  /// hold soil (its points reach nodes soil.lo ... soil.hi, a point in cell c nodes c ... c + p).
  NodeBox<Dim> content(const NodeBox<Dim>& soil, const NodeBox<Dim>& within) const {
    NodeBox<Dim> nodes;
    for (int a = 0; a < Dim; ++a) nodes.lo[a] = std::numeric_limits<int>::max(), nodes.hi[a] = -1;
    auto take = [&](const std::array<int, Dim>& ijk) {
      for (int a = 0; a < Dim; ++a) nodes.lo[a] = std::min(nodes.lo[a], ijk[a]), nodes.hi[a] = std::max(nodes.hi[a], ijk[a]);
    };
    NodeBox<Dim> scan = grid_.all_nodes();
    if (!within.empty())
      for (int a = 0; a < Dim; ++a) scan.lo[a] = within.lo[a], scan.hi[a] = within.hi[a] + Shape::degree;
    grid_.for_each_node(scan, [&](std::size_t i, const std::array<int, Dim>& ijk) {
      if (phi_[i] > kWetPhase) take(ijk);
    });
    // node i's clamped B-spline lives on cells i - p ... i
    NodeBox<Dim> cells;
    for (int a = 0; a < Dim; ++a) {
      cells.lo[a] = nodes.hi[a] < 0 ? std::numeric_limits<int>::max() : std::max(0, nodes.lo[a] - Shape::degree);
      cells.hi[a] = std::min(grid_.axis(a).cells - 1, nodes.hi[a]);
      if (!soil.empty()) {
        cells.lo[a] = std::min(cells.lo[a], soil.lo[a]);
        cells.hi[a] = std::max(cells.hi[a], soil.hi[a] - Shape::degree);
      }
    }
    return cells;
  }

  /// The content widened by `factor` kHalo cells (and `current` kept), clipped to the grid, and
  /// reaching every grid face with a prescribed pressure (the pressure acts through the air).
  NodeBox<Dim> wanted_region(const NodeBox<Dim>& soil, const NodeBox<Dim>& current, int factor) const {
    const NodeBox<Dim> all = all_cells(), c = content(soil, current);
    if (c.empty()) return all;  // neither water nor soil: the whole grid
    NodeBox<Dim> r;
    for (int a = 0; a < Dim; ++a) {
      r.lo[a] = std::max(all.lo[a], c.lo[a] - factor * kHalo);
      r.hi[a] = std::min(all.hi[a], c.hi[a] + factor * kHalo);
      if (!current.empty()) r.lo[a] = std::min(r.lo[a], current.lo[a]), r.hi[a] = std::max(r.hi[a], current.hi[a]);
    }
    for (const auto& pf : pressure_faces_) (pf.side == 0 ? r.lo[pf.axis] : r.hi[pf.axis]) = pf.side == 0 ? all.lo[pf.axis] : all.hi[pf.axis];
    return r;
  }

  /// True while the water and the soil stay more than p cells inside every face of the region
  /// that lies inside the grid.
  bool region_holds_content(const NodeBox<Dim>& soil) const {
    const NodeBox<Dim> c = content(soil, region_), all = all_cells();
    for (int a = 0; a < Dim; ++a) {
      if (region_.lo[a] > all.lo[a] && c.lo[a] - region_.lo[a] < Shape::degree) return false;
      if (region_.hi[a] < all.hi[a] && region_.hi[a] - c.hi[a] < Shape::degree) return false;
    }
    return true;
  }

  /// The fluid and the phase field on the cells `region`: their grid, pattern and conditions,
  /// and the nodal state copied from the whole grid's.
  void set_region(const NodeBox<Dim>& region, bool count = true) {
    Vec<Dim> lo, hi;
    for (int a = 0; a < Dim; ++a) {
      lo[a] = grid_.min()[a] + region.lo[a] * grid_.h();
      hi[a] = grid_.min()[a] + (region.hi[a] + 1) * grid_.h();
    }
    const bool first = fmap_.empty();
    bool same = !first;
    for (int a = 0; a < Dim && same; ++a) same = region.lo[a] == region_.lo[a] && region.hi[a] == region_.hi[a];
    region_ = region;
    if (!same) {
      fgrid_ = Grid<Dim>(lo, hi, grid_.h(), Shape::degree, true);
      fmap_.resize(fgrid_.num_nodes());
      fgrid_.for_each_node(fgrid_.all_nodes(), [&](std::size_t j, std::array<int, Dim> ijk) {
        for (int a = 0; a < Dim; ++a) ijk[a] += region.lo[a];
        fmap_[j] = grid_.index(ijk);
      });
      fluid_.setup(fgrid_, props_, region_conditions(region));
      phase_.setup(fgrid_, fluid_.basis(), phase_prm_);
      fsoil_.resize(fgrid_.num_nodes());
      if (count && !first) ++region_changes_;
    }
    for (std::size_t j = 0; j < fmap_.size(); ++j) {
      const std::size_t i = fmap_[j];
      fluid_.v[j] = v_[i];
      fluid_.v_old[j] = v_old_[i];
      fluid_.p[j] = p_[i];
      fluid_.phi[j] = phi_[i];
    }
    fluid_.refactorise();
  }

  /// The soil's nodal fields onto the region's nodes.
  void gather_soil() {
    const std::size_t n = fmap_.size();
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t i = fmap_[j];
      fsoil_.n[j] = soil_.n[i];
      fsoil_.theta[j] = soil_.theta[i];
      fsoil_.k[j] = soil_.k[i];
      fsoil_.rho_p[j] = soil_.rho_p[i];
      fsoil_.vs[j] = soil_.vs[i];
    }
  }
  /// The fluid's new state back onto the whole grid's nodes.
  void scatter_fluid() {
    const std::size_t n = fmap_.size();
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t i = fmap_[j];
      v_[i] = fluid_.v[j];
      v_old_[i] = fluid_.v_old[j];
      p_[i] = fluid_.p[j];
      phi_[i] = fluid_.phi[j];
    }
  }

  /// p at t = 0: hydrostatic under the phase field's water, rho(phi) |g| integrated down each
  /// vertical line of the fluid region's nodes from its top (p = 0 there); the first step's solve
  /// replaces it, and the soil's first pressure force reads the solved one. It spares the first
  /// steps the pressure increment from zero to hydrostatic (PSPG on the increment, fem/fluid.hpp).
  /// False when there is none (no gravity, or gravity ramped).
  bool initial_hydrostatic_pressure(const scene::Scene& s) {
    const double g = -s.gravity[1];
    if (!(g > 0.0) || s.gravity_ramp > 0.0 || s.initialisation.enabled()) return false;
    const auto& pr = props_;
    // down the region's own grid (its node positions: clamped B-splines at its faces), onto the
    // whole grid's nodes by fmap_
    const Grid<Dim>& fg = fgrid_;
    const int j_top = fg.nodes_per_axis()[1] - 1;
    NodeBox<Dim> top = fg.all_nodes();
    top.lo[1] = top.hi[1] = j_top;
    fg.for_each_node(top, [&](std::size_t, std::array<int, Dim> ijk) {
      double pp = 0.0;
      for (int j = j_top; j >= 0; --j) {
        ijk[1] = j;
        const std::size_t i = fmap_[fg.index(ijk)];
        if (j < j_top) {
          auto up = ijk;
          up[1] = j + 1;
          const std::size_t iu = fmap_[fg.index(up)];
          const double phi = std::clamp(0.5 * (phi_[i] + phi_[iu]), 0.0, 1.0);
          pp += (pr.rho_w * phi + pr.rho_a * (1.0 - phi)) * g * (fg.node_position(up)[1] - fg.node_position(ijk)[1]);
        }
        p_[i] = pp;
      }
    });
    return true;
  }

  /// (i)-(ii) Soil P2G and the fluid's view of the soil.
  void soil_to_grid(State<Dim>& st, const StepContext& ctx, const Vec<Dim>& b) {
    ParticleSet<Dim>& ps = st.solid;
    const std::size_t nodes = grid_.num_nodes();
    if (!has_soil_) {
      if (soil_.n.size() != nodes) soil_.resize(nodes);
      return;
    }
    long bad = -1;
    box_ = transfer::evaluate_shapes<Shape>(grid_, ps, sd_, bad);
    // Under mpirun: points that crossed a cut move to their rank first.
    if (parallel::migrate_sets<Shape>(domain_, grid_, st.step, parallel::StepSet{ps, schedule_, sd_, box_, bad})[0]) {
      st.index_ids();
      regroup_by_material(ps, material_particles_);
    }
    if (bad >= 0) st.health.report(bad, "solid", "left the grid (or position not finite)");
    collect_face_forces<Shape>(grid_, loads_, ps, st.index_of_id, ctx.t, box_, face_forces_);
    soil_extent_ = domain_.union_box(box_);  // mpirun: every rank's points' nodes (the fluid region follows them)
    box_ = domain_.node_box(box_);
    parallel::share_face_forces<Shape>(domain_, grid_, face_forces_, box_);  // mpirun: every rank's, in order
    transfer::build_schedule(grid_, sd_, schedule_);
    transfer::clear_nodes(grid_, box_, solid_);
    transfer::scatter_mass_momentum_force(grid_, schedule_, ps, sd_, b, solid_);
    parallel::weigh_face_forces(domain_, grid_, face_forces_, carries_mass(solid_));
    add_weighed_face_forces(grid_, face_forces_, solid_);
    // theta, n and k (eqs. 78, 79, 81)
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) { sums_[i] = SoilSums{}; });
    schedule_.run([&](int p) {
      const double V = ps.V[p], n = ps.n[p];
      const double k = to_intrinsic_ * perm_[ps.material[p]].at_point(n, V, ps.V0[p]);
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>&) {
        SoilSums& s = sums_[i];
        s.V += N * V;
        s.Vs += N * (1.0 - n) * V;
        s.mk += N * ps.m[p] * k;
      });
    }, sums_);
    // n = 1, theta = k = 0, v_s = 0 where no soil: reset where the soil was (its last node box)
    if (soil_.n.size() != nodes) soil_.resize(nodes);
    grid_.parallel_for_each_node(soil_box_, [&](std::size_t i, const auto&) {
      soil_.n[i] = 1.0;
      soil_.theta[i] = soil_.rho_p[i] = soil_.k[i] = 0.0;
      soil_.vs[i].setZero();
    });
    soil_box_ = box_;
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      const double m = solid_.acc[i].m;
      if (!(m > transfer::empty_node_mass)) {
        solid_.vL[i].setZero();
        return;
      }
      const SoilSums& s = sums_[i];
      soil_.theta[i] = std::min(1.0, s.V / support_[i]);
      soil_.n[i] = std::clamp(1.0 - s.Vs / support_[i], kMinNodalPorosity, 1.0);
      soil_.k[i] = s.mk / m;
      soil_.rho_p[i] = m / support_[i];
      solid_.vL[i] = solid_.acc[i].mv / m;
      soil_.vs[i] = solid_.vL[i];
    });
    // mpirun: the fluid (solved whole on every rank) and the cells of (v) read the soil's nodal
    // fields anywhere: each rank's own columns to every rank.
    domain_.share_owned_columns(soil_.n, soil_.theta, soil_.k, soil_.rho_p, soil_.vs);
  }


  /// (v) The fluid's pressure on the skeleton and the drag coefficient, per node, integrated over
  /// the cells that hold soil (eq. 54; Q lumped):
  ///   F_I = int ((1 - n) grad N_I - N_I grad n) p^{L+1},   Q_I = int N_I c(|v_f^L - v_s^L|).
  void fluid_on_soil(double) {
    std::fill(soil_force_.begin(), soil_force_.end(), Vec<Dim>::Zero());
    std::fill(drag_.begin(), drag_.end(), 0.0);
    // the cells with a node in the soil's node box
    std::array<int, Dim> lo, hi;
    for (int a = 0; a < Dim; ++a) lo[a] = std::max(0, box_.lo[a] - (S - 1)), hi[a] = std::min(grid_.axis(a).cells - 1, box_.hi[a]);
    const int threads = omp_get_max_threads();
    if (static_cast<int>(cell_.size()) < threads) cell_.resize(threads);
    const auto& pr = props_;
    fem::for_each_cell_coloured<Dim, S>(lo, hi, [&](const std::array<int, Dim>& c) {
      typename Basis::Cell& cl = cell_[omp_get_thread_num()];
      basis_.eval(c, cl);
      // A cell with soil: a node with soil mass (rho_p > 0 exactly there; under mpirun known for
      // every node, the cells reach below the rank's box).
      bool soil = false;
      for (int k = 0; k < Basis::K; ++k) soil = soil || soil_.rho_p[cl.node[k]] > 0.0;
      if (!soil) return;
      fem::FluidPoint<Dim> f;
      for (int gp = 0; gp < Basis::G; ++gp) {
        // v_f^L: fluid_.v_old after the step
        double n = 0.0, pp = 0.0, theta = 0.0, k = 0.0, phi = 0.0;
        Vec<Dim> gn = Vec<Dim>::Zero(), vf = Vec<Dim>::Zero(), vs = Vec<Dim>::Zero();
        for (int kk = 0; kk < Basis::K; ++kk) {
          const std::size_t i = cl.node[kk];
          const double N = cl.N[gp][kk];
          n += N * soil_.n[i];
          gn += soil_.n[i] * cl.dN[gp][kk];
          pp += N * p_[i];
          theta += N * soil_.theta[i];
          k += N * soil_.k[i];
          phi += N * phi_[i];
          vf += N * v_old_[i];
          vs += N * soil_.vs[i];
        }
        phi = std::clamp(phi, 0.0, 1.0);
        const double rho = pr.rho_w * phi + pr.rho_a * (1.0 - phi), mu = pr.mu_w * phi + pr.mu_a * (1.0 - phi);
        const double cd = fem::drag_coefficient(std::clamp(theta, 0.0, 1.0), n, k, mu, rho, (vf - vs).norm(), pr);
        const double w = cl.JxW[gp];
        for (int kk = 0; kk < Basis::K; ++kk) {
          const std::size_t i = cl.node[kk];
          soil_force_[i] += w * pp * ((1.0 - n) * cl.dN[gp][kk] - cl.N[gp][kk] * gn);
          drag_[i] += w * cl.N[gp][kk] * cd;
        }
      }
    });
  }

  /// (v) v_s^{L+1} = (M v_s^L + dt (F + Q v_f^{L+1})) / (M + dt Q), local damping on F; BCs.
  void update_soil_grid(double dt) {
    const double alpha = damping_;
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      const auto& nd = solid_.acc[i];
      const double m = nd.m;
      if (!(m > transfer::empty_node_mass)) {
        solid_.v[i].setZero();
        return;
      }
      const Vec<Dim> vL = solid_.vL[i];
      const Vec<Dim> F = local_damping<Dim>(Vec<Dim>(nd.f + soil_force_[i]), vL, alpha);
      const double Q = drag_[i];
      solid_.v[i] = (m * vL + dt * (F + Q * v_[i])) / (m + dt * Q);
    });
    bcs_solid_.apply(grid_, box_, solid_.v, true);
  }

  /// (vi) L = sum v_s (x) grad N; F, V, porosity ((1 - n) V constant, n <= 0.99); F-bar when the
  /// scene asks; the effective stress.
  long update_soil(State<Dim>& st, double dt) {
    ParticleSet<Dim>& ps = st.solid;
    const long n = static_cast<long>(ps.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      MatD<Dim> L = MatD<Dim>::Zero();
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double, const Vec<Dim>& dN) {
        L.noalias() += solid_.v[i] * dN.transpose();
      });
      ps.L[p] = L;
    }
    fbar_.apply(grid_, box_, schedule_, sd_, dt, st, materials_, material_particles_);
    long bad = transfer::no_particle;
#pragma omp parallel for schedule(static) reduction(min : bad) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      const double J = porous::update_skeleton<Dim>(ps.L[p], dt, ps.F[p], ps.V[p], ps.V0[p], ps.n[p]);
      ps.n[p] = std::min(ps.n[p], kMaxPointPorosity);
      if (!(J > 0.0) || !(ps.n[p] > 0.0)) bad = std::min(bad, p);
    }
    for (std::size_t k = 0; k < materials_.size(); ++k) {
      if (material_particles_[k].empty() || !materials_[k]) continue;
      const long m_bad = materials_[k]->update_stress(ps, material_particles_[k], dt);
      if (m_bad >= 0) st.health.report(m_bad, "solid", "stress update failed (" + materials_[k]->name() + ")");
    }
    return bad == transfer::no_particle ? -1 : bad;
  }

  /// A non-finite nodal velocity, pressure or phase field: the node is reported.
  void check_fluid(State<Dim>& st) const {
    for (std::size_t j = 0; j < fluid_.p.size(); ++j)
      if (!std::isfinite(fluid_.p[j]) || !fluid_.v[j].allFinite()) {
        const std::size_t i = fmap_[j];
        const Vec<Dim> x = grid_.node_position(grid_ijk(i));
        st.health.report_node(static_cast<long>(i), {x[0], x[1], Dim == 3 ? x[Dim - 1] : 0.0}, "fluid",
                              "fluid velocity or pressure not finite");
        return;
      }
  }
  std::array<int, Dim> grid_ijk(std::size_t i) const {
    std::array<int, Dim> ijk;
    for (int a = 0; a < Dim; ++a) {
      ijk[a] = static_cast<int>(i % static_cast<std::size_t>(grid_.nodes_per_axis()[a]));
      i /= static_cast<std::size_t>(grid_.nodes_per_axis()[a]);
    }
    return ijk;
  }

  bool inside(const Vec<Dim>& x) const {
    for (int a = 0; a < Dim; ++a)
      if (!(x[a] >= grid_.min()[a] - 1e-12 && x[a] <= grid_.max()[a] + 1e-12)) return false;
    return true;
  }
  template <class Fn>
  void interpolate(const Vec<Dim>& x, Fn&& fn) const {
    shape::ShapeData<Dim, S> sd;
    for (int a = 0; a < Dim; ++a) Shape::eval(grid_.axis(a), x[a], 0.0, sd.base[a], sd.w[a], sd.dw[a]);
    shape::for_each_node(grid_, sd, [&](std::size_t i, double N, const Vec<Dim>&) { fn(i, N); });
  }

  /// int g(fields) dOmega over the grid's cells (serial, fixed order): the fluid's energies. Under
  /// mpirun every rank holds the whole fluid: rank 0 gives the integral, the others 0 (the run
  /// sums the ranks' energies).
  template <class Fn>
  double fluid_integral(Fn&& g) const {
    double sum = 0.0;
    if (parallel::rank() != 0) return sum;
    typename Basis::Cell c;
    NodeBox<Dim> cells;
    for (int a = 0; a < Dim; ++a) cells.lo[a] = 0, cells.hi[a] = fgrid_.axis(a).cells - 1;
    fem::FluidPoint<Dim> f;
    fgrid_.for_each_node(cells, [&](std::size_t, const std::array<int, Dim>& ijk) {
      fluid_.basis().eval(ijk, c);
      for (int gp = 0; gp < Basis::G; ++gp) {
        fluid_.fields_at(c, gp, fsoil_, f);
        // fields_at's v is v^L of the coming step: the current nodal velocity
        sum += c.JxW[gp] * g(f);
      }
    });
    return sum;
  }

  Grid<Dim> grid_;
  GridBoundary<Dim> bcs_solid_;
  ParticleLoads<Dim> loads_;
  double flip_, damping_, scene_damping_;
  std::vector<std::unique_ptr<MaterialModel<Dim>>> materials_;
  std::vector<std::vector<int>> material_particles_;
  PhaseMaterials<Dim> phase_materials_;  // initialisation.materials: swapped in by set_initialisation
  std::vector<porous::Permeability> perm_;  // per material (soils)
  double to_intrinsic_ = 0.0;               // k [m^2] per k_h [m/s]: mu_w / (rho_w g)
  fem::FluidProperties props_;
  struct FaceCondition {
    std::uint8_t bits = 0;  // Fluid::Conditions::fixed's bits
    double value = 0.0;     // Pa, the prescribed pressure of an open face
  };
  std::array<FaceCondition, 2 * Dim> faces_;  // x_min, x_max, y_min, ...
  bool whole_grid_ = false;                    // solver.air.domain "grid"
  NodeBox<Dim> region_;                        // cells of grid_ the fluid is solved on
  Grid<Dim> fgrid_;                            // those cells as a grid (clamped B-splines)
  std::vector<std::size_t> fmap_;              // fgrid_'s node -> grid_'s node
  long region_changes_ = 0;
  std::vector<Vec<Dim>> v_, v_old_;  // m/s, the fluid's v^L, v^{L-1} on grid_'s nodes (0 outside the region)
  std::vector<double> p_, phi_;      // Pa and the phase field on grid_'s nodes
  fem::SoilOnGrid<Dim> fsoil_;       // soil_ on fgrid_'s nodes
  NodeBox<Dim> soil_box_;            // the soil's node box of the last step (soil_ set there)
  fem::PhaseFieldParameters phase_prm_;
  fem::Fluid<Dim, Shape> fluid_;
  struct PressureFace {
    int axis, side;
    double value;  // Pa
  };
  std::vector<PressureFace> pressure_faces_;  // grid faces with a prescribed p != 0 (their work)
  fem::PhaseField<Dim, Shape> phase_;
  double phase_mobility_ = 0.0;   // 1/s, M_phi
  double water_volume0_ = -1.0;  // m^Dim, int n phi at the first step (-1 before it)
  double water_target_ = -1.0;   // m^Dim, water_volume0_ less the outflow through open faces so far
  double water_corrected_ = 0.0;  // m^Dim, the phase field's volume corrections summed
  int substeps_ = 1;               // solver.soil_substeps: soil steps per fluid step
  int substep_ = 0;                // this step's place in its group of substeps_ (0: the fluid steps)
  double soil_time_ = 0.0;         // s, the soil's time since the start (the initialisation included)
  double fluid_time_ = 0.0;        // s, the fluid's (ahead of the soil's within a group)
  fem::SoilOnGrid<Dim> soil_;
  NodeFields<Dim> solid_;
  std::vector<SoilSums> sums_;
  std::vector<Vec<Dim>> soil_force_;  // N: the fluid's pressure on the skeleton (v)
  std::vector<double> drag_;          // kg/s: Q_I (v)
  std::vector<double> support_;       // m^Dim: Omega_I = int N_I
  Basis basis_;  // the B-splines on grid_'s cells (the soil's); fluid_.basis() is the region's
  std::vector<typename Basis::Cell> cell_;
  NodeBox<Dim> box_;
  NodeBox<Dim> soil_extent_;  // the nodes every rank's soil points reach this step (one rank: box_)
  bool has_soil_ = false;     // the run has soil points (on some rank)
  std::vector<shape::ShapeData<Dim, S>> sd_;
  std::vector<FaceForce<Dim, S>> face_forces_;
  StripeSchedule schedule_;
  Reorder<Dim> reorder_;
  FBar<Dim, S> fbar_;
  parallel::Domain<Dim> domain_;  // mpirun: this rank's stripes and soil points
};

}  // namespace

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_mpm_fem(const scene::Scene& s, const State<Dim>& state) {
  return make_for_shape<MpmFem, Dim>(s, state);
}

template std::unique_ptr<Formulation<2>> make_mpm_fem<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_mpm_fem<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
