// Formulation `semi-implicit-double-point`: seed 001's incremental fractional-step two-phase MPM
// (Xie, Navas, López-Querol 2025, §3-4.5) with the water on its own points (State::fluid), which
// move with the water velocity and take the nodal porosity of the soil (eqs. 46-51). The stages
// common to both variants are core.hpp's and pressure.hpp's (docs/formulations.md derives them).
//
// One step (numbers are the paper's algorithm steps, §4.5):
//   (0) reorder both sets into scatter order every 10 steps (memory locality only)
//   (1) shape data of soil and water points, active node box, scatter schedules
//   (2) P2G: M_s, M_s v_s, nodal porosity and conductivity (soil-mass weighted, eqs. 44-47),
//       effective-stress forces; the water points first take their porosity and volume from the
//       nodal porosity, then M_w and M_w v_w (eqs. 50-51); the points' moments of (5a) in the same
//       passes (cell moments)
//   (5a)-(5b) L, D_s, D_w (eqs. 61-63), the nodal p^t, free-surface and drained nodes
//   (3)-(4) M_w = n_I sum S rho_w V (eq. 50); body forces; water and soil predictors (eqs. 52-53)
//       with the drag implicit and the pressure force -G p^t; BCs
//   (5c) pressure increment: L dp = -(1/dt) div q* (eq. 60, conservation form); CHOLMOD
//   (6) corrections v^{t+1} = v* - dt/M (G dp) (eqs. 64-68); BCs; p^{t+1} at the water points
//   (7) G2P (FLIP/PIC) of the soil points, positions; MUSL remap of the soil velocity (step 8a)
//   (8)-(9) F, V, porosity (1 - n) J = 1 - n0; F-bar; stress; the water points' G2P and
//       positions. Their porosity and volume (step 8h with the M_s erratum, eq. 36) come from the
//       next step's nodal porosity, in its water P2G (docs/formulations.md, "Water points'
//       porosity"); the initialisation's tie, or the escaped water's removal, last.
#include <array>
#include <span>

#include "solver/formulations/semi_implicit/core.hpp"
#include "solver/porous/free_surface.hpp"
#include "solver/porous/tie.hpp"

namespace swmpm {
namespace {

using semi_implicit::Weights;

template <int Dim, class Shape>
class SemiImplicitDoublePoint final : public semi_implicit::Core<Dim, Shape> {
  using Core = semi_implicit::Core<Dim, Shape>;
  using Core::S, Core::kCellMoments, Core::reorder_interval;
  using Core::grid_, Core::box_, Core::schedule_, Core::reorder_, Core::material_particles_, Core::sd_,
      Core::pressure_, Core::water_, Core::node_, Core::flip_, Core::domain_;
  using Pressure = typename Core::Pressure;

 public:
  SemiImplicitDoublePoint(const scene::Scene& s, const State<Dim>& state)
      : Core(s, state, state.fluid, "semi-implicit-double-point") {
    remove_escaped_ = s.solver.escaped_water == "remove";
    rho_w_points_.resize(s.materials.size(), 0.0);
    for (std::size_t k = 0; k < s.materials.size(); ++k)
      if (s.materials[k].model == scene::MaterialModel::fluid) rho_w_points_[k] = s.materials[k].at("density");
    const std::size_t nodes = grid_.num_nodes();
    water_sums_.resize(nodes);  // zero (NodeArray)
    support_.resize(nodes);
    for (std::size_t i = 0; i < nodes; ++i) support_[i] = porous::basis_integral<Shape>(grid_, i);
    const ParticleSet<Dim>& ws = state.fluid;
    this->derive_laplace_if_single_densities(state.solid, ws, [&](int p) { return rho_w_points_[ws.material[p]]; });
  }
  std::string name() const override { return "semi-implicit-double-point"; }
  /// mpirun: both sets over the ranks, the cuts balanced on their particles together.
  void distribute(State<Dim>& st) override {
    parallel::distribute<Shape>(domain_, grid_, st, schedule_, &wschedule_);
    regroup_by_material(st.solid, material_particles_);
    pressure_.distribute(domain_);
    this->fbar_.distribute(domain_);
  }

  void step(State<Dim>& st, const StepContext& ctx) override {
    // The nodal data of the last step are overwritten below: output fields not filled by now stay
    // as they are (a failed step leaves them; a completed one marks them stale again).
    output_fields_stale_ = water_output_stale_ = false;
    ParticleSet<Dim>& ps = st.solid;
    ParticleSet<Dim>& ws = st.fluid;
    const double dt = ctx.dt;
    StageClock lap(this->times_);

    if (reorder(st)) lap("reorder");                                                         // (0)

    evaluate_shapes(st);                                                                     // (1)
    this->prepare_nodes(st, ctx);
    lap("shape functions");

    auto soil_weights = [&](int p, bool without_l) { return soil_point_weights(ps, p, without_l); };
    if (remove_escaped_) this->template scatter_soil<false, true>(ps, soil_weights);         // (2)
    else this->template scatter_soil<false, false>(ps, soil_weights);
    this->nodal_porosity();
    const long bad_n = scatter_water_points(ws);
    if (bad_n >= 0) st.health.report(bad_n, "fluid", "water-point porosity outside (0, 1]");
    this->add_face_forces();
    lap("p2g");

    assemble_pressure(ps, ws);                                                               // (5a)-(5b)
    lap("pressure assembly");

    water_mass_from_porosity();                                                              // (3)-(4)
    this->predict(dt, Core::gravity(ctx));
    lap("predictor");

    if (!this->solve_pressure(st, dt)) return;                                               // (5c)
    lap("pressure solve");

    this->correct(dt);                                                                       // (6)
    const long bad_p = pressure_.update_points(wschedule_, sdw_, ws, [&](int p) { return ws.m[p]; });
    output_fields_stale_ = water_output_stale_ = true;  // the soil points' p, v_f; the water points' n, V
    if (bad_p >= 0) st.health.report(bad_p, "fluid", "pore pressure not finite");
    lap("correction");

    this->template gather_soil<false>(ps, dt);                                               // (7)
    lap("g2p + musl remap");

    this->update_soil(st, dt);                                                               // (8)-(9)
    porous::gather_free_points(grid_, sdw_, flip_, dt, ws, water_);  // the water points' G2P, positions
    if (tie_) report_untied(st, porous::tie_positions(ps, st.index_of_id, partner_, ws));
    else if (remove_escaped_) remove_escaped_water(ws);
    lap("stress and porosity");
  }

  double kinetic_energy(const State<Dim>& st) const override {
    const auto &ps = st.solid, &ws = st.fluid;
    return fixed_order_sum(ps.size(), [&](std::size_t p) { return 0.5 * ps.m[p] * ps.v[p].squaredNorm(); }) +
           fixed_order_sum(ws.size(), [&](std::size_t p) { return 0.5 * ws.m[p] * ws.v[p].squaredNorm(); });
  }
  double external_power(const State<Dim>& st, const StepContext& ctx) const override {
    const auto &ps = st.solid, &ws = st.fluid;
    const Vec<Dim> b = Core::gravity(ctx);
    const double gravity = fixed_order_sum(ps.size(), [&](std::size_t p) { return b.dot(ps.m[p] * ps.v[p]); }) +
                           fixed_order_sum(ws.size(), [&](std::size_t p) { return b.dot(ws.m[p] * ws.v[p]); });
    return Core::external_power(gravity, st, ctx);
  }
  void set_initialisation(State<Dim>& st, const scene::Initialisation* phase) override {
    // The phase's seepage velocities belong to its permeability, not the scene's: each water point
    // with a coincident soil point restarts at that point's velocity (see single_point.cpp).
    if (this->set_phase(phase) && !partner_.empty())
      report_untied(st, porous::tie_velocities(st.solid, st.index_of_id, partner_, st.fluid));
    tie_ = phase && phase->tie_water;
    if ((tie_ || (phase && phase->hydraulic_conductivity)) && partner_.empty())
      partner_ = parallel::coincident_points(domain_, st.solid, st.fluid);  // over every rank's points (mpirun)
  }
  /// Restart: beyond the core's, the water points' schedule order, the initialisation's water-point
  /// partners and the escaped-water totals (the same on every rank under mpirun). The output-only
  /// fields are complete in a checkpoint (the loop completes them first), so nothing is stale
  /// after a restore.
  void save(Checkpoint& c) const override {
    this->save_core(c);
    save_order(c, "formulation/water_schedule_order", wschedule_, "fluid");
    c.put_global("formulation/partner", partner_);
    c.header["formulation_state"] = {{"escaped_points", escaped_points_}, {"escaped_mass", escaped_mass_}};
  }
  void restore(const Checkpoint& c, State<Dim>& st) override {
    this->restore_core(c, st);
    restore_order(c, "formulation/water_schedule_order", wschedule_);
    c.get("formulation/partner", partner_);
    escaped_points_ = c.header.at("formulation_state").at("escaped_points");
    escaped_mass_ = c.header.at("formulation_state").at("escaped_mass");
    output_fields_stale_ = water_output_stale_ = false;
  }
  std::vector<typename Formulation<Dim>::Counter> counters() const override {
    auto c = Core::counters();
    if (remove_escaped_) {
      c.push_back({"escaped_water_points", static_cast<double>(escaped_points_), "water points removed (solver.escaped_water)"});
      c.push_back({"escaped_water_mass", escaped_mass_, "kg (per metre in 2D)"});
    }
    return c;
  }

  /// The soil points' pore pressure, p^{t+1} interpolated from the nodes (the projected p^t plus
  /// the increment, with the step's shape data), and the water velocity v_w^{t+1} at them; the
  /// water points' porosity and volume where they are now. For output and monitors only: the time
  /// loop asks for them when it writes.
  void complete_output_fields(State<Dim>& st, bool water_points) override {
    if (water_points && water_output_stale_) {
      water_output_stale_ = false;
      complete_water_porosity(st.solid, st.fluid);
    }
    complete_soil_fields(st.solid);
  }

 private:
  /// complete_output_fields of the soil points: p^{t+1} and v_w^{t+1}, with the step's shape data.
  void complete_soil_fields(ParticleSet<Dim>& ps) {
    if (!output_fields_stale_) return;
    output_fields_stale_ = false;
    const auto& dp = pressure_.dp();
    const long m = static_cast<long>(ps.size());
#pragma omp parallel for schedule(static) if (m > parallel_threshold)
    for (long p = 0; p < m; ++p) {
      double value = 0.0;
      Vec<Dim> vw = Vec<Dim>::Zero();
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>&) {
        value += N * (pressure_.p_at_node(i) + dp[i]);
      });
      shape::for_each_node(grid_, sd_[p], [&](std::size_t i, double N, const Vec<Dim>&) { vw += N * water_.v[i]; });
      ps.p[p] = value;
      ps.v_f[p] = vw;
    }
  }

  /// Double-point water P2G sums of one node in register pairs: {sum S m, sum S rho_w V} and, in
  /// 2D, sum S m v (3D: water_.acc's mv), one packed multiply-add each per point and node; copied
  /// into water_.acc and node_ after the pass. (With sum S m v as an Eigen vector here instead:
  /// 18 more instructions per point-step, callgrind B4 6².)
  struct WaterSums {
    Pair m_raw{0.0, 0.0};
    Pair mv{0.0, 0.0};
  };

  /// (0) Both sets in last step's schedule order every reorder_interval steps.
  bool reorder(State<Dim>& st) {
    const bool soil = reorder_for_locality(st, schedule_, reorder_, material_particles_, reorder_interval, &domain_);
    return reorder_set(st.fluid, st.step, wschedule_, wreorder_, reorder_interval, &domain_) || soil;
  }
  /// (1) The shape data of the soil points and of the water points (weights only with the cell
  /// moments: they take no gradient in the P2G, the moments, the G2P or the projection; the
  /// point-wise D^w and L need them), the box of both sets, the water's schedule. Under mpirun the
  /// points of both sets that crossed a cut move to their rank first (parallel::migrate_sets),
  /// and the box is the rank's.
  void evaluate_shapes(State<Dim>& st) {
    long bad = -1, wbad = -1;
    box_ = transfer::evaluate_shapes<Shape>(grid_, st.solid, sd_, bad);
    NodeBox<Dim> wbox = transfer::evaluate_shapes<Shape>(grid_, st.fluid, sdw_, wbad);
    parallel::own_both_sets<Shape>(domain_, grid_, st, material_particles_, parallel::StepSet{st.solid, schedule_, sd_, box_, bad},
                                   parallel::StepSet{st.fluid, wschedule_, sdw_, wbox, wbad});
    if (bad >= 0) st.health.report(bad, "solid", "left the grid (or position not finite)");
    if (wbad >= 0) st.health.report(wbad, "fluid", "water point left the grid (or position not finite)");
    this->join_box(wbox);
    box_ = domain_.node_box(box_);
    transfer::build_schedule(grid_, sdw_, wschedule_);
  }

  /// A tied water point whose soil point this rank does not hold (tie_positions; mpirun only: a
  /// tied pair shares its position and so its stripe).
  static void report_untied(State<Dim>& st, long w) {
    if (w >= 0)
      st.health.report(w, "fluid", "tied water point whose soil point another rank holds (the pair's supports differ)");
  }

  /// A water point's porosity n_p and volume V = m / (n_p rho_w) (eq. 36: n V = n0 V0); returns V.
  double set_water_porosity(ParticleSet<Dim>& ws, std::size_t p, double np) const {
    ws.n[p] = np;
    return ws.V[p] = ws.m[p] / (np * rho_w_points_[ws.material[p]]);
  }

  /// (2) Water points (eqs. 50-51, 56), in one pass per point:
  ///   (8h)-(8i) of the previous step: the porosity at the point, n_p = sum S n_I (n_I of this
  ///   step's soil points, nodal_porosity()), and its volume V = m / (n_p rho_w) (eq. 36);
  ///   P2G: sum S rho_w V, sum S m v, sum S m (the velocity weights of eq. 51), from which
  ///   water_mass_from_porosity forms M_w and the predictor the body force n_I (sum S rho_w V) b;
  ///   the points' extent for the free surface.
  /// The seed maps the soil's porosity with the shape functions of the step that updated it
  /// (step 8h); here the next step's soil P2G maps it, with the points where they now are, and no
  /// pass of its own (docs/formulations.md, "Water points' porosity"). Returns the first point
  /// whose porosity is outside (0, 1], or -1.
  long scatter_water_points(ParticleSet<Dim>& ws) {
    const bool laplace_derived = pressure_.laplace_derived();
    auto& surface = pressure_.surface();
    long bad = transfer::no_particle;
    auto scatter = [&](int p) __attribute__((always_inline)) {
      double np = 0.0;
      shape::for_each_node(grid_, sdw_[p], [&](std::size_t i, double N, const auto&) { np += N * node_[i].n; });
      if (!(np > 0.0 && np <= 1.0 + 1e-12)) {
#pragma omp critical(swmpm_water_porosity)
        bad = std::min(bad, static_cast<long>(p));
      }
      const double m = ws.m[p], rhoV = rho_w_points_[ws.material[p]] * set_water_porosity(ws, p, np);
      const Vec<Dim> mv = m * ws.v[p];
      const Vec<Dim> x_lo = ws.x[p] - ws.l[p], x_hi = ws.x[p] + ws.l[p];
      surface.add_at_base(grid_, sdw_[p], x_lo, x_hi);
      if constexpr (kCellMoments) {
        const Weights c = water_point_weights(ws, p, laplace_derived);
        pressure_.moments().template add<false, true>(grid_, sdw_[p].base, ws.x[p], 0.0, c.w, c.l);
      }
      const Pair m_rhoV{m, rhoV}, mv_pair{mv[0], mv[1]};
      shape::for_each_node(grid_, sdw_[p], [&](std::size_t i, double N, const auto&) {
        WaterSums& w = water_sums_[i];
        w.m_raw += N * m_rhoV;
        if constexpr (Dim == 2) w.mv += N * mv_pair;
        else water_.acc[i].mv += N * mv;
        surface.add_at_node(i, N, x_lo, x_hi);
      });
    };
    // Under mpirun the scattered node arrays are exchanged at the cuts (StripeSchedule::run); the
    // free surface's test reads the extents of supports starting below a node (the ghosts' too).
    if constexpr (Dim == 2) wschedule_.run(scatter, water_sums_, surface.extents());
    else wschedule_.run(scatter, water_sums_, water_.acc, surface.extents());
    if constexpr (porous::SupportCut<Dim, Shape>::kBaseExtent) pressure_.fill_ghosts(surface.extents());
    // Into the node fields the rest of the step reads (and zero for the next step's points).
    this->grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) {
      WaterSums& w = water_sums_[i];
      auto& a = water_.acc[i];
      a.m = w.m_raw[0];
      if constexpr (Dim == 2) a.mv = Vec<Dim>(w.mv[0], w.mv[1]);
      node_[i].w_raw = w.m_raw[1];
      w = WaterSums{};
    });
    return bad == transfer::no_particle ? -1 : bad;
  }

  /// (3) v_w^t = sum S m v / sum S m, then M_w = n_I sum S rho_w V (eq. 50), whose body force
  /// M_w b (eq. 56) the predictor adds (no load acts on the water).
  void water_mass_from_porosity() {
    this->nodal_water_velocity();
    grid_.parallel_for_each_node(box_, [&](std::size_t i, const auto&) { water_.acc[i].m = node_[i].n * node_[i].w_raw; });
  }

  /// (5a)-(5b) the nodal p^t from the water points' pressures, the nodes' roles, then D^s from
  /// the soil points, D^w from the water points and L from both.
  void assemble_pressure(const ParticleSet<Dim>& ps, const ParticleSet<Dim>& ws) {
    pressure_.fit(wschedule_, sdw_, ws, [&](int p) { return ws.V[p]; });
    pressure_.set_node_roles(water_);
    if constexpr (kCellMoments) {
      pressure_.assemble_from_moments(schedule_);
    } else {
      pressure_.run_operators(schedule_, [&](int p) { pressure_.template add_operators<true, false>(sd_[p], soil_point_weights(ps, p)); });
      pressure_.run_operators(wschedule_, [&](int p) { pressure_.template add_operators<false, true>(sdw_[p], water_point_weights(ws, p)); });
    }
  }
  /// A soil point carries the soil's shares only, s = (1 - n) V and l = V (1 - n)/rho_s; a water
  /// point the water's, w = n V and l = n V / rho_w (without_l: l left 0, derived by the moments).
  Weights soil_point_weights(const ParticleSet<Dim>& ps, int p, bool without_l = false) const {
    const double V = ps.V[p], n = ps.n[p];
    if (without_l) return {(1.0 - n) * V, 0.0, 0.0};
    return {(1.0 - n) * V, 0.0, V * (1.0 - n) / Core::grain_density(ps, p)};
  }
  Weights water_point_weights(const ParticleSet<Dim>& ws, int p, bool without_l = false) const {
    const double nV = ws.n[p] * ws.V[p];
    return {0.0, nV, without_l ? 0.0 : nV / rho_w_points_[ws.material[p]]};
  }

  /// Output only: the water points' porosity and volume where the points are now, as the next
  /// step's P2G will find them (scatter_water_points): the soil's porosity mapped to the nodes
  /// with the soil points' current shape functions, n_I = sum S m n / sum S m (1 where no soil),
  /// interpolated at each water point, V = m / (n rho_w). The soil's sums go in one thread in
  /// point order (the same numbers with any number of threads); frames are rare.
  /// Under mpirun the step has moved the points by less than a cell since they were binned, so
  /// their supports lie within kGhost columns of their rank's own: each rank sums its soil points,
  /// the ghost columns' sums are added to their owners' (PETSc's ADD_VALUES) and the totals copied
  /// back (the ranks' partial sums added in another order than one rank's: equal to rounding).
  void complete_water_porosity(const ParticleSet<Dim>& ps, ParticleSet<Dim>& ws) {
    static_assert(Pressure::kGhost >= S, "a point's support after a step's move must lie within the ghost columns");
    long bad = -1;
    NodeBox<Dim> box = transfer::evaluate_shapes<Shape>(grid_, ps, out_sd_, bad);
    const NodeBox<Dim> wbox = transfer::evaluate_shapes<Shape>(grid_, ws, out_sdw_, bad);
    for (int a = 0; a < Dim; ++a) {
      box.lo[a] = std::min(box.lo[a], wbox.lo[a]);
      box.hi[a] = std::max(box.hi[a], wbox.hi[a]);
    }
    if (out_m_.empty()) {  // zero (NodeArray): memory only for the nodes the boxes reach
      out_m_.resize(grid_.num_nodes());
      out_mn_.resize(grid_.num_nodes());
    }
    if (domain_.active()) {  // the rank's own columns and the ghosts either side, on every other axis
      const int a = domain_.axis();
      const auto [lo, hi] = domain_.owned_columns();
      for (int b = 0; b < Dim; ++b) box.lo[b] = 0, box.hi[b] = grid_.nodes_per_axis()[b] - 1;
      box.lo[a] = std::max(0, lo - Pressure::kGhost);
      box.hi[a] = std::min(grid_.nodes_per_axis()[a] - 1, hi + Pressure::kGhost - 1);
    }
    grid_.for_each_node(box, [&](std::size_t i, const auto&) { out_m_[i] = out_mn_[i] = 0.0; });  // all the sets reach
    for (std::size_t p = 0; p < ps.size(); ++p) {
      const double m = ps.m[p], mn = m * ps.n[p];
      shape::for_each_node(grid_, out_sd_[p], [&](std::size_t i, double N, const auto&) {
        out_m_[i] += N * m;
        out_mn_[i] += N * mn;
      });
    }
    for (auto* sums : {&out_m_, &out_mn_}) {
      domain_.add_ghosts_to_owners(*sums, Pressure::kGhost);
      domain_.fill_ghosts(*sums, Pressure::kGhost);
    }
    const long n = static_cast<long>(ws.size());
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) {
      double np = 0.0;
      shape::for_each_node(grid_, out_sdw_[p], [&](std::size_t i, double N, const auto&) {
        np += N * porous::porosity_at_node(out_mn_[i], out_m_[i], 1.0);
      });
      set_water_porosity(ws, static_cast<std::size_t>(p), np);
    }
  }

  /// solver.escaped_water = remove: the water points outside the soil leave the run — an outflow
  /// through the drained free surface into a reservoir that is not modelled (B2: the water
  /// squeezed out of the top would otherwise float above the soil as a sheet thinner than a cell,
  /// whose surface nodes take p = 0 and cut the soil off its drained top). "Outside": the soil's
  /// volume fraction at the point (porous::volume_fraction_at_point) is below one half (the
  /// soil's surface is where it is 1/2). Shape data and nodal sums of the start of the step;
  /// removal keeps the order of the remaining points (thread-independent).
  void remove_escaped_water(ParticleSet<Dim>& ws) {
    const long n = static_cast<long>(ws.size());
    escaped_.resize(ws.size());
    auto soil_volume = [&](std::size_t i) { return node_[i].soil_volume; };
    auto support = [&](std::size_t i) { return support_[i]; };
#pragma omp parallel for schedule(static) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) escaped_[p] = porous::volume_fraction_at_point(grid_, sdw_[p], soil_volume, support) < 0.5;
    const std::size_t n0 = ws.size();
    long removed = 0;
    double mass = 0.0;
    for (std::size_t p = 0; p < n0; ++p)
      if (escaped_[p]) ++removed, mass += ws.m[p];
    // The run's totals (mpirun: over the ranks, the same on every rank).
    std::array<double, 2> totals{static_cast<double>(removed), mass};
    parallel::sum(std::span<double>(totals));
    escaped_points_ += static_cast<long>(totals[0]);
    escaped_mass_ += totals[1];
    if (removed == 0) return;
    ws.for_each_field([&](auto& f) {
      if (f.size() != n0) return;  // fields the water points do not use
      std::size_t k = 0;
      for (std::size_t p = 0; p < n0; ++p)
        if (!escaped_[p]) f[k++] = f[p];
      f.resize(k);
    });
  }

  std::vector<double> rho_w_points_;   // per fluid material: the water points' density
  bool tie_ = false;                   // initialisation: water points follow their soil points
  std::vector<std::int64_t> partner_;  // per water-point id: the coincident soil point's id (-1: none)
  bool remove_escaped_ = false;        // solver.escaped_water = remove
  std::vector<char> escaped_;          // per water point, this step (reused)
  long escaped_points_ = 0;            // removed so far
  double escaped_mass_ = 0.0;          // kg (per metre in 2D), removed so far
  NodeArray<WaterSums> water_sums_;  // zero between steps (scatter_water_points)
  std::vector<double> support_;        // per node: integral of its basis function over the grid
  std::vector<shape::ShapeData<Dim, S, !kCellMoments>> sdw_;       // weights only with the cell moments
  std::vector<shape::ShapeData<Dim, S, false>> out_sd_, out_sdw_;  // complete_water_porosity (output only)
  NodeArray<double> out_m_, out_mn_;                               // per node, complete_water_porosity
  bool output_fields_stale_ = false;  // the soil points' p and v_f lag the last step (complete_output_fields)
  bool water_output_stale_ = false;   // the water points' n and V lag the last step
  StripeSchedule wschedule_;
  Reorder<Dim> wreorder_;
};

}  // namespace

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_semi_implicit_double_point(const scene::Scene& s, const State<Dim>& state) {
  return make_for_shape<SemiImplicitDoublePoint, Dim>(s, state);
}

template std::unique_ptr<Formulation<2>> make_semi_implicit_double_point<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_semi_implicit_double_point<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
