// The one time loop: every formulation runs through solve().
#pragma once

#include <string>

namespace swmpm {

struct SolveOptions {
  int threads = 0;     // 0: all cores
  bool quiet = false;  // no terminal output (log.txt is still written)
  bool resume = false;  // continue from RUN_DIR/checkpoint.bin (--resume)
};

/// Runs the formulation of RUN_DIR/scene.json on RUN_DIR/particles/*.vtu and writes output/,
/// monitors.csv, run.json and log.txt. Returns the process exit status: 0 completed, 3 diverged,
/// 4 interrupted. Setup errors (bad run directory, unsupported model) throw std::runtime_error.
int solve(const std::string& run_dir, const SolveOptions& options);

}  // namespace swmpm
