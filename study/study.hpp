// `swmpm study SCENE.json`: the user's scene at several resolutions, its cost against the
// estimated discretisation error of every monitor, and the cheapest resolution that meets a
// tolerance (issue 26, item 5; docs/study.md).
//
// The resolution is the cell size h. Every level keeps the scene's particles per cell (so the
// particle spacing refines with h) and its time-step rule: dt "auto" follows h through the CFL
// condition, a fixed time.dt is scaled with h (the same Courant number). Levels are
// h_j = h0 / r^j (h0 the scene's cell size, r the ratio, default 2 so that lattices nest and body
// edges stay on the particle lattice). The study runs each level through the same pipeline as
// `swmpm run` (preprocess, solve) in STUDY_DIR/runs/<label>/, from the coarsest to the finest the
// budget allows, and writes STUDY_DIR/{study.json, report.md, report.html, cost-error.png,
// scenes/<label>.json}.
#pragma once

#include <string>
#include <vector>

namespace swmpm::study {

struct StudyOptions {
  std::string scene_path;
  std::string out_dir;             // STUDY_DIR; empty: study/<scene name>
  double budget_minutes = 30.0;    // wall time the whole study may take
  double tolerance = 0.02;         // relative error the recommended level must meet
  int levels = 3;                  // at least this many levels (three for Richardson)
  double ratio = 2.0;              // refinement ratio r between levels
  std::vector<double> cell_sizes;  // explicit levels (coarse to fine, constant ratio); empty: planned
  std::vector<std::string> monitors;  // MONITOR or MONITOR.QUANTITY; empty: every monitor quantity
  std::string metric = "both";     // end | history | both
  double from = 0.0;               // s: the history metric starts here
  int threads = 0;                 // per run; 0: all cores
  bool quiet = false, overwrite = false, trust_geometry = false;
  double max_memory = 0.0;         // B, --max-memory per run
};

/// Runs the study. Returns the exit status: 0 when the report is written, 1 when the budget cannot
/// hold the fewest levels (after the coarsest run measured the cost), 4 when interrupted.
/// Throws scene::SceneError, files::RunDirectoryError and std::invalid_argument (an option; the
/// message names it) before anything is written; files::WriteError on a failed write.
int run_study(const StudyOptions& options);

}  // namespace swmpm::study
