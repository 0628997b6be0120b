// Stability indicators of every run (issue 26, item 4): what the time loop measures at each frame
// (measure), and the run's record of them (StabilityReport): the per-frame history, the worst
// value of each with its place and time, one warning at an indicator's first crossing of its
// threshold, and the end summary, for run.json ("stability") and log.txt. The measures are those
// of indicators.hpp, which the tests use too. Definitions, thresholds and the run.json keys:
// docs/verification.md, "Stability indicators of every run", and docs/architecture.md.
#pragma once

#include <array>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "solver/formulation.hpp"

namespace swmpm::diagnostics {

/// The indicators, in the order of run.json and the log.
enum Indicator : int {
  pressure_checkerboard,
  mean_stress_checkerboard,
  energy_error,
  spurious_velocity,  // the at-rest speed over the run's velocity scale (below)
  porosity_min,
  porosity_max,
  J_min,
  J_max,
  cavitation_fraction,
  kIndicators
};

/// An indicator's run.json key, its name in messages, and its threshold: crossed when the value
/// is above it (`above`) or below it.
struct IndicatorSpec {
  const char* key;
  const char* label;
  double threshold;
  bool above;
};
inline constexpr std::array<IndicatorSpec, kIndicators> kSpecs{{
    {"pressure_checkerboard", "pressure checkerboard index", 0.1, true},
    {"mean_stress_checkerboard", "mean-stress checkerboard index", 0.1, true},
    {"energy_error", "energy balance error", 0.05, true},
    {"spurious_velocity", "spurious velocity at rest (over the velocity scale)", 0.25, true},
    {"porosity_min", "smallest porosity", 0.02, false},
    {"porosity_max", "largest porosity", 0.95, true},
    {"J_min", "smallest J = V/V0", 0.5, false},
    {"J_max", "largest J = V/V0", 2.0, true},
    {"cavitation_fraction", "cavitating fraction (points or nodes whose water is below -100 kPa gauge)", 0.01, true},
}};
inline bool crosses(Indicator k, double v) { return kSpecs[k].above ? v > kSpecs[k].threshold : v < kSpecs[k].threshold; }

/// Where a value was found: a point of a set by its stable id, or a grid node by its flat index.
struct Place {
  std::string set;  // "solid", "water" or "grid"; empty: nowhere in particular
  long id = -1;     // particle id, or node index
  std::array<double, 3> x{0, 0, 0};  // m
  int dim = 2;
  std::string text() const;            // "solid particle 12 at (0.5, 0.25)"
  nlohmann::ordered_json json() const;  // {"set", "particle" | "node", "position"}
};

/// One frame's indicators. value NaN: not measured at this frame (no point at rest yet);
/// a non-empty `omitted[k]`: the quantity does not exist in this run (why).
struct FrameIndicators {
  double time = 0.0;  // s
  std::array<double, kIndicators> value;
  std::array<Place, kIndicators> where;
  std::array<std::string, kIndicators> omitted;
  double spurious_speed = std::numeric_limits<double>::quiet_NaN();  // m/s, the at-rest speed itself
  double velocity_scale = std::numeric_limits<double>::quiet_NaN();  // m/s, what it is divided by
  std::size_t water_points = 0, cavitating = 0;  // the points cavitation counts, and those below the bound
  FrameIndicators() { value.fill(std::numeric_limits<double>::quiet_NaN()); }
};

/// The energies the formulation reports (J, or J/m in 2D): kinetic and stored now, their sum at
/// the start, and the external work since (solver/run.cpp's EnergyGuard).
struct Energies {
  double kinetic = 0.0, stored = 0.0, initial = 0.0, work = 0.0;
};

/// The indicators of a state, for one frame. `grid`: the formulation's grid fields of this frame
/// (mpm-fem: "pressure" and "phase_field" on the nodes, where its water is), or null.
/// `elapsed`: s since the run started (the initialisation's start included); `gravity` as ramped.
template <int Dim>
FrameIndicators measure(const State<Dim>& s, const GridFields* grid, const Energies& e,
                        const std::array<double, 3>& gravity, double elapsed);

/// The typical spacing (indicators.hpp's typical_spacing) of a set the ranks hold in shares
/// (`V0`: this rank's, `whole`: the set's size over the ranks), the same value. Collective.
double typical_spacing_over_ranks(std::span<const double> V0, int dim, long whole);

/// The run's record of its indicators.
class StabilityReport {
 public:
  /// Adds a frame's indicators; returns the warning lines of the indicators that cross their
  /// threshold for the first time in the run (later crossings are counted for the summary).
  std::vector<std::string> add(const FrameIndicators& f);
  /// The log's line for a frame.
  static std::string frame_line(const FrameIndicators& f);
  /// The log's last lines: the worst of each indicator, and each crossed one with its count.
  std::vector<std::string> summary() const;
  /// run.json's "stability": thresholds, omitted quantities, the per-frame history as arrays, the
  /// worst values, the warnings, the cost. restore() reads it back (resumed runs).
  nlohmann::ordered_json json() const;
  void restore(const nlohmann::ordered_json& j);
  void add_seconds(double s) { seconds_ += s; }
  double seconds() const { return seconds_; }
  std::size_t frames() const { return time_.size(); }
  /// The worst value of an indicator so far (NaN: never measured), and the frames that crossed.
  double worst(Indicator k) const { return worst_[k].value; }
  int crossings(Indicator k) const { return worst_[k].crossings; }

 private:
  struct Worst {
    double value = std::numeric_limits<double>::quiet_NaN();
    double time = 0.0;
    Place where;
    int crossings = 0;
  };
  std::vector<double> time_;
  std::array<std::vector<double>, kIndicators> history_;
  std::vector<double> spurious_speed_;
  std::array<Worst, kIndicators> worst_;
  std::array<std::string, kIndicators> omitted_;
  std::vector<std::string> warnings_;
  double seconds_ = 0.0;
};

}  // namespace swmpm::diagnostics
