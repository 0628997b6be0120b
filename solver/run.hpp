// The one time loop: every formulation runs through solve().
#pragma once

#include <functional>
#include <memory>
#include <string>

namespace swmpm {

namespace scene {
struct Scene;
}
template <int Dim>
class Formulation;
template <int Dim>
struct State;

/// Builds the formulation in place of the one the scene names (tests: a formulation that wraps a
/// real one to exercise the loop's hooks). Called once, with the run's initial state.
template <int Dim>
using FormulationFactory =
    std::function<std::unique_ptr<Formulation<Dim>>(const scene::Scene&, const State<Dim>&)>;

struct SolveOptions {
  int threads = 0;     // 0: all cores
  bool quiet = false;  // no terminal output (log.txt is still written)
  bool resume = false;  // continue from RUN_DIR/checkpoint.bin (--resume)
  double max_memory = 0.0;  // B, --max-memory: refuse a run that needs more (0: the machine's memory)
  /// Called from the time loop at most twice a second with the share of the run's time span done
  /// (0 to 1), whether or not the terminal shows progress: `swmpm study` draws one bar over its runs.
  std::function<void(double done)> progress = nullptr;
};

/// Runs the formulation of RUN_DIR/scene.json on RUN_DIR/particles/*.vtu and writes output/,
/// monitors.csv, run.json and log.txt. Returns the process exit status: 0 completed, 3 diverged,
/// 4 interrupted. Setup errors (bad run directory, unsupported model) throw std::runtime_error.
int solve(const std::string& run_dir, const SolveOptions& options);
/// solve() with the formulation the factory of the scene's dimension builds (an empty factory:
/// the scene's formulation, make_formulation).
int solve(const std::string& run_dir, const SolveOptions& options, const FormulationFactory<2>& factory_2d,
          const FormulationFactory<3>& factory_3d);

}  // namespace swmpm
