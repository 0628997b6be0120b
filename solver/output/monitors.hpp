// monitors.csv: one row per recorded time, one column per "<monitor>.<quantity>".
// A point monitor follows one particle: the particle nearest to `at` at t = 0 (or the given id), a
// soil point, or with `points: "water"` a water point of the double-point set (State::fluid).
// A global monitor (no `at`, no `particle`) records energies of the whole system.
#pragma once

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
  /// `st` is the run's initial state (the particles monitors follow are chosen at t = 0); with
  /// `resume_bytes` the file is kept to that length and appended to (a resumed run).
  Monitors(const scene::Scene& s, const State<Dim>& st, const std::filesystem::path& path,
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
  /// One line per point monitor: which particle it follows and where it started.
  std::vector<std::string> describe(const State<Dim>& st) const;

 private:
  enum class Q { disp, vel, vel_fluid, stress, p_mean, q_dev, eps_p, pore, porosity, kinetic, strain, total, work };
  struct Column {
    std::int64_t particle;  // particle id, -1 for global
    Q q;
    int comp;
    bool water = false;  // a water point's id (State::fluid)
  };
  /// The current index of water point `id` (the formulation may reorder the set, or remove
  /// escaped water), or -1: the index found last time when it still holds the id, else a search.
  int water_index(const ParticleSet<Dim>& ws, std::int64_t id);
  std::vector<std::string> names_;
  std::vector<std::int64_t> monitor_particle_;  // ids, -1 for global
  std::vector<char> monitor_water_;             // per monitor: follows a water point
  std::vector<std::pair<std::int64_t, int>> water_found_;  // water point id -> index last found
  std::vector<Column> columns_;
  files::CheckedFile out_;
  std::ostringstream row_;  // one row, formatted before it is written
};

}  // namespace swmpm
