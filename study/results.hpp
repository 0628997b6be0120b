// What a study measured and estimated: shared by study.cpp (which runs the levels and computes the
// estimates) and report.cpp (which writes study.json, report.md, report.html and the chart).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene/files.hpp"
#include "study/richardson.hpp"

namespace swmpm::study {

/// One resolution of the study and what its run reported.
struct LevelRun {
  int j = 0;                 // h = h0 / r^j
  double h = 0.0;            // m, cell size
  std::string label;         // "h0.025": scenes/<label>.json, runs/<label>/
  std::string status;        // run.json status (completed, diverged, ...), "refused: ..." or "failed: ..."
  double predicted = 0.0;    // s, the wall time predicted before it ran (0: the first run, not predicted)
  double preprocess = 0.0;   // s, preprocess's wall time
  double wall = 0.0;         // s, run.json wall_seconds (solve)
  double loop = 0.0;         // s, run.json loop_seconds
  double particles = 0.0;    // all phases
  double steps = 0.0, dt = 0.0, end_time = 0.0, us_per_particle_step = 0.0;
  nlohmann::json worst;      // run.json stability.worst (null: not run)
  std::vector<std::string> crossed;  // indicators that crossed their threshold: "energy_error 0.07 (above 0.05)"
  bool completed() const { return status == "completed"; }
  double cost() const { return preprocess + wall; }  // s, what the level cost the study
};

/// The estimate of one monitor quantity under one metric.
struct Series {
  std::string column;   // monitors.csv column "<monitor>.<quantity>"
  std::string metric;   // end | history
  std::string skipped;  // why it was not estimated (empty: estimated)
  Extrapolation e;
  double scale = 0.0;   // the relative errors are e.error / scale
  double magnitude = 0.0;  // largest |q| of the finest run's history
  std::size_t samples = 0;
  std::vector<double> relative;  // per level of the block
  std::string name() const { return column + " (" + metric + ")"; }
};

struct Results {
  std::string scene_path, scene_name, study_dir, formulation, shape_function, dt_rule;
  int dimension = 2;
  double h0 = 0.0, ratio = 2.0, tolerance = 0.02, budget_seconds = 0.0, from = 0.0, end_time = 0.0;
  std::string metric;
  bool fixed = false;             // the levels came from --cell-sizes
  std::vector<LevelRun> levels;   // every level run, coarse to fine
  std::size_t first = 0, count = 0;  // the block of consecutive completed levels the estimates use
  std::vector<Series> series;
  std::vector<std::string> notes;  // planning decisions (a level dropped for the budget, ...)
  // The verdict: the cheapest level of the block whose every estimated relative error is within
  // the tolerance (-1: none), else the worst series at the finest level and the cell size that
  // would meet the tolerance at its order, with the cost predicted for it.
  int recommended = -1;
  std::string worst_series;
  double worst_error = 0.0;
  double needed_cell_size = std::numeric_limits<double>::quiet_NaN();
  double needed_seconds = std::numeric_limits<double>::quiet_NaN();
  double total_seconds = 0.0;
};

/// Writes study.json, cost-error.png, report.md and report.html into the study directory (each
/// claimed on `ledger`, which is the study directory's). Returns the report.md path.
std::string write_outputs(const Results& r, files::RunDirectory& ledger);

}  // namespace swmpm::study
