// The time loop (written once): dt control, gravity ramp, frames, monitors, progress, divergence.
#include "solver/run.hpp"

#include <omp.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "scene/auto_formulation.hpp"
#include "scene/budget.hpp"
#include "scene/expression.hpp"
#include "scene/files.hpp"
#include "scene/formulations.hpp"
#include "scene/input.hpp"
#include "scene/pointcloud.hpp"
#include "scene/scene.hpp"
#include "solver/cpu_load.hpp"
#include "solver/diagnostics/stability.hpp"
#include "solver/formulation.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/materials/material.hpp"
#include "solver/output/checkpoint.hpp"
#include "solver/output/monitors.hpp"
#include "solver/output/particle_io.hpp"
#include "solver/parallel/comm.hpp"
#include "solver/parallel/domain.hpp"
#include "solver/shape/shape.hpp"
#include "swmpm/version.hpp"

namespace fs = std::filesystem;

namespace swmpm {
namespace {

volatile std::sig_atomic_t g_interrupted = 0;  // the signal that asked the run to stop (0: none)
extern "C" void on_stop_signal(int sig) { g_interrupted = sig; }

/// Writes to log.txt always and to the terminal unless quiet. A failed write to log.txt throws
/// files::WriteError once (the run stops on it); later lines go to the terminal only.
class Log {
 public:
  explicit Log(bool quiet) : quiet_(quiet) {}
  void open(const fs::path& path) { file_ = files::CheckedFile(path); }
  void open_to_append(const fs::path& path) {
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    file_ = ec ? files::CheckedFile(path) : files::CheckedFile(path, static_cast<std::size_t>(size));
  }
  void line(const std::string& s) {
    if (!quiet_) std::cout << s << std::endl;
    to_file(s);
  }
  /// A line for log.txt only (the per-frame stability indicators: the terminal shows warnings).
  void file_line(const std::string& s) { to_file(s); }
  /// A warning: log.txt, and stderr unless quiet.
  void warning(const std::string& s) {
    if (!quiet_) std::cerr << s << std::endl;
    to_file(s);
  }
  /// A failure (diverged, interrupted, a failed write): one line on stderr even when quiet
  /// (interface.md §1: a failing command says why on stderr), and log.txt where it can be written.
  void failure(const std::string& s) {
    std::cerr << "swmpm: " << s << std::endl;
    try {
      to_file(s);
    } catch (const files::WriteError&) {
    }
  }

 private:
  void to_file(const std::string& s) {
    if (!file_.is_open() || broken_) return;
    try {
      file_.write(s + "\n");
    } catch (const files::WriteError&) {
      broken_ = true;
      throw;
    }
  }
  files::CheckedFile file_;
  bool quiet_;
  bool broken_ = false;
};

/// What a solve writes in its run directory; a new solve replaces these (swmpm's own, on the
/// ledger) and keeps preprocess's scene.json and particles/.
bool solve_output(const std::string& relative) {
  return relative == "run.json" || relative == "log.txt" || relative == "monitors.csv" || relative == "report.md" || relative == "report.html" ||
         relative == "checkpoint.bin" || relative.rfind("checkpoint/", 0) == 0 ||
         relative.rfind("output/", 0) == 0 || relative.rfind("plots/", 0) == 0;
}

/// run.json while the run goes on: status `running`. Padded to 8 KiB, so that the final run.json
/// can overwrite it in place when the disk has no room for a new file.
std::string running_report(const std::string& formulation, const nlohmann::json& choice) {
  nlohmann::ordered_json rj;
  rj["status"] = "running";
  rj["formulation"] = formulation;
  rj["formulation_choice"] = choice;  // how "auto" chose, before the first step (scene/auto_formulation.hpp)
  rj["pid"] = static_cast<long>(::getpid());
  rj["started_unix_seconds"] = static_cast<long>(std::time(nullptr));
  rj["software_version"] = version;
  rj["git_hash"] = git_hash;
  std::string text = rj.dump(2) + "\n";
  if (text.size() < 8192) text.append(8192 - text.size() - 1, ' ').push_back('\n');
  return text;
}

std::string fmt(double v, int prec = 6) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

std::size_t peak_memory_bytes() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<std::size_t>(ru.ru_maxrss) * 1024;  // ru_maxrss is in KiB on Linux
}

constexpr int kEnergyCheckEvery = 10;     // steps between energy checks (also at checkpoints and frames)
constexpr double kEnergyFactor = 10.0;     // allowed growth over the initial energy plus the external work
constexpr double kEnergyFloor = 1e-9;      // J (J/m in 2D): below this nothing is judged

using Json = nlohmann::ordered_json;

/// Time control: the phases (an initialisation before t = 0, then the analysis to time.end), the
/// dt of each step, and the time as a compensated sum that lands exactly on the phase's end.
struct Clock {
  double t_start = 0.0, end = 0.0, eps_t = 0.0;  // s
  bool auto_dt = true;
  bool initialising = false;
  double time_carry = 0.0;                                               // Kahan compensation of the time
  double dt_min = std::numeric_limits<double>::max(), dt_max = 0.0;      // s, the stable steps
  /// One step's dt; `lands`: it ends the phase exactly at `target` (time.end, or 0 after the
  /// initialisation). `dt_stable` is the dt before that shortening.
  struct Step {
    double dt, dt_stable, target;
    bool lands;
  };

  Clock() = default;
  explicit Clock(const scene::Scene& s) : end(s.time.end), auto_dt(!s.time.dt.has_value()) {
    const scene::Initialisation& init = s.initialisation;
    t_start = init.enabled() ? -init.duration : 0.0;  // the initialisation runs before t = 0
    eps_t = 1e-12 * (end - t_start);
    initialising = init.enabled();
  }
  bool ended(double t) const { return t >= end - eps_t; }
  /// The first mark of the lattice mark + k interval after time t (+ eps_t), in one step: adding
  /// the interval until it passes t spun for ever where the interval is below t's round-off
  /// (output.interval 1e-20 at t = 0.01: mark + interval == mark).
  double next_mark(double mark, double interval, double t) const {
    if (!(interval > 0.0) || mark > t + eps_t) return mark;
    const double k = std::floor((t + eps_t - mark) / interval) + 1.0;
    const double next = mark + k * interval;
    return next > t + eps_t ? next : std::nextafter(t + eps_t, std::numeric_limits<double>::infinity());
  }

  template <int Dim>
  Step next(const scene::Scene& s, const Formulation<Dim>& f, const State<Dim>& st) const {
    std::string reason;
    const double dt = auto_dt ? s.time.cfl * f.critical_time_step(st, reason) : *s.time.dt;
    // Land on the phase's end (time.end, or 0 after the initialisation): a step that reaches it,
    // or falls short of it only by the round-off of the summed steps (t = 1 - 2e-12 after 1e5
    // steps of 1e-5 s), ends exactly there; no sliver step follows.
    const double target = initialising ? 0.0 : end;
    const bool lands = target - st.time <= dt * (1.0 + 1e-6);
    return {lands ? target - st.time : dt, dt, target, lands};
  }

  /// The state's time and step after the step `st`.
  template <int Dim>
  void advance(State<Dim>& s, const Step& st) {
    if (st.lands) {
      s.time = st.target;
      time_carry = 0.0;
    } else {  // compensated (Kahan) sum: t stays within round-off of the exact sum of the steps
      const double y = st.dt - time_carry, t_new = s.time + y;
      time_carry = (t_new - s.time) - y;
      s.time = t_new;
    }
    ++s.step;
    dt_min = std::min(dt_min, st.dt_stable);
    dt_max = std::max(dt_max, st.dt_stable);
  }

  void save(Json& loop) const {
    loop["initialising"] = initialising, loop["time_carry"] = time_carry;
    loop["dt_min"] = dt_min, loop["dt_max"] = dt_max;
  }
  void restore(const Json& loop) {
    initialising = loop.at("initialising"), time_carry = loop.at("time_carry");
    dt_min = loop.at("dt_min"), dt_max = loop.at("dt_max");
  }
};

/// Energy check: kinetic + stored energy can grow only by the work of gravity and loads (damping,
/// drag and plasticity dissipate). A step that creates energy many times over is an instability
/// even when every value stays finite (a run may blow up and ring down again). The external work
/// is integrated every step (trapezoidal rule; the end-of-step power is the next step's start
/// power, one pass over the particles per step).
/// A material can also release stored energy below its initial value: Nor-Sand's
/// pressure-dependent elasticity starts at p_ref at zero elastic strain, so an unloaded body
/// expands and its stored energy goes negative while kinetic energy rises. The sum is then
/// conserved only up to the integration error of that exchange, so the largest release so far is
/// allowed on top (B5's slope undamped, first steps: 0.029 J kinetic, -0.028 J stored, sum
/// 2.6e-4 J, initial energy and work 0). A blow-up grows past any such bound.
struct EnergyGuard {
  double work = 0.0, power = 0.0;  // J, W: external work so far, power at the current state
  double stored0 = 0.0, energy0 = 0.0, work_max = 0.0, released_max = 0.0;  // J

  template <int Dim>
  void start(const Formulation<Dim>& f, const State<Dim>& s, const StepContext& ctx) {
    stored0 = parallel::sum(f.strain_energy(s));  // sums over the ranks (mpirun)
    energy0 = parallel::sum(f.kinetic_energy(s)) + stored0;
    power = parallel::sum(f.external_power(s, ctx));
  }
  /// Trapezoidal rule on the power of external forces over a step of `dt` ending with `end_ctx`.
  template <int Dim>
  void add_work(const Formulation<Dim>& f, const State<Dim>& s, const StepContext& end_ctx, double dt) {
    const double power_end = parallel::sum(f.external_power(s, end_ctx));
    work += 0.5 * dt * (power + power_end);
    power = power_end;
    work_max = std::max(work_max, work);
  }
  /// Empty while the energy is within bounds; else the diagnosis.
  template <int Dim>
  std::string created(const Formulation<Dim>& f, const State<Dim>& s) {
    const double stored = parallel::sum(f.strain_energy(s));
    const double e = parallel::sum(f.kinetic_energy(s)) + stored;
    released_max = std::max(released_max, stored0 - stored);
    const double allowed = kEnergyFactor * (energy0 + work_max) + released_max + kEnergyFloor;
    if (e <= allowed) return {};
    std::ostringstream os;
    os << "energy check: kinetic + stored energy " << e << " J at t = " << s.time << " s (step " << s.step
       << ") is more than " << kEnergyFactor << " x (initial energy " << energy0
       << " J + largest external work so far " << work_max << " J) + the largest release of stored energy "
       << released_max << " J: the scheme is creating energy, i.e. it is unstable (reduce dt or time.cfl)";
    return os.str();
  }

  void save(Json& loop) const {
    loop["work"] = work, loop["power"] = power, loop["stored0"] = stored0, loop["energy0"] = energy0;
    loop["work_max"] = work_max, loop["released_max"] = released_max;
  }
  void restore(const Json& loop) {
    work = loop.at("work"), power = loop.at("power"), stored0 = loop.at("stored0"), energy0 = loop.at("energy0");
    work_max = loop.at("work_max"), released_max = loop.at("released_max");
  }
};

/// What is due after a step: the energy check, the in-memory last-good snapshot
/// (solver.checkpoint_every), a monitor row, a frame, a restart checkpoint on disk.
struct Due {
  bool energy_check = false, snapshot = false, monitor = false, frame = false, restart = false;
};

template <int Dim>
class Runner {
 public:
  Runner(const std::string& run_dir, const SolveOptions& opt, const FormulationFactory<Dim>& factory)
      : dir_(run_dir), run_dir_(run_dir), opt_(opt), factory_(factory), log_(opt.quiet || parallel::rank() != 0) {}

  int run() {
    const auto wall_start = std::chrono::steady_clock::now();
    // Under mpirun every rank reads the scene and rank 0 the particles, which it deals out in
    // slices (read_particles); rank 0 alone writes the run
    // directory's files (but for each rank's piece of a frame). A bad input stops every rank
    // with one message and nothing written (parallel::together).
    parallel::together([&] { load_state(); });
    parallel::together([&] {
      if (root()) prepare_run_directory();
    });
    make_monitors();
    log_header();
    std::signal(SIGINT, on_stop_signal);
    std::signal(SIGTERM, on_stop_signal);  // a scheduler's or `kill`'s stop: as an interrupt
    tty_ = !opt_.quiet && isatty(fileno(stderr));
    loop_start_ = last_progress_ = std::chrono::steady_clock::now();

    // A write that fails (a full disk, a file size limit, a removed folder) stops the run with
    // status `failed`: the frames before it are complete, results.pvd lists them, run.json says why.
    try {
      if (resume_) resume_from_checkpoint();
      else start();
      while (!clock_.ended(state_.time)) {
        if (parallel::distributed() ? parallel::any(g_interrupted != 0) : g_interrupted != 0) {
          status_ = "interrupted";
          break;
        }
        const Clock::Step st = clock_.next(scene_, *f_, state_);
        const StepContext ctx{load_clock(state_.time), st.dt, gravity_at(state_.time)};
        try {
          f_->step(state_, ctx);
          if (parallel::distributed() ? parallel::any(!state_.health.ok()) : !state_.health.ok()) {
            fail(shared_failure(ctx));
            break;
          }
          guard_.add_work(*f_, state_, {load_clock(state_.time + st.dt), st.dt, gravity_at(state_.time + st.dt)}, st.dt);
        } catch (const scene::ExpressionValueError& e) {  // a load function's value is inf or NaN
          fail(load_function_failure(e));
          break;
        }
        clock_.advance(state_, st);
        const Due due = due_after_step(end_initialisation_if_due());
        if (due.energy_check) {
          if (std::string why = guard_.created(*f_, state_); !why.empty()) {
            fail(std::move(why));
            break;
          }
        }
        write_outputs(due);
        show_progress();
        adapt_threads();
      }
      if (tty_) std::fprintf(stderr, "\r%*s\r", 90, "");
      finish();
    } catch (const files::WriteError& e) {
      // On several ranks only a failure every rank saw (a frame's pieces) ends the run in order;
      // a file rank 0 alone writes (log, monitors, results.pvd) stops every rank at once.
      if (parallel::distributed() && !all_ranks_failed_) {
        log_.failure("rank " + std::to_string(parallel::rank()) + ": " + e.what());
        parallel::abort(5);
      }
      diagnosis_ = diagnosis_.empty() ? e.what() : diagnosis_ + "; then " + e.what();
      status_ = "failed";
      log_.failure(std::string("FAILED: ") + e.what() + "; the run stops here. " +
                   (frames_.empty() ? std::string("No frame is complete")
                                    : "The last complete frame is t = " + fmt(frames_.back().time) + " s") +
                   " (step " + std::to_string(state_.step) + ")");
    } catch (const std::exception& e) {
      // On several ranks a failure of one rank inside the loop (the others wait for it in a
      // collective) stops them all: one line naming the rank, then MPI_Abort.
      if (!parallel::distributed()) throw;
      log_.failure("rank " + std::to_string(parallel::rank()) + ": " + e.what());
      parallel::abort(1);
    }
    return report(wall_start);
  }

 private:
  // ---- setup -------------------------------------------------------------------------------

  /// The scene, the particle sets of preprocess, the formulation, and (--resume) the checkpoint,
  /// checked before anything is written.
  void load_state() {
    scene_ = scene::load_scene((dir_ / "scene.json").string());
    scene_text_ = read_text(dir_ / "scene.json");  // what checkpoints record, read once
    clock_ = Clock(scene_);
    const fs::path particles = dir_ / "particles" / "solid.vtu";
    const fs::path phase_field = dir_ / "particles" / "phase_field.vtu";
    // A scene of free water only (a dam break) has no solid points: preprocess writes no
    // particles/solid.vtu, and the solid set is empty (with its pore-fluid fields). The water is
    // in particles/fluid.vtu (double-point) or particles/phase_field.vtu (mpm-fem).
    const scene::WaterLayout layout = scene::row_of(scene_.formulation).water;
    const bool water_points = layout.fluid_particles, grid_water = layout.free_water_on_grid;
    if (!fs::exists(particles) && ((water_points && fs::exists(dir_ / "particles" / "fluid.vtu")) ||
                                   (grid_water && fs::exists(phase_field))))
      state_.solid.add_fluid();
    else state_.solid = read_particles(particles);
    if (needs_material_state(scene_)) state_.solid.add_material_state();
    index_whole_ids();
    const fs::path water = dir_ / "particles" / "fluid.vtu";
    if (scene::row_of(scene_.formulation).water.fluid_particles) {
      if (!fs::exists(water))
        throw std::runtime_error(water.string() + " is missing: a double-point formulation needs water points; "
                                 "run swmpm preprocess again");
      state_.fluid = read_particles(water);
      // Semi-implicit water points use neither skeleton nor single-point pore-fluid fields: freed,
      // so reordering and snapshots do not carry them.
      // explicit-double-point keeps `sigma` on them: the liquid's viscous deviatoric stress.
      state_.fluid.make_water_points(/*keep_stress=*/scene_.formulation == scene::Formulation::explicit_double_point);
    }
    if (grid_water) load_phase_field(phase_field);
    const fs::path surfaces = dir_ / "particles" / "surfaces.vtu";
    if (!scene::surface_bit_names(scene_).empty()) {
      if (!fs::exists(surfaces))
        throw std::runtime_error(surfaces.string() + " is missing: the scene names surfaces in boundaries or loads; "
                                 "run swmpm preprocess again");
      state_.surfaces = surface_samples_from_cloud<Dim>(scene::read_vtu(surfaces.string()), surfaces.string());
    }
    // mpirun: each rank holds a slice (State::shares); the formulation's distribute sends the
    // particles to their owners.
    state_.shares = parallel::distributed();
    solid_total_ = parallel::sum(static_cast<long>(state_.solid.size()));
    fluid_total_ = parallel::sum(static_cast<long>(state_.fluid.size()));
    // The grid's and the points' memory before the formulation allocates its grid (a rank's: the
    // whole grid and its share of the points, the largest slice).
    scene::check_run_memory(scene_, (dir_ / "scene.json").string(),
                            static_cast<double>(parallel::max(static_cast<long>(state_.solid.size() + state_.fluid.size()))),
                            scene::memory_limit(opt_.max_memory));
    f_ = factory_ ? factory_(scene_, state_) : make_formulation<Dim>(scene_, state_);
    if (parallel::distributed()) refuse_what_cannot_run_on_several_ranks();
    // The initial state's critical step, once: the interval check, the estimate and the log read it.
    dt_crit0_ = f_->critical_time_step(state_, dt_reason_);
    dt0_ = scene_.time.dt ? *scene_.time.dt : scene_.time.cfl * dt_crit0_;
    refuse_intervals_below_the_step();
    if (!opt_.resume) estimate_cost();
    reporters_ = make_materials<Dim>(scene_);  // frames' material state fields (pure functions of the particles)
    compression_ = scene::vtu_compression(scene_.output.compression);
    threads_ = threads_now_ = threads_fewest_ = omp_get_max_threads();
    // --resume: the checkpoint must be this scene's and this version's.
    if (opt_.resume) resume_ = read_checkpoint(f_->name());
  }

  /// The particles of `file` (particles/solid.vtu or fluid.vtu). Under mpirun rank 0 reads them
  /// and deals them out in slices of the file's order (parallel::scatter_slices): no other rank
  /// ever holds the whole set, and rank 0 only until its slice is cut.
  ParticleSet<Dim> read_particles(const fs::path& file) const {
    ParticleSet<Dim> ps;
    parallel::together([&] {
      if (root()) ps = particles_from_cloud<Dim>(scene::read_vtu(file.string()), file.string());
    });
    parallel::scatter_slices(ps, parallel::start_slices(parallel::max(static_cast<long>(ps.size()))));
    return ps;
  }

  /// The id table (State::index_of_id) sized for the whole set's ids, whichever rank holds them.
  void index_whole_ids() {
    std::int64_t max_id = -1;
    for (const auto i : state_.solid.id) max_id = std::max(max_id, i);
    state_.index_of_id.assign(static_cast<std::size_t>(parallel::max(static_cast<long>(max_id)) + 1), -1);
    state_.index_ids();
  }

  /// mpm-fem: the initial phase field preprocess wrote on the grid's nodes (State::phase_field),
  /// checked against the scene's grid (the node count of its shape function) and for `phi`.
  void load_phase_field(const fs::path& file) {
    if (!fs::exists(file))
      throw std::runtime_error(file.string() + " is missing: " + scene::to_string(scene_.formulation) +
                               " starts its water from the phase field preprocess writes there; run swmpm preprocess "
                               "again");
    state_.phase_field = scene::read_vtu(file.string());
    const std::size_t nodes = shape::with_policy(scene_.grid.shape_function, [&]<class Shape>() {
      return scene_grid<Dim>(scene_.grid, Shape::degree, Shape::bspline).num_nodes();
    });
    if (state_.phase_field.size() != nodes)
      throw std::runtime_error(file.string() + ": " + std::to_string(state_.phase_field.size()) + " nodes, but the "
                               "scene's grid (" + scene::to_string(scene_.grid.shape_function) + ") has " +
                               std::to_string(nodes) + "; run swmpm preprocess again");
    state_.phase_field.get("phi", file.string());  // throws naming the file when phi is missing
  }

  /// An output interval below the time step would write every step (and one of 1e-20 s made the
  /// loop spin): refused with the key, the value and the step, before anything is written (exit 2).
  void refuse_intervals_below_the_step() const {
    const double dt = dt0_;
    std::vector<std::string> problems;
    auto check = [&](const char* path, double interval, const char* zero) {
      if (interval > 0.0 && interval < dt)
        problems.push_back((dir_ / "scene.json").string() + ": " + path + ": got " + fmt(interval) +
                           " s, below the time step dt = " + fmt(dt) + " s" +
                           (scene_.time.dt ? "" : " (time.cfl x the critical step)") + "; expected " +
                           (*zero ? std::string("0 (") + zero + ") or " : std::string()) + "at least dt");
    };
    check("/output/interval", scene_.output.interval, "the first and last frames only");
    check("/output/monitor_interval", scene_.output.monitor_interval, "a row every step");
    if (scene_.output.checkpoint_interval) check("/output/checkpoint_interval", *scene_.output.checkpoint_interval, "");
    if (!problems.empty()) throw scene::SceneError(problems);
  }

  /// Steps, frames, bytes and wall time of a fresh run from its first step: past a hard limit (a
  /// year of wall time, more output than the disk's free space) refused before anything is written
  /// (exit 2); past a soft one a warning in the log (scene/budget.hpp).
  void estimate_cost() {
    estimate_ = scene::estimate_run(scene_, static_cast<double>(solid_total_ + fluid_total_), dt0_,
                                    clock_.t_start);
    std::error_code ec;
    const auto space = fs::space(dir_, ec);
    estimate_warnings_ = scene::check_run_estimate(scene_, (dir_ / "scene.json").string(), estimate_, dt0_, dt_reason_,
                                                   ec ? 0.0 : static_cast<double>(space.available));
  }

  /// The run directory: an earlier solve's files give way (only those swmpm wrote), a file of a
  /// name the solve writes that swmpm did not write stops it before anything is written. A resumed
  /// run keeps what the checkpoint covers and removes the frames written after it. Then log.txt,
  /// the `running` run.json and monitors.csv.
  void prepare_run_directory() {
    if (resume_) {
      const int frames_kept = resume_->header.at("loop").at("frame_count");
      run_dir_.remove_owned([&](const std::string& rel) {
        int k = -1;
        for (const char* frame : {"output/solid_%d.vtu", "output/fluid_%d.vtu", "output/grid_%d.vtu"})
          if (std::sscanf(rel.c_str(), frame, &k) == 1) return k >= frames_kept;
        return false;
      });
    } else {
      run_dir_.remove_owned(solve_output);
    }
    const auto foreign = run_dir_.foreign(files::swmpm_files_in(dir_));
    for (const auto& f : foreign)
      if (solve_output(f))
        throw files::RunDirectoryError((dir_ / f).string() +
                                       " exists and swmpm did not write it; swmpm never replaces or removes a file it "
                                       "did not write: move it away");
    run_dir_.claim("log.txt");
    if (resume_) log_.open_to_append(dir_ / "log.txt");
    else log_.open(dir_ / "log.txt");
    run_dir_.write_text("run.json", running_report(f_->name(), scene::choice_of(scene_)), true);
    run_dir_.claim("monitors.csv");
    std::filesystem::create_directories(dir_ / "output");
  }

  /// monitors.csv: rank 0 writes it; the other ranks (mpirun) compute their share of each row.
  void make_monitors() {
    const std::string stamp = "# swmpm " + std::string(version) + " (" + git_hash + "), scene " + scene_.name +
                              ", formulation " + f_->name();
    std::optional<std::size_t> monitor_bytes;
    if (resume_) monitor_bytes = resume_->header.at("loop").at("monitor_bytes").get<std::size_t>();
    monitors_ = std::make_unique<Monitors<Dim>>(scene_, state_, *f_, root() ? dir_ / "monitors.csv" : fs::path(),
                                                stamp, monitor_bytes);
  }

  bool root() const { return parallel::rank() == 0; }

  /// mpirun: a scene whose formulation (or one of its options) does not run on several ranks yet
  /// is refused before anything is written.
  void refuse_what_cannot_run_on_several_ranks() const {
    const std::string file = (dir_ / "scene.json").string();
    if (std::string why = f_->on_several_ranks(scene_); !why.empty())
      throw scene::SceneError({file + ": " + why + "; run it without mpirun (" + std::to_string(parallel::ranks()) +
                               " ranks asked)"});
  }

  /// The diagnosis of a failed step: the failing rank's (the lowest one's, mpirun), on every rank.
  std::string shared_failure(const StepContext& ctx) const {
    std::string mine = state_.health.ok() ? std::string() : describe_failure(ctx);
    if (!parallel::distributed()) return mine;
    std::string first;
    for (const auto& bytes : parallel::gather_to_root(std::vector<char>(mine.begin(), mine.end())))
      if (first.empty() && !bytes.empty()) first.assign(bytes.begin(), bytes.end());
    return parallel::broadcast(first);
  }

  /// The run's first lines in the log: what runs, what each monitor follows, the dt.
  void log_header() {
    log_.line("swmpm " + std::string(version) + " (" + git_hash + ") solving " + scene_.name + ": " + f_->name() +
              ", " + std::to_string(Dim) + "D, " + scene::to_string(scene_.grid.shape_function) + ", " +
              std::to_string(solid_total_) + " solid particles" +
              (fluid_total_ ? ", " + std::to_string(fluid_total_) + " water points" : std::string()) +
              ", " + std::to_string(threads_) + " threads");
    for (const auto& l : scene::explain_lines(scene::choice_of(scene_))) log_.line(l);
    for (const auto& l : monitors_->describe()) log_.line(l);
    const double dt_crit = dt_crit0_;
    if (clock_.auto_dt) {
      log_.line("dt auto: " + fmt(scene_.time.cfl * dt_crit) + " s = cfl " + fmt(scene_.time.cfl) + " x " +
                fmt(dt_crit) + " s, limited by " + dt_reason_);
    } else {
      log_.line("dt " + fmt(*scene_.time.dt) + " s (critical " + fmt(dt_crit) + " s by " + dt_reason_ + ")");
      if (*scene_.time.dt > dt_crit) log_.line("warning: dt exceeds the critical time step; the run may diverge");
    }
    if (!resume_) log_.line(estimate_.summary);
    for (const auto& w : estimate_warnings_) {
      log_.line(w);
      if (opt_.quiet) std::cerr << w << "\n";  // a warning is shown even when the terminal is quiet
    }
  }

  // ---- time control ------------------------------------------------------------------------

  /// A fresh run: the initialisation phase (if any) starts, frame 0 and the first monitor row, the
  /// energy check's initial state, the first snapshot.
  void start() {
    f_->distribute(state_);  // mpirun: each rank keeps its share of the particles
    state_.time = clock_.t_start;
    begin_initialisation();
    take_snapshot(last_good_);  // the initial state is the first good one
    last_good_time_ = clock_.t_start;
    guard_.start(*f_, state_, StepContext{0.0, 0.0, gravity_at(clock_.t_start)});  // before frame 0's indicators
    write_frame(clock_.t_start);
    next_frame_ = scene_.output.interval > 0 ? clock_.t_start + scene_.output.interval : clock_.end;
    monitors_->record(state_, *f_, guard_.work);
    next_monitor_ = clock_.t_start + scene_.output.monitor_interval;
    next_restart_ = clock_.t_start + restart_interval();
    first_step_ = state_.step;
  }

  /// The initialisation phase (scene.initialisation, if any) starts.
  void begin_initialisation() {
    const auto& init = scene_.initialisation;
    if (!init.enabled()) return;
    f_->set_initialisation(state_, &init);
    std::ostringstream os;
    os << "initialisation from t = " << clock_.t_start << " s to 0: gravity ramped over " << init.gravity_ramp
       << " s, " << (init.plasticity ? "plastic flow on" : "elastic (plastic flow off)");
    if (init.hydraulic_conductivity) os << ", k = " << *init.hydraulic_conductivity << " m/s";
    if (init.damping) os << ", damping " << *init.damping;
    if (!init.materials.empty()) {  // the parameters the models run with instead of the scene's
      os << ", materials";
      const char* sep = " ";
      for (const auto& [name, params] : init.materials) {
        os << sep << name << ":";
        for (const auto& [key, value] : params) os << " " << key << " " << value;
        sep = "; ";
      }
    }
    if (fluid_total_ && init.tie_water) os << ", water points tied to their soil points";
    log_.line(os.str());
  }

  /// The initialisation phase ends at t = 0: the analysis starts from this state. True if it did.
  bool end_initialisation_if_due() {
    if (!clock_.initialising || state_.time < -clock_.eps_t) return false;
    const auto& init = scene_.initialisation;
    state_.time = 0.0;
    clock_.time_carry = 0.0;
    clock_.initialising = false;
    f_->set_initialisation(state_, nullptr);
    if (init.reset_displacement) {
      state_.solid.x0 = state_.solid.x;
      state_.fluid.x0 = state_.fluid.x;
    }
    std::ostringstream os;
    const double kinetic = parallel::sum(f_->kinetic_energy(state_)), stored = parallel::sum(f_->strain_energy(state_));
    os << "initialisation done after " << state_.step << " steps: kinetic energy " << kinetic
       << " J, stored " << stored << " J; the analysis starts at t = 0"
       << (init.reset_displacement ? " (displacements measured from here)" : "");
    log_.line(os.str());
    return true;
  }

  Due due_after_step(bool phase_ended) const {
    const double t = state_.time, eps_t = clock_.eps_t;
    Due d;
    d.snapshot = state_.step % scene_.solver.checkpoint_every == 0;
    d.frame = t >= next_frame_ - eps_t || clock_.ended(t) || phase_ended;
    d.energy_check = state_.step % kEnergyCheckEvery == 0 || d.snapshot || d.frame;
    d.monitor = t >= next_monitor_ - eps_t || phase_ended;
    // Restart checkpoints on disk: every output.checkpoint_interval, or with every frame.
    d.restart = !clock_.ended(t) && (scene_.output.checkpoint_interval ? t >= next_restart_ - eps_t : d.frame);
    return d;
  }

  double restart_interval() const {
    return scene_.output.checkpoint_interval ? *scene_.output.checkpoint_interval : scene_.time.end;
  }

  /// Gravity at time t: ramped over `gravity_ramp` from t = 0, or, with an initialisation phase,
  /// over its `gravity_ramp` from its start at t = -duration (then full from t = 0).
  std::array<double, 3> gravity_at(double t) const {
    const auto& in = scene_.initialisation;
    double r = 1.0;
    if (in.enabled()) {
      if (t < 0.0 && in.gravity_ramp > 0.0) r = std::clamp((t + in.duration) / in.gravity_ramp, 0.0, 1.0);
    } else if (scene_.gravity_ramp > 0.0) {
      r = std::min(1.0, t / scene_.gravity_ramp);
    }
    return {scene_.gravity[0] * r, scene_.gravity[1] * r, scene_.gravity[2] * r};
  }

  /// The loads' clock: loads act during the initialisation phase (t < 0) as they do at t = 0.
  static double load_clock(double t) { return std::max(t, 0.0); }

  /// Fewer threads than asked while other processes keep cores busy (CpuLoad), checked every second
  /// of wall time: down at once, back up when two checks agree. Results do not depend on it.
  void adapt_threads() {
    if (threads_ <= 1) return;
    const auto now = std::chrono::steady_clock::now();
    // The first look after 0.3 s (a short run on a loaded machine gains most from it), then every 1 s.
    if (std::chrono::duration<double>(now - last_load_check_).count() < (threads_checked_ ? 1.0 : 0.3)) return;
    threads_checked_ = true;
    last_load_check_ = now;
    const double others = cpu_load_.others_busy_cores();
    if (others < 0.0) return;
    const int free = std::clamp(static_cast<int>(std::floor(cpu_load_.cores() - others + 0.3)), 1, threads_);
    if (free == threads_now_ || (free > threads_now_ && ++raise_votes_ < 2)) {
      if (free == threads_now_) raise_votes_ = 0;
      return;
    }
    raise_votes_ = 0;
    omp_set_num_threads(free);
    std::ostringstream os;
    os << "threads: " << free << " of " << threads_ << " from t = " << state_.time << " s (other processes keep "
       << std::setprecision(2) << others << " of " << cpu_load_.cores() << " cores busy)";
    if (tty_) std::fprintf(stderr, "\r%*s\r", 90, "");
    log_.line(os.str());
    threads_now_ = free;
    threads_fewest_ = std::min(threads_fewest_, free);
  }

  void show_progress() {
    if (!tty_ && !opt_.progress) return;
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - last_progress_).count() <= 0.5) return;
    last_progress_ = now;
    if (opt_.progress) opt_.progress((state_.time - clock_.t_start) / std::max(clock_.end - clock_.t_start, 1e-300));
    if (!tty_) return;
    const double el = std::chrono::duration<double>(now - loop_start_).count();
    const double rate = static_cast<double>(state_.step) / el;
    const double eta = el * (clock_.end - state_.time) / std::max(state_.time - clock_.t_start, 1e-300);
    std::fprintf(stderr, "\r  t = %.4g / %.4g s | step %ld | %.0f steps/s | ETA %.0f s   ", state_.time, clock_.end,
                 state_.step, rate, eta);
    std::fflush(stderr);
  }

  // ---- outputs after a step: snapshot, monitors, frames, restart -----------------------------

  void write_outputs(const Due& due) {
    // The output-only fields (Formulation::complete_output_fields): the water points' too for
    // frames, snapshots and monitors that follow water points.
    const bool water_points = due.snapshot || due.frame || due.restart || (due.monitor && monitors_->reads_water_points());
    if (water_points || (due.monitor && monitors_->reads_output_fields())) f_->complete_output_fields(state_, water_points);
    if (due.snapshot) {
      take_snapshot(last_good_);
      last_good_time_ = state_.time;
    }
    if (due.monitor) {
      monitors_->record(state_, *f_, guard_.work);
      next_monitor_ = scene_.output.monitor_interval > 0
                          ? clock_.next_mark(next_monitor_, scene_.output.monitor_interval, state_.time)
                          : next_monitor_;
    }
    if (due.frame) {
      write_frame(state_.time);
      if (scene_.output.interval > 0)
        next_frame_ = clock_.next_mark(next_frame_, scene_.output.interval, state_.time);
      else
        next_frame_ = clock_.end;
    }
    if (due.restart) {
      next_restart_ = clock_.next_mark(next_restart_, restart_interval(), state_.time);
      write_checkpoint();
    }
  }

  /// One frame: a VTU per particle set, the formulation's grid fields (Formulation::grid_fields,
  /// unless `grid` is false), then results.pvd, which lists a frame only once all of its files are
  /// complete (each is written atomically; a failure throws files::WriteError). Then the frame's
  /// stability indicators (not for the last good state of a diverged run, `grid` false: its
  /// energies and grid fields are gone).
  void write_frame(double t, bool grid = true) {
    const auto start = std::chrono::steady_clock::now();
    const int k = frame_count_++;
    const std::size_t listed = frames_.size();
    GridFields nodes;
    // The file of a group in this frame, claimed on the ledger and listed (the listing is undone
    // if a write fails).
    auto file = [&](const char* group, int part) {
      char name[64];
      std::snprintf(name, sizeof name, "%s_%06d.vtu", group, k);
      run_dir_.claim(std::string("output/") + name);
      frames_.push_back({t, group, part, name});
      return (dir_ / "output" / name).string();
    };
    // mpirun: a frame's set is a .pvtu over one piece per rank; rank 0 lists it.
    const int R = parallel::ranks();
    auto pieces = [&](const char* group, int part) {
      char name[64];
      std::snprintf(name, sizeof name, "%s_%06d.pvtu", group, k);
      if (root()) {
        run_dir_.claim(std::string("output/") + name);
        for (int r = 0; r < R; ++r) run_dir_.claim("output/" + scene::pvtu_piece_name(name, r));
      }
      frames_.push_back({t, group, part, name});
      return (dir_ / "output" / name).string();
    };
    const bool fluid_set = parallel::distributed() ? parallel::max(static_cast<long>(state_.fluid.size())) > 0
                                                   : state_.fluid.size() > 0;
    try {
      scene::PointCloud solid = particles_to_cloud(state_.solid);
      add_material_reports(solid, state_.solid, reporters_);
      scene::PointCloud fluid;
      if (fluid_set) fluid = water_points_to_cloud(state_.fluid);
      fluid.points.resize(state_.fluid.size());
      f_->add_point_fields(state_, solid, fluid);
      if (parallel::distributed()) {
        // Rank 0 claims every piece's name on the ledger before any rank writes one; a rank that
        // cannot write its piece fails the frame on every rank (the others would wait for it).
        const std::string solid_file = pieces("solid", 0);
        const std::string fluid_file = fluid_set ? pieces("fluid", 1) : std::string();
        parallel::barrier();
        write_on_every_rank(solid_file, "another rank could not write its piece", [&] {
          scene::write_pvtu_piece(solid_file, solid, parallel::rank(), R, compression_);
          if (fluid_set) scene::write_pvtu_piece(fluid_file, fluid, parallel::rank(), R, compression_);
        });
      } else {
        scene::write_vtu(file("solid", 0), solid, compression_);
        if (fluid_set) scene::write_vtu(file("fluid", 1), fluid, compression_);
      }
      if (grid) {
        nodes = f_->grid_fields(state_);
        if (!nodes.empty()) scene::write_lattice_vtu(file("grid", 2), nodes.cloud, nodes.nodes, compression_);
      }
      if (root()) {
        run_dir_.claim("output/results.pvd");
        scene::write_pvd((dir_ / "output" / "results.pvd").string(), frames_);
      }
    } catch (...) {
      frames_.resize(listed);
      throw;
    }
    frame_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (grid) record_stability(nodes);
  }

  /// The frame's stability indicators (solver/diagnostics/stability.hpp): a line in log.txt, a
  /// warning (log.txt and stderr) at an indicator's first crossing of its threshold, and the
  /// history run.json gets. Timed apart from the frame's files (run.json stability.seconds).
  void record_stability(const GridFields& nodes) {
    const auto start = std::chrono::steady_clock::now();
    const diagnostics::Energies e{parallel::sum(f_->kinetic_energy(state_)), parallel::sum(f_->strain_energy(state_)),
                                  guard_.energy0, guard_.work};
    // mpirun: every rank measures its share (with copies of the points near it); rank 0 records.
    const diagnostics::FrameIndicators fi = diagnostics::measure<Dim>(
        state_, nodes.empty() ? nullptr : &nodes, e, gravity_at(state_.time), state_.time - clock_.t_start);
    if (!root()) return;
    const std::vector<std::string> warnings = stability_.add(fi);
    stability_.add_seconds(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    log_.file_line(diagnostics::StabilityReport::frame_line(fi));
    if (!warnings.empty() && tty_) std::fprintf(stderr, "\r%*s\r", 90, "");
    for (const auto& w : warnings) log_.warning(w);
  }

  // ---- checkpoints: the in-memory last-good state and the restart file ----------------------

  /// A state the run can continue from, in memory: step, time, the particle sets and the
  /// formulation's own state (Formulation::save). The last-good snapshot is one; the restart file
  /// is one plus the loop's state (write_checkpoint). `c` keeps its memory from the last one.
  void take_snapshot(Checkpoint& c) const {
    c.clear();
    c.header["step"] = state_.step;
    c.header["time"] = state_.time;
    save_set(c, "solid", state_.solid);
    save_set(c, "fluid", state_.fluid);
    f_->save(c);
  }

  /// mpirun: the restart file's parts, nothing gathered: `piece`, this rank's particle sets (in
  /// key order, their keys among their fields) and each particle order of the formulation's state
  /// (Checkpoint::put_order) as indices into them; `c` (rank 0 writes it), the header and the
  /// formulation's global arrays (the same on every rank). Checkpoint::assembled puts them
  /// together as the one-rank run's snapshot.
  void take_pieces(Checkpoint& c, Checkpoint& piece) const {
    Checkpoint mine;
    f_->save(mine);
    c.clear();
    piece.clear();
    c.header = mine.header;
    c.header.erase("particle_orders");
    c.header.erase("global_arrays");
    c.header["step"] = state_.step;
    c.header["time"] = state_.time;
    save_set(piece, "solid", state_.solid);
    save_set(piece, "fluid", state_.fluid);
    const auto orders = mine.header.value("particle_orders", nlohmann::ordered_json::object());
    const auto global = mine.header.value("global_arrays", nlohmann::ordered_json::object());
    for (const auto& name : mine.names()) {
      if (global.contains(name)) {
        c.copy_array(mine, name);
        c.header["global_arrays"][name] = true;
      } else if (orders.contains(name)) {
        piece.copy_array(mine, name);
        piece.header["particle_orders"][name] = orders.at(name);
      } else {  // grid arrays of a formulation: not on several ranks yet
        throw std::logic_error(f_->name() + ": its restart array " + name + " is neither particles' nor global");
      }
    }
  }

  /// The bytes of an element of each of a set's fields (ParticleSet::for_each_field's order).
  static std::vector<std::size_t> field_bytes(const ParticleSet<Dim>& ps) {
    std::vector<std::size_t> bytes;
    const_cast<ParticleSet<Dim>&>(ps).for_each_field(
        [&](auto& f) { bytes.push_back(sizeof(typename std::decay_t<decltype(f)>::value_type)); });
    return bytes;
  }

  /// The index of the particle key among a set's fields (ParticleSet::for_each_field's order).
  static int key_field() {
    ParticleSet<Dim> ps;
    int k = 0, at = -1;
    ps.for_each_field([&](auto& f) {
      if (static_cast<const void*>(&f) == static_cast<const void*>(&ps.key)) at = k;
      ++k;
    });
    return at;
  }

  /// Puts a snapshot's particle sets and formulation state in place (the clock is the caller's).
  void restore_snapshot(const Checkpoint& c) {
    restore_set(c, "solid", state_.solid);
    restore_set(c, "fluid", state_.fluid);
    state_.index_ids();
    f_->restore(c, state_);
  }

  /// Runs write(); under mpirun every rank learns whether any rank's write failed
  /// (files::WriteError), and then all throw: the failing rank its own error, the others one
  /// naming `file` with `elsewhere`. The run then ends in order on every rank (status failed).
  template <class Write>
  void write_on_every_rank(const std::string& file, const char* elsewhere, Write&& write) {
    if (!parallel::distributed()) return write();
    std::exception_ptr failed;
    try {
      write();
    } catch (const files::WriteError&) {
      failed = std::current_exception();
    }
    if (!parallel::any(failed != nullptr)) return;
    all_ranks_failed_ = true;
    if (failed) std::rethrow_exception(failed);
    throw files::WriteError(file, elsewhere);
  }

  /// RUN_DIR/checkpoint.bin (solver/output/checkpoint.hpp), replaced atomically.
  /// Under mpirun in pieces, so that no rank holds more than its own particles: each rank writes
  /// RUN_DIR/checkpoint/piece-<generation>-<rank>.bin (take_pieces), then rank 0 checkpoint.bin,
  /// which names them; the pieces of the checkpoint before are removed only after that, so a kill
  /// at any moment leaves one whole checkpoint. A resume on any number of ranks puts the pieces
  /// together (Checkpoint::assembled).
  void write_checkpoint() {
    const auto start = std::chrono::steady_clock::now();
    Checkpoint c, piece;
    const bool pieces = parallel::distributed();
    if (pieces) take_pieces(c, piece);
    else take_snapshot(c);
    c.header["software_version"] = version;
    c.header["git_hash"] = git_hash;
    c.header["formulation"] = f_->name();
    c.header["dimension"] = Dim;
    c.header["scene"] = scene_text_;
    Json frames = Json::array();
    for (const auto& e : frames_) frames.push_back({e.time, e.group, e.part, e.file});
    Json loop = Json::object();
    clock_.save(loop);
    guard_.save(loop);
    loop["next_frame"] = next_frame_, loop["next_monitor"] = next_monitor_, loop["next_restart"] = next_restart_;
    loop["frame_count"] = frame_count_;
    loop["frames"] = frames;
    loop["monitor_bytes"] = monitors_->bytes();
    loop["stability"] = stability_.json();
    loop["checkpoint_generation"] = ++checkpoint_generation_;
    c.header["loop"] = loop;
    std::vector<std::string> names;
    if (pieces) {
      const int R = parallel::ranks();
      for (int r = 0; r < R; ++r)
        names.push_back("checkpoint/piece-" + std::to_string(checkpoint_generation_) + "-" + std::to_string(r) + ".bin");
      c.header["pieces"] = {{"generation", checkpoint_generation_},
                            {"key_field", key_field()},
                            {"fields", {{"solid", field_bytes(state_.solid)}, {"fluid", field_bytes(state_.fluid)}}},
                            {"orders", piece.header.value("particle_orders", Json::object())},
                            {"files", names}};
      piece.header["generation"] = checkpoint_generation_;
      piece.header["rank"] = parallel::rank();
      piece.header["step"] = state_.step;
      // Rank 0 claims every piece's name on the ledger before any rank writes one; a rank that
      // cannot write its piece fails the checkpoint on every rank, and checkpoint.bin stays the last.
      if (root())
        for (const auto& n : names) run_dir_.claim(n);
      parallel::barrier();
      const std::string mine = names[static_cast<std::size_t>(parallel::rank())];
      write_on_every_rank((dir_ / mine).string(), "another rank could not write its piece",
                          [&] { piece.write(dir_ / mine); });
    }
    // Rank 0 writes; a failure stops every rank in order (as a frame's piece does).
    write_on_every_rank((dir_ / "checkpoint.bin").string(), "rank 0 could not write it", [&] {
      if (!root()) return;
      run_dir_.claim("checkpoint.bin");
      c.write(dir_ / "checkpoint.bin");
    });
    // The checkpoint before is replaced: its pieces go.
    if (root())
      for (const auto& old : pieces_before_)
        if (std::find(names.begin(), names.end(), old) == names.end()) {
          std::error_code ec;
          fs::remove(dir_ / old, ec);
        }
    pieces_before_ = names;
    checkpoint_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++checkpoints_;
  }

  /// The checkpoint to resume from, refused (CheckpointError, exit 2) when another version wrote
  /// it or the scene changed since: the message says what differs.
  Checkpoint read_checkpoint(const std::string& formulation) {
    const fs::path file = dir_ / "checkpoint.bin";
    Checkpoint c = Checkpoint::read(file);
    const std::string theirs = c.header.value("software_version", "?") + " (" + c.header.value("git_hash", "?") + ")";
    const std::string ours = std::string(version) + " (" + git_hash + ")";
    if (theirs != ours)
      throw CheckpointError(file.string() + ": written by swmpm " + theirs + ", this is swmpm " + ours +
                            "; a checkpoint resumes only with the version that wrote it (run the solve again "
                            "without --resume)");
    const std::string& now = scene_text_;
    const std::string then = c.header.value("scene", "");
    if (now != then) {
      std::string paths;
      try {
        for (const auto& d : nlohmann::json::diff(scene::parse_json(then, "checkpoint"), scene::parse_json(now, "scene.json")))
          paths += (paths.empty() ? "" : ", ") + d.value("path", std::string("?"));
      } catch (const std::exception&) {
        paths = "the file";
      }
      throw CheckpointError(file.string() + ": the scene changed since the checkpoint (" + paths + " in " +
                            (dir_ / "scene.json").string() +
                            "); resume the scene it was written for, or run the solve again without --resume");
    }
    if (c.header.value("formulation", "") != formulation || c.header.value("dimension", 0) != Dim)
      throw CheckpointError(file.string() + ": written by formulation " + c.header.value("formulation", "?") +
                            ", the scene's is " + formulation);
    const std::size_t R = c.pieces();
    if (R == 0) return c;
    // Written by several ranks in pieces: rank m of M reads pieces [m R / M, (m + 1) R / M) (one
    // rank all of them: the whole snapshot), a share of the run that the formulation's distribute
    // sends to the particles' owners (State::shares).
    pieces_before_ = c.header.at("pieces").at("files").get<std::vector<std::string>>();
    const std::size_t M = static_cast<std::size_t>(parallel::ranks()), m = static_cast<std::size_t>(parallel::rank());
    resume_shares_ = M > 1;
    return c.assembled(dir_, m * R / M, (m + 1) * R / M);
  }

  /// Puts the checkpoint's state in place of the run's initial one: the formulation (built from
  /// the initial particles) gets the initialisation phase as the run went (started, then ended
  /// unless the checkpoint is inside it), then the clock, the snapshot (particle sets and the
  /// formulation's state) and the loop's state. The checkpoint is also the first last-good state;
  /// results.pvd loses the frames after it.
  void resume_from_checkpoint() {
    const Checkpoint& c = *resume_;
    const auto& l = c.header.at("loop");
    begin_initialisation();
    clock_.restore(l);
    if (!clock_.initialising && scene_.initialisation.enabled()) f_->set_initialisation(state_, nullptr);
    // The replay acts on the initial particles, which the checkpoint's replace: what it found
    // there (under mpirun a tied pair split between two ranks' slices) does not count.
    state_.health = Health{};
    state_.step = c.header.at("step");
    state_.time = c.header.at("time");
    restore_snapshot(c);
    // mpirun: each rank keeps its share of the checkpoint's particles (of a whole checkpoint), or
    // sends the pieces it read to their owners (of one in pieces).
    state_.shares = resume_shares_;
    f_->distribute(state_);
    guard_.restore(l);
    next_frame_ = l.at("next_frame"), next_monitor_ = l.at("next_monitor"), next_restart_ = l.at("next_restart");
    frame_count_ = l.at("frame_count");
    checkpoint_generation_ = l.value("checkpoint_generation", 0L);
    if (l.contains("stability")) stability_.restore(l.at("stability"));
    frames_.clear();
    for (const auto& e : l.at("frames"))
      frames_.push_back({e.at(0).get<double>(), e.at(1).get<std::string>(), e.at(2).get<int>(), e.at(3).get<std::string>()});
    if (parallel::distributed()) take_snapshot(last_good_);  // the checkpoint is a good state (this rank's share)
    else last_good_ = c;
    last_good_time_ = state_.time;
    if (root()) scene::write_pvd((dir_ / "output" / "results.pvd").string(), frames_);  // without the frames after it
    log_.line("resumed from the checkpoint at step " + std::to_string(state_.step) + ", t = " + fmt(state_.time, 10) +
              " s (" + std::to_string(frame_count_) + " frames kept)");
    first_step_ = state_.step;
  }

  static std::string read_text(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  // ---- failure and the end of the loop -------------------------------------------------------

  void fail(std::string diagnosis) {
    status_ = "diverged";
    diagnosis_ = std::move(diagnosis);
  }

  /// "<scene.json>: /loads/<i>/function: got "...", which is inf at t = ... s; ..." for the load
  /// whose expression it is.
  std::string load_function_failure(const scene::ExpressionValueError& e) const {
    std::string where = "/loads";
    for (std::size_t i = 0; i < scene_.loads.size(); ++i)
      if (scene_.loads[i].function.expression == e.expression()) {
        where = "/loads/" + std::to_string(i) + "/function";
        break;
      }
    return scene_.source_file + ": " + where + ": " + e.what();
  }

  /// The failed particle, before (the last good snapshot) and now, or the failed grid node. A
  /// "fluid" report names a water point of the double-point set (State::fluid) when there is one;
  /// otherwise the index is a soil point's (single-point formulations carry the pore water on the
  /// soil points).
  std::string describe_failure(const StepContext& ctx) const {
    const auto& h = state_.health;
    std::ostringstream os;
    auto when = [&] {
      os << " in the step from t = " << state_.time << " s (step " << state_.step + 1 << ", dt = " << ctx.dt << " s)";
    };
    if (h.particle < 0 && h.node >= 0) {
      os << h.phase << " grid node " << h.node << " at (";
      for (int a = 0; a < Dim; ++a) os << (a ? ", " : "") << h.node_x[a];
      os << ") " << h.what;
      when();
      os << ". Try a smaller dt (or cfl), or check the loads and the boundary conditions there.";
      return os.str();
    }
    const long p = h.particle;
    const bool water_point = h.phase == "fluid" && p < static_cast<long>(state_.fluid.size());
    const ParticleSet<Dim>& now = water_point ? state_.fluid : state_.solid;
    if (p < 0 || p >= static_cast<long>(now.size())) {
      os << h.phase << " " << h.what;
      when();
      os << ". " << (h.remedy.empty() ? "Try a smaller dt (or cfl), or check the loads." : h.remedy);
      return os.str();
    }
    ParticleSet<Dim> before;  // the last good snapshot's set, which may hold the particles in another order
    restore_set(last_good_, water_point ? "fluid" : "solid", before);
    long q = 0;
    while (q < static_cast<long>(before.size()) && before.id[q] != now.id[p]) ++q;
    const int body = now.body[p];
    os << h.phase << " particle " << now.id[p];
    if (body >= 0 && body < static_cast<int>(scene_.bodies.size())) os << " (body \"" << scene_.bodies[body].name << "\")";
    os << " " << h.what;
    when();
    os << "; ";
    if (q < static_cast<long>(before.size())) {
      os << "it was at (";
      for (int a = 0; a < Dim; ++a) os << (a ? ", " : "") << before.x[q][a];
      os << ") with speed " << before.v[q].norm() << " m/s at the last good state; now at (";
    } else {
      os << "now at (";
    }
    for (int a = 0; a < Dim; ++a) os << (a ? ", " : "") << now.x[p][a];
    os << "). "
       << (h.remedy.empty() ? "Try a smaller dt (or cfl), a finer output interval to see the onset, or check the loads."
                            : h.remedy);
    return os.str();
  }

  /// After the loop: a diverged run ends its frames with the last good state, an interrupted one
  /// with the state at the stop, a completed one with its end state (unless that frame exists).
  void finish() {
    if (status_ == "diverged") {
      log_.failure("DIVERGED: " + diagnosis_);
      // Every frame written so far passed the checks; the snapshot is newer only if it was taken
      // after the last frame. Either way the series ends with the last good state, in time order.
      // Its grid fields are gone (the nodes hold the failed step's): particles only.
      if (frames_.empty() || last_good_time_ > frames_.back().time) {
        restore_snapshot(last_good_);
        write_frame(last_good_time_, false);
      }
      last_good_frame_time_ = frames_.back().time;
      log_.line("the last frame (t = " + fmt(last_good_frame_time_) + " s) is the last good state; the run failed in step " +
                std::to_string(state_.step + 1));
    } else if (status_ == "interrupted") {
      f_->complete_output_fields(state_, true);
      write_frame(state_.time);
      log_.failure(std::string("interrupted by ") + (g_interrupted == SIGTERM ? "SIGTERM" : "SIGINT") + " at t = " +
                   fmt(state_.time) + " s; wrote the current state as the final frame");
    } else if (frames_.empty() || frames_.back().time < state_.time - clock_.eps_t) {
      f_->complete_output_fields(state_, true);
      write_frame(state_.time);
    }
  }

  // ---- the run report: run.json and the log's summary ----------------------------------------

  /// Writes the final run.json and the log's last lines; returns the exit status.
  int report(std::chrono::steady_clock::time_point wall_start) {
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    const double loop_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start_).count();
    // interface.md §3: wall microseconds / (particles x steps), all phases counted; the loop-only
    // figure (no input; frame writing included, frame_seconds says how much) is what the
    // benchmarks compare (they write the first and last frames only).
    // Points of both sets count (double-point: soil and water points, as the paper counts them).
    // A resumed run counts the steps it made itself.
    const long steps_here = state_.step - first_step_;
    // mpirun: the run's particles over all ranks; each rank's count and communication time.
    const long solid_n = parallel::sum(static_cast<long>(state_.solid.size()));
    const long fluid_n = parallel::sum(static_cast<long>(state_.fluid.size()));
    const std::vector<long> per_rank = parallel::all_gather(static_cast<long>(state_.solid.size() + state_.fluid.size()));
    const double comm_seconds = parallel::communication_seconds();
    const double comm_max = parallel::max(comm_seconds), comm_sum = parallel::sum(comm_seconds);
    std::array<double, 3> traffic{parallel::communication_seconds(parallel::Traffic::collective),
                                  parallel::communication_seconds(parallel::Traffic::exchange),
                                  parallel::communication_seconds(parallel::Traffic::migration)};
    parallel::max(std::span<double>(traffic));
    const long active_cells = parallel::sum(static_cast<long>(f_->active_cells(state_)));
    const long peak_memory = parallel::sum(static_cast<long>(peak_memory_bytes()));
    const long particle_bytes = parallel::sum(static_cast<long>(state_.solid.size() * state_.solid.bytes_per_particle() +
                                                                state_.fluid.size() * state_.fluid.bytes_per_particle()));
    const double particle_steps = static_cast<double>(solid_n + fluid_n) * static_cast<double>(steps_here);
    const double us_pps = steps_here > 0 && particle_steps > 0 ? 1e6 * wall / particle_steps : 0.0;
    const double loop_us_pps = steps_here > 0 && particle_steps > 0 ? 1e6 * loop_wall / particle_steps : 0.0;
    // A fluid on the grid (mpm-fem) costs per node: wall us / (grid nodes x steps) as well.
    const double node_steps = static_cast<double>(f_->fluid_nodes()) * static_cast<double>(steps_here);
    const double us_pns = steps_here > 0 && node_steps > 0 ? 1e6 * loop_wall / node_steps : 0.0;
    const int frames = static_cast<int>(std::count_if(frames_.begin(), frames_.end(), [](const auto& e) { return e.part == 0; }));

    Json rj;
    rj["status"] = status_;
    if (!diagnosis_.empty()) rj["diagnosis"] = diagnosis_;
    if (status_ == "diverged" && state_.health.particle < 0 && state_.health.node >= 0) {
      const auto& x = state_.health.node_x;
      rj["failed_node"] = {{"index", state_.health.node}, {"position", std::vector<double>(x.begin(), x.begin() + Dim)}};
    }
    rj["formulation"] = f_->name();
    rj["formulation_reason"] = scene_.formulation_reason;
    rj["formulation_choice"] = scene::choice_of(scene_);
    rj["dimension"] = Dim;
    rj["shape_function"] = scene::to_string(scene_.grid.shape_function);
    rj["particles"] = {{"solid", solid_n}};
    if (fluid_n) rj["particles"]["fluid"] = fluid_n;
    rj["active_cells"] = active_cells;
    rj["ranks"] = parallel::ranks();
    if (parallel::distributed()) {
      // interface.md §4 (mpirun): the particles per rank at the end, and the wall time each rank
      // spent communicating (collectives, the exchange of shared node columns, migration).
      rj["particles_per_rank"] = {{"min", *std::min_element(per_rank.begin(), per_rank.end())},
                                  {"max", *std::max_element(per_rank.begin(), per_rank.end())},
                                  {"each", per_rank}};
      rj["communication_seconds"] = {{"max", comm_max},
                                     {"mean", comm_sum / parallel::ranks()},
                                     {"collectives_max", traffic[0]},
                                     {"exchange_max", traffic[1]},
                                     {"migration_max", traffic[2]}};
    }
    rj["steps"] = state_.step;
    if (resume_) {
      rj["resumed_from_step"] = first_step_;
      rj["resumed_from_time"] = resume_->header.at("time");
    }
    // Mean for "auto", over the initialisation too (it starts at t_start < 0).
    rj["dt"] = clock_.auto_dt ? (state_.step ? (state_.time - clock_.t_start) / static_cast<double>(state_.step) : 0.0)
                              : *scene_.time.dt;
    rj["dt_min"] = state_.step ? clock_.dt_min : 0.0;
    rj["dt_max"] = clock_.dt_max;
    rj["dt_limit"] = dt_reason_;
    rj["end_time"] = state_.time;
    rj["wall_seconds"] = wall;
    rj["loop_seconds"] = loop_wall;
    rj["frame_seconds"] = frame_seconds_;
    rj["checkpoints"] = checkpoints_;
    rj["checkpoint_seconds"] = checkpoint_seconds_;  // part of loop_seconds
    rj["threads"] = threads_;
    rj["threads_fewest"] = threads_fewest_;  // fewer while other processes kept cores busy
    rj["us_per_particle_step"] = us_pps;
    rj["loop_us_per_particle_step"] = loop_us_pps;
    if (f_->fluid_nodes() > 0) {
      rj["fluid_nodes"] = f_->fluid_nodes();
      rj["loop_us_per_fluid_node_step"] = us_pns;
    }
    rj["peak_memory_bytes"] = peak_memory;  // summed over the ranks
    rj["particle_bytes"] = particle_bytes;
    rj["frames"] = frames;
    if (status_ == "diverged") rj["last_good_frame_time"] = last_good_frame_time_;
    Json stages;
    const auto& st = f_->stage_times();
    for (std::size_t k = 0; k < st.names.size(); ++k) stages[st.names[k]] = st.seconds[k];
    rj["stage_seconds"] = stages;
    const auto counters = f_->counters();
    if (!counters.empty()) {
      Json cj;
      for (const auto& c : counters) cj[c.name] = c.value;
      rj["counters"] = cj;
    }
    rj["stability"] = stability_.json();
    rj["software_version"] = version;
    rj["git_hash"] = git_hash;
    const int exit_code = status_ == "completed" ? 0 : status_ == "diverged" ? 3 : status_ == "interrupted" ? 4 : 5;
    if (!root()) return exit_code;
    write_run_report(rj.dump(2) + "\n");

    try {
      std::ostringstream summary;
      summary << status_ << ": " << state_.step << " steps to t = " << fmt(state_.time) << " s in " << fmt(wall, 4)
              << " s wall (" << fmt(us_pps, 4) << " us per particle-step, " << fmt(loop_us_pps, 4)
              << " in the time loop";
      if (f_->fluid_nodes() > 0) summary << "; " << fmt(us_pns, 4) << " us per fluid node-step in the time loop";
      summary << ", " << threads_ << " threads";
      if (parallel::distributed())
        summary << " on each of " << parallel::ranks() << " ranks; " << solid_n + fluid_n << " particles, "
                << *std::min_element(per_rank.begin(), per_rank.end()) << " to "
                << *std::max_element(per_rank.begin(), per_rank.end()) << " per rank; communication "
                << fmt(comm_max, 3) << " s on the busiest rank";
      summary << ")";
      log_.line(summary.str());
      std::ostringstream split;
      double total = 0.0;
      for (double s : st.seconds) total += s;
      // Shares of the stages' sum; the stages cover the formulation's step only, so say how much of
      // the loop that is, and the frames' share (the rest: monitors, energy checks, time-step control).
      split << "stages (" << fmt(100.0 * total / std::max(loop_wall, 1e-300), 3) << "% of the time loop, " << frames
            << " frames " << fmt(100.0 * frame_seconds_ / std::max(loop_wall, 1e-300), 3)
            << "%; the rest writes monitors, checks energy and takes the stability indicators):";
      for (std::size_t k = 0; k < st.names.size(); ++k)
        split << " " << st.names[k] << " " << fmt(100.0 * st.seconds[k] / std::max(total, 1e-300), 3) << "%";
      log_.line(split.str());
      for (const auto& c : counters) log_.line(c.name + ": " + fmt(c.value, 6) + (c.unit.empty() ? "" : " " + c.unit));
      const auto stability = stability_.summary();
      for (std::size_t k = 0; k < stability.size(); ++k) {
        if (k == 0) log_.line(stability[k] + "; measuring them took " + fmt(stability_.seconds(), 3) + " s (" +
                              fmt(100.0 * stability_.seconds() / std::max(loop_wall, 1e-300), 3) + "% of the time loop)");
        else log_.warning(stability[k]);
      }
    } catch (const files::WriteError& e) {  // log.txt; run.json is already written
      log_.failure(e.what());
    }
    return status_ == "completed" ? 0 : status_ == "diverged" ? 3 : status_ == "interrupted" ? 4 : 5;
  }

  /// The final run.json, replacing the `running` one. On a full disk, the padded `running` file
  /// is overwritten in place (no new block needed); if even that fails, stderr says so.
  void write_run_report(const std::string& text) {
    try {
      run_dir_.write_text("run.json", text, true);
    } catch (const files::WriteError& e) {
      const bool in_place = files::overwrite_in_place(dir_ / "run.json", text);
      log_.failure(std::string(e.what()) + (in_place ? "; wrote it in place of the running one" : "; run.json is stale"));
      if (!in_place) status_ = "failed";
    }
  }

  fs::path dir_;
  files::RunDirectory run_dir_;  // the ledger of what swmpm wrote in dir_
  SolveOptions opt_;
  FormulationFactory<Dim> factory_;  // empty: the scene's formulation
  Log log_;
  CpuLoad cpu_load_;  // other processes' load: adapt_threads
  int threads_now_ = 1, threads_fewest_ = 1, raise_votes_ = 0;
  bool threads_checked_ = false;
  std::chrono::steady_clock::time_point last_load_check_ = std::chrono::steady_clock::now();
  double dt_crit0_ = 0.0, dt0_ = 0.0;           // s, the initial state's critical and first step
  scene::RunEstimate estimate_;                // a fresh run's cost, from its first step
  std::vector<std::string> estimate_warnings_;  // soft limits passed
  scene::Scene scene_;
  std::string scene_text_;  // RUN_DIR/scene.json as read at the start
  State<Dim> state_;
  std::unique_ptr<Formulation<Dim>> f_;
  std::unique_ptr<Monitors<Dim>> monitors_;
  std::optional<Checkpoint> resume_;  // --resume: the checkpoint the run continues from
  std::vector<std::unique_ptr<MaterialModel<Dim>>> reporters_;  // per scene material, for add_material_reports
  scene::VtuCompression compression_ = scene::VtuCompression::zlib;  // output.compression
  int threads_ = 1;
  std::string dt_reason_;

  // The loop's state between steps (what a checkpoint holds besides the snapshot).
  Clock clock_;
  EnergyGuard guard_;
  double next_frame_ = 0.0, next_monitor_ = 0.0, next_restart_ = 0.0;  // s
  std::vector<scene::PvdEntry> frames_;  // one entry per group and frame
  int frame_count_ = 0;
  Checkpoint last_good_;  // the in-memory last-good snapshot (solver.checkpoint_every)
  double last_good_time_ = 0.0;
  diagnostics::StabilityReport stability_;  // the indicators of every frame so far

  // The run's outcome and timings.
  std::string status_ = "completed", diagnosis_;
  long first_step_ = 0;  // the step this invocation started from (a resumed run's checkpoint)
  bool tty_ = false;
  std::chrono::steady_clock::time_point loop_start_, last_progress_;
  double frame_seconds_ = 0.0;      // wall time spent writing frames (part of loop_seconds)
  double checkpoint_seconds_ = 0.0;  // wall time spent writing restart checkpoints (part of loop_seconds)
  int checkpoints_ = 0;
  long checkpoint_generation_ = 0;          // checkpoints written by the run, resumes included
  std::vector<std::string> pieces_before_;  // the pieces of the last checkpoint (mpirun), relative
  long solid_total_ = 0, fluid_total_ = 0;  // the run's particles (over the ranks), as read
  bool resume_shares_ = false;              // the checkpoint read is this rank's pieces, not the whole
  bool all_ranks_failed_ = false;  // mpirun: a write error every rank knows of (write_frame)
  double last_good_frame_time_ = 0.0;
};

}  // namespace

int solve(const std::string& run_dir, const SolveOptions& options) { return solve(run_dir, options, {}, {}); }

int solve(const std::string& run_dir, const SolveOptions& options, const FormulationFactory<2>& factory_2d,
          const FormulationFactory<3>& factory_3d) {
  if (!fs::exists(fs::path(run_dir) / "scene.json"))
    throw std::runtime_error(run_dir + ": not a run directory (no scene.json; run `swmpm preprocess` first)");
  if (options.threads > 0) omp_set_num_threads(options.threads);
  const scene::Scene s = scene::load_scene((fs::path(run_dir) / "scene.json").string());
  if (s.dimension == 2) return Runner<2>(run_dir, options, factory_2d).run();
  return Runner<3>(run_dir, options, factory_3d).run();
}

}  // namespace swmpm
