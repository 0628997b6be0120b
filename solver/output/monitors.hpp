// monitors.csv: one row per recorded time, one column per "<monitor>.<quantity>".
// A point monitor follows one particle: the particle nearest to `at` at t = 0 (or the given id), a
// soil point, or with `points: "water"` a water point of the double-point set (State::fluid).
// A global monitor (no `at`, no `particle`) records energies of the whole system.
// A water_level gauge (scene::Monitor::gauge, the file's "at": [x] in 2D, [x, z] in 3D) records the
// height of the liquid's free surface on the vertical line through (x, ·, z), y being vertical:
//
//     water_level = max { y_p + l_p,y : p a liquid point, |x_p − x| ≤ h/2 (and |z_p − z| ≤ h/2 in 3D) }
//
// over the liquid points of the double-point formulations (State::fluid: free water and pore water
// alike), y_p the point's position, l_p,y the half-height of its domain (ParticleSet::l, the initial
// GIMP half-size) and h the grid's cell size; h/2 is widened by 1e-9 of itself for round-off, so
// that a line through nodes sees the points on both sides at h/2. NaN when no liquid point is that
// close. Read afresh at every row: O(number of liquid points) per gauge, no allocation.
//
// A formulation whose fluid lives on the grid (Formulation::fluid_on_grid(), mpm-fem: an Eulerian
// fluid with a phase field phi, 1 water, 0 air) has no liquid points. There a monitor with
// "phase": "fluid" and `at` is an Eulerian probe: a fixed point of the grid, not a particle; each
// row reads the fluid's fields there from the last completed step's nodes,
//
//     pore_pressure = grid_value(at, pressure),  velocity_x|y|z = grid_value(at, velocity_x|y|z),
//
// and a water_level gauge reads grid_water_level(x, z): the highest height on its vertical line
// where phi crosses 1/2 from below, scanning down from the grid's top (NaN where phi < 1/2 on the
// whole line). Both are the formulation's interpolation of its nodal values (formulation.hpp).
// A monitor that follows a soil point (phase "solid", or `particle`) is the same as elsewhere.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "scene/files.hpp"
#include "scene/scene.hpp"
#include "solver/formulation.hpp"

namespace swmpm {

template <int Dim>
class Monitors {
 public:
  /// `st` is the run's initial state (the particles monitors follow are chosen at t = 0), `f` the
  /// run's formulation (whether its fluid is on the grid); with `resume_bytes` the file is kept to
  /// that length and appended to (a resumed run).
  Monitors(const scene::Scene& s, const State<Dim>& st, const Formulation<Dim>& f, const std::filesystem::path& path,
           const std::string& header_comment, std::optional<std::size_t> resume_bytes = std::nullopt);
  /// Bytes written to monitors.csv so far (a checkpoint records it).
  std::size_t bytes() const { return out_.size(); }
  /// Appends one row at the state's time.
  void record(const State<Dim>& st, const Formulation<Dim>& f, double external_work);
  /// Whether a column reads a field a formulation may fill only for output (pore pressure, water
  /// velocity at the soil points: Formulation::complete_output_fields).
  bool reads_output_fields() const {
    for (const auto& c : columns_)
      if (!c.water && (c.q == Q::pore || c.q == Q::vel_fluid)) return true;
    return false;
  }
  /// Whether a column reads a water point's porosity, which the formulation completes for output
  /// only (complete_output_fields with `water_points`).
  bool reads_water_points() const {
    for (const auto& c : columns_)
      if (c.water && c.q == Q::porosity) return true;
    return false;
  }
  /// One line per monitor: the particle it follows and where it started, a gauge's line, an
  /// Eulerian probe's point and what it reads, or "whole system".
  std::vector<std::string> describe() const;

 private:
  // Point quantities, then those of no particle (kinetic onwards: energies, work, a gauge's level,
  // an Eulerian probe's grid value).
  enum class Q {
    disp, vel, vel_fluid, stress, p_mean, q_dev, eps_p, pore, porosity,  // of one particle
    kinetic, strain, total, work, level, probe                            // of none
  };
  struct Column {
    std::int64_t particle;  // particle id, -1 for global
    Q q;
    int comp;            // component; for Q::level the index into gauges_, for Q::probe into probes_
    bool water = false;  // a water point's id (State::fluid)
    GridQuantity grid = GridQuantity::pressure;  // Q::probe: what it reads
  };
  /// A water_level gauge's vertical line [m].
  struct Gauge {
    double x, z;        // z unused in 2D
    bool grid = false;  // reads the formulation's phase field (grid_water_level), not liquid points
  };
  /// The level on a gauge's line (the definition above) [m], NaN when no liquid point is near it.
  double water_level(const ParticleSet<Dim>& ws, const Gauge& g) const;
  /// The current index of water point `id` (the formulation may reorder the set, or remove
  /// escaped water), or -1: the index found last time when it still holds the id, else a search.
  int water_index(const ParticleSet<Dim>& ws, std::int64_t id);
  std::vector<std::string> names_;
  std::vector<std::int64_t> monitor_particle_;  // ids, -1 for global
  std::vector<char> monitor_water_;             // per monitor: follows a water point
  std::vector<std::array<double, 3>> monitor_x0_;  // per monitor: the followed point's x0 (m; for the log)
  std::vector<int> monitor_gauge_;              // per monitor: index into gauges_, -1 for none
  std::vector<int> monitor_probe_;              // per monitor: index into probes_, -1 for none
  std::vector<Gauge> gauges_;
  std::vector<std::array<double, 3>> probes_;   // m, the Eulerian probes' fixed points
  std::vector<std::vector<std::string>> probe_reads_;  // per probe: its quantities, for describe()
  double reach_ = 0.0;  // m, a gauge reads the liquid points within this horizontal distance: h/2
  std::vector<std::pair<std::int64_t, int>> water_found_;  // water point id -> index last found
  std::vector<Column> columns_;
  files::CheckedFile out_;
  std::vector<double> values_, highest_;  // a row's values on this rank (record)
  std::ostringstream row_;  // one row, formatted before it is written
};

}  // namespace swmpm
