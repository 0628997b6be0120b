// `swmpm study`: plan the levels, run them through preprocess and solve, estimate each monitor's
// error (richardson.hpp), pick the cheapest level within the tolerance, write the report
// (report.cpp). docs/study.md describes what the user sees; the rules are written once here.
#include "study/study.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "postprocess/postprocess.hpp"
#include "preprocess/preprocess.hpp"
#include "scene/budget.hpp"
#include "scene/files.hpp"
#include "scene/input.hpp"
#include "scene/scene.hpp"
#include "solver/run.hpp"
#include "study/results.hpp"

namespace swmpm::study {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Relative errors are relative to the extrapolated value, but never to less than this share of
/// the largest magnitude the quantity reaches: a value near zero (a velocity at rest, a pressure
/// dissipated) would make any error look huge.
constexpr double kScaleFloor = 0.1;
/// Ratios of explicit --cell-sizes may differ by this much and still count as constant.
constexpr double kRatioTolerance = 1e-6;
/// The study's own files in STUDY_DIR (the runs have their own ledgers in runs/<label>/).
const std::vector<std::string> kOwnFiles{"study.json", "report.md", "report.html", "cost-error.png"};

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

std::string num(double v, int digits = 4) {
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

/// "h0.025" (4 significant digits: enough to tell levels of any ratio apart).
std::string label_of(double h) { return "h" + num(h, 4); }

/// Whether a grid of cell size h has the two cells per axis the solver needs.
bool grid_allows(const scene::Scene& s, double h) {
  scene::Scene t = s;
  t.grid.cell_size = h;
  for (int a = 0; a < s.dimension; ++a)
    if ((s.grid.max[static_cast<std::size_t>(a)] - s.grid.min[static_cast<std::size_t>(a)]) / h < 2.0 - 1e-9) return false;
  return true;
}

/// Box bodies whose faces lie off the particle lattice of cell size h ((k + 1/2) h/n from the grid's
/// min, so a face belongs on a multiple of h/n): that level seeds a body up to half a particle
/// spacing larger or smaller than the scene's, an error of order h that refining does reduce but
/// that a ratio other than 2 brings in at some levels and not at others.
std::vector<std::string> off_lattice(const scene::Scene& s, double h) {
  std::vector<std::string> out;
  for (const auto& b : s.bodies) {
    if (b.geometry.type != "box") continue;
    const double spacing = h / b.particles_per_cell;
    for (int a = 0; a < s.dimension; ++a) {
      const auto i = static_cast<std::size_t>(a);
      for (double face : {b.geometry.min[i], b.geometry.max[i]}) {
        const double k = (face - s.grid.min[i]) / spacing;
        if (std::abs(k - std::round(k)) > 1e-6) {
          out.push_back("body \"" + b.name + "\": its face at " + std::string(1, "xyz"[a]) + " = " + num(face, 6) +
                        " m is off the particle lattice of h = " + num(h, 6) + " m (spacing " + num(spacing, 4) + " m)");
          break;
        }
      }
    }
  }
  return out;
}

/// The options a user typed, checked before anything runs; the message names the option.
void check_options(const StudyOptions& o) {
  auto bad = [](const std::string& what) { throw std::invalid_argument(what); };
  if (!(o.budget_minutes > 0.0) || !std::isfinite(o.budget_minutes))
    bad("--budget: got " + num(o.budget_minutes) + ", expected a positive number of minutes");
  if (!(o.tolerance > 0.0 && o.tolerance < 1.0))
    bad("--tolerance: got " + num(o.tolerance) + ", expected a relative error between 0 and 1 (0.02 is 2 %)");
  if (o.levels < 3 || o.levels > 8) bad("--levels: got " + std::to_string(o.levels) + ", expected 3 to 8");
  if (!(o.ratio > 1.0 && o.ratio <= 4.0)) bad("--ratio: got " + num(o.ratio) + ", expected a number above 1 and at most 4");
  if (o.metric != "end" && o.metric != "history" && o.metric != "both")
    bad("--metric: got \"" + o.metric + "\", expected end, history or both");
  if (!(o.from >= 0.0) || !std::isfinite(o.from)) bad("--from: got " + num(o.from) + ", expected a time >= 0 [s]");
  if (!o.cell_sizes.empty()) {
    if (o.cell_sizes.size() < 3) bad("--cell-sizes: got " + std::to_string(o.cell_sizes.size()) + " sizes, expected 3 or more");
    for (double h : o.cell_sizes)
      if (!(h > 0.0) || !std::isfinite(h)) bad("--cell-sizes: got " + num(h) + ", expected positive cell sizes [m]");
    const double r = o.cell_sizes[0] / o.cell_sizes[1];
    if (!(r > 1.0)) bad("--cell-sizes: expected sizes from coarse to fine (each smaller than the one before)");
    for (std::size_t k = 1; k < o.cell_sizes.size(); ++k)
      if (std::abs(o.cell_sizes[k - 1] / o.cell_sizes[k] / r - 1.0) > kRatioTolerance)
        bad("--cell-sizes: the ratio of " + num(o.cell_sizes[k - 1], 6) + " to " + num(o.cell_sizes[k], 6) + " is " +
            num(o.cell_sizes[k - 1] / o.cell_sizes[k], 6) + ", not " + num(r, 6) +
            " like the first two; expected a constant refinement ratio (Richardson extrapolation needs one)");
  }
}

/// The monitors.csv columns the study estimates: every "<monitor>.<quantity>" of the scene, or
/// those --monitor names (a monitor name selects all its quantities).
std::vector<std::string> selected_columns(const scene::Scene& s, const StudyOptions& o) {
  std::vector<std::string> all;
  for (const auto& m : s.output.monitors)
    for (const auto& q : m.quantities) all.push_back(m.name + "." + q);
  if (all.empty())
    throw scene::SceneError({o.scene_path + ": /output/monitors: the scene has no monitor, and the study estimates the "
                             "error of monitored quantities; expected at least one monitor"});
  if (o.monitors.empty()) return all;
  std::vector<std::string> out;
  for (const auto& want : o.monitors) {
    bool found = false;
    for (const auto& c : all)
      if (c == want || c.substr(0, c.find('.')) == want) {
        if (std::find(out.begin(), out.end(), c) == out.end()) out.push_back(c);
        found = true;
      }
    if (!found) {
      std::string list;
      for (const auto& c : all) list += (list.empty() ? "" : ", ") + c;
      throw std::invalid_argument("--monitor: got \"" + want + "\", which is no monitor or monitor.quantity of " +
                                  o.scene_path + " (available: " + list + ")");
    }
  }
  return out;
}

/// One progress line over the whole study on a terminal: the share of the predicted total done,
/// the run in progress, and the time left (the predictions corrected by how the finished runs
/// compared with theirs).
class ProgressBar {
 public:
  explicit ProgressBar(bool on) : on_(on) {}
  void start_level(std::size_t index, std::size_t total, const std::string& label, double predicted) {
    index_ = index;
    total_ = total;
    label_ = label;
    predicted_ = predicted;
    level_start_ = Clock::now();
    draw(0.0, true);
  }
  void plan(double done_predicted, double total_predicted, double correction) {
    done_ = done_predicted;
    all_ = total_predicted;
    correction_ = correction;
  }
  void update(double fraction) { draw(fraction, false); }
  void clear() {
    if (on_) std::fprintf(stderr, "\r%*s\r", 100, "");
  }

 private:
  void draw(double fraction, bool force) {
    if (!on_) return;
    const auto now = Clock::now();
    if (!force && std::chrono::duration<double>(now - last_).count() < 0.5) return;
    last_ = now;
    fraction = std::clamp(fraction, 0.0, 1.0);
    char line[200];
    if (all_ > 0.0) {
      const double done = std::min(1.0, (done_ + fraction * predicted_) / all_);
      const int width = 24, filled = static_cast<int>(done * width);
      const double left = std::max(0.0, (all_ - done_ - fraction * predicted_) * correction_);
      std::snprintf(line, sizeof line, "  study [%s%s] %3.0f %% | run %zu of %zu (%s) | ETA %s   ",
                    std::string(static_cast<std::size_t>(filled), '#').c_str(),
                    std::string(static_cast<std::size_t>(width - filled), '.').c_str(), 100.0 * done, index_ + 1, total_,
                    label_.c_str(), scene::format_duration(left).c_str());
    } else {  // the first run: it measures what the others will cost
      std::snprintf(line, sizeof line, "  study: run 1 (%s) measures the cost of the others | %3.0f %% of it   ",
                    label_.c_str(), 100.0 * fraction);
    }
    std::fprintf(stderr, "\r%s", line);
    std::fflush(stderr);
  }

  bool on_;
  std::size_t index_ = 0, total_ = 0;
  std::string label_;
  double predicted_ = 0.0, done_ = 0.0, all_ = 0.0, correction_ = 1.0;
  Clock::time_point level_start_ = Clock::now(), last_ = Clock::now();
};

class Study {
 public:
  explicit Study(const StudyOptions& o) : o_(o) {}

  int run() {
    check_options(o_);
    // The scene is checked as preprocess checks it (writes nothing; throws SceneError).
    pre::explain(o_.scene_path);
    s_ = scene::load_scene(o_.scene_path);
    columns_ = selected_columns(s_, o_);
    r_.scene_path = o_.scene_path;
    r_.scene_name = s_.name;
    r_.dimension = s_.dimension;
    r_.formulation = scene::to_string(s_.formulation);
    r_.shape_function = scene::to_string(s_.grid.shape_function);
    r_.h0 = s_.grid.cell_size;
    r_.tolerance = o_.tolerance;
    r_.budget_seconds = 60.0 * o_.budget_minutes;
    r_.metric = o_.metric;
    r_.from = o_.from;
    r_.end_time = s_.time.end;
    r_.dt_rule = s_.time.dt ? "time.dt " + num(*s_.time.dt, 6) + " s at h0, scaled with h (the same Courant number)"
                            : "auto: cfl " + num(s_.time.cfl, 3) + " x the critical step, which follows h";
    if (!(o_.from < s_.time.end))
      throw std::invalid_argument("--from: got " + num(o_.from) + " s, expected a time before the scene's time.end " +
                                  num(s_.time.end) + " s");
    plan_candidates();
    for (const auto& L : candidates_)
      for (const auto& line : off_lattice(s_, L.h)) r_.notes.push_back(line + ": that level models a slightly different body");
    dir_ = o_.out_dir.empty() ? fs::path("study") / s_.name : fs::path(o_.out_dir);
    r_.study_dir = dir_.string();
    prepare_directory();

    // Run from the coarsest: it is the cheapest, and its measured cost predicts the others'.
    if (!o_.quiet) {
      std::cout << "study: " << candidates_.size() << " levels possible, " << candidates_.front().label << " to "
                << candidates_.back().label << " (ratio " << num(r_.ratio, 4) << "); " << candidates_.front().label
                << " runs first and measures the cost; the finest that fits --budget " << num(o_.budget_minutes)
                << " min runs last\n";
      for (const auto& note : r_.notes) std::cout << "study: note: " << note << "\n";
      std::cout << std::flush;
    }
    files::RunDirectory ledger(dir_);
    bar_ = ProgressBar(!o_.quiet && isatty(fileno(stderr)));
    const auto study_start = Clock::now();
    int status = 0;
    for (std::size_t k = 0; k < candidates_.size(); ++k) {
      LevelRun L = candidates_[k];
      if (k > 0) {
        if (!r_.levels.back().completed() && r_.levels.back().wall <= 0.0) break;  // refused: no cost to scale
        if (k == 1) {
          if (const int refused = plan_after_first(); refused != 0) {
            bar_.clear();
            return refused;
          }
        } else {
          replan();
        }
        if (k >= candidates_.size()) break;
        L = candidates_[k];
        L.predicted = predict(L.j);
        bar_.plan(done_predicted_, done_predicted_ + remaining_predicted(k), correction());
      }
      bar_.start_level(k, candidates_.size(), L.label, L.predicted);
      status = run_level(L, ledger);
      r_.levels.push_back(L);
      done_predicted_ += L.predicted > 0.0 ? L.predicted : L.cost();
      actual_ += L.cost();
      predicted_ += L.predicted > 0.0 ? L.predicted : L.cost();
      say(L);
      if (status == 4 || status == 5) break;  // interrupted, or a write failed: the study stops too
    }
    bar_.clear();
    r_.total_seconds = seconds_since(study_start);
    if (status == 4 || status == 5) {
      std::cerr << "swmpm study: stopped: run " << r_.levels.back().label << " ended with status "
                << r_.levels.back().status << "; no report was written (the runs so far are in "
                << (dir_ / "runs").string() << ")\n";
      return status;
    }
    estimate();
    const std::string report = write_outputs(r_, ledger);
    summary(report);
    return r_.count >= 3 ? 0 : 3;
  }

 private:
  /// The levels that may run, coarse to fine: --cell-sizes as given, or h0 r^-j for j from the
  /// coarsest the grid allows (at most levels - 1 coarsenings of the scene's h0) to levels - 1
  /// refinements of it. Which of the fine ones run is for the budget to say (plan_after_first).
  void plan_candidates() {
    const double h0 = s_.grid.cell_size;
    if (!o_.cell_sizes.empty()) {
      r_.ratio = o_.cell_sizes[0] / o_.cell_sizes[1];
      for (std::size_t k = 0; k < o_.cell_sizes.size(); ++k) {
        const double h = o_.cell_sizes[k];
        if (!grid_allows(s_, h))
          throw std::invalid_argument("--cell-sizes: " + num(h, 6) + " m leaves fewer than 2 cells along an axis of the grid of " +
                                      o_.scene_path + "; expected smaller cell sizes");
        candidates_.push_back(level(static_cast<int>(k), h));
      }
      fixed_ = true;
      r_.fixed = true;
      return;
    }
    r_.ratio = o_.ratio;
    int j_min = -(o_.levels - 1);
    while (j_min < 0 && !grid_allows(s_, h0 * std::pow(o_.ratio, -j_min))) ++j_min;
    if (!grid_allows(s_, h0))
      throw scene::SceneError({o_.scene_path + ": /grid/cell_size: the grid has fewer than 2 cells along an axis"});
    for (int j = j_min; j <= o_.levels - 1; ++j) candidates_.push_back(level(j, h0 * std::pow(o_.ratio, -j)));
    if (j_min < 0)
      r_.notes.push_back("coarser levels than the scene's h0 = " + num(h0, 6) + " m run first: they cost little (" +
                         num(std::pow(o_.ratio, s_.dimension + 1), 3) + "x less per coarsening) and show the trend");
  }

  LevelRun level(int j, double h) const {
    LevelRun L;
    L.j = j;
    L.h = h;
    L.label = label_of(h);
    return L;
  }

  /// Refuses an existing study unless --overwrite (then removes only what swmpm wrote: the runs
  /// of the earlier study and its own files), and any file of a name it would write that swmpm
  /// did not write. Nothing is removed before every check has passed.
  void prepare_directory() {
    files::RunDirectory ledger(dir_);
    if (ledger.holds_a_run() && !o_.overwrite)
      throw files::RunDirectoryError(dir_.string() + ": holds an earlier swmpm study or run; pass --overwrite to replace "
                                     "it (only the files swmpm wrote there are removed), or choose another folder (-o)");
    std::vector<std::string> names = kOwnFiles;
    for (const auto& L : candidates_) names.push_back("scenes/" + L.label + ".json");
    if (const auto foreign = ledger.foreign(names); !foreign.empty())
      throw files::RunDirectoryError((dir_ / foreign.front()).string() +
                                     " exists and swmpm did not write it; swmpm never replaces or removes a file it did "
                                     "not write: choose an empty or new folder (-o)");
    // Runs of an earlier study (named by its scenes/<label>.json) and the runs this one will write.
    std::set<std::string> labels;
    for (const auto& L : candidates_) labels.insert(L.label);
    if (o_.overwrite) {
      for (const auto& rel : ledger_entries())
        if (rel.rfind("scenes/", 0) == 0 && rel.size() > 12) labels.insert(fs::path(rel).stem().string());
    }
    for (const auto& label : labels) pre::check_run_directory(files::RunDirectory(dir_ / "runs" / label), o_.overwrite);
    if (!o_.overwrite) return;
    for (const auto& label : labels) files::RunDirectory(dir_ / "runs" / label).remove_owned([](const std::string&) { return true; });
    std::error_code ec;
    fs::remove(dir_ / "runs", ec);  // only when empty
    files::RunDirectory(dir_).remove_owned([](const std::string&) { return true; });
  }

  std::vector<std::string> ledger_entries() const {
    std::vector<std::string> out;
    std::ifstream in(dir_ / ".swmpm-files");
    for (std::string line; std::getline(in, line);)
      if (!line.empty()) out.push_back(line);
    return out;
  }

  /// Preprocess and solve one level; fills in what its run.json says. Returns solve's status
  /// (0 completed, 3 diverged, 4 interrupted, 5 a failed write), or 2 when the level was refused.
  int run_level(LevelRun& L, files::RunDirectory& ledger) {
    scene::Scene ls = s_;
    ls.grid.cell_size = L.h;
    if (ls.time.dt) *ls.time.dt *= L.h / s_.grid.cell_size;
    const std::string scene_rel = "scenes/" + L.label + ".json";
    ledger.write_text(scene_rel, scene::to_json(ls).dump(2) + "\n");
    const fs::path run_dir = dir_ / "runs" / L.label;
    const auto t0 = Clock::now();
    std::string dir;
    try {
      pre::PreprocessOptions po;
      po.quiet = true;
      po.overwrite = o_.overwrite;
      po.trust_geometry = o_.trust_geometry;
      po.max_memory = o_.max_memory;
      dir = pre::preprocess((dir_ / scene_rel).string(), run_dir.string(), po);
    } catch (const scene::SceneError& e) {  // e.g. a fine level over the memory limit
      L.status = "refused: " + e.lines().front();
      return 2;
    }
    L.preprocess = seconds_since(t0);
    SolveOptions so;
    so.threads = o_.threads;
    so.quiet = true;
    so.max_memory = o_.max_memory;
    so.progress = [this](double done) { bar_.update(done); };
    int rc = 0;
    try {
      rc = swmpm::solve(dir, so);
    } catch (const files::WriteError&) {
      throw;
    } catch (const std::exception& e) {
      L.status = std::string("failed: ") + e.what();
      return 2;
    }
    read_run(L, run_dir);
    return rc;
  }

  void read_run(LevelRun& L, const fs::path& run_dir) const {
    const nlohmann::json rj = scene::read_json_file((run_dir / "run.json").string(), "run.json");
    L.status = rj.value("status", "unknown");
    L.wall = rj.value("wall_seconds", 0.0);
    L.loop = rj.value("loop_seconds", 0.0);
    L.steps = rj.value("steps", 0.0);
    L.dt = rj.value("dt", 0.0);
    L.end_time = rj.value("end_time", 0.0);
    L.us_per_particle_step = rj.value("us_per_particle_step", 0.0);
    if (rj.contains("particles"))
      for (const auto& [phase, n] : rj["particles"].items()) L.particles += n.get<double>();
    if (rj.contains("stability") && rj["stability"].contains("worst")) {
      L.worst = rj["stability"]["worst"];
      const auto& thresholds = rj["stability"].value("thresholds", nlohmann::json::object());
      for (const auto& [key, w] : L.worst.items()) {
        if (!w.is_object() || w.value("crossed_frames", 0) <= 0) continue;
        std::string bound;
        if (thresholds.contains(key))
          for (const auto& [side, value] : thresholds[key].items()) bound = " (" + side + " " + num(value.get<double>(), 3) + ")";
        L.crossed.push_back(key + " " + num(w.value("value", kNaN), 3) + bound);
      }
    }
  }

  // ---- cost: measured on the last run, scaled by particles x steps ------------------------------

  /// The wall time of level j predicted from the finest level run so far: its time loop scales
  /// with particles x steps (h^-dim x h^-1), preprocess and setup with particles (h^-dim). A run
  /// that stopped early (diverged) is scaled to the whole span.
  double predict(int j) const {
    const LevelRun* base = nullptr;
    for (const auto& L : r_.levels)
      if (L.wall > 0.0) base = &L;
    if (base == nullptr) return 0.0;
    const double t_start = s_.initialisation.enabled() ? -s_.initialisation.duration : 0.0;
    const double reached = base->end_time - t_start, span = s_.time.end - t_start;
    const double stretch = reached > 0.0 ? std::max(1.0, span / reached) : 1.0;
    const double per = std::pow(r_.ratio, j - base->j);
    const double dim = static_cast<double>(s_.dimension);
    return base->loop * stretch * std::pow(per, dim + 1.0) + (base->cost() - base->loop) * std::pow(per, dim);
  }

  double remaining_predicted(std::size_t from) const {
    double s = 0.0;
    for (std::size_t k = from; k < candidates_.size(); ++k) s += predict(candidates_[k].j);
    return s;
  }

  /// How the finished runs compared with their predictions (1 before any was predicted).
  double correction() const { return predicted_ > 0.0 && actual_ > 0.0 ? actual_ / predicted_ : 1.0; }

  /// After the first run: the finest level whose cumulative predicted cost stays within the
  /// budget; at least --levels levels, or the study is refused (status 1) with what it would need.
  int plan_after_first() {
    const double spent = r_.levels.front().cost();
    const std::size_t fewest = static_cast<std::size_t>(fixed_ ? candidates_.size() : o_.levels);
    double total = spent;
    std::size_t keep = 1;
    for (std::size_t k = 1; k < candidates_.size(); ++k) {
      const double next = total + predict(candidates_[k].j);
      if (next > r_.budget_seconds && k >= fewest) break;
      total = next;
      keep = k + 1;
    }
    if (total > r_.budget_seconds) {
      std::cerr << "swmpm study: --budget " << num(o_.budget_minutes) << " min is too small: the " << keep
                << " levels from h = " << num(candidates_.front().h, 6) << " to " << num(candidates_[keep - 1].h, 6)
                << " m would take about " << scene::format_duration(total) << " (measured " << num(spent, 3)
                << " s at h = " << num(candidates_.front().h, 6) << " m, x"
                << num(std::pow(r_.ratio, s_.dimension + 1), 3) << " per refinement); expected --budget "
                << num(std::ceil(total / 60.0 * 1.2), 4) << " or more"
                << (fixed_ ? ", or coarser --cell-sizes" : ", a smaller --ratio or a coarser scene cell size")
                << " (the first run is kept in " << (dir_ / "runs" / candidates_.front().label).string() << ")\n";
      return 1;
    }
    if (keep < candidates_.size()) {
      r_.notes.push_back("the budget of " + num(o_.budget_minutes) + " min stops the study at h = " +
                         num(candidates_[keep - 1].h, 6) + " m: h = " + num(candidates_[keep].h, 6) +
                         " m would add about " + scene::format_duration(predict(candidates_[keep].j)));
      candidates_.resize(keep);
    }
    return 0;
  }

  /// Before each later run: the prediction from the latest run; a planned finest level that would
  /// now take the study past 1.25 x its budget is dropped while --levels levels remain.
  void replan() {
    if (fixed_) return;
    const std::size_t next = r_.levels.size();
    while (candidates_.size() > static_cast<std::size_t>(o_.levels) && candidates_.size() > next) {
      const double total = actual_ + remaining_predicted(next);
      if (total <= 1.25 * r_.budget_seconds) break;
      r_.notes.push_back("h = " + num(candidates_.back().h, 6) + " m was dropped: the runs so far predict " +
                         scene::format_duration(total) + " for the study, over the budget of " +
                         num(o_.budget_minutes) + " min");
      candidates_.pop_back();
    }
  }

  void say(const LevelRun& L) {
    if (o_.quiet) return;
    bar_.clear();
    std::cout << "study: " << L.label << ": " << L.status;
    if (L.wall > 0.0)
      std::cout << ", " << num(L.particles, 6) << " particles, " << num(L.steps, 6) << " steps, "
                << num(L.cost(), 3) << " s" << (L.predicted > 0.0 ? " (predicted " + num(L.predicted, 3) + " s)" : "");
    if (!L.crossed.empty()) {
      std::cout << "; stability thresholds crossed:";
      for (const auto& c : L.crossed) std::cout << " " << c;
    }
    std::cout << "\n" << std::flush;
  }

  // ---- estimates -----------------------------------------------------------------------------

  /// The block: the longest run of consecutive completed levels that ends at the finest completed.
  void choose_block() {
    const auto& lv = r_.levels;
    std::size_t end = lv.size();
    while (end > 0 && !lv[end - 1].completed()) --end;
    std::size_t first = end;
    while (first > 0 && lv[first - 1].completed()) --first;
    r_.first = first;
    r_.count = end - first;
  }

  static double interpolate(const std::vector<double>& t, const std::vector<double>& v, double x) {
    if (x <= t.front()) return v.front();
    if (x >= t.back()) return v.back();
    const auto it = std::upper_bound(t.begin(), t.end(), x);
    const std::size_t i = static_cast<std::size_t>(it - t.begin());
    const double w = (x - t[i - 1]) / (t[i] - t[i - 1]);
    return (1.0 - w) * v[i - 1] + w * v[i];
  }

  void estimate() {
    choose_block();
    if (r_.count < 3) {
      r_.notes.push_back("fewer than three consecutive levels completed: no error is estimated");
      return;
    }
    std::vector<post::Table> tables;
    for (std::size_t k = r_.first; k < r_.first + r_.count; ++k)
      tables.push_back(post::read_csv((dir_ / "runs" / r_.levels[k].label / "monitors.csv").string()));
    for (const auto& column : columns_) {
      std::vector<std::vector<double>> t, v;
      bool finite = true;
      for (const auto& tab : tables) {
        t.push_back(tab.column("time"));
        v.push_back(tab.column(column));
        for (double x : v.back()) finite = finite && std::isfinite(x);
      }
      double magnitude = 0.0;
      for (double x : v.back())
        if (std::isfinite(x)) magnitude = std::max(magnitude, std::abs(x));
      for (const std::string metric : {"end", "history"}) {
        if (o_.metric != "both" && o_.metric != metric) continue;
        Series s;
        s.column = column;
        s.metric = metric;
        s.magnitude = magnitude;
        std::vector<std::vector<double>> q;
        if (!finite) s.skipped = "a run wrote a value that is not a number (no water on a gauge line?)";
        else if (magnitude == 0.0) s.skipped = "zero in the finest run";
        if (s.skipped.empty()) {
          if (metric == "end") {
            for (const auto& vk : v) q.push_back({vk.back()});
          } else {
            // The coarsest level's monitor times in [from, end]; every level interpolated onto them.
            std::vector<double> times;
            for (double x : t.front())
              if (x >= o_.from - 1e-12) times.push_back(x);
            if (times.size() < 2) s.skipped = "fewer than two monitor rows after --from";
            for (std::size_t k = 0; k < v.size() && s.skipped.empty(); ++k) {
              std::vector<double> row;
              for (double x : times) row.push_back(interpolate(t[k], v[k], x));
              q.push_back(std::move(row));
            }
          }
        }
        if (s.skipped.empty()) {
          s.samples = q.front().size();
          s.e = extrapolate(q, r_.ratio, magnitude);
          const double reference = metric == "end" ? std::abs(s.e.extrapolated.front()) : rms(s.e.extrapolated);
          s.scale = std::max(reference, kScaleFloor * magnitude);
          for (double e : s.e.error) s.relative.push_back(e / s.scale);
        }
        r_.series.push_back(std::move(s));
      }
    }
    recommend();
  }

  /// The cheapest level of the block whose every estimate is within the tolerance; else the cell
  /// size the worst estimate needs, at its observed order (first order when flagged).
  void recommend() {
    const std::size_t n = r_.count;
    double best_cost = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < n; ++k) {
      bool ok = true;
      for (const auto& s : r_.series)
        if (s.skipped.empty() && !(s.relative[k] <= r_.tolerance)) ok = false;
      const LevelRun& L = r_.levels[r_.first + k];
      if (ok && !L.crossed.empty()) {
        r_.notes.push_back(L.label + " is within the tolerance but its run crossed a stability threshold (" +
                           L.crossed.front() + "): not recommended");
        ok = false;
      }
      if (ok && L.cost() < best_cost) {
        best_cost = L.cost();
        r_.recommended = static_cast<int>(r_.first + k);
      }
    }
    const LevelRun& finest = r_.levels[r_.first + n - 1];
    for (const auto& s : r_.series) {
      if (!s.skipped.empty()) continue;
      if (s.relative[n - 1] > r_.worst_error || r_.worst_series.empty()) {
        r_.worst_error = s.relative[n - 1];
        r_.worst_series = s.name();
      }
      if (r_.recommended >= 0 || !(s.relative[n - 1] > r_.tolerance)) continue;
      const double p = s.e.asymptotic && !s.e.converged ? s.e.order : 1.0;
      const double h = cell_size_for(finest.h, s.relative[n - 1], r_.tolerance, p);
      if (std::isnan(r_.needed_cell_size) || h < r_.needed_cell_size) r_.needed_cell_size = h;
    }
    if (!std::isnan(r_.needed_cell_size)) {
      const double per = finest.h / r_.needed_cell_size;
      const double dim = static_cast<double>(s_.dimension);
      r_.needed_seconds = finest.loop * std::pow(per, dim + 1.0) + (finest.cost() - finest.loop) * std::pow(per, dim);
    }
  }

  void summary(const std::string& report) const {
    if (o_.quiet) return;
    if (r_.count < 3) {
      std::cout << "study: fewer than three consecutive levels completed; no error estimated\n";
    } else if (r_.recommended >= 0) {
      const LevelRun& L = r_.levels[static_cast<std::size_t>(r_.recommended)];
      std::cout << "study: cheapest within " << num(100.0 * r_.tolerance, 3) << " %: " << L.label << " (cell size "
                << num(L.h, 6) << " m, " << num(L.cost(), 3) << " s)\n";
    } else {
      std::cout << "study: no level is within " << num(100.0 * r_.tolerance, 3) << " % (worst at the finest: "
                << r_.worst_series << ", " << num(100.0 * r_.worst_error, 3) << " %); a cell size of about "
                << num(r_.needed_cell_size, 3) << " m would be, in about "
                << scene::format_duration(r_.needed_seconds) << "\n";
    }
    std::cout << "study: " << report << "\n";
  }

  StudyOptions o_;
  scene::Scene s_;
  std::vector<std::string> columns_;
  std::vector<LevelRun> candidates_;
  bool fixed_ = false;  // --cell-sizes: the levels as given
  fs::path dir_;
  Results r_;
  ProgressBar bar_{false};
  double done_predicted_ = 0.0, actual_ = 0.0, predicted_ = 0.0;
};

}  // namespace

int run_study(const StudyOptions& options) { return Study(options).run(); }

}  // namespace swmpm::study
