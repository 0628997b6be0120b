// Formulation `dry`: single-phase explicit MPM, MUSL (Sulsky et al. 1995) with a FLIP/PIC blend.
//
// One step (each line a named stage, timed):
//   (1) shape data at x_n, active node box, scatter schedule
//   (2) P2G: m_i, (mv)_i, f_i = f_int + f_body                 (transfer::scatter_mass_momentum_force)
//   (3) + tractions on face particles                          (ParticleLoads)
//   (4) grid: vL_i = (mv)_i / m_i, local damping, v_i = vL_i + dt f_i / m_i, BCs on v_i
//   (5) G2P: v_p (FLIP/PIC blend), x_p += dt sum N v_i
//   (6) MUSL: remap momentum with the new v_p, v_i = (mv)_i / m_i, BCs   (fused with (5): one pass)
//   (7) L_p = sum v_i (x) grad N_ip; F, V; then F-bar when solver.stabilisation.fbar is set (transfer/fbar.hpp)
//   (8) stress update per material
#include <sstream>
#include <omp.h>

#include <limits>

#include "solver/formulation.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/loads.hpp"
#include "solver/materials/material.hpp"
#include "solver/parallel/particles.hpp"
#include "solver/transfer/fbar.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm {
namespace {

template <int Dim, class Shape>
class Dry final : public Formulation<Dim> {
  static constexpr int S = Shape::support;

 public:
  Dry(const scene::Scene& s, const State<Dim>& state)
      : grid_(make_grid<Dim>(s, Shape::degree, Shape::bspline)),
        bcs_(s, grid_, state.surfaces),
        loads_(s, grid_, state.solid, state.surfaces),
        flip_(s.solver.flip),
        damping_(s.solver.damping),
        scene_damping_(s.solver.damping),
        materials_(make_materials<Dim>(s)),
        phase_materials_(s),
        material_particles_(group_by_material(state.solid, s.materials.size())),
        fbar_(s, grid_) {
    nodes_.resize(grid_.num_nodes());
  }

  std::string name() const override { return "dry"; }

  void step(State<Dim>& st, const StepContext& ctx) override {
    ParticleSet<Dim>& ps = st.solid;
    const double dt = ctx.dt;
    Vec<Dim> b;
    for (int a = 0; a < Dim; ++a) b[a] = ctx.gravity[a];
    StageClock lap(this->times_);

    // (0) every reorder_interval steps, store the particles in last step's schedule order, so the
    //     transfers below walk particle memory sequentially (results stay thread-independent).
    if (reorder_for_locality(st, schedule_, reorder_, material_particles_, reorder_interval, &domain_)) lap("reorder");
    long bad = -1;
    box_ = transfer::evaluate_shapes<Shape>(grid_, ps, sd_, bad);                       // (1)
    // Under mpirun: particles that crossed a cut move to their rank; the rank's node box.
    if (parallel::own_particles<Shape>(domain_, grid_, st, schedule_, sd_, box_, bad))
      regroup_by_material(ps, material_particles_);
    if (bad >= 0) st.health.report(bad, "solid", "left the grid (or position not finite)");
    // Tractions act at the particles' face points (ParticleLoads).
    collect_face_forces<Shape>(grid_, loads_, ps, st.index_of_id, ctx.t, box_, face_forces_);
    parallel::share_face_forces<Shape>(domain_, grid_, face_forces_, box_);  // mpirun: every rank's, in order
    lap("shape functions");
    transfer::build_schedule(grid_, sd_, schedule_);
    lap("schedule");
    transfer::clear_nodes(grid_, box_, nodes_);

    transfer::scatter_mass_momentum_force(grid_, schedule_, ps, sd_, b, nodes_);       // (2)
    parallel::weigh_face_forces(domain_, grid_, face_forces_, carries_mass(nodes_));      // (3)
    add_weighed_face_forces(grid_, face_forces_, nodes_);
    lap("p2g");

    update_grid(dt);                                                                    // (4)
    lap("grid update");

    transfer::gather_velocity_position_remap(grid_, schedule_, box_, sd_, dt, flip_, ps, nodes_);  // (5)-(6)
    bcs_.apply(grid_, box_, nodes_.v, false);
    lap("g2p + musl remap");

    bad = transfer::gather_velocity_gradient(grid_, nodes_, sd_, dt, ps);               // (7)
    if (bad >= 0) st.health.report(bad, "solid", "volume ratio J = det F <= 0 (or not finite)");
    lap("velocity gradient");
    if (fbar_.apply(grid_, box_, schedule_, sd_, dt, st, materials_, material_particles_)) lap("f-bar");  // (7b)

    for (std::size_t k = 0; k < materials_.size(); ++k) {                               // (8)
      if (material_particles_[k].empty()) continue;
      const long m_bad = materials_[k]->update_stress(ps, material_particles_[k], dt);
      if (m_bad >= 0) st.health.report(m_bad, "solid", "stress update failed (" + materials_[k]->name() + ")");
    }
    lap("stress update");
  }

  double critical_time_step(const State<Dim>& st, std::string& reason) const override {
    // CFL: dt = h / (c_p + |v|max), c_p = sqrt(M / rho) the P-wave speed of each material.
    // Per material the largest modulus and the smallest density, over all ranks.
    const ParticleSet<Dim>& ps = st.solid;
    const std::size_t K = materials_.size();
    std::vector<double> rho_min(K, std::numeric_limits<double>::max());
    for (std::size_t k = 0; k < K; ++k)
      for (int p : material_particles_[k]) rho_min[k] = std::min(rho_min[k], ps.m[p] / ps.V[p]);
    parallel::min(std::span<double>(rho_min));
    const std::vector<double> modulus = max_p_wave_moduli(materials_, ps, material_particles_);
    double c_max = 0.0;
    for (std::size_t k = 0; k < K; ++k)
      if (rho_min[k] < std::numeric_limits<double>::max()) c_max = std::max(c_max, std::sqrt(modulus[k] / rho_min[k]));
    double v_max = 0.0;
    const long n = static_cast<long>(ps.size());
#pragma omp parallel for reduction(max : v_max) if (n > parallel_threshold)
    for (long p = 0; p < n; ++p) v_max = std::max(v_max, ps.v[p].norm());
    v_max = parallel::max(v_max);
    std::ostringstream os;
    os << "P-wave CFL (c = " << c_max << " m/s, |v|max = " << v_max << " m/s)";
    reason = os.str();
    return grid_.h() / (c_max + v_max);
  }

  double kinetic_energy(const State<Dim>& st) const override {
    return fixed_order_sum(st.solid.size(), [&](std::size_t p) { return 0.5 * st.solid.m[p] * st.solid.v[p].squaredNorm(); });
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
    loads_.for_each_force(ctx.t, st.index_of_id, [&](int p, const Vec<Dim>& f_p, const Vec<Dim>&, bool) { power += f_p.dot(ps.v[p]); });
    return power;
  }
  void set_initialisation(State<Dim>&, const scene::Initialisation* phase) override {
    phase_materials_.set(materials_, phase);  // the phase's parameters and plastic flag (materials/material.hpp)
    damping_ = phase_damping(phase, scene_damping_);
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
  void save(Checkpoint& c) const override { save_order(c, "formulation/schedule_order", schedule_); }
  void restore(const Checkpoint& c, State<Dim>& st) override {
    regroup_by_material(st.solid, material_particles_);  // the checkpoint's particle order
    restore_order(c, "formulation/schedule_order", schedule_);
  }

 private:
  void update_grid(double dt) {
    // vL_i = (mv)_i / m_i;  f_i -= alpha |f_i| sign(vL_i) (local damping);  v_i = vL_i + dt f_i / m_i
    const double alpha = damping_;
    grid_.for_each_node(box_, [&](std::size_t i, const auto&) {
      const auto& nd = nodes_.acc[i];
      const double m = nd.m;
      if (m <= transfer::empty_node_mass) {
        nodes_.vL[i].setZero();
        nodes_.v[i].setZero();
        return;
      }
      const Vec<Dim> vL = nd.mv / m;
      const Vec<Dim> f = local_damping<Dim>(nd.f, vL, alpha);
      nodes_.vL[i] = vL;
      nodes_.v[i] = vL + dt / m * f;
    });
    // BCs act on the end-of-step velocity only: vL keeps the momentum the particles brought, so
    // the FLIP increment v - vL removes what a wall takes away (constraining vL as well would
    // hide that loss and let particles push into walls step after step).
    bcs_.apply(grid_, box_, nodes_.v, true);
  }

  Grid<Dim> grid_;
  GridBoundary<Dim> bcs_;
  ParticleLoads<Dim> loads_;
  double flip_, damping_, scene_damping_;
  std::vector<std::unique_ptr<MaterialModel<Dim>>> materials_;
  PhaseMaterials<Dim> phase_materials_;  // initialisation.materials: swapped in by set_initialisation
  std::vector<std::vector<int>> material_particles_;
  NodeFields<Dim> nodes_;
  NodeBox<Dim> box_;
  std::vector<shape::ShapeData<Dim, S>> sd_;
  StripeSchedule schedule_;
  Reorder<Dim> reorder_;
  parallel::Domain<Dim> domain_;  // mpirun: this rank's stripes (inactive at one rank)
  std::vector<FaceForce<Dim, S>> face_forces_;
  FBar<Dim, S> fbar_;
  static constexpr long reorder_interval = 10;  // steps
};

}  // namespace

template <int Dim>
std::unique_ptr<Formulation<Dim>> make_dry(const scene::Scene& s, const State<Dim>& state) {
  return make_for_shape<Dry, Dim>(s, state);
}

template std::unique_ptr<Formulation<2>> make_dry<2>(const scene::Scene&, const State<2>&);
template std::unique_ptr<Formulation<3>> make_dry<3>(const scene::Scene&, const State<3>&);

}  // namespace swmpm
