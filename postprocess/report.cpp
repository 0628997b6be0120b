// report: RUN_DIR/report.md, one page that says what was run, what it cost, how it compares with
// the references given, and shows the plots. Reads scene.json and run.json as JSON (not through the
// scene parser) so a report can still be written for a run made by an older or newer version.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "postprocess/format.hpp"
#include "postprocess/postprocess.hpp"
#include "scene/files.hpp"
#include "scene/input.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace swmpm::post {

namespace {

json load(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw std::runtime_error(path.string() + ": missing (is this a run directory written by swmpm?)");
  return scene::read_json_file(path.string(), "JSON file");
}

/// A string for a Markdown table cell: '|' would end the cell.
std::string cell(const std::string& s) {
  std::string out;
  for (char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c);
  return out;
}

/// A JSON value as a person reads it: numbers with 6 digits, arrays as (a, b), strings bare.
std::string text(const json& v) {
  if (v.is_number()) return num(v.get<double>());
  if (v.is_string()) return cell(v.get<std::string>());
  if (v.is_array()) {
    std::string s = "(";
    for (std::size_t k = 0; k < v.size(); ++k) s += (k ? ", " : "") + text(v[k]);
    return s + ")";
  }
  if (v.is_null()) return "—";
  return v.dump();
}

std::string get(const json& j, const std::string& key) { return j.contains(key) ? text(j[key]) : "—"; }

void setup_section(std::ostream& md, const json& scene, const json& run) {
  const int dim = scene.value("dimension", run.value("dimension", 2));
  md << "## Setup\n\n| | |\n|---|---|\n"
     << "| scene | " << get(scene, "name") << " |\n"
     << "| formulation | " << get(run.contains("formulation") ? run : scene, "formulation") << " |\n"
     << "| dimension | " << dim << (dim == 2 ? " (plane strain; extensive quantities per metre)" : "") << " |\n";
  if (scene.contains("grid")) {
    const auto& g = scene["grid"];
    md << "| shape function | " << get(g, "shape_function") << " |\n";
    std::string cells;
    if (g.contains("min") && g.contains("max") && g.contains("cell_size")) {
      const double h = g["cell_size"].get<double>();
      for (std::size_t a = 0; a < g["min"].size(); ++a)
        cells += (a ? " × " : "") + std::to_string(std::lround((g["max"][a].get<double>() - g["min"][a].get<double>()) / h));
    }
    md << "| grid | cell size " << get(g, "cell_size") << " m, from " << get(g, "min") << " to " << get(g, "max")
       << " m, " << cells << " cells";
    if (run.contains("active_cells")) md << ", " << get(run, "active_cells") << " holding particles";
    md << " |\n";
  }
  if (run.contains("particles") && run["particles"].is_object()) {
    md << "| particles |";
    for (const auto& [phase, n] : run["particles"].items()) md << " " << phase << " " << text(n);
    md << " |\n";
  }
  md << "| gravity | " << get(scene, "gravity") << " m/s²";
  if (scene.value("gravity_ramp", 0.0) > 0.0) md << ", ramped over " << get(scene, "gravity_ramp") << " s";
  md << " |\n";
  if (scene.contains("time")) {
    const auto& t = scene["time"];
    md << "| time | end " << get(t, "end") << " s, dt " << get(t, "dt");
    if (t.contains("cfl") && t.value("dt", json()).is_string()) md << " (cfl " << get(t, "cfl") << ")";  // auto
    md << " |\n";
  }
  if (scene.contains("materials")) {
    md << "\nMaterials:\n\n| name | model | parameters |\n|---|---|---|\n";
    for (const auto& m : scene["materials"]) {
      std::string params;
      for (const auto& [key, value] : m.items())
        if (key != "name" && key != "model") params += (params.empty() ? "" : ", ") + key + " " + text(value);
      md << "| " << get(m, "name") << " | " << get(m, "model") << " | " << params << " |\n";
    }
  }
  if (scene.contains("bodies")) {
    md << "\nBodies:\n\n| name | geometry | solid | fluid | particles per cell |\n|---|---|---|---|---|\n";
    for (const auto& b : scene["bodies"])
      md << "| " << get(b, "name") << " | " << (b.contains("geometry") ? get(b["geometry"], "type") : "—") << " | "
         << get(b, "solid") << " | " << get(b, "fluid") << " | " << get(b, "particles_per_cell") << " |\n";
  }
}

void cost_section(std::ostream& md, const json& run) {
  md << "\n## Cost\n\n| | |\n|---|---|\n"
     << "| status | " << get(run, "status") << (run.contains("diagnosis") ? " — " + get(run, "diagnosis") : "") << " |\n"
     << "| steps | " << get(run, "steps") << " to t = " << get(run, "end_time") << " s |\n"
     << "| dt | " << get(run, "dt") << " s (mean; min " << get(run, "dt_min") << ", max " << get(run, "dt_max")
     << "), limited by " << get(run, "dt_limit") << " |\n"
     << "| wall time | " << get(run, "wall_seconds") << " s (time loop " << get(run, "loop_seconds") << " s) |\n"
     << "| µs per particle-step | " << get(run, "us_per_particle_step") << " (time loop "
     << get(run, "loop_us_per_particle_step") << ") |\n"
     << "| threads | " << get(run, "threads") << " |\n";
  if (run.contains("peak_memory_bytes"))
    md << "| peak memory | " << num(run["peak_memory_bytes"].get<double>() / (1024.0 * 1024.0), 4) << " MiB |\n";
  md << "| frames | " << get(run, "frames") << " |\n"
     << "| software | swmpm " << get(run, "software_version") << " (" << get(run, "git_hash") << ") |\n";
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
    md << "\nWhere the time loop's time went (stages of the formulation, and the rest of the loop):\n\n"
       << "| stage | seconds | share of the loop |\n|---|---|---|\n";
    for (const auto& [seconds, stage] : stages)
      md << "| " << cell(stage) << " | " << num(seconds, 4) << " | " << num(whole > 0 ? 100.0 * seconds / whole : 0.0, 3)
         << " % |\n";
    if (whole > total)
      md << "| frames, monitors, energy checks | " << num(whole - total, 4) << " | "
         << num(100.0 * (whole - total) / whole, 3) << " % |\n";
  }
}

void comparison_section(std::ostream& md, const std::string& run_dir, const std::vector<ReferenceSpec>& refs) {
  if (refs.empty()) return;
  md << "\n## Comparison with references\n\n"
     << "The monitor is interpolated linearly onto the reference times inside the run's time span. Relative L2 = "
        "‖run − reference‖₂ / ‖reference‖₂.\n\n"
     << "| monitor | reference | points | span [s] | relative L2 | max abs error (at t) | peak run (at t) | peak reference (at t) |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  for (const auto& r : refs) {
    const Comparison c = compare(run_dir, r.column, r.path);
    md << "| " << c.monitor << " | " << c.reference << " | " << c.points << " | " << num(c.t_first) << " – "
       << num(c.t_last) << " | " << num(c.rel_l2, 4) << " | " << num(c.max_abs, 4) << " (" << num(c.max_abs_time)
       << ") | " << num(c.peak_run) << " (" << num(c.peak_run_time) << ") | " << num(c.peak_ref) << " ("
       << num(c.peak_ref_time) << ") |\n";
  }
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

  // Plots: monitor plots when missing (always when references are to be overlaid), and the final
  // displacement field when no field picture exists yet.
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
  std::vector<std::string> field_pngs;
  auto collect_fields = [&] {
    field_pngs.clear();
    if (fs::is_directory(plots))
      for (const auto& e : fs::directory_iterator(plots))
        if (e.path().extension() == ".png" && e.path().filename().string().rfind("field_", 0) == 0)
          field_pngs.push_back(e.path().string());
    // field_<quantity>_<t>.png: by quantity, then by time as a number (0.5 before 10).
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
    std::sort(field_pngs.begin(), field_pngs.end(), [&](const auto& a, const auto& b) { return key(a) < key(b); });
  };
  collect_fields();
  if (field_pngs.empty() && fs::exists(dir / "output" / "results.pvd")) {
    // The soil's displacement at the last frame; a run of free water only (no soil points in its
    // solid frames) shows its water points' speed instead.
    const RunSeries solid(run_dir, "solid");
    const double t_last = solid.frames().back().time;
    if (solid.load(solid.nearest_frame(t_last)).size() > 0) plot_fields(run_dir, "displacement_magnitude", {t_last});
    else plot_fields(run_dir, "velocity_magnitude", {t_last}, "fluid");
    collect_fields();
  }

  const fs::path path = dir / "report.md";
  std::ostringstream md;
  md << "# Run report: " << get(scene, "name") << "\n\n"
     << "Run directory `" << run_dir << "`. Everything below is read from its `scene.json`, `run.json`, "
     << "`monitors.csv` and `output/`; units SI.\n\n";
  setup_section(md, scene, run);
  cost_section(md, run);
  comparison_section(md, run_dir, references);
  md << "\n## Plots\n\n";
  for (const auto& png : monitor_pngs) {
    const std::string rel = fs::relative(png, dir).string();
    md << "- monitor `" << fs::path(png).stem().string() << "`: [" << rel << "](" << rel << ")\n";
  }
  for (const auto& png : field_pngs) {
    const std::string rel = fs::relative(png, dir).string();
    md << "- field `" << fs::path(png).stem().string().substr(6) << "`: [" << rel << "](" << rel << ")\n";
  }
  md << "\n";
  for (const auto& png : monitor_pngs) md << "![" << fs::path(png).stem().string() << "](" << fs::relative(png, dir).string() << ")\n\n";
  for (const auto& png : field_pngs) md << "![" << fs::path(png).stem().string() << "](" << fs::relative(png, dir).string() << ")\n\n";
  ledger.write_text("report.md", md.str());
  return path.string();
}

}  // namespace swmpm::post
