// The study's outputs: study.json (every number, for scripts and tests), cost-error.png (wall
// time against estimated relative error, log-log, one series per monitor quantity and metric), and
// one page as report.md and report.html (self-contained, the chart embedded).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "postprocess/page.hpp"
#include "postprocess/postprocess.hpp"
#include "scene/budget.hpp"
#include "study/results.hpp"
#include "swmpm/version.hpp"

namespace swmpm::study {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

std::string num(double v, int digits = 4) {
  if (std::isnan(v)) return "—";
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

std::string percent(double relative) { return std::isnan(relative) ? "—" : num(100.0 * relative, 3) + " %"; }

/// A number for JSON: NaN and infinities as null.
Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json numbers(const std::vector<double>& v) {
  Json a = Json::array();
  for (double x : v) a.push_back(number(x));
  return a;
}

Json to_json(const Results& r) {
  Json j;
  j["scene"] = r.scene_path;
  j["name"] = r.scene_name;
  j["formulation"] = r.formulation;
  j["dimension"] = r.dimension;
  j["shape_function"] = r.shape_function;
  j["cell_size"] = r.h0;
  j["ratio"] = r.ratio;
  j["cell_sizes_given"] = r.fixed;
  j["dt_rule"] = r.dt_rule;
  j["tolerance"] = r.tolerance;
  j["budget_seconds"] = r.budget_seconds;
  j["metric"] = r.metric;
  j["history_from"] = r.from;
  j["total_seconds"] = r.total_seconds;
  Json levels = Json::array();
  for (const auto& L : r.levels) {
    Json l;
    l["label"] = L.label;
    l["cell_size"] = L.h;
    l["run_dir"] = "runs/" + L.label;
    l["status"] = L.status;
    l["particles"] = L.particles;
    l["steps"] = L.steps;
    l["dt"] = L.dt;
    l["preprocess_seconds"] = L.preprocess;
    l["wall_seconds"] = L.wall;
    l["cost_seconds"] = L.cost();
    l["predicted_seconds"] = number(L.predicted > 0.0 ? L.predicted : NAN);
    l["us_per_particle_step"] = L.us_per_particle_step;
    l["stability_crossed"] = L.crossed;
    l["stability_worst"] = L.worst;
    levels.push_back(l);
  }
  j["levels"] = levels;
  Json block = Json::array();
  for (std::size_t k = r.first; k < r.first + r.count; ++k) block.push_back(r.levels[k].label);
  j["estimated_levels"] = block;
  Json estimates = Json::array();
  for (const auto& s : r.series) {
    Json e;
    e["column"] = s.column;
    e["metric"] = s.metric;
    if (!s.skipped.empty()) {
      e["skipped"] = s.skipped;
      estimates.push_back(e);
      continue;
    }
    e["samples"] = s.samples;
    e["order"] = number(s.e.order);
    e["orders"] = numbers(s.e.orders);
    e["asymptotic"] = s.e.asymptotic;
    e["converged"] = s.e.converged;
    e["flag"] = s.e.why;
    e["scale"] = s.scale;
    e["magnitude"] = s.magnitude;
    if (s.metric == "end") e["extrapolated"] = number(s.e.extrapolated.front());
    e["error"] = numbers(s.e.error);
    e["relative_error"] = numbers(s.relative);
    estimates.push_back(e);
  }
  j["estimates"] = estimates;
  j["recommended"] = r.recommended >= 0 ? Json(r.levels[static_cast<std::size_t>(r.recommended)].label) : Json(nullptr);
  j["worst_series"] = r.worst_series;
  j["worst_relative_error"] = r.worst_error;
  j["needed_cell_size"] = number(r.needed_cell_size);
  j["needed_seconds"] = number(r.needed_seconds);
  j["notes"] = r.notes;
  j["software_version"] = version;
  j["git_hash"] = git_hash;
  return j;
}

void draw_chart(const Results& r, const std::string& png) {
  std::vector<post::ChartSeries> series;
  std::vector<std::string> columns;  // one colour per column; the metric picks the point
  for (const auto& s : r.series) {
    if (!s.skipped.empty()) continue;
    if (std::find(columns.begin(), columns.end(), s.column) == columns.end()) columns.push_back(s.column);
    post::ChartSeries c;
    c.title = s.name() + (s.e.asymptotic ? "" : " [not asymptotic]");
    c.dashed = !s.e.asymptotic;
    c.colour = static_cast<int>(std::find(columns.begin(), columns.end(), s.column) - columns.begin());
    c.point = s.metric == "end" ? 5 : 6;
    for (std::size_t k = 0; k < r.count; ++k) {
      c.x.push_back(r.levels[r.first + k].cost());
      c.y.push_back(100.0 * s.relative[k]);
    }
    series.push_back(std::move(c));
  }
  post::ChartLabels labels;
  labels.title = "study of " + r.scene_name + ": cost against estimated error (levels " +
                 r.levels[r.first].label + " ... " + r.levels[r.first + r.count - 1].label + ")";
  labels.x = "wall time of the run [s] (preprocess + solve)";
  labels.y = "estimated relative error [%]";
  labels.y_line = 100.0 * r.tolerance;
  labels.y_line_title = "tolerance " + num(100.0 * r.tolerance, 3) + " %";
  post::plot_loglog(series, labels, png);
}

std::string stability_text(const LevelRun& L) {
  if (L.worst.is_null()) return "—";
  std::string out = L.crossed.empty() ? "no threshold crossed" : "**crossed**:";
  for (std::size_t k = 0; k < L.crossed.size(); ++k) out += (k ? ", " : " ") + L.crossed[k];
  // The indicators a user looks at first: the worst energy error and checkerboards.
  std::string worst;
  for (const char* key : {"energy_error", "pressure_checkerboard", "mean_stress_checkerboard"})
    if (L.worst.contains(key) && L.worst[key].is_object())
      worst += (worst.empty() ? "" : ", ") + std::string(key) + " " + num(L.worst[key].value("value", NAN), 3);
  return worst.empty() ? out : out + "; worst " + worst;
}

post::Page page(const Results& r, bool chart) {
  post::Page p;
  p.title = "Resolution study: " + r.scene_name;
  p.add_paragraph("Scene `" + r.scene_path + "`, formulation `" + r.formulation + "`, " + std::to_string(r.dimension) +
                  "D, shape function `" + r.shape_function + "`. swmpm " + version + " (" + git_hash +
                  "). Written by `swmpm study`; every number is also in `study.json`.");
  p.add_heading("Verdict");
  if (r.count < 3) {
    p.add_paragraph("**No error was estimated**: fewer than three consecutive levels completed (see the runs below).");
  } else if (r.recommended >= 0) {
    const LevelRun& L = r.levels[static_cast<std::size_t>(r.recommended)];
    p.add_paragraph("**" + L.label + "** (cell size " + num(L.h, 6) + " m, " + num(L.particles, 6) + " particles, " +
                    num(L.cost(), 3) + " s) is the cheapest level whose estimated error is within the tolerance of " +
                    percent(r.tolerance) + " for every estimated quantity and whose run crossed no stability threshold. The largest estimate at the finest level is " +
                    percent(r.worst_error) + " (" + r.worst_series + ").");
  } else {
    p.add_paragraph("**No level is within the tolerance of " + percent(r.tolerance) + "**. The largest estimate at the finest level is " +
                    percent(r.worst_error) + " (" + r.worst_series + "). At its observed order (first order where the runs are "
                    "not in the asymptotic range) a cell size of about **" + num(r.needed_cell_size, 3) +
                    " m** would meet it, predicted to take about " + scene::format_duration(r.needed_seconds) +
                    " for one run on this machine.");
  }
  std::vector<std::string> method{
      (r.fixed ? "Levels: the cell sizes given by --cell-sizes, ratio r = " + num(r.ratio, 4) + " (the scene's is " + num(r.h0, 6) + " m)"
               : "Levels: cell size h = h0 / r^j with r = " + num(r.ratio, 4) + " (h0 = " + num(r.h0, 6) + " m, the scene's)") +
          "; particles per cell as in the scene, so the particle spacing refines with h; dt: " + r.dt_rule + ".",
      "Metrics: **end** = the monitor's value at the end time (" + num(r.end_time, 6) + " s); **history** = the RMS over the "
          "monitor's rows from t = " + num(r.from, 6) + " s, every level interpolated linearly onto the coarsest level's times.",
      "Richardson extrapolation on the three finest levels: observed order p = ln(|q1 − q2| / |q2 − q3|) / ln r, "
          "q_ext = q3 + (q3 − q2) / (r^p − 1), the error of a level |q − q_ext|. Relative to |q_ext| (end) or its RMS "
          "(history), but never to less than 10 % of the largest |q| of the finest run.",
      "Not asymptotic (flagged, and then not extrapolated; the finest level's error is taken as |q2 − q3| / (r − 1), "
          "first order): when the last change is not smaller than the one before, when successive changes point "
          "opposite ways, or when p is outside [0.5, 4].",
      "The estimate is of the discretisation error only: a difference between the model and reality (or an analytic "
          "solution of simpler equations) is not seen by refining.",
  };
  p.add_heading("Method");
  p.add_bullets(method);
  if (!r.notes.empty()) {
    p.add_heading("Planning");
    p.add_bullets(r.notes);
  }

  p.add_heading("Runs");
  std::vector<std::vector<std::string>> rows;
  for (const auto& L : r.levels)
    rows.push_back({L.label, num(L.h, 6), num(L.particles, 6), num(L.steps, 6), num(L.dt, 4), num(L.cost(), 3),
                    L.predicted > 0.0 ? num(L.predicted, 3) : "(measured first)", num(L.us_per_particle_step, 3),
                    L.status, stability_text(L)});
  p.add_table({"level", "cell size [m]", "particles", "steps", "dt [s]", "wall time [s]", "predicted [s]",
               "µs per particle-step", "status", "stability indicators (worst of the run)"},
              rows);
  p.add_paragraph("Each run is a complete run directory, `runs/<level>/` (open `runs/<level>/output/results.pvd` in "
                  "ParaView); its scene is `scenes/<level>.json`. Stability thresholds: docs/verification.md, "
                  "\"Stability indicators of every run\".");

  if (r.count >= 3) {
    p.add_heading("Estimated error");
    std::vector<std::string> header{"quantity", "metric", "observed order", "asymptotic", "extrapolated (end)"};
    for (std::size_t k = 0; k < r.count; ++k) header.push_back(r.levels[r.first + k].label);
    std::vector<std::vector<std::string>> est;
    for (const auto& s : r.series) {
      std::vector<std::string> row{"`" + s.column + "`", s.metric};
      if (!s.skipped.empty()) {
        row.push_back("—");
        row.push_back("not estimated: " + s.skipped);
        row.push_back("—");
        for (std::size_t k = 0; k < r.count; ++k) row.push_back("—");
        est.push_back(row);
        continue;
      }
      std::string orders;
      for (std::size_t k = 0; k < s.e.orders.size(); ++k) orders += (k ? ", " : "") + num(s.e.orders[k], 3);
      row.push_back(s.e.converged ? "— (round-off)" : orders);
      row.push_back(s.e.asymptotic ? "yes" : "**no**: " + s.e.why);
      row.push_back(s.metric == "end" ? num(s.e.extrapolated.front(), 6) : "—");
      for (std::size_t k = 0; k < r.count; ++k) {
        const std::string v = percent(s.relative[k]);
        row.push_back(s.relative[k] <= r.tolerance ? v : "**" + v + "**");
      }
      est.push_back(row);
    }
    p.add_table(header, est);
    p.add_paragraph("Observed orders: of each three consecutive levels, coarse first; the last decides. Bold: over the "
                    "tolerance of " + percent(r.tolerance) + ".");
    if (chart) p.add_image("Wall time against estimated relative error (log-log); dashed: not in the asymptotic range", "cost-error.png");
  }
  return p;
}

}  // namespace

std::string write_outputs(const Results& r, files::RunDirectory& ledger) {
  const fs::path dir = ledger.dir();
  ledger.write_text("study.json", to_json(r).dump(2) + "\n");
  const bool chart = r.count >= 3;
  if (chart) {
    ledger.claim("cost-error.png");
    draw_chart(r, (dir / "cost-error.png").string());
  }
  const post::Page p = page(r, chart);
  ledger.write_text("report.md", p.markdown());
  ledger.write_text("report.html", p.html(dir.string()));
  return (dir / "report.md").string();
}

}  // namespace swmpm::study
