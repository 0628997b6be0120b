#include "scene/budget.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <sys/resource.h>

#include "scene/formulations.hpp"

namespace swmpm::scene {

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

namespace {

/// The memory this process may have: the machine's (MemTotal), or less under an address-space
/// limit (ulimit -v) or a cgroup's memory.max (a container, a batch job). 0: unknown.
double available_memory() {
  double bytes = 0.0;
  auto take = [&](double b) {
    if (b > 0.0 && (bytes == 0.0 || b < bytes)) bytes = b;
  };
  {
    std::ifstream in("/proc/meminfo");
    std::string key, unit;
    double kb = 0.0;
    while (in >> key >> kb >> unit)
      if (key == "MemTotal:") take(kb * 1024.0);
  }
  rlimit r{};
  if (getrlimit(RLIMIT_AS, &r) == 0 && r.rlim_cur != RLIM_INFINITY) take(static_cast<double>(r.rlim_cur));
  std::ifstream cgroup("/sys/fs/cgroup/memory.max");
  std::string max;
  if (cgroup >> max && max != "max") {
    try {
      take(std::stod(max));
    } catch (const std::exception&) {
    }
  }
  return bytes;
}

const Cost& cost_of(const Scene& s) { return row_of(s.formulation).cost; }

double node_bytes(const Scene& s) {
  const Cost& c = cost_of(s);
  return c.bytes_per_node * (s.dimension == 3 ? c.node_bytes_3d : 1.0);
}

/// Points a body of `particles` seeds in the solver: double-point bodies with soil and water have
/// one set of each (the water's only below a water table: `wet` of them, < 0 all); mpm-fem's
/// free water lives on the grid.
double solver_points(const Scene& s, std::size_t b, double particles, double wet) {
  const WaterLayout w = row_of(s.formulation).water;
  const Body& body = s.bodies[b];
  if (!w.fluid_particles && !w.free_water_on_grid && body.solid.empty()) return particles;
  double points = body.solid.empty() ? 0.0 : particles;
  if (w.fluid_particles && !body.fluid.empty()) points += body.solid.empty() || wet < 0.0 ? particles : wet;
  return points;
}

/// Bytes preprocess holds per particle while it seeds: the seed points, the kept copy, the clouds.
constexpr double kPreprocessBytesPerParticle = 300.0;
/// Lattice points seeding may scan (an inside test each; about a minute).
constexpr double kMaxScanned = 2e9;

}  // namespace

MemoryLimit memory_limit(double max_memory) {
  if (max_memory > 0.0) return {max_memory, "--max-memory " + format_bytes(max_memory)};
  const double machine = available_memory();
  return {machine, "the memory this process may use, " + format_bytes(machine) +
                       " (the machine's, a ulimit -v or a cgroup's memory.max; --max-memory sets it)"};
}

double parse_memory_size(const std::string& text) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    throw std::invalid_argument("got \"" + text + "\", expected a size such as 8G, 512M or 2e9");
  }
  std::string unit = text.substr(used);
  std::transform(unit.begin(), unit.end(), unit.begin(), [](unsigned char c) { return std::toupper(c); });
  if (!unit.empty() && unit.back() == 'B') unit.pop_back();
  double factor = 1.0;
  if (unit == "K") factor = 1024.0;
  else if (unit == "M") factor = 1024.0 * 1024.0;
  else if (unit == "G") factor = 1024.0 * 1024.0 * 1024.0;
  else if (unit == "T") factor = 1024.0 * 1024.0 * 1024.0 * 1024.0;
  else if (!unit.empty()) throw std::invalid_argument("got \"" + text + "\", expected a size such as 8G, 512M or 2e9");
  if (!(value > 0.0) || !std::isfinite(value * factor))
    throw std::invalid_argument("got \"" + text + "\", expected a positive size such as 8G, 512M or 2e9");
  return value * factor;
}

std::string format_bytes(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 5) {
    bytes /= 1024.0;
    ++u;
  }
  return num(bytes) + " " + units[u];
}

std::string format_duration(double seconds) {
  if (seconds < 120.0) return num(seconds) + " s";
  if (seconds < 7200.0) return num(seconds / 60.0) + " min";
  if (seconds < 2.0 * 86400.0) return num(seconds / 3600.0) + " h";
  if (seconds < 2.0 * 365.25 * 86400.0) return num(seconds / 86400.0) + " days";
  return num(seconds / (365.25 * 86400.0)) + " years";
}

GridExtent grid_extent(const Scene& s) {
  GridExtent g;
  const ShapeFunction f = s.grid.shape_function;
  // Nodes per axis: cells + 1 (linear, GIMP), cells + p (B-splines of degree p).
  const double extra = f == ShapeFunction::bspline2 ? 2.0 : f == ShapeFunction::bspline3 ? 3.0 : 1.0;
  g.nodes = 1.0;
  for (int a = 0; a < s.dimension; ++a) {
    const auto i = static_cast<std::size_t>(a);
    g.cells[i] = std::max(1.0, std::ceil((s.grid.max[i] - s.grid.min[i]) / s.grid.cell_size - 1e-9));
    g.nodes *= g.cells[i] + extra;
  }
  return g;
}

double run_memory(const Scene& s, double points) {
  return points * cost_of(s).bytes_per_point + grid_extent(s).nodes * node_bytes(s);
}

namespace {

/// Refuses when the run's memory (the grid and `points`, or preprocess's `particles`) exceeds the
/// limit, naming the grid's box when the grid dominates, else the cell size (and the largest body's
/// particles per cell when `largest` is known).
void refuse_over(const Scene& s, const std::string& scene_file, double points, double particles,
                 const BodyCount* largest, std::size_t largest_index, const MemoryLimit& limit) {
  const GridExtent g = grid_extent(s);
  const double grid_bytes = g.nodes * node_bytes(s);
  const double point_bytes = points * cost_of(s).bytes_per_point;
  const double need = std::max(grid_bytes + point_bytes, particles * kPreprocessBytesPerParticle);
  if (!(limit.bytes > 0.0) || need <= limit.bytes) return;
  const bool grid = grid_bytes >= point_bytes;
  // A grid far longer along one axis than another is a box too large for its bodies (a max of
  // 1e6 m); a grid of many cells along every axis has too fine a cell.
  double few = g.cells[0], many = g.cells[0];
  for (int a = 1; a < s.dimension; ++a) {
    few = std::min(few, g.cells[static_cast<std::size_t>(a)]);
    many = std::max(many, g.cells[static_cast<std::size_t>(a)]);
  }
  const bool box = grid && many > 1000.0 * few;
  std::ostringstream os;
  os << scene_file << ": ";
  if (grid) {
    os << (box ? "/grid/max" : "/grid/cell_size") << ": the grid of " << num(g.nodes) << " nodes (";
  } else {
    os << "/grid/cell_size: " << num(points) << " particles";
    if (largest)
      os << " (" << num(largest->particles) << " in body \"" << s.bodies[largest_index].name << "\", "
         << s.bodies[largest_index].particles_per_cell << " per cell and axis)";
    os << " on a grid of " << num(g.nodes) << " nodes (";
  }
  os << num(g.cells[0]);
  for (int a = 1; a < s.dimension; ++a) os << " x " << num(g.cells[static_cast<std::size_t>(a)]);
  os << " cells of " << num(s.grid.cell_size) << " m) would need at least " << format_bytes(need) << ", more than "
     << limit.what << "; expected ";
  if (box) os << "a grid box (/grid/min, /grid/max) closer around the bodies";
  else if (grid) os << "a coarser /grid/cell_size";
  else
    os << "a coarser /grid/cell_size"
       << (largest ? " or fewer /bodies/" + std::to_string(largest_index) + "/particles_per_cell" : std::string());
  throw SceneError({os.str()});
}

}  // namespace

void check_memory(const Scene& s, const std::string& scene_file, const std::vector<BodyCount>& bodies,
                  const MemoryLimit& limit) {
  double particles = 0.0, points = 0.0, scanned = 0.0;
  std::size_t largest = 0;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    particles += bodies[b].particles;
    points += solver_points(s, b, bodies[b].particles, bodies[b].wet);
    scanned += bodies[b].scanned;
    if (bodies[b].particles > bodies[largest].particles) largest = b;
  }
  if (scanned > kMaxScanned)
    throw SceneError({scene_file + ": /grid/cell_size: seeding would test " + num(scanned) +
                      " lattice points of the bodies' bounding boxes (cell_size " + num(s.grid.cell_size) +
                      " m), more than " + num(kMaxScanned) + "; expected a coarser /grid/cell_size or fewer /bodies/" +
                      std::to_string(largest) + "/particles_per_cell"});
  refuse_over(s, scene_file, points, particles, bodies.empty() ? nullptr : &bodies[largest], largest, limit);
}

void check_run_memory(const Scene& s, const std::string& scene_file, double points, const MemoryLimit& limit) {
  refuse_over(s, scene_file, points, 0.0, nullptr, 0, limit);
}

double step_microseconds(const Scene& s, Formulation f, double points) {
  const Cost& c = row_of(f).cost;
  // The grid's work runs once per step of the fluid: every soil_substeps-th step in mpm-fem
  // (solver.soil_substeps, default 1), every step elsewhere.
  const double grid_share = f == Formulation::mpm_fem ? 1.0 / std::max(1, s.solver.soil_substeps) : 1.0;
  return 20.0 + points * c.us_per_point_step + grid_extent(s).nodes * c.us_per_node_step * grid_share;
}

RunEstimate estimate_run(const Scene& s, double points, double dt, double t0) {
  RunEstimate e;
  const double span = s.time.end - t0;
  e.steps = std::ceil(span / dt);
  e.frames = (s.output.interval > 0.0 ? std::floor(span / s.output.interval) : 0.0) + 2.0;
  e.monitor_rows = s.output.monitor_interval > 0.0 ? std::floor(span / s.output.monitor_interval) + 1.0 : e.steps + 1.0;
  double columns = 1.0;
  for (const Monitor& m : s.output.monitors) columns += static_cast<double>(m.quantities.size());
  const GridExtent g = grid_extent(s);
  const bool grid_frames = row_of(s.formulation).water.free_water_on_grid;
  // Lower bounds: a compressed frame holds ~20 B per point (uniform fields compress well); a row
  // ~12 characters per column.
  const double frame_bytes = 1024.0 + 20.0 * points + (grid_frames ? 20.0 * g.nodes : 0.0);
  e.output_bytes = e.frames * frame_bytes + e.monitor_rows * 12.0 * columns;
  e.wall_seconds = e.steps * step_microseconds(s, s.formulation, points) * 1e-6;
  std::ostringstream os;
  os << "estimate: " << num(e.steps) << " steps (" << num(span) << " s at dt " << num(dt) << " s), " << num(e.frames)
     << " frames, " << num(e.monitor_rows) << " monitor rows, at least " << format_bytes(e.output_bytes)
     << " of output, about " << format_duration(e.wall_seconds) << " on one thread at the bench machine's speed";
  e.summary = os.str();
  return e;
}

std::vector<std::string> check_run_estimate(const Scene& s, const std::string& scene_file, const RunEstimate& e,
                                            double dt, const std::string& dt_reason, double free_disk_bytes) {
  constexpr double kYear = 365.25 * 86400.0, kDay = 86400.0, kLargeOutput = 20.0 * 1024 * 1024 * 1024;
  // The key that drives the step count: a step below a nanosecond is the culprit, else the end time.
  std::string step_key, step_what;
  if (dt < 1e-9) {
    step_key = s.time.dt ? "/time/dt" : "/materials";
    step_what = s.time.dt ? "dt " + num(dt) + " s"
                          : "dt auto " + num(dt) + " s, limited by " + dt_reason +
                                ": check the materials' density and stiffness";
  } else {
    step_key = "/time/end";
    step_what = "time.end " + num(s.time.end) + " s at dt " + num(dt) + " s";
  }
  const std::string steps_line = scene_file + ": " + step_key + ": the run would take " + num(e.steps) + " steps (" +
                                 step_what + "), about " + format_duration(e.wall_seconds) +
                                 " on one thread at the bench machine's speed";
  const std::string frames_key = e.frames * 20.0 >= e.monitor_rows ? "/output/interval" : "/output/monitor_interval";
  const std::string output_line = scene_file + ": " + frames_key + ": the run would write at least " +
                                  format_bytes(e.output_bytes) + " (" + num(e.frames) + " frames, " +
                                  num(e.monitor_rows) + " monitor rows)";
  std::vector<std::string> problems;
  if (!(e.wall_seconds <= kYear))
    problems.push_back(steps_line + ", more than a year; expected a run that ends: a shorter time.end or a larger step");
  if (free_disk_bytes > 0.0 && e.output_bytes > free_disk_bytes)
    problems.push_back(output_line + ", more than the " + format_bytes(free_disk_bytes) +
                       " free on the run directory's disk; expected a larger " + frames_key);
  if (!problems.empty()) throw SceneError(problems);
  std::vector<std::string> warnings;
  if (e.wall_seconds > kDay) warnings.push_back("warning: " + steps_line);
  if (e.output_bytes > kLargeOutput || (free_disk_bytes > 0.0 && e.output_bytes > 0.5 * free_disk_bytes))
    warnings.push_back("warning: " + output_line +
                       (free_disk_bytes > 0.0 ? ", of " + format_bytes(free_disk_bytes) + " free" : std::string()));
  return warnings;
}

}  // namespace swmpm::scene
