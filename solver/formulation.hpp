// The contract between the one time loop (solver/run.cpp) and a formulation.
//
// A formulation owns its grid fields and kernels; the loop owns time, loads' clocks, output,
// monitors, progress and divergence handling. step() advances the state from t to t + dt with the
// body force of ctx (gravity already ramped) and must report the first particle whose state went
// bad (non-finite, J <= 0, outside the grid), or a grid node whose value did, in `Health` instead
// of throwing. The hooks after step() (output fields, grid fields, save/restore) are called by the
// loop between steps, per frame, monitor row or snapshot: never per particle.
#pragma once

#include <omp.h>

#include <array>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "scene/pointcloud.hpp"
#include "scene/scene.hpp"
#include "solver/output/checkpoint.hpp"
#include "solver/particles/particles.hpp"

namespace swmpm {

struct StepContext {
  double t = 0.0;   // s, time at the start of the step, as the loads' clock (0 during the
                    // initialisation phase, which runs at negative times: loads act as at t = 0)
  double dt = 0.0;  // s
  std::array<double, 3> gravity{0, 0, 0};  // m/s^2, ramp applied
};

/// Why a step failed: the smallest particle index with a problem, or else the smallest grid node
/// (flat index) with one, and what it was. A particle report takes precedence over a node report.
/// `remedy`: what to change, when the formulation knows (a state out of physical bounds that a
/// scene switch removes); empty: the time loop's generic advice (a smaller dt, the loads).
struct Health {
  long particle = -1;
  long node = -1;
  std::array<double, 3> node_x{0, 0, 0};  // m, the failed node's position (node >= 0)
  std::string phase;
  std::string what;
  std::string remedy;
  bool ok() const { return particle < 0 && node < 0; }
  void report(long p, std::string ph, std::string w, std::string r = {}) {
    if (p >= 0 && (particle < 0 || p < particle)) {
      particle = p;
      phase = std::move(ph);
      what = std::move(w);
      remedy = std::move(r);
    }
  }
  /// A value at grid node `i` (at `x`) went bad: kept unless a particle or a smaller node was reported.
  void report_node(long i, const std::array<double, 3>& x, std::string ph, std::string w) {
    if (i >= 0 && particle < 0 && (node < 0 || i < node)) {
      node = i;
      node_x = x;
      phase = std::move(ph);
      what = std::move(w);
      remedy.clear();
    }
  }
};

/// Grid fields a formulation adds to a frame (Formulation::grid_fields): `cloud.points` are the
/// node positions in the grid's flat order (x fastest: i + n0 (j + n1 k)), `nodes` the nodes per
/// axis (1 for the axes a 2D grid lacks), `cloud.arrays` the fields, 1 (scalar) or 3 (vector)
/// components per node. No arrays: no grid file for the frame.
struct GridFields {
  std::array<int, 3> nodes{1, 1, 1};
  scene::PointCloud cloud;
  bool empty() const { return cloud.arrays.empty(); }
};

template <int Dim>
struct State {
  ParticleSet<Dim> solid;
  /// Water points of the double-point formulations (particles/fluid.vtu; empty otherwise): x, v,
  /// m (water mass, constant), V (the mixture volume the point stands for, V = m / (n rho_w)),
  /// and through add_fluid() n (porosity at the point) and p (pore pressure, compression positive).
  ParticleSet<Dim> fluid;
  SurfaceSamples<Dim> surfaces;  // named-surface samples at t = 0 (empty without named surfaces)
  /// mpm-fem: the initial phase field preprocess wrote (particles/phase_field.vtu): the grid's
  /// nodes in flat order (x fastest) with the array `phi` (1 water, 0 air); empty otherwise.
  scene::PointCloud phase_field;
  double time = 0.0;
  long step = 0;
  /// mpirun: each rank holds a share of the sets (any slice of them, with their keys; a resume from
  /// a checkpoint's pieces) rather than the whole; the formulation's distribute then moves the
  /// particles to their owners (parallel::distribute) and clears it.
  bool shares = false;
  Health health;
  /// Current index of each particle id. Formulations may reorder particles for memory locality;
  /// ids are stable, so monitors and loads refer to particles by id through this table.
  std::vector<int> index_of_id;
  void index_ids() {
    std::int64_t max_id = -1;
    for (auto i : solid.id) max_id = std::max(max_id, i);
    // Under mpirun a rank holds some particles only: the table keeps the size of the whole set
    // (sized for every rank's ids at the start), and ids held elsewhere read -1.
    index_of_id.assign(std::max(index_of_id.size(), static_cast<std::size_t>(max_id + 1)), -1);
    for (std::size_t p = 0; p < solid.size(); ++p) index_of_id[solid.id[p]] = static_cast<int>(p);
  }
};

/// A field of an Eulerian fluid on the grid (mpm-fem) that a monitor reads at a fixed point.
enum class GridQuantity { pressure, velocity_x, velocity_y, velocity_z, phase };

/// Wall time spent in each named stage of step(), for the log and the benchmarks.
struct StageTimes {
  std::vector<std::string> names;
  std::vector<double> seconds;
  void add(const char* name, double s);
};

/// A step's clock: lap("stage") adds the wall time since the last lap (or since the clock
/// started) to `times` under that stage's name.
class StageClock {
 public:
  explicit StageClock(StageTimes& times) : times_(times), t0_(omp_get_wtime()) {}
  void operator()(const char* stage) {
    const double t1 = omp_get_wtime();
    times_.add(stage, t1 - t0_);
    t0_ = t1;
  }
  /// Starts the next lap now (after stages timed elsewhere and added to the times directly).
  void restart() { t0_ = omp_get_wtime(); }

 private:
  StageTimes& times_;
  double t0_;
};

template <int Dim>
class Formulation {
 public:
  virtual ~Formulation() = default;
  virtual std::string name() const = 0;
  /// Largest stable dt at the current state (s), and a sentence saying what limits it.
  virtual double critical_time_step(const State<Dim>& s, std::string& reason) const = 0;
  virtual void step(State<Dim>& s, const StepContext& ctx) = 0;
  /// Kinetic and stored elastic energy of the system [J or J/m], summed in a fixed order.
  virtual double kinetic_energy(const State<Dim>& s) const = 0;
  virtual double strain_energy(const State<Dim>& s) const = 0;
  /// Power of body forces and tractions [W or W/m] at the state, with the loads of ctx.
  virtual double external_power(const State<Dim>& s, const StepContext& ctx) const = 0;
  /// The initialisation phase (scene.initialisation) starts (`phase` set) or ends (nullptr):
  /// the phase's material parameters (initialisation.materials) and plastic flow off or on in the
  /// material models (PhaseMaterials::set, materials/material.hpp), the phase's permeability and
  /// damping in place of the scene's, and (double-point) the water points tied to their soil
  /// points. Called between steps by the time loop.
  virtual void set_initialisation(State<Dim>& s, const scene::Initialisation* phase) = 0;
  /// Under mpirun (solver/parallel/): what in this scene the formulation cannot yet do on several
  /// ranks, or empty when it runs there. Asked before anything is written.
  virtual std::string on_several_ranks(const scene::Scene& /*s*/) const {
    return "formulation " + name() + " does not run on several ranks yet";
  }
  /// Under mpirun: the particles each rank read (a slice, State::shares, or a whole one-rank
  /// checkpoint) go to their owners (parallel::distribute).
  /// Called once by the time loop, before frame 0 of a fresh run.
  virtual void distribute(State<Dim>& /*s*/) {}
  /// Cells holding at least one particle, at the last step.
  virtual std::size_t active_cells(const State<Dim>& s) const = 0;
  /// Fills the fields a formulation keeps only for output (semi-implicit double-point: the pore
  /// pressure and the water velocity interpolated at the soil points, from the last completed
  /// step's nodal solution; with `water_points`, also the water points' porosity and volume where
  /// they now are). The time loop calls it before monitors (soil fields only), frames and
  /// in-memory snapshots (`water_points`) read the particles; the step itself does not need these
  /// fields, so they are not computed every step.
  virtual void complete_output_fields(State<Dim>& /*s*/, bool /*water_points*/) {}
  const StageTimes& stage_times() const { return times_; }
  /// Run totals a formulation reports beside the stage times (run.json "counters", the log's last
  /// lines): name, value, unit. Empty unless something happened (double-point: escaped water).
  struct Counter {
    std::string name;
    double value;
    std::string unit;
  };
  virtual std::vector<Counter> counters() const { return {}; }
  /// Restart (solver/output/checkpoint.hpp): what a step carries to the next beyond the particle
  /// sets (the schedule order the next reordering reads, a linear solver's reused factor, counters),
  /// so that a resumed run continues bit for bit. restore() is called on a formulation built from
  /// the run's initial particles, after set_initialisation has been replayed as the run went
  /// (what it derives — damping, permeability, plastic flags, Nor-Sand's memory of an elastic
  /// phase — is then as it was) and after the checkpoint's particle sets are in `s`; it regroups
  /// whatever indexes the particles.
  /// The same pair keeps the in-memory last-good state (solver.checkpoint_every): the loop's
  /// snapshot is a Checkpoint in memory built as the restart file is, and a diverged run restores
  /// it (particles, then restore()) before it writes the last good state as its final frame.
  virtual void save(Checkpoint& c) const = 0;
  virtual void restore(const Checkpoint& c, State<Dim>& s) = 0;
  /// Grid fields for a frame at the current state (the last completed step's nodal values), written
  /// beside the particle frames as output/grid_NNNNNN.vtu (group `grid` of results.pvd). Called
  /// once per frame, after complete_output_fields; none by default. Not for the last-good frame
  /// of a diverged run (its nodal values are gone).
  virtual GridFields grid_fields(const State<Dim>& /*s*/) const { return {}; }
  /// Per-point fields a formulation adds to a frame's particle files beside those of the sets
  /// (explicit-double-point: `liquefied` on the solid points, `free_surface` on the liquid points).
  /// Called once per frame, after complete_output_fields; arrays added with the clouds' sizes.
  virtual void add_point_fields(const State<Dim>& /*s*/, scene::PointCloud& /*solid*/, scene::PointCloud& /*fluid*/) const {}
  /// An Eulerian fluid on the grid (mpm-fem): monitors of the fluid phase read it at their fixed
  /// point `at` (grid_value) and water_level gauges read the height where phi = 1/2
  /// (grid_water_level), from the last completed step's nodal values, instead of following water
  /// points. Both NaN outside the grid (and the level NaN where phi < 1/2 on the whole line).
  virtual bool fluid_on_grid() const { return false; }
  /// The grid nodes that carry the fluid's unknowns (mpm-fem), for the cost per node-step; 0 otherwise.
  virtual std::size_t fluid_nodes() const { return 0; }
  virtual double grid_value(const std::array<double, 3>& /*x*/, GridQuantity /*q*/) const {
    return std::numeric_limits<double>::quiet_NaN();
  }
  /// The highest height y on the vertical line (x, y, z) where phi crosses 1/2 from below
  /// (scanning down from the grid's top): the water's free surface.
  virtual double grid_water_level(double /*x*/, double /*z*/) const { return std::numeric_limits<double>::quiet_NaN(); }

 protected:
  StageTimes times_;
};

/// The formulation the scene names, for the scene's shape function (chosen here, once).
template <int Dim>
std::unique_ptr<Formulation<Dim>> make_formulation(const scene::Scene& s, const State<Dim>& state);
/// Whether this build has a solver for the formulation (formulations/registry.cpp).
bool has_solver(scene::Formulation f);

}  // namespace swmpm
