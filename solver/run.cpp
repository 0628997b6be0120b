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
#include <sstream>

#include <nlohmann/json.hpp>

#include "scene/files.hpp"
#include "scene/pointcloud.hpp"
#include "scene/scene.hpp"
#include "solver/formulation.hpp"
#include "solver/formulations/registry.hpp"
#include "solver/materials/material.hpp"
#include "solver/output/checkpoint.hpp"
#include "solver/output/monitors.hpp"
#include "solver/output/particle_io.hpp"
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
  return relative == "run.json" || relative == "log.txt" || relative == "monitors.csv" || relative == "report.md" ||
         relative == "checkpoint.bin" ||
         relative.rfind("output/", 0) == 0 || relative.rfind("plots/", 0) == 0;
}

/// run.json while the run goes on: status `running`. Padded to 8 KiB, so that the final run.json
/// can overwrite it in place when the disk has no room for a new file.
std::string running_report(const std::string& formulation) {
  nlohmann::ordered_json rj;
  rj["status"] = "running";
  rj["formulation"] = formulation;
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

template <int Dim>
class Runner {
 public:
  Runner(const std::string& run_dir, const SolveOptions& opt)
      : dir_(run_dir), run_dir_(run_dir), opt_(opt), log_(opt.quiet) {}

  int run() {
    const auto wall_start = std::chrono::steady_clock::now();
    scene_ = scene::load_scene((dir_ / "scene.json").string());
    scene_text_ = read_text(dir_ / "scene.json");  // what checkpoints record, read once
    const fs::path particles = dir_ / "particles" / "solid.vtu";
    state_.solid = particles_from_cloud<Dim>(scene::read_vtu(particles.string()), particles.string());
    if (needs_material_state(scene_)) state_.solid.add_material_state();
    state_.index_ids();
    const fs::path water = dir_ / "particles" / "fluid.vtu";
    if (scene_.formulation == scene::Formulation::semi_implicit_double_point ||
        scene_.formulation == scene::Formulation::explicit_double_point) {
      if (!fs::exists(water))
        throw std::runtime_error(water.string() + " is missing: a double-point formulation needs water points; "
                                 "run swmpm preprocess again");
      state_.fluid = particles_from_cloud<Dim>(scene::read_vtu(water.string()), water.string());
      // Semi-implicit water points use neither skeleton nor single-point pore-fluid fields: freed,
      // so reordering and snapshots do not carry them.
      if (scene_.formulation == scene::Formulation::semi_implicit_double_point) state_.fluid.make_water_points();
    }
    const fs::path surfaces = dir_ / "particles" / "surfaces.vtu";
    if (!scene::surface_bit_names(scene_).empty()) {
      if (!fs::exists(surfaces))
        throw std::runtime_error(surfaces.string() + " is missing: the scene names surfaces in boundaries or loads; "
                                 "run swmpm preprocess again");
      state_.surfaces = surface_samples_from_cloud<Dim>(scene::read_vtu(surfaces.string()), surfaces.string());
    }
    auto formulation = make_formulation<Dim>(scene_, state_);
    reporters_ = make_materials<Dim>(scene_);  // frames' material state fields (pure functions of the particles)
    compression_ = scene::vtu_compression(scene_.output.compression);
    threads_ = omp_get_max_threads();

    // --resume: the checkpoint must be this scene's and this version's; checked before anything
    // is written.
    std::optional<Checkpoint> resume;
    if (opt_.resume) resume = read_checkpoint(formulation->name());

    // The run directory: an earlier solve's files give way (only those swmpm wrote), a file of a
    // name the solve writes that swmpm did not write stops it before anything is written. A
    // resumed run keeps what the checkpoint covers and removes the frames written after it.
    if (resume) {
      const int frames_kept = resume->header.at("loop").at("frame_count");
      run_dir_.remove_owned([&](const std::string& rel) {
        int k = -1;
        return (std::sscanf(rel.c_str(), "output/solid_%d.vtu", &k) == 1 ||
                std::sscanf(rel.c_str(), "output/fluid_%d.vtu", &k) == 1) &&
               k >= frames_kept;
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
    if (resume) log_.open_to_append(dir_ / "log.txt");
    else log_.open(dir_ / "log.txt");
    run_dir_.write_text("run.json", running_report(formulation->name()), true);
    run_dir_.claim("monitors.csv");
    std::filesystem::create_directories(dir_ / "output");
    const std::string stamp = "# swmpm " + std::string(version) + " (" + git_hash + "), scene " + scene_.name +
                              ", formulation " + formulation->name();
    std::optional<std::size_t> monitor_bytes;
    if (resume) monitor_bytes = resume->header.at("loop").at("monitor_bytes").get<std::size_t>();
    Monitors<Dim> monitors(scene_, state_, dir_ / "monitors.csv", stamp, monitor_bytes);

    log_.line("swmpm " + std::string(version) + " (" + git_hash + ") solving " + scene_.name + ": " +
              formulation->name() + ", " + std::to_string(Dim) + "D, " + scene::to_string(scene_.grid.shape_function) +
              ", " + std::to_string(state_.solid.size()) + " solid particles" +
              (state_.fluid.size() ? ", " + std::to_string(state_.fluid.size()) + " water points" : std::string()) +
              ", " + std::to_string(threads_) + " threads");
    for (const auto& l : monitors.describe(state_)) log_.line(l);

    std::string dt_reason;
    const bool auto_dt = !scene_.time.dt.has_value();
    {
      const double dt_crit = formulation->critical_time_step(state_, dt_reason);
      if (auto_dt) {
        log_.line("dt auto: " + fmt(scene_.time.cfl * dt_crit) + " s = cfl " + fmt(scene_.time.cfl) + " x " +
                  fmt(dt_crit) + " s, limited by " + dt_reason);
      } else {
        log_.line("dt " + fmt(*scene_.time.dt) + " s (critical " + fmt(dt_crit) + " s by " + dt_reason + ")");
        if (*scene_.time.dt > dt_crit)
          log_.line("warning: dt exceeds the critical time step; the run may diverge");
      }
    }

    std::signal(SIGINT, on_stop_signal);
    std::signal(SIGTERM, on_stop_signal);  // a scheduler's or `kill`'s stop: as an interrupt
    const double end = scene_.time.end;
    const scene::Initialisation& init = scene_.initialisation;
    const double t_start = init.enabled() ? -init.duration : 0.0;  // the initialisation runs before t = 0
    const double eps_t = 1e-12 * (end - t_start);
    bool& initialising = loop_.initialising;
    initialising = init.enabled();
    state_.time = t_start;
    if (initialising) {
      formulation->set_initialisation(state_, &init);
      std::ostringstream os;
      os << "initialisation from t = " << t_start << " s to 0: gravity ramped over " << init.gravity_ramp << " s, "
         << (init.plasticity ? "plastic flow on" : "elastic (plastic flow off)");
      if (init.hydraulic_conductivity) os << ", k = " << *init.hydraulic_conductivity << " m/s";
      if (init.damping) os << ", damping " << *init.damping;
      if (state_.fluid.size() && init.tie_water) os << ", water points tied to their soil points";
      log_.line(os.str());
    }
    double &next_frame = loop_.next_frame, &next_monitor = loop_.next_monitor, &work = loop_.work;
    double &dt_min = loop_.dt_min, &dt_max = loop_.dt_max, dt = 0.0;
    ParticleSet<Dim> last_good, last_good_water;
    last_good.copy_state_from(state_.solid);
    last_good_water.copy_state_from(state_.fluid);
    double last_good_time = t_start;
    std::string status = "completed", diagnosis;
    const bool tty = !opt_.quiet && isatty(fileno(stderr));
    auto last_progress = std::chrono::steady_clock::now();
    const auto loop_start = last_progress;

    // A write that fails (a full disk, a file size limit, a removed folder) stops the run with
    // status `failed`: the frames before it are complete, results.pvd lists them, run.json says why.
    long first_step = 0;  // the step this invocation started from (a resumed run's checkpoint)
    try {
    if (!resume) {
      write_frame(t_start);
      next_frame = scene_.output.interval > 0 ? t_start + scene_.output.interval : end;
      monitors.record(state_, *formulation, work);
      next_monitor = t_start + scene_.output.monitor_interval;
    }

    // Energy check: kinetic + stored energy can grow only by the work of gravity and loads
    // (damping, drag and plasticity dissipate). A step that creates energy many times over is an
    // instability even when every value stays finite (a run may blow up and ring down again).
    // The external work is integrated every step (trapezoidal rule; the end-of-step power is the
    // next step's start power, one pass over the particles per step).
    // A material can also release stored energy below its initial value: Nor-Sand's
    // pressure-dependent elasticity starts at p_ref at zero elastic strain, so an unloaded body
    // expands and its stored energy goes negative while kinetic energy rises. The sum is then
    // conserved only up to the integration error of that exchange, so the largest release so far
    // is allowed on top (B5's slope undamped, first steps: 0.029 J kinetic, -0.028 J stored, sum
    // 2.6e-4 J, initial energy and work 0). A blow-up grows past any such bound.
    double &stored0 = loop_.stored0, &energy0 = loop_.energy0;
    double &work_max = loop_.work_max, &released_max = loop_.released_max, &power = loop_.power;
    double& time_carry = loop_.time_carry;  // Kahan compensation of state_.time
    if (!resume) {
      stored0 = formulation->strain_energy(state_);
      energy0 = formulation->kinetic_energy(state_) + stored0;
      power = formulation->external_power(state_, StepContext{0.0, 0.0, gravity_at(t_start)});
      loop_.next_restart = t_start + restart_interval();
    } else {
      restore(*resume, *formulation);
      last_good.copy_state_from(state_.solid);  // the checkpoint is a good state
      last_good_water.copy_state_from(state_.fluid);
      last_good_time = state_.time;
      scene::write_pvd((dir_ / "output" / "results.pvd").string(), frames_);  // without the frames after it
      log_.line("resumed from the checkpoint at step " + std::to_string(state_.step) + ", t = " + fmt(state_.time, 10) +
                " s (" + std::to_string(loop_.frame_count) + " frames kept)");
    }
    first_step = state_.step;
    auto energy_created = [&]() -> bool {
      const double stored = formulation->strain_energy(state_);
      const double e = formulation->kinetic_energy(state_) + stored;
      released_max = std::max(released_max, stored0 - stored);
      const double allowed = kEnergyFactor * (energy0 + work_max) + released_max + kEnergyFloor;
      if (e <= allowed) return false;
      std::ostringstream os;
      os << "energy check: kinetic + stored energy " << e << " J at t = " << state_.time << " s (step "
         << state_.step << ") is more than " << kEnergyFactor << " x (initial energy " << energy0
         << " J + largest external work so far " << work_max << " J) + the largest release of stored energy "
         << released_max << " J: the scheme is creating energy, i.e. it is unstable (reduce dt or time.cfl)";
      diagnosis = os.str();
      return true;
    };

    const bool monitors_read_output_fields = monitors.reads_output_fields();
    while (state_.time < end - eps_t) {
      if (g_interrupted) {
        status = "interrupted";
        break;
      }
      if (auto_dt) {
        std::string reason;
        dt = scene_.time.cfl * formulation->critical_time_step(state_, reason);
      } else {
        dt = *scene_.time.dt;
      }
      const double dt_stable = dt;  // before the last step is shortened to land on time.end (or on 0)
      // Land on the phase's end (time.end, or 0 after the initialisation): a step that reaches it,
      // or falls short of it only by the round-off of the summed steps (t = 1 - 2e-12 after 1e5
      // steps of 1e-5 s), ends exactly there; no sliver step follows.
      const double target = initialising ? 0.0 : end;
      const bool lands = target - state_.time <= dt * (1.0 + 1e-6);
      if (lands) dt = target - state_.time;
      StepContext ctx{load_clock(state_.time), dt, gravity_at(state_.time)};
      formulation->step(state_, ctx);
      if (!state_.health.ok()) {
        status = "diverged";
        diagnosis = describe_failure(last_good, last_good_water, ctx);
        break;
      }
      {  // trapezoidal rule on the power of external forces
        StepContext end_ctx{load_clock(state_.time + dt), dt, gravity_at(state_.time + dt)};
        const double power_end = formulation->external_power(state_, end_ctx);
        work += 0.5 * dt * (power + power_end);
        power = power_end;
        work_max = std::max(work_max, work);
      }
      if (lands) {
        state_.time = target;
        time_carry = 0.0;
      } else {  // compensated (Kahan) sum: t stays within round-off of the exact sum of the steps
        const double y = dt - time_carry, t_new = state_.time + y;
        time_carry = (t_new - state_.time) - y;
        state_.time = t_new;
      }
      ++state_.step;
      dt_min = std::min(dt_min, dt_stable);
      dt_max = std::max(dt_max, dt_stable);

      bool phase_ended = false;
      if (initialising && state_.time >= -eps_t) {  // t = 0: the analysis starts from this state
        state_.time = 0.0;
        time_carry = 0.0;
        initialising = false;
        phase_ended = true;
        formulation->set_initialisation(state_, nullptr);
        if (init.reset_displacement) {
          state_.solid.x0 = state_.solid.x;
          state_.fluid.x0 = state_.fluid.x;
        }
        std::ostringstream os;
        os << "initialisation done after " << state_.step << " steps: kinetic energy "
           << formulation->kinetic_energy(state_) << " J, stored " << formulation->strain_energy(state_)
           << " J; the analysis starts at t = 0" << (init.reset_displacement ? " (displacements measured from here)" : "");
        log_.line(os.str());
      }
      const bool checkpoint = state_.step % scene_.solver.checkpoint_every == 0;
      const bool frame_due = state_.time >= next_frame - eps_t || state_.time >= end - eps_t || phase_ended;
      if ((state_.step % kEnergyCheckEvery == 0 || checkpoint || frame_due) && energy_created()) {
        status = "diverged";
        break;
      }
      const bool monitor_due = state_.time >= next_monitor - eps_t || phase_ended;
      // Restart checkpoints on disk: every output.checkpoint_interval, or with every frame.
      const bool restart_due = state_.time < end - eps_t &&
                               (scene_.output.checkpoint_interval ? state_.time >= loop_.next_restart - eps_t : frame_due);
      if (checkpoint || frame_due || restart_due || (monitor_due && monitors_read_output_fields))
        formulation->complete_output_fields(state_, checkpoint || frame_due || restart_due);
      if (checkpoint) {
        last_good.copy_state_from(state_.solid);  // reuses capacity: no allocation after the first copy
        last_good_water.copy_state_from(state_.fluid);
        last_good_time = state_.time;
      }
      if (monitor_due) {
        monitors.record(state_, *formulation, work);
        next_monitor += scene_.output.monitor_interval;
        if (scene_.output.monitor_interval > 0)
          while (next_monitor <= state_.time + eps_t) next_monitor += scene_.output.monitor_interval;
      }
      if (frame_due) {
        write_frame(state_.time);
        if (scene_.output.interval > 0)
          while (next_frame <= state_.time + eps_t) next_frame += scene_.output.interval;
        else
          next_frame = end;
      }
      if (restart_due) {
        while (loop_.next_restart <= state_.time + eps_t) loop_.next_restart += restart_interval();
        write_checkpoint(*formulation, monitors);
      }
      if (tty) {
        const auto now = std::chrono::steady_clock::now();
        if (std::chrono::duration<double>(now - last_progress).count() > 0.5) {
          last_progress = now;
          const double el = std::chrono::duration<double>(now - loop_start).count();
          const double rate = static_cast<double>(state_.step) / el;
          const double eta = el * (end - state_.time) / std::max(state_.time - t_start, 1e-300);
          std::fprintf(stderr, "\r  t = %.4g / %.4g s | step %ld | %.0f steps/s | ETA %.0f s   ", state_.time, end,
                       state_.step, rate, eta);
          std::fflush(stderr);
        }
      }
    }
    if (tty) std::fprintf(stderr, "\r%*s\r", 90, "");

    if (status == "diverged") {
      log_.failure("DIVERGED: " + diagnosis);
      // Every frame written so far passed the checks; the snapshot is newer only if it was taken
      // after the last frame. Either way the series ends with the last good state, in time order.
      if (frames_.empty() || last_good_time > frames_.back().time) {
        ParticleSet<Dim> failed = std::move(state_.solid), failed_water = std::move(state_.fluid);
        state_.solid = std::move(last_good);
        state_.fluid = std::move(last_good_water);
        write_frame(last_good_time);
        state_.solid = std::move(failed);
        state_.fluid = std::move(failed_water);
      }
      last_good_frame_time_ = frames_.back().time;
      log_.line("the last frame (t = " + fmt(last_good_frame_time_) + " s) is the last good state; the run failed in step " +
                std::to_string(state_.step + 1));
    } else if (status == "interrupted") {
      formulation->complete_output_fields(state_, true);
      write_frame(state_.time);
      log_.failure(std::string("interrupted by ") + (g_interrupted == SIGTERM ? "SIGTERM" : "SIGINT") + " at t = " +
                   fmt(state_.time) + " s; wrote the current state as the final frame");
    } else if (frames_.empty() || frames_.back().time < state_.time - eps_t) {
      formulation->complete_output_fields(state_, true);
      write_frame(state_.time);
    }
    } catch (const files::WriteError& e) {
      diagnosis = diagnosis.empty() ? e.what() : diagnosis + "; then " + e.what();
      status = "failed";
      log_.failure(std::string("FAILED: ") + e.what() + "; the run stops here. " +
                   (frames_.empty() ? std::string("No frame is complete")
                                    : "The last complete frame is t = " + fmt(frames_.back().time) + " s") +
                   " (step " + std::to_string(state_.step) + ")");
    }

    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    const double loop_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
    // interface.md §3: wall microseconds / (particles x steps), all phases counted; the loop-only
    // figure (no input; frame writing included, frame_seconds says how much) is what the
    // benchmarks compare (they write the first and last frames only).
    // Points of both sets count (double-point: soil and water points, as the paper counts them).
    // A resumed run counts the steps it made itself.
    const long steps_here = state_.step - first_step;
    const double particle_steps =
        static_cast<double>(state_.solid.size() + state_.fluid.size()) * static_cast<double>(steps_here);
    const double us_pps = steps_here > 0 ? 1e6 * wall / particle_steps : 0.0;
    const double loop_us_pps = steps_here > 0 ? 1e6 * loop_wall / particle_steps : 0.0;

    nlohmann::ordered_json rj;
    rj["status"] = status;
    if (!diagnosis.empty()) rj["diagnosis"] = diagnosis;
    rj["formulation"] = formulation->name();
    rj["dimension"] = Dim;
    rj["shape_function"] = scene::to_string(scene_.grid.shape_function);
    rj["particles"] = {{"solid", state_.solid.size()}};
    if (state_.fluid.size()) rj["particles"]["fluid"] = state_.fluid.size();
    rj["active_cells"] = formulation->active_cells(state_);
    rj["steps"] = state_.step;
    if (resume) {
      rj["resumed_from_step"] = first_step;
      rj["resumed_from_time"] = resume->header.at("time");
    }
    rj["dt"] = auto_dt ? (state_.step ? state_.time / static_cast<double>(state_.step) : 0.0) : *scene_.time.dt;  // mean for "auto"
    rj["dt_min"] = state_.step ? dt_min : 0.0;
    rj["dt_max"] = dt_max;
    rj["dt_limit"] = dt_reason;
    rj["end_time"] = state_.time;
    rj["wall_seconds"] = wall;
    rj["loop_seconds"] = loop_wall;
    rj["frame_seconds"] = frame_seconds_;
    rj["checkpoints"] = checkpoints_;
    rj["checkpoint_seconds"] = checkpoint_seconds_;  // part of loop_seconds
    rj["threads"] = threads_;
    rj["us_per_particle_step"] = us_pps;
    rj["loop_us_per_particle_step"] = loop_us_pps;
    rj["peak_memory_bytes"] = peak_memory_bytes();
    rj["particle_bytes"] = state_.solid.size() * state_.solid.bytes_per_particle() +
                           state_.fluid.size() * state_.fluid.bytes_per_particle();
    rj["frames"] = static_cast<int>(std::count_if(frames_.begin(), frames_.end(), [](const auto& e) { return e.part == 0; }));
    if (status == "diverged") rj["last_good_frame_time"] = last_good_frame_time_;
    nlohmann::ordered_json stages;
    const auto& st = formulation->stage_times();
    for (std::size_t k = 0; k < st.names.size(); ++k) stages[st.names[k]] = st.seconds[k];
    rj["stage_seconds"] = stages;
    const auto counters = formulation->counters();
    if (!counters.empty()) {
      nlohmann::ordered_json cj;
      for (const auto& c : counters) cj[c.name] = c.value;
      rj["counters"] = cj;
    }
    rj["software_version"] = version;
    rj["git_hash"] = git_hash;
    write_run_report(rj.dump(2) + "\n", status);

    try {
    std::ostringstream summary;
    summary << status << ": " << state_.step << " steps to t = " << fmt(state_.time) << " s in " << fmt(wall, 4)
            << " s wall (" << fmt(us_pps, 4) << " us per particle-step, " << fmt(loop_us_pps, 4)
            << " in the time loop, " << threads_ << " threads)";
    log_.line(summary.str());
    std::ostringstream split;
    double total = 0.0;
    for (double s : st.seconds) total += s;
    // Shares of the stages' sum; the stages cover the formulation's step only, so say how much of
    // the loop that is, and the frames' share (the rest: monitors, energy checks, time-step control).
    split << "stages (" << fmt(100.0 * total / std::max(loop_wall, 1e-300), 3) << "% of the time loop, "
          << rj["frames"].get<int>() << " frames " << fmt(100.0 * frame_seconds_ / std::max(loop_wall, 1e-300), 3)
          << "%; the rest writes monitors and checks energy):";
    for (std::size_t k = 0; k < st.names.size(); ++k)
      split << " " << st.names[k] << " " << fmt(100.0 * st.seconds[k] / std::max(total, 1e-300), 3) << "%";
    log_.line(split.str());
    for (const auto& c : counters) log_.line(c.name + ": " + fmt(c.value, 6) + (c.unit.empty() ? "" : " " + c.unit));
    } catch (const files::WriteError& e) {  // log.txt; run.json is already written
      log_.failure(e.what());
    }
    return status == "completed" ? 0 : status == "diverged" ? 3 : status == "interrupted" ? 4 : 5;
  }

 private:
  /// The time loop's own state between steps (what a checkpoint holds besides the particles and
  /// the formulation's state).
  struct Loop {
    bool initialising = false;
    double next_frame = 0.0, next_monitor = 0.0, next_restart = 0.0;  // s
    double work = 0.0, power = 0.0;  // J, W: external work so far, power at the current state
    double stored0 = 0.0, energy0 = 0.0, work_max = 0.0, released_max = 0.0;  // J: the energy check
    double dt_min = std::numeric_limits<double>::max(), dt_max = 0.0;        // s
    double time_carry = 0.0;  // Kahan compensation of the time
    int frame_count = 0;
  };

  double restart_interval() const {
    return scene_.output.checkpoint_interval ? *scene_.output.checkpoint_interval : scene_.time.end;
  }

  static std::string read_text(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  /// RUN_DIR/checkpoint.bin (solver/output/checkpoint.hpp), replaced atomically.
  void write_checkpoint(const Formulation<Dim>& f, const Monitors<Dim>& monitors) {
    const auto start = std::chrono::steady_clock::now();
    Checkpoint c;
    c.header["software_version"] = version;
    c.header["git_hash"] = git_hash;
    c.header["formulation"] = f.name();
    c.header["dimension"] = Dim;
    c.header["step"] = state_.step;
    c.header["time"] = state_.time;
    c.header["scene"] = scene_text_;
    loop_.frame_count = frame_count_;
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    for (const auto& e : frames_) frames.push_back({e.time, e.group, e.part, e.file});
    c.header["loop"] = {{"initialising", loop_.initialising}, {"next_frame", loop_.next_frame},
                        {"next_monitor", loop_.next_monitor}, {"next_restart", loop_.next_restart},
                        {"work", loop_.work},                 {"power", loop_.power},
                        {"stored0", loop_.stored0},           {"energy0", loop_.energy0},
                        {"work_max", loop_.work_max},         {"released_max", loop_.released_max},
                        {"dt_min", loop_.dt_min},             {"dt_max", loop_.dt_max},
                        {"time_carry", loop_.time_carry},     {"frame_count", loop_.frame_count},
                        {"frames", frames},                   {"monitor_bytes", monitors.bytes()}};
    save_set(c, "solid", state_.solid);
    save_set(c, "fluid", state_.fluid);
    f.save(c);
    run_dir_.claim("checkpoint.bin");
    c.write(dir_ / "checkpoint.bin");
    checkpoint_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++checkpoints_;
  }

  /// The checkpoint to resume from, refused (CheckpointError, exit 2) when another version wrote
  /// it or the scene changed since: the message says what differs.
  Checkpoint read_checkpoint(const std::string& formulation) const {
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
        for (const auto& d : nlohmann::json::diff(nlohmann::json::parse(then), nlohmann::json::parse(now)))
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
    return c;
  }

  /// Puts the checkpoint's state in place of the run's initial one: the formulation (built from
  /// the initial particles) gets the initialisation phase as it then was, the particle sets, the
  /// time loop's state and its own.
  void restore(const Checkpoint& c, Formulation<Dim>& f) {
    const auto& l = c.header.at("loop");
    const bool initialising = l.at("initialising");
    if (!initialising && scene_.initialisation.enabled()) f.set_initialisation(state_, nullptr);
    restore_set(c, "solid", state_.solid);
    restore_set(c, "fluid", state_.fluid);
    state_.index_ids();
    state_.step = c.header.at("step");
    state_.time = c.header.at("time");
    loop_.initialising = initialising;
    loop_.next_frame = l.at("next_frame"), loop_.next_monitor = l.at("next_monitor");
    loop_.next_restart = l.at("next_restart"), loop_.work = l.at("work"), loop_.power = l.at("power");
    loop_.stored0 = l.at("stored0"), loop_.energy0 = l.at("energy0"), loop_.work_max = l.at("work_max");
    loop_.released_max = l.at("released_max"), loop_.dt_min = l.at("dt_min"), loop_.dt_max = l.at("dt_max");
    loop_.time_carry = l.at("time_carry");
    frame_count_ = loop_.frame_count = l.at("frame_count");
    frames_.clear();
    for (const auto& e : l.at("frames"))
      frames_.push_back({e.at(0).get<double>(), e.at(1).get<std::string>(), e.at(2).get<int>(), e.at(3).get<std::string>()});
    f.restore(c, state_);
  }

  /// The final run.json, replacing the `running` one. On a full disk, the padded `running` file
  /// is overwritten in place (no new block needed); if even that fails, stderr says so.
  void write_run_report(const std::string& text, std::string& status) {
    try {
      run_dir_.write_text("run.json", text, true);
    } catch (const files::WriteError& e) {
      const bool in_place = files::overwrite_in_place(dir_ / "run.json", text);
      log_.failure(std::string(e.what()) + (in_place ? "; wrote it in place of the running one" : "; run.json is stale"));
      if (!in_place) status = "failed";
    }
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

  /// The failed particle, before (the last good snapshot) and now. A "fluid" report names a water
  /// point of the double-point set (State::fluid) when there is one; otherwise the index is a
  /// soil point's (single-point formulations carry the pore water on the soil points).
  std::string describe_failure(const ParticleSet<Dim>& before_solid, const ParticleSet<Dim>& before_fluid,
                               const StepContext& ctx) const {
    const auto& h = state_.health;
    const long p = h.particle;
    const bool water_point = h.phase == "fluid" && p < static_cast<long>(state_.fluid.size());
    const ParticleSet<Dim>& now = water_point ? state_.fluid : state_.solid;
    const ParticleSet<Dim>& before = water_point ? before_fluid : before_solid;
    std::ostringstream os;
    if (p < 0 || p >= static_cast<long>(now.size())) {
      os << h.phase << " " << h.what << " in the step from t = " << state_.time << " s (step " << state_.step + 1
         << ", dt = " << ctx.dt << " s). Try a smaller dt (or cfl), or check the loads.";
      return os.str();
    }
    // The snapshot may hold the particles in another order: find this one by id.
    long q = 0;
    while (q < static_cast<long>(before.size()) && before.id[q] != now.id[p]) ++q;
    const int body = now.body[p];
    os << h.phase << " particle " << now.id[p];
    if (body >= 0 && body < static_cast<int>(scene_.bodies.size())) os << " (body \"" << scene_.bodies[body].name << "\")";
    os << " " << h.what << " in the step from t = " << state_.time << " s (step " << state_.step + 1 << ", dt = " << ctx.dt
       << " s); ";
    if (q < static_cast<long>(before.size())) {
      os << "it was at (";
      for (int a = 0; a < Dim; ++a) os << (a ? ", " : "") << before.x[q][a];
      os << ") with speed " << before.v[q].norm() << " m/s at the last good state; now at (";
    } else {
      os << "now at (";
    }
    for (int a = 0; a < Dim; ++a) os << (a ? ", " : "") << now.x[p][a];
    os << "). Try a smaller dt (or cfl), a finer output interval to see the onset, or check the loads.";
    return os.str();
  }

  /// One frame: a VTU per particle set, then results.pvd, which lists a frame only once all of its
  /// files are complete (each is written atomically; a failure throws files::WriteError).
  void write_frame(double t) {
    const auto start = std::chrono::steady_clock::now();
    const int k = frame_count_++;
    const std::size_t listed = frames_.size();
    auto write_set = [&](const char* phase, int part, const scene::PointCloud& cloud) {
      char name[64];
      std::snprintf(name, sizeof name, "%s_%06d.vtu", phase, k);
      run_dir_.claim(std::string("output/") + name);
      scene::write_vtu((dir_ / "output" / name).string(), cloud, compression_);
      frames_.push_back({t, phase, part, name});
    };
    try {
      scene::PointCloud solid = particles_to_cloud(state_.solid);
      add_material_reports(solid, state_.solid, reporters_);
      write_set("solid", 0, solid);
      if (state_.fluid.size()) write_set("fluid", 1, water_points_to_cloud(state_.fluid));
      run_dir_.claim("output/results.pvd");
      scene::write_pvd((dir_ / "output" / "results.pvd").string(), frames_);
    } catch (...) {
      frames_.resize(listed);
      throw;
    }
    frame_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  fs::path dir_;
  files::RunDirectory run_dir_;  // the ledger of what swmpm wrote in dir_
  SolveOptions opt_;
  Log log_;
  scene::Scene scene_;
  State<Dim> state_;
  int threads_ = 1;
  std::vector<scene::PvdEntry> frames_;  // one entry per phase and frame
  std::vector<std::unique_ptr<MaterialModel<Dim>>> reporters_;  // per scene material, for add_material_reports
  scene::VtuCompression compression_ = scene::VtuCompression::zlib;  // output.compression
  int frame_count_ = 0;
  Loop loop_;
  std::string scene_text_;  // RUN_DIR/scene.json as read at the start
  double frame_seconds_ = 0.0;
  double checkpoint_seconds_ = 0.0;  // wall time spent writing restart checkpoints (part of loop_seconds)
  int checkpoints_ = 0;  // wall time spent writing frames (part of loop_seconds)
  double last_good_frame_time_ = 0.0;
};

}  // namespace

int solve(const std::string& run_dir, const SolveOptions& options) {
  if (!fs::exists(fs::path(run_dir) / "scene.json"))
    throw std::runtime_error(run_dir + ": not a run directory (no scene.json; run `swmpm preprocess` first)");
  if (options.threads > 0) omp_set_num_threads(options.threads);
  const scene::Scene s = scene::load_scene((fs::path(run_dir) / "scene.json").string());
  if (s.dimension == 2) return Runner<2>(run_dir, options).run();
  return Runner<3>(run_dir, options).run();
}

}  // namespace swmpm
