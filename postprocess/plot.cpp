// PNG plots a person looks at: monitor histories (with reference curves) and field snapshots.
// gnuplot (pngcairo) runs as a subprocess fed a script on stdin; the data go through temporary
// files of plain numbers, so no plot depends on how a CSV's header or comments look.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "postprocess/format.hpp"
#include "scene/files.hpp"
#include "scene/input.hpp"
#include "postprocess/postprocess.hpp"

namespace fs = std::filesystem;

namespace swmpm::post {

namespace {

/// A private temporary folder, removed with everything in it when it goes out of scope.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "swmpm-plot-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("cannot create a temporary folder in " + fs::temp_directory_path().string());
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

/// A string for a single-quoted gnuplot literal: a quote inside is written twice.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

void gnuplot(const std::string& script, const fs::path& png, const std::string& temporary, const TempDir& tmp);

/// The line of a script that names its PNG; run_gnuplot puts the file's temporary name in.
constexpr const char* kSetOutput = "set output @OUTPUT@\n";

/// Runs gnuplot on `script` (which holds kSetOutput) and replaces `png` with what it drew
/// (files::write_atomically); throws with gnuplot's first error line unless the PNG was written.
void run_gnuplot(const std::string& script, const fs::path& png, const TempDir& tmp) {
  std::string text = script;
  const std::size_t at = text.find(kSetOutput);
  if (at == std::string::npos) throw std::logic_error("run_gnuplot: the script sets no output");
  files::write_atomically(png, [&](const std::string& temporary) {
    text.replace(at, std::strlen(kSetOutput), "set output " + quoted(temporary) + "\n");
    gnuplot(text, png, temporary, tmp);
  });
}

void gnuplot(const std::string& script, const fs::path& png, const std::string& temporary, const TempDir& tmp) {
  const fs::path log = tmp / "gnuplot.log";
  FILE* pipe = popen(("gnuplot > " + log.string() + " 2>&1").c_str(), "w");
  if (pipe == nullptr) throw std::runtime_error("cannot start gnuplot (apt-get install gnuplot-nox)");
  std::fputs(script.c_str(), pipe);
  const int rc = pclose(pipe);
  std::error_code ec;
  if (rc == 0 && fs::file_size(temporary, ec) > 0 && !ec) return;
  std::ifstream in(log);
  std::string line, first;
  while (std::getline(in, line))
    if (!line.empty() && line.find_first_not_of(" ^") != std::string::npos && first.empty()) first = line;
  if (first.find("not found") != std::string::npos) first = "gnuplot not found (apt-get install gnuplot-nox)";
  throw std::runtime_error("gnuplot failed to draw " + png.string() + (first.empty() ? "" : ": " + first));
}

/// Writes columns of numbers, one row per line, for gnuplot.
void write_columns(const fs::path& path, const std::vector<const std::vector<double>*>& cols) {
  std::ofstream out(path);
  out.precision(10);
  for (std::size_t i = 0; i < cols.front()->size(); ++i) {
    for (std::size_t c = 0; c < cols.size(); ++c) out << (c ? " " : "") << (*cols[c])[i];
    out << "\n";
  }
  if (!out) throw std::runtime_error(path.string() + ": cannot write a temporary plot file");
}

std::string label(const std::string& quantity, int dimension) {
  const std::string u = unit_of(quantity, dimension);
  return u.empty() ? quantity : quantity + " [" + u + "]";
}

/// A tick step of 1, 2 or 5 × 10^k giving about `count` ticks over `range`.
double nice_step(double range, double count) {
  const double raw = range / std::max(count, 1.0);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double f : {1.0, 2.0, 5.0})
    if (f * mag >= raw) return f * mag;
  return 10.0 * mag;
}

/// The run's dimension (2 or 3) from RUN_DIR/run.json or scene.json; 2 when neither says.
int run_dimension(const fs::path& dir) {
  for (const char* name : {"run.json", "scene.json"}) {
    try {
      const int d = scene::read_json_file((dir / name).string(), "JSON file").value("dimension", 0);
      if (d == 2 || d == 3) return d;
    } catch (const std::exception&) {
    }
  }
  return 2;
}

}  // namespace

std::vector<std::string> plot_monitors(const std::string& run_dir, const std::vector<ReferenceSpec>& references) {
  const fs::path dir(run_dir);
  if (!fs::is_directory(dir)) throw std::runtime_error(run_dir + ": not a run directory (no such directory)");
  const fs::path csv = dir / "monitors.csv";
  if (!fs::exists(csv)) throw std::runtime_error(csv.string() + ": missing (run `swmpm solve " + run_dir + "` first)");
  const Table t = read_csv(csv.string());
  if (t.columns.empty() || t.columns.front().empty()) throw std::runtime_error(csv.string() + ": no rows to plot");
  const int dim = run_dimension(dir);
  TempDir tmp;
  // Each reference becomes a two-column file; a spec that names no column is an error, not a
  // silently missing curve.
  std::map<std::string, std::vector<std::pair<fs::path, std::string>>> overlays;
  for (std::size_t r = 0; r < references.size(); ++r) {
    const auto& ref = references[r];
    if (!t.has(ref.column)) {
      std::string list;
      for (std::size_t k = 1; k < t.names.size(); ++k) list += (list.empty() ? "" : ", ") + t.names[k];
      throw std::runtime_error("--reference " + ref.column + "=" + ref.path + ": not a column of monitors.csv (available: " + list + ")");
    }
    const Curve c = read_reference(ref.path);
    const fs::path data = tmp / ("reference" + std::to_string(r) + ".dat");
    write_columns(data, {&c.t, &c.v});
    overlays[ref.column].push_back({data, "reference: " + fs::path(ref.path).filename().string() + " (" + c.name + ")"});
  }
  // Group columns "<monitor>.<quantity>" by monitor.
  std::map<std::string, std::vector<std::size_t>> groups;
  for (std::size_t k = 1; k < t.names.size(); ++k) groups[t.names[k].substr(0, t.names[k].find('.'))].push_back(k);
  const fs::path run_data = tmp / "monitors.dat";
  std::vector<const std::vector<double>*> cols;
  for (const auto& c : t.columns) cols.push_back(&c);
  write_columns(run_data, cols);
  files::RunDirectory run(dir);
  std::vector<std::string> written;
  for (const auto& [monitor, panel_cols] : groups) {
    run.claim("plots/" + monitor + ".png");  // never over a file swmpm did not write
    const fs::path png = dir / "plots" / (monitor + ".png");
    const int rows = static_cast<int>(panel_cols.size());
    std::ostringstream gp;
    gp << "set terminal pngcairo size 900," << 260 * rows + 60 << " font 'Sans,10' noenhanced\n"
       << kSetOutput
       // Headroom above the curves keeps the key (top right) off the data.
       << "set grid\nset key top right opaque box\nset offsets 0, 0, graph 0.18, graph 0.04\nset format y '%g'\n"
       << "set multiplot layout " << rows << ",1 title " << quoted("monitor " + monitor + " (" + run_dir + ")") << "\n";
    for (std::size_t c : panel_cols) {
      const std::string quantity = t.names[c].substr(monitor.size() + 1);
      gp << "set xlabel 'time [s]'\nset ylabel " << quoted(label(quantity, dim)) << "\n";
      // A column without a finite value (a water_level gauge whose line never held water): an
      // empty panel that says so (gnuplot refuses to plot nothing).
      if (std::none_of(t.columns[c].begin(), t.columns[c].end(), [](double v) { return std::isfinite(v); })) {
        const double t0 = t.columns[0].empty() ? 0.0 : t.columns[0].front(), t1 = t.columns[0].empty() ? 1.0 : t.columns[0].back();
        gp << "set label 1 " << quoted(t.names[c] + ": no finite value in the run") << " at graph 0.5, 0.5 center\n"
           << "unset key\nplot [" << t0 << ":" << (t1 > t0 ? t1 : t0 + 1.0) << "] [0:1] NaN notitle\n"
           << "unset label 1\nset key top right opaque box\n";
        continue;
      }
      gp << "plot " << quoted(run_data.string()) << " using 1:" << c + 1 << " with lines lw 2 lc rgb '#1b6ca8' title "
         << quoted(t.names[c] + " (run)");
      for (const auto& [data, title] : overlays[t.names[c]])
        gp << ", " << quoted(data.string()) << " using 1:2 with linespoints dt 2 lw 1.5 pt 6 ps 0.8 lc rgb '#d95f02' title "
           << quoted(title);
      gp << "\n";
    }
    gp << "unset multiplot\n";
    run_gnuplot(gp.str(), png, tmp);
    written.push_back(png.string());
  }
  return written;
}

std::vector<std::string> plot_fields(const std::string& run_dir, const std::string& quantity,
                                     const std::vector<double>& times, const std::string& phase) {
  const RunSeries series(run_dir, phase);
  const int dim = series.dimension();
  const fs::path plots = fs::path(run_dir) / "plots";
  files::RunDirectory run(run_dir);
  TempDir tmp;
  std::vector<std::string> written;
  for (double t_req : times) {
    const std::size_t k = series.nearest_frame(t_req);
    const auto frame = series.load(k);
    const Quantity q(frame, quantity, series.fluid_on_solid_frames());
    const double h = particle_spacing(frame, dim);
    const auto* half = frame.find("half_size");
    // 3D: the layer of particles nearest the middle of the body in z, seen along z.
    double z_layer = 0.0;
    if (dim == 3) {
      double z_lo = frame.points[0][2], z_hi = z_lo;
      for (const auto& x : frame.points) z_lo = std::min(z_lo, x[2]), z_hi = std::max(z_hi, x[2]);
      const double z_mid = 0.5 * (z_lo + z_hi);
      z_layer = z_lo;
      for (const auto& x : frame.points)
        if (std::abs(x[2] - z_mid) < std::abs(z_layer - z_mid)) z_layer = x[2];
    }
    std::vector<double> xs, ys, hx, hy, vs;
    for (std::size_t p = 0; p < frame.size(); ++p) {
      if (dim == 3 && std::abs(frame.points[p][2] - z_layer) > 0.5 * h) continue;
      const double v = q(p);
      if (!std::isfinite(v)) continue;
      xs.push_back(frame.points[p][0]);
      ys.push_back(frame.points[p][1]);
      // Each particle is drawn as its domain (initial half-size).
      hx.push_back(half ? half->values[3 * p] : 0.5 * h);
      hy.push_back(half ? half->values[3 * p + 1] : 0.5 * h);
      vs.push_back(v);
    }
    if (xs.empty()) throw std::runtime_error(series.frames()[k].path + ": no particle to draw");
    // Equal scales: the picture's shape follows the body's, its longer side about 800 px.
    const auto [x_lo, x_hi] = std::minmax_element(xs.begin(), xs.end());
    const auto [y_lo, y_hi] = std::minmax_element(ys.begin(), ys.end());
    // A margin of a particle spacing, at least 2 % of the larger extent, keeps the body off the frame.
    const double pad = std::max(h, 0.02 * std::max(*x_hi - *x_lo, *y_hi - *y_lo));
    const double x0 = *x_lo - pad, x1 = *x_hi + pad, y0 = *y_lo - pad, y1 = *y_hi + pad;
    // Longer side 800 px; a long, flat body keeps at least 200 px of height (up to 1600 px wide).
    const double dx = x1 - x0, dy = y1 - y0;
    const double scale = std::max(800.0 / std::max(dx, dy), std::min(200.0 / dy, 1600.0 / dx));  // px per m
    const double plot_w = dx * scale, plot_h = dy * scale;
    // Squares grown by 0.75 px overlap their neighbours: antialiased edges leave no light seams.
    for (auto& l : hx) l += 0.75 / scale;
    for (auto& l : hy) l += 0.75 / scale;
    const fs::path data = tmp / ("field" + std::to_string(k) + ".dat");
    write_columns(data, {&xs, &ys, &hx, &hy, &vs});
    // The layout is fixed in pixels, not left to gnuplot: the plot area, then right of it the
    // colour bar, its tick labels and its label (gnuplot's own cblabel placement can overlap the
    // tick labels when the plot's aspect ratio is forced).
    const double left = 90, right_room = 190, bottom = 60, top = 50;
    const double width = std::max(560.0, left + plot_w + right_room);
    const double height = std::max(300.0, bottom + plot_h + top);
    const double x_plot = left + 0.5 * (width - left - plot_w - right_room);  // centred when widened
    const double y_plot = bottom + 0.5 * (height - bottom - plot_h - top);
    const double bar_x = x_plot + plot_w + 18, bar_w = 22;
    auto sx = [&](double px) { return num(px / width, 8); };
    auto sy = [&](double px) { return num(px / height, 8); };
    const auto [v_lo_it, v_hi_it] = std::minmax_element(vs.begin(), vs.end());
    double v_lo = *v_lo_it, v_hi = *v_hi_it;
    if (v_hi - v_lo <= 1e-12 * std::max(std::abs(v_lo), std::abs(v_hi))) {  // a uniform field
      const double spread = v_lo != 0.0 ? 0.01 * std::abs(v_lo) : 1.0;
      v_lo -= spread;
      v_hi += spread;
    }
    const double t = series.frames()[k].time;
    std::string title = label(quantity, dim) + " at t = " + num(t) + " s";
    if (std::abs(t - t_req) > 1e-9 * std::max(1.0, std::abs(t_req))) title += " (frame nearest " + num(t_req) + " s)";
    if (dim == 3) title += ", particles at z = " + num(z_layer) + " m";

    const std::string name = "field_" + quantity + "_" + num(t_req) + ".png";
    run.claim("plots/" + name);
    const fs::path png = plots / name;
    std::ostringstream gp;
    gp << "set terminal pngcairo size " << std::lround(width) << "," << std::lround(height) << " font 'Sans,11' noenhanced\n"
       << kSetOutput
       << "set title " << quoted(title) << "\nset size ratio -1\n"
       << "set lmargin at screen " << sx(x_plot) << "\nset rmargin at screen " << sx(x_plot + plot_w) << "\n"
       << "set bmargin at screen " << sy(y_plot) << "\nset tmargin at screen " << sy(y_plot + plot_h) << "\n"
       << "set colorbox vertical user origin screen " << sx(bar_x) << "," << sy(y_plot) << " size screen "
       << sx(bar_w) << "," << sy(plot_h) << "\n"
       << "set label 1 " << quoted(label(quantity, dim)) << " at screen " << sx(bar_x + bar_w + 80) << ","
       << sy(y_plot + 0.5 * plot_h) << " center rotate by 90\n"
       << "set xrange [" << x0 << ":" << x1 << "]\nset yrange [" << y0 << ":" << y1 << "]\n"
       << "set xtics " << nice_step(x1 - x0, std::max(2.0, plot_w / 90.0)) << "\nset ytics "
       << nice_step(y1 - y0, std::max(2.0, plot_h / 60.0)) << "\n"
       << "set format x '%g'\nset format y '%g'\nset format cb '%g'\n"
       << "set xlabel 'x [m]'\nset ylabel 'y [m]'\n"
       << "set cbrange [" << v_lo << ":" << v_hi << "]\n"
       // viridis: ordered in lightness, readable in grey and by colour-blind readers
       << "set palette defined (0 '#440154', 1 '#3b528b', 2 '#21918c', 3 '#5ec962', 4 '#fde725')\n"
       << "plot " << quoted(data.string())
       << " using 1:2:3:4:5 with boxxyerror fs solid 1.0 noborder lc palette z notitle\n";
    run_gnuplot(gp.str(), png, tmp);
    written.push_back(png.string());
  }
  return written;
}

void plot_element_curves(const CsvResult& table, const std::string& title, const std::string& png) {
  const auto index = [&](const std::string& name) {
    const auto it = std::find(table.names.begin(), table.names.end(), name);
    return it == table.names.end() ? -1 : static_cast<int>(it - table.names.begin());
  };
  for (const char* name : {"axial_strain", "p", "q", "volumetric_strain"})
    if (index(name) < 0) throw std::runtime_error(std::string("plot_element_curves: no column ") + name);
  // Panels: (x column, y column, x scale, y scale, x label, y label); percent and kPa on the axes.
  struct Panel {
    int x, y;
    double fx, fy;
    std::string xlabel, ylabel;
  };
  const int ea = index("axial_strain"), u = index("excess_pore_pressure"), psi = index("state_parameter");
  std::vector<Panel> panels{{index("p"), index("q"), 1e-3, 1e-3, "p' [kPa]", "q [kPa]"},
                            {ea, index("q"), 100.0, 1e-3, "axial strain [%]", "q [kPa]"}};
  if (u >= 0)
    panels.push_back({ea, u, 100.0, 1e-3, "axial strain [%]", "excess pore pressure [kPa]"});
  else
    panels.push_back({ea, index("volumetric_strain"), 100.0, 100.0, "axial strain [%]",
                      "volumetric strain [%] (compression +)"});
  if (psi >= 0) panels.push_back({ea, psi, 100.0, 1.0, "axial strain [%]", "state parameter psi = v - v_c(p') [-]"});

  // One data block per run (gnuplot `index`), split where the p0 column changes.
  const int p0 = index("p0");
  const TempDir tmp;
  const fs::path data = tmp / "element.dat";
  std::vector<double> block_p0;
  {
    std::ofstream out(data);
    out.precision(10);
    for (std::size_t i = 0; i < table.rows.size(); ++i) {
      const auto& row = table.rows[i];
      if (p0 >= 0 && (block_p0.empty() || row[static_cast<std::size_t>(p0)] != block_p0.back())) {
        if (!block_p0.empty()) out << "\n\n";
        block_p0.push_back(row[static_cast<std::size_t>(p0)]);
      }
      for (std::size_t c = 0; c < row.size(); ++c) out << (c ? " " : "") << row[c];
      out << "\n";
    }
    if (!out) throw std::runtime_error(data.string() + ": cannot write a temporary plot file");
  }
  if (block_p0.empty()) block_p0.push_back(std::nan(""));
  const std::string d = quoted(data.string());
  std::ostringstream gp;
  const bool grid2 = panels.size() == 4;
  gp << "set terminal pngcairo size " << (grid2 ? "1200,900" : "1500,480") << " font 'sans,10'\n"
     << kSetOutput
     << "set grid\n" << (block_p0.size() > 1 ? "set key top right\n" : "unset key\n")
     << "set multiplot layout " << (grid2 ? "2,2" : "1,3") << " title " << quoted(title) << "\n";
  for (const Panel& pl : panels) {
    gp << "set xlabel " << quoted(pl.xlabel) << "\nset ylabel " << quoted(pl.ylabel) << "\nplot ";
    for (std::size_t b = 0; b < block_p0.size(); ++b) {
      std::ostringstream label;
      if (!std::isnan(block_p0[b])) label << "p0 = " << block_p0[b] * 1e-3 << " kPa";
      gp << (b ? ", " : "") << d << " index " << b << " using ($" << pl.x + 1 << "*" << pl.fx << "):($" << pl.y + 1
         << "*" << pl.fy << ") with lines lw 2 title " << quoted(label.str());
    }
    gp << "\n";
  }
  gp << "unset multiplot\n";
  run_gnuplot(gp.str(), png, tmp);
}

}  // namespace swmpm::post

namespace swmpm::post {

void plot_loglog(const std::vector<ChartSeries>& series, const ChartLabels& labels, const std::string& png) {
  TempDir tmp;
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900," << 560 + 9 * series.size() << " font 'Sans,10' noenhanced\n"
     << kSetOutput << "set grid xtics ytics mxtics mytics\nset logscale xy\nset format x '%g'\nset format y '%g'\n"
     << "set key below left Left reverse maxrows " << (series.size() + 1) / 2 << "\nset bmargin "
     << 5 + (series.size() + 1) / 2 << "\nset title " << quoted(labels.title) << "\nset xlabel " << quoted(labels.x)
     << "\nset ylabel " << quoted(labels.y) << "\nset offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05\n";
  std::vector<std::string> plots;
  static const char* colours[] = {"#1b6ca8", "#d95f02", "#1b9e77", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d"};
  for (std::size_t s = 0; s < series.size(); ++s) {
    std::vector<double> x, y;  // a log axis shows positive values only
    for (std::size_t i = 0; i < series[s].x.size(); ++i)
      if (series[s].x[i] > 0.0 && series[s].y[i] > 0.0 && std::isfinite(series[s].x[i]) && std::isfinite(series[s].y[i])) {
        x.push_back(series[s].x[i]);
        y.push_back(series[s].y[i]);
      }
    if (x.empty()) continue;
    const fs::path data = tmp / ("series" + std::to_string(s) + ".dat");
    write_columns(data, {&x, &y});
    const std::size_t colour = series[s].colour >= 0 ? static_cast<std::size_t>(series[s].colour) : s;
    const int point = series[s].point >= 0 ? series[s].point : static_cast<int>(5 + s % 8);
    plots.push_back(quoted(data.string()) + " using 1:2 with linespoints lw 2 pt " + std::to_string(point) +
                    " ps 1.2 lc rgb '" + colours[colour % 8] + "'" + (series[s].dashed ? " dt 2" : "") + " title " +
                    quoted(series[s].title));
  }
  if (plots.empty()) {
    gp << "set label 1 'no positive error to draw' at graph 0.5, 0.5 center\nunset logscale\nplot [0:1] [0:1] NaN notitle\n";
  } else {
    if (labels.y_line > 0.0) {
      gp << "set arrow 1 from graph 0, first " << labels.y_line << " to graph 1, first " << labels.y_line
         << " nohead dt 3 lw 1.5 lc rgb '#cc0000'\nset label 2 " << quoted(labels.y_line_title) << " at graph 0.01, first "
         << labels.y_line * 1.12 << " tc rgb '#cc0000'\n";
    }
    gp << "plot ";
    for (std::size_t k = 0; k < plots.size(); ++k) gp << (k ? ", " : "") << plots[k];
    gp << "\n";
  }
  run_gnuplot(gp.str(), png, tmp);
}

}  // namespace swmpm::post
