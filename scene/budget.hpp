// What a scene will cost before it runs: grid size (without integer overflow), particles, memory,
// steps, frames, bytes of output and wall time, from the scene and the formulation's row
// (scene/formulations.hpp, Cost). A scene that cannot fit in memory, or whose run would not end, is
// refused naming the key that drives the estimate (issue 27, items 4 and 5); one that is merely
// large gets a warning. docs/scene-format.md, "Limits".
#pragma once

#include <array>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace swmpm::scene {

/// Cells along one axis the grid may have: its node indices are 32-bit per axis, and a node index
/// of a particle's support (cells + degree + a few) must stay far from overflow.
inline constexpr double kMaxCellsPerAxis = 1 << 28;

/// The memory a run may use: `--max-memory`, or this machine's physical memory.
struct MemoryLimit {
  double bytes = 0.0;
  std::string what;  // "--max-memory 2 GB" or "this machine's memory, 23.5 GB"
};
/// `max_memory` in bytes (0: this machine's physical memory, /proc/meminfo MemTotal).
MemoryLimit memory_limit(double max_memory);
/// "8G", "512M", "2.5GB", "1e9" (bytes) -> bytes; throws std::invalid_argument.
double parse_memory_size(const std::string& text);
/// x with 3 significant digits ("%.3g"): "0.000133", "29.9", "3.15e+04".
std::string num(double x);
/// "1.2 GB", "340 MB", ...
std::string format_bytes(double bytes);
/// "3.2 h", "14 min", "40 s", "2.1 days", "3e+08 years".
std::string format_duration(double seconds);

/// Cells along each axis and nodes of the whole grid, in double (no overflow).
struct GridExtent {
  std::array<double, 3> cells{1, 1, 1};
  double nodes = 0.0;
};
GridExtent grid_extent(const Scene& s);

/// Lower bound of the solver's memory for `points` particles (and water points) on the scene's grid.
double run_memory(const Scene& s, double points);

/// Particles a body would seed: an estimate, with the lattice points its seeding scans.
struct BodyCount {
  double particles = 0.0;  // estimated particles of the body (inside its geometry)
  double scanned = 0.0;    // lattice points of its bounding box that seeding visits
  double wet = -1.0;       // of `particles`, those that carry pore water (below a water table); < 0: all
};

/// Refuses (SceneError naming `scene_file` and the key) a scene whose grid alone, or whose run with
/// `bodies[b]` particles, needs more than `limit`, or whose seeding would scan an absurd number of
/// lattice points. `bodies` may be empty (the grid only).
void check_memory(const Scene& s, const std::string& scene_file, const std::vector<BodyCount>& bodies,
                  const MemoryLimit& limit);

/// The solver's check, with the particles and water points preprocess wrote.
void check_run_memory(const Scene& s, const std::string& scene_file, double points, const MemoryLimit& limit);

/// What a run will cost from its first step: steps at the initial dt, frames, bytes and wall time.
struct RunEstimate {
  double steps = 0.0, frames = 0.0, monitor_rows = 0.0;
  double output_bytes = 0.0;  // frames + monitors.csv, a lower bound (compressed frames)
  double wall_seconds = 0.0;  // one thread at the bench machine's speed (Cost)
  std::string summary;        // one line for the log
};
/// One step of formulation `f` with `points` particles (and water points) on the scene's grid [µs],
/// one thread at the bench machine's speed: a fixed 20 µs, plus the Cost row's per particle and per
/// node of the whole grid.
double step_microseconds(const Scene& s, Formulation f, double points);

/// `points`: particles and water points; `dt`: the step the run starts with; `t_from`: the time it
/// starts from (the initialisation's start, or a checkpoint's time).
RunEstimate estimate_run(const Scene& s, double points, double dt, double t_from);

/// Hard limits refuse the run (SceneError, exit 2): a wall time over a year at the bench's speed, or
/// output over the free space of the run directory's disk. Soft ones are returned as warnings
/// (a day, 20 GB, half the free space), each naming the key that drives it.
std::vector<std::string> check_run_estimate(const Scene& s, const std::string& scene_file, const RunEstimate& e,
                                            double dt, const std::string& dt_reason, double free_disk_bytes);

}  // namespace swmpm::scene
