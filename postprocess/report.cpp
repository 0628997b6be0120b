// report: RUN_DIR/report.md and RUN_DIR/report.html, one page that says what was run, which
// formulation ran and why, what it cost, how stable it stayed (the run's own indicators), how it
// compares with the references given, and shows the monitors and the fields at the last frame.
// The two files hold the same page: report.md links the PNGs in plots/, report.html embeds them
// (base64 data URIs, VTK's encoder) so that it is one self-contained file to send or archive.
// Reads scene.json and run.json as JSON (not through the scene parser) so a report can still be
// written for a run made by an older or newer version.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "postprocess/format.hpp"
#include "postprocess/page.hpp"
#include "postprocess/postprocess.hpp"
#include "scene/budget.hpp"
#include "scene/files.hpp"
#include "scene/input.hpp"
#include "scene/pointcloud.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace swmpm::post {

namespace {

json load(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw std::runtime_error(path.string() + ": missing (is this a run directory written by swmpm?)");
  return scene::read_json_file(path.string(), "JSON file");
}

/// A JSON value as a person reads it: numbers with 6 digits, arrays as (a, b), strings bare.
std::string text(const json& v) {
  if (v.is_number()) return num(v.get<double>());
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string s = "(";
    for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + text(v[k]);
    return s + ")";
  }
  if (v.is_null()) return "—";
  return v.dump();
}

std::string get(const json& j, const std::string& key) { return j.contains(key) ? text(j[key]) : "—"; }

using Rows = std::vector<std::vector<std::string>>;

void setup_section(Page& page, const json& scene, const json& run) {
  const int dim = scene.value("dimension", run.value("dimension", 2));
  Rows rows{{"scene", get(scene, "name")},
            {"formulation", get(run.contains("formulation") ? run : scene, "formulation")},
            {"dimension", std::to_string(dim) + (dim == 2 ? " (plane strain; extensive quantities per metre)" : "")}};
  if (scene.contains("grid")) {
    const auto& g = scene["grid"];
    rows.push_back({"shape function", get(g, "shape_function")});
    std::string cells;
    if (g.contains("min") && g.contains("max") && g.contains("cell_size")) {
      const double h = g["cell_size"].get<double>();
      for (std::size_t a = 0; a < g["min"].size(); ++a)
        cells += (a ? " × " : "") + std::to_string(std::lround((g["max"][a].get<double>() - g["min"][a].get<double>()) / h));
    }
    std::string grid = "cell size " + get(g, "cell_size") + " m, from " + get(g, "min") + " to " + get(g, "max") +
                       " m, " + cells + " cells";
    if (run.contains("active_cells")) grid += ", " + get(run, "active_cells") + " holding particles";
    rows.push_back({"grid", grid});
  }
  if (run.contains("particles") && run["particles"].is_object()) {
    std::string p;
    for (const auto& [phase, n] : run["particles"].items()) p += (p.empty() ? "" : ", ") + phase + " " + text(n);
    rows.push_back({"particles", p});
  }
  std::string gravity = get(scene, "gravity") + " m/s²";
  if (scene.value("gravity_ramp", 0.0) > 0.0) gravity += ", ramped over " + get(scene, "gravity_ramp") + " s";
  rows.push_back({"gravity", gravity});
  if (scene.contains("time")) {
    const auto& t = scene["time"];
    std::string time = "end " + get(t, "end") + " s, dt " + get(t, "dt");
    if (t.contains("cfl") && t.value("dt", json()).is_string()) time += " (cfl " + get(t, "cfl") + ")";  // auto
    rows.push_back({"time", time});
  }
  page.add_heading("Setup");
  page.add_table({"", ""}, rows);
  if (scene.contains("materials")) {
    Rows m_rows;
    for (const auto& m : scene["materials"]) {
      std::string params;
      for (const auto& [key, value] : m.items())
        if (key != "name" && key != "model") params += (params.empty() ? "" : ", ") + key + " " + text(value);
      m_rows.push_back({get(m, "name"), get(m, "model"), params});
    }
    page.add_paragraph("Materials:");
    page.add_table({"name", "model", "parameters"}, m_rows);
  }
  if (scene.contains("bodies")) {
    Rows b_rows;
    for (const auto& b : scene["bodies"]) {
      std::string geometry = b.contains("geometry") ? get(b["geometry"], "type") : "—";
      if (b.contains("geometry") && b["geometry"].contains("file")) geometry += " " + get(b["geometry"], "file");
      b_rows.push_back({get(b, "name"), geometry, get(b, "solid"), get(b, "fluid"), get(b, "particles_per_cell")});
    }
    page.add_paragraph("Bodies:");
    page.add_table({"name", "geometry", "solid", "fluid", "particles per cell"}, b_rows);
  }
}

/// Which formulation ran and why: named in the scene, or chosen by "auto" with both estimates.
/// A duration in seconds at `key` ("47 s", "3.2 min"), or "—".
std::string duration_at(const json& j, const std::string& key) {
  return j.contains(key) && j[key].is_number() ? scene::format_duration(j[key].get<double>()) : "—";
}

void formulation_section(Page& page, const json& run) {
  page.add_heading("Formulation");
  const json choice = run.value("formulation_choice", json());
  const std::string ran = get(run, "formulation");
  if (!choice.is_object() || !choice.value("automatic", false)) {
    const std::string reason = run.value("formulation_reason", std::string());
    page.add_paragraph("`" + ran + "`, as the scene file names it." + (reason.empty() ? "" : " " + reason));
    return;
  }
  page.add_paragraph("`" + ran + "`, chosen by `\"formulation\": \"auto\"` before the first step: " +
                     choice.value("reason", std::string("(no reason recorded)")));
  const json estimates = choice.value("estimates", json::array());
  if (!estimates.is_array() || estimates.empty()) return;
  Rows rows;
  for (const auto& e : estimates)
    rows.push_back({get(e, "formulation"), get(e, "dt"), get(e, "steps"), get(e, "us_per_point_step"),
                    duration_at(e, "wall_seconds"), get(e, "dt_reason")});
  page.add_paragraph("The estimates it compared (one thread; µs per point-step as measured on the bench machine):");
  page.add_table({"formulation", "dt [s]", "steps", "µs per point-step", "estimated wall time", "step limited by"}, rows);
  if (run.contains("wall_seconds"))
    page.add_paragraph("This run took " + duration_at(run, "wall_seconds") + " on " + get(run, "threads") + " thread(s).");
}

void cost_section(Page& page, const json& run) {
  Rows rows{{"status", get(run, "status") + (run.contains("diagnosis") ? " — " + get(run, "diagnosis") : "")},
            {"steps", get(run, "steps") + " to t = " + get(run, "end_time") + " s"},
            {"dt", get(run, "dt") + " s (mean; min " + get(run, "dt_min") + ", max " + get(run, "dt_max") +
                       "), limited by " + get(run, "dt_limit")},
            {"wall time", get(run, "wall_seconds") + " s (time loop " + get(run, "loop_seconds") + " s)"},
            {"µs per particle-step",
             get(run, "us_per_particle_step") + " (time loop " + get(run, "loop_us_per_particle_step") + ")"},
            {"threads", get(run, "threads")}};
  if (run.contains("peak_memory_bytes"))
    rows.push_back({"peak memory", num(run["peak_memory_bytes"].get<double>() / (1024.0 * 1024.0), 4) + " MiB"});
  rows.push_back({"frames", get(run, "frames")});
  rows.push_back({"software", "swmpm " + get(run, "software_version") + " (" + get(run, "git_hash") + ")"});
  page.add_heading("Cost");
  page.add_table({"", ""}, rows);
  if (run.contains("stage_seconds") && run["stage_seconds"].is_object() && !run["stage_seconds"].empty()) {
    // Largest first: JSON objects come back in key order, which says nothing about cost.
    std::vector<std::pair<double, std::string>> stages;
    double total = 0.0;
    for (const auto& [stage, s] : run["stage_seconds"].items()) {
      stages.emplace_back(s.get<double>(), stage);
      total += s.get<double>();
    }
    std::sort(stages.rbegin(), stages.rend());
    // Shares of the time loop: the stages time the formulation's step; the rest of the loop writes
    // frames and monitors and checks energy (a large share in small or frame-heavy runs).
    const double loop = run.contains("loop_seconds") ? run["loop_seconds"].get<double>() : total;
    const double whole = std::max(loop, total);
    Rows s_rows;
    for (const auto& [seconds, stage] : stages)
      s_rows.push_back({stage, num(seconds, 4), num(whole > 0 ? 100.0 * seconds / whole : 0.0, 3) + " %"});
    if (whole > total)
      s_rows.push_back({"frames, monitors, energy checks", num(whole - total, 4), num(100.0 * (whole - total) / whole, 3) + " %"});
    page.add_paragraph("Where the time loop's time went (stages of the formulation, and the rest of the loop):");
    page.add_table({"stage", "seconds", "share of the loop"}, s_rows);
  }
}

/// The run's own stability indicators (run.json `stability`): per indicator its threshold, the
/// worst value with its time and place, and how many frames crossed the threshold.
void stability_section(Page& page, const json& run) {
  page.add_heading("Stability");
  if (!run.contains("stability") || !run["stability"].is_object()) {
    page.add_paragraph("run.json has no `stability` record (a run made before the indicators existed).");
    return;
  }
  const json& st = run["stability"];
  const json thresholds = st.value("thresholds", json::object());
  const json worst = st.value("worst", json::object());
  const json omitted = st.value("omitted", json::object());
  const std::size_t frames = st.contains("frames") ? st["frames"].value("time", json::array()).size() : 0;
  // In run.json's order (the reader's json sorts keys), then any indicator a newer version adds.
  std::vector<std::string> keys{"pressure_checkerboard", "mean_stress_checkerboard", "energy_error",
                                "spurious_velocity",     "porosity_min",             "porosity_max",
                                "J_min",                 "J_max",                    "cavitation_fraction"};
  for (const auto& [key, limit] : thresholds.items())
    if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
  Rows rows;
  int crossed = 0;
  for (const std::string& key : keys) {
    if (!thresholds.contains(key)) continue;
    const json& limit = thresholds[key];
    std::string name = key;
    std::replace(name.begin(), name.end(), '_', ' ');
    std::string bound = "—";
    if (limit.is_object() && !limit.empty()) bound = limit.begin().key() + " " + text(limit.begin().value());
    if (omitted.contains(key)) {
      rows.push_back({name, bound, "not measured", "", "", omitted[key].is_string() ? omitted[key].get<std::string>() : ""});
      continue;
    }
    const json w = worst.value(key, json());
    if (!w.is_object()) {
      rows.push_back({name, bound, "—", "", "", ""});
      continue;
    }
    const int n = w.value("crossed_frames", 0);
    crossed += n > 0;
    std::string where;
    if (const json at = w.value("where", json()); at.is_object() && at.contains("set"))
      where = get(at, "set") + " " + (at.contains("node") ? get(at, "node") : get(at, "particle")) + " at " + get(at, "position");
    rows.push_back({name, bound, num(w.value("value", 0.0), 4), get(w, "time"), where,
                    n > 0 ? "CROSSED in " + std::to_string(n) + " of " + std::to_string(frames) + " frames" : "within"});
  }
  const std::string definitions = "docs/verification.md, \"Stability indicators of every run\"";
  page.add_paragraph(crossed == 0 ? "Every indicator stayed within its threshold over the " + std::to_string(frames) +
                                        " frames (definitions: " + definitions + ")."
                                  : std::to_string(crossed) +
                                        " indicator(s) crossed their threshold: read the results with care (definitions "
                                        "and what a crossing means: " + definitions + ").");
  page.add_table({"indicator", "threshold", "worst", "at t [s]", "where", "verdict"}, rows);
}

void comparison_section(Page& page, const std::string& run_dir, const std::vector<ReferenceSpec>& refs) {
  if (refs.empty()) return;
  page.add_heading("Comparison with references");
  page.add_paragraph("The monitor is interpolated linearly onto the reference times inside the run's time span. "
                     "Relative L2 = ‖run − reference‖₂ / ‖reference‖₂.");
  Rows rows;
  for (const auto& r : refs) {
    const Comparison c = compare(run_dir, r.column, r.path);
    rows.push_back({c.monitor, c.reference, std::to_string(c.points), num(c.t_first) + " – " + num(c.t_last),
                    num(c.rel_l2, 4), num(c.max_abs, 4) + " (" + num(c.max_abs_time) + ")",
                    num(c.peak_run) + " (" + num(c.peak_run_time) + ")", num(c.peak_ref) + " (" + num(c.peak_ref_time) + ")"});
  }
  page.add_table({"monitor", "reference", "points", "span [s]", "relative L2", "max abs error (at t)", "peak run (at t)",
                  "peak reference (at t)"},
                 rows);
}

/// plots/field_*.png, by quantity, then by time as a number (0.5 before 10).
std::vector<std::string> field_pictures(const fs::path& plots) {
  std::vector<std::string> pngs;
  if (fs::is_directory(plots))
    for (const auto& e : fs::directory_iterator(plots))
      if (e.path().extension() == ".png" && e.path().filename().string().rfind("field_", 0) == 0)
        pngs.push_back(e.path().string());
  auto key = [](const std::string& path) {
    const std::string stem = fs::path(path).stem().string();
    const auto cut = stem.rfind('_');
    double t = 0.0;
    try {
      t = std::stod(stem.substr(cut + 1));
    } catch (const std::exception&) {
    }
    return std::make_pair(stem.substr(0, cut), t);
  };
  std::sort(pngs.begin(), pngs.end(), [&](const auto& a, const auto& b) { return key(a) < key(b); });
  return pngs;
}

/// The last frame's pictures when the run has none yet: the soil's displacement and, when its
/// points carry pore water, the pore pressure; a run of free water only (no soil points in its
/// solid frames) shows its water: mpm-fem's grid fields (the phase field and the pressure), or
/// the water points' speed.
void draw_last_frame(const std::string& run_dir) {
  const RunSeries solid(run_dir, "solid");
  const double t_last = solid.frames().back().time;
  const scene::PointCloud last = solid.load(solid.nearest_frame(t_last));
  if (last.size() == 0) {
    bool grid = false;
    for (const auto& e : scene::read_pvd((fs::path(run_dir) / "output" / "results.pvd").string())) grid = grid || e.group == "grid";
    if (grid) {
      plot_fields(run_dir, "phase_field", {t_last}, "grid");
      plot_fields(run_dir, "pressure", {t_last}, "grid");
    } else {
      plot_fields(run_dir, "velocity_magnitude", {t_last}, "fluid");
    }
    return;
  }
  plot_fields(run_dir, "displacement_magnitude", {t_last});
  const auto names = available_quantities(last);
  if (std::find(names.begin(), names.end(), "pore_pressure") != names.end())
    plot_fields(run_dir, "pore_pressure", {t_last});
}

}  // namespace

std::string write_report(const std::string& run_dir, const std::vector<ReferenceSpec>& references) {
  const fs::path dir(run_dir);
  if (!fs::is_directory(dir)) throw std::runtime_error(run_dir + ": not a run directory (no such directory)");
  const json scene = load(dir / "scene.json");
  const json run = load(dir / "run.json");
  for (const auto& r : references) compare(run_dir, r.column, r.path);  // every error before any file is written
  files::RunDirectory ledger(dir);
  ledger.claim("report.md");  // refused up front when a report.md there is not swmpm's
  ledger.claim("report.html");

  // Plots: monitor plots when missing (always when references are to be overlaid), and the last
  // frame's fields when no field picture exists yet.
  const fs::path plots = dir / "plots";
  std::vector<std::string> monitor_pngs;
  if (fs::exists(dir / "monitors.csv")) {
    const Table t = read_csv((dir / "monitors.csv").string());
    bool missing = !references.empty();
    for (std::size_t k = 1; k < t.names.size(); ++k) {
      const std::string png = (plots / (t.names[k].substr(0, t.names[k].find('.')) + ".png")).string();
      if (std::find(monitor_pngs.begin(), monitor_pngs.end(), png) == monitor_pngs.end()) monitor_pngs.push_back(png);
      missing = missing || !fs::exists(png);
    }
    if (missing && !monitor_pngs.empty()) plot_monitors(run_dir, references);
  }
  std::vector<std::string> field_pngs = field_pictures(plots);
  if (field_pngs.empty() && fs::exists(dir / "output" / "results.pvd")) {
    draw_last_frame(run_dir);
    field_pngs = field_pictures(plots);
  }

  const std::string title = "Run report: " + get(scene, "name");
  Page page;
  page.title = title;
  page.add_paragraph("Run directory `" + run_dir + "`. Everything below is read from its `scene.json`, `run.json`, "
                 "`monitors.csv` and `output/`; units SI.");
  setup_section(page, scene, run);
  formulation_section(page, run);
  cost_section(page, run);
  stability_section(page, run);
  comparison_section(page, run_dir, references);
  if (!monitor_pngs.empty()) {
    page.add_heading("Monitors");
    for (const auto& png : monitor_pngs) page.add_image("monitor " + fs::path(png).stem().string(), fs::relative(png, dir).string());
  }
  if (!field_pngs.empty()) {
    page.add_heading("Fields");
    for (const auto& png : field_pngs) {
      // field_<quantity>_<t>.png
      const std::string stem = fs::path(png).stem().string().substr(6);
      const auto cut = stem.rfind('_');
      page.add_image(stem.substr(0, cut) + " at t = " + stem.substr(cut + 1) + " s", fs::relative(png, dir).string());
    }
  }
  ledger.write_text("report.md", page.markdown());
  ledger.write_text("report.html", page.html(dir.string()));
  return (dir / "report.md").string();
}

}  // namespace swmpm::post
