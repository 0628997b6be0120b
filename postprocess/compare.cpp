// compare: a monitor of the run against a reference curve (analytic, another code, a test).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "postprocess/format.hpp"
#include "postprocess/postprocess.hpp"

namespace fs = std::filesystem;

namespace swmpm::post {

namespace {

/// Piecewise-linear a(t) through (ts, vs) (ts increasing); t must lie inside [ts.front(), ts.back()].
double interpolate(const std::vector<double>& ts, const std::vector<double>& vs, double t) {
  const auto hi = std::upper_bound(ts.begin(), ts.end(), t);
  if (hi == ts.begin()) return vs.front();
  if (hi == ts.end()) return vs.back();
  const auto k = static_cast<std::size_t>(hi - ts.begin());
  const double t0 = ts[k - 1], t1 = ts[k];
  const double w = t1 > t0 ? (t - t0) / (t1 - t0) : 1.0;
  return (1.0 - w) * vs[k - 1] + w * vs[k];
}

}  // namespace

Comparison compare(const std::string& run_dir, const std::string& monitor, const std::string& reference_path,
                   const std::string& reference_column) {
  if (!fs::is_directory(run_dir)) throw std::runtime_error(run_dir + ": not a run directory (no such directory)");
  const std::string csv = (fs::path(run_dir) / "monitors.csv").string();
  if (!fs::exists(csv)) throw std::runtime_error(csv + ": missing (run `swmpm solve " + run_dir + "` first)");
  const Table run = read_csv(csv);
  if (!run.has(monitor)) {
    std::string list;
    for (std::size_t k = 1; k < run.names.size(); ++k) list += (list.size() ? ", " : "") + run.names[k];
    throw std::runtime_error("--monitor \"" + monitor + "\": not a column of " + csv + " (available: " + list + ")");
  }
  const auto& ts = run.columns[0];
  const auto& vs = run.column(monitor);
  if (ts.empty()) throw std::runtime_error(csv + ": no rows");
  const Curve ref = read_reference(reference_path, reference_column);

  Comparison c;
  c.monitor = monitor;
  c.reference = reference_path;
  c.peak_run_time = c.peak_ref_time = c.max_abs_time = std::numeric_limits<double>::quiet_NaN();
  double err2 = 0.0, ref2 = 0.0;
  const double t_min = ts.front(), t_max = ts.back();
  // Round-off in the CSVs' times must not drop the end points of an equal time span.
  const double slack = 1e-9 * std::max(1.0, std::abs(t_max));
  for (std::size_t k = 0; k < ref.t.size(); ++k) {
    const double t = ref.t[k];
    if (t < t_min - slack || t > t_max + slack) continue;
    const double a = interpolate(ts, vs, t), r = ref.v[k];
    if (c.points == 0) c.t_first = t;
    c.t_last = t;
    ++c.points;
    err2 += (a - r) * (a - r);
    ref2 += r * r;
    if (std::isnan(c.max_abs_time) || std::abs(a - r) > c.max_abs) {
      c.max_abs = std::abs(a - r);
      c.max_abs_time = t;
    }
    if (std::isnan(c.peak_ref_time) || std::abs(r) > std::abs(c.peak_ref)) {
      c.peak_ref = r;
      c.peak_ref_time = t;
    }
  }
  if (c.points == 0)
    throw std::runtime_error(reference_path + ": no reference time inside the run's time span [" + num(t_min) + ", " +
                             num(t_max) + "] s");
  // The run's own peak over the same span, from its rows (not the interpolated values).
  for (std::size_t k = 0; k < ts.size(); ++k) {
    if (ts[k] < c.t_first - slack || ts[k] > c.t_last + slack) continue;
    if (std::isnan(c.peak_run_time) || std::abs(vs[k]) > std::abs(c.peak_run)) {
      c.peak_run = vs[k];
      c.peak_run_time = ts[k];
    }
  }
  if (std::isnan(c.peak_run_time)) {  // a single reference time between two rows
    c.peak_run = interpolate(ts, vs, c.t_first);
    c.peak_run_time = c.t_first;
  }
  c.rel_l2 = ref2 > 0.0 ? std::sqrt(err2 / ref2) : (err2 > 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
  return c;
}

std::string describe(const Comparison& c) {
  std::ostringstream s;
  s << "compare " << c.monitor << " with " << c.reference << ": " << c.points << " reference points in t = ["
    << num(c.t_first) << ", " << num(c.t_last) << "] s\n"
    << "  relative L2 error  " << num(c.rel_l2, 4) << "  (||run - reference||_2 / ||reference||_2)\n"
    << "  max abs error      " << num(c.max_abs, 4) << " at t = " << num(c.max_abs_time) << " s\n"
    << "  peak |value|       run " << num(c.peak_run) << " at t = " << num(c.peak_run_time) << " s, reference "
    << num(c.peak_ref) << " at t = " << num(c.peak_ref_time) << " s\n";
  return s.str();
}

}  // namespace swmpm::post
