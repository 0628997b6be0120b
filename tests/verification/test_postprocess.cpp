// `swmpm postprocess` on the elastic column (examples/elastic-column, frames every 0.01 s):
// histories read back from the VTU series agree with the monitors the solver recorded; profiles
// and kernel averages agree with the closed form σ_yy = −ρ g (H − y); compare passes against the
// analytic settlement and fails against a wrong one; plots are real PNGs; report.md holds the
// numbers; bad input gives one line on stderr and a non-zero status.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double rho = 1800.0, g = 9.81, H = 1.0, E = 1.0e6, nu = 0.3;
const double M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu));  // constrained modulus [Pa]

/// Settlement of the column at initial height y [m] (downward positive).
double settlement(double y) { return rho * g * (H * y - 0.5 * y * y) / M; }
/// σ_yy at the current height y: the particle there started at y0 = y + u(y0).
double exact_stress_yy(double y) {
  double y0 = y;
  for (int k = 0; k < 5; ++k) y0 = y + settlement(y0);
  return -rho * g * (H - y0);
}

using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

std::size_t lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

/// The example column with a frame every 0.01 s (about 100 frames of 160 particles).
std::string column_run(const std::string& name) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json");
  s["output"]["interval"] = 0.01;
  return swmpm::testing::run_scene(s, "post-" + name);
}

/// Linear interpolation of (ts, vs) at t.
double at(const std::vector<double>& ts, const std::vector<double>& vs, double t) {
  const auto hi = std::upper_bound(ts.begin(), ts.end(), t);
  if (hi == ts.begin()) return vs.front();
  if (hi == ts.end()) return vs.back();
  const auto k = static_cast<std::size_t>(hi - ts.begin());
  const double w = (t - ts[k - 1]) / (ts[k] - ts[k - 1]);
  return (1 - w) * vs[k - 1] + w * vs[k];
}

/// ‖a − b‖₂ / ‖b‖₂ of a history (time, value) against a monitor column.
double history_vs_monitor(const swmpm::post::Table& hist, const swmpm::post::Table& mon, const std::string& column) {
  double e2 = 0.0, r2 = 0.0;
  const auto& t = hist.columns[0];
  for (std::size_t k = 0; k < t.size(); ++k) {
    const double m = at(mon.columns[0], mon.column(column), t[k]);
    e2 += std::pow(hist.columns[1][k] - m, 2);
    r2 += m * m;
  }
  return std::sqrt(e2 / r2);
}

void write_reference(const fs::path& path, double scale) {
  // The static settlement of the top particle (y0 = H − h/4 = 0.9875 m) once the ramp and the
  // oscillation are over (t ≥ 0.8 s); the run is then within 1 % of it.
  std::ofstream out(path);
  out << "# analytic top settlement of the elastic column\ntime,displacement_y\n";
  for (int k = 0; k <= 10; ++k) out << 0.8 + 0.02 * k << "," << -scale * settlement(0.9875) << "\n";
}

bool is_png(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return in.gcount() == 8 && std::equal(sig, sig + 8, reinterpret_cast<const char*>(png)) &&
         fs::file_size(path) > 5000;  // a drawn plot, not an empty canvas
}

}  // namespace

// history (nearest) from ~100 frames against the monitors the solver wrote: the same particle,
// so they agree to the CSV's rounding; asserted within 2 % relative L2.
TEST(Postprocess, HistoryNearestMatchesMonitors) {
  const std::string run = column_run("history");
  const fs::path dir = fs::path(run).parent_path();
  const auto mon = swmpm::post::read_csv(run + "/monitors.csv");
  const Result top = swmpm_cmd("postprocess " + run + " history --point 0.05,1.0 --quantity displacement_y --out " +
                                   (dir / "top.csv").string(), dir);
  ASSERT_EQ(top.status, 0) << top.err;
  const Result base = swmpm_cmd("postprocess " + run + " history --point 0.05,0.0 --phase solid --quantity stress_yy", dir);
  ASSERT_EQ(base.status, 0) << base.err;
  std::ofstream(dir / "base.csv") << base.out;  // without --out the CSV goes to standard output

  const auto h_top = swmpm::post::read_csv((dir / "top.csv").string());
  const auto h_base = swmpm::post::read_csv((dir / "base.csv").string());
  EXPECT_GE(h_top.columns[0].size(), 95u);
  EXPECT_EQ(h_top.names, (std::vector<std::string>{"time", "displacement_y"}));
  const std::string header = swmpm::testing::read_text((dir / "top.csv").string());
  EXPECT_NE(header.find("# swmpm history"), std::string::npos);
  EXPECT_NE(header.find("followed by its id"), std::string::npos) << header;
  const double e_top = history_vs_monitor(h_top, mon, "top.displacement_y");
  const double e_base = history_vs_monitor(h_base, mon, "base.stress_yy");
  std::printf("history vs monitor, relative L2: top.displacement_y %.3g, base.stress_yy %.3g\n", e_top, e_base);
  EXPECT_LT(e_top, 0.02);
  EXPECT_LT(e_base, 0.02);
}

/// The straight line through (y_p, v_p) of the particles within `band` of height y, at y: what
/// the frame's data say the value there is, independent of the solver's own error.
double local_linear_fit(const swmpm::scene::PointCloud& frame, const std::string& array, int comp, double y, double band) {
  const auto& a = frame.get(array, "frame");
  double n = 0, sy = 0, sv = 0, syy = 0, syv = 0;
  for (std::size_t p = 0; p < frame.size(); ++p) {
    const double dy = frame.points[p][1] - y, v = a.values[p * a.components + comp];
    if (std::abs(dy) > band) continue;
    n += 1, sy += dy, sv += v, syy += dy * dy, syv += dy * v;
  }
  const double slope = (n * syv - sy * sv) / (n * syy - sy * sy);
  return (sv - slope * sy) / n;
}

// interpolate: kernel averages in the interior at the end. σ_yy against the closed form at the
// current height within 1 % of ρgH; against a straight-line fit of the frame's own particles
// around the point (which isolates the averaging from the solver's error, itself about 0.5–1 % for
// the settlement), σ_yy within 0.5 % of ρgH and the settlement within 1 % (measured: up to 0.1 %
// of ρgH and 0.3 %).
TEST(Postprocess, HistoryInterpolateOnASmoothField) {
  const std::string run = column_run("interpolate");
  const auto frame = swmpm::testing::last_frame(run);
  swmpm::post::HistoryOptions o;
  o.method = swmpm::post::Method::interpolate;
  for (double y : {0.25, 0.5, 0.75}) {
    o.point = {0.05, y, 0.0};
    o.quantity = "stress_yy";
    const double s = swmpm::post::history(run, o).rows.back()[1];
    o.quantity = "displacement_y";
    const double u = swmpm::post::history(run, o).rows.back()[1];
    const double s_fit = local_linear_fit(frame, "stress", 1, y, 0.1);
    const double u_fit = local_linear_fit(frame, "displacement", 1, y, 0.1);
    std::printf("interpolate at y = %.2f: stress_yy %.1f Pa, exact %.1f (%.3f %% of rho g H), fit %.1f (%.3f %% of rho g H); "
                "displacement_y %.5g m, fit %.5g (%.3f %%)\n",
                y, s, exact_stress_yy(y), 100 * std::abs(s - exact_stress_yy(y)) / (rho * g * H), s_fit,
                100 * std::abs(s - s_fit) / (rho * g * H), u, u_fit, 100 * std::abs(u / u_fit - 1));
    EXPECT_LT(std::abs(s - exact_stress_yy(y)), 0.01 * rho * g * H) << "y = " << y;
    EXPECT_LT(std::abs(s - s_fit), 0.005 * rho * g * H) << "y = " << y;
    EXPECT_LT(std::abs(u / u_fit - 1), 0.01) << "y = " << y;
  }
}

// profile of σ_yy along the column's axis at the end, nearest and interpolate: within 3 % RMS
// (of ρgH) of −ρg(H − y).
TEST(Postprocess, ProfileOfVerticalStress) {
  const std::string run = column_run("profile");
  const fs::path dir = fs::path(run).parent_path();
  for (const char* method : {"nearest", "interpolate"}) {
    const fs::path csv = dir / (std::string("profile-") + method + ".csv");
    const Result r = swmpm_cmd("postprocess " + run + " profile --from 0.05,0 --to 0.05,1 --time 1 --quantity stress_yy --method " +
                                   method + " --out " + csv.string(), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("t = 1 s"), std::string::npos) << "says which frame: " << r.out;
    const auto t = swmpm::post::read_csv(csv.string());
    EXPECT_EQ(t.names, (std::vector<std::string>{"s", "x", "y", "stress_yy"}));
    ASSERT_EQ(t.columns[0].size(), 50u);
    double e2 = 0.0;
    std::size_t n = 0;
    for (std::size_t k = 0; k < 50; ++k) {
      const double v = t.columns[3][k], y = t.columns[2][k];
      EXPECT_NEAR(t.columns[0][k], y, 1e-12);  // s along a vertical line from y = 0
      if (std::isnan(v)) continue;
      e2 += std::pow((v - -rho * g * (H - y)) / (rho * g * H), 2);
      ++n;
    }
    const double rms = std::sqrt(e2 / static_cast<double>(n));
    std::printf("profile %s: %zu of 50 points with a value, RMS error %.3f %% of rho g H\n", method, n, 100 * rms);
    EXPECT_GE(n, 49u);
    EXPECT_LT(rms, 0.03);
  }
  // Points beyond the body get an empty value: a line that runs 0.3 m past the top.
  const Result r = swmpm_cmd("postprocess " + run + " profile --from 0.05,0.5 --to 0.05,1.3 --time 1 --quantity stress_yy --points 9", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("1.3,\n"), std::string::npos) << r.out;
}

// `frame`: every particle of one frame as CSV, read through VTK: the column's 160 particles with
// their positions and arrays; sigma_yy against rho g (H - y0) as in the profile test.
TEST(Postprocess, FrameTableHoldsEveryParticle) {
  const std::string run = column_run("frame");
  const fs::path dir = fs::path(run).parent_path();
  const fs::path csv = dir / "frame.csv";
  const Result r = swmpm_cmd("postprocess " + run + " frame --time 1 --out " + csv.string(), dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("t = 1 s"), std::string::npos) << "says which frame: " << r.out;
  const auto t = swmpm::post::read_csv(csv.string());
  ASSERT_EQ(t.columns[0].size(), 160u);
  const std::vector<std::string> first{"x", "y", "id", "mass", "volume", "half_size_x", "half_size_y"};
  ASSERT_GE(t.names.size(), first.size());
  EXPECT_EQ(std::vector<std::string>(t.names.begin(), t.names.begin() + 7), first);
  const auto& y = t.column("y");
  const auto& uy = t.column("displacement_y");
  const auto& syy = t.column("stress_yy");
  double e2 = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) e2 += std::pow((syy[k] - -rho * g * (H - (y[k] - uy[k]))) / (rho * g * H), 2);
  const double rms = std::sqrt(e2 / static_cast<double>(y.size()));
  std::printf("frame: 160 rows, sigma_yy RMS error %.3f %% of rho g H\n", 100 * rms);
  EXPECT_LT(rms, 0.03);
  // A fluid frame of a dry run is an error naming the phase.
  const Result bad = swmpm_cmd("postprocess " + run + " frame --time 1 --phase fluid", dir);
  EXPECT_NE(bad.status, 0);
}

TEST(Postprocess, CompareAgainstAnalyticSettlement) {
  const std::string run = column_run("compare");
  const fs::path dir = fs::path(run).parent_path();
  write_reference(dir / "right.csv", 1.0);
  write_reference(dir / "wrong.csv", 1.2);
  Result r = swmpm_cmd("postprocess " + run + " compare --monitor top.displacement_y --reference " +
                           (dir / "right.csv").string() + " --tolerance 0.02", dir);
  EXPECT_EQ(r.status, 0) << r.out << r.err;
  for (const char* word : {"relative L2 error", "max abs error", "peak |value|"})
    EXPECT_NE(r.out.find(word), std::string::npos) << word << " in " << r.out;
  r = swmpm_cmd("postprocess " + run + " compare --monitor top.displacement_y --reference " +
                    (dir / "wrong.csv").string() + " --tolerance 0.02", dir);
  EXPECT_EQ(r.status, 1) << r.out << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("tolerance"), std::string::npos) << r.err;
  // The library's numbers: about 0.5 % against the right curve, 1 − 1/1.2 ≈ 17 % against the wrong.
  const auto right = swmpm::post::compare(run, "top.displacement_y", (dir / "right.csv").string());
  const auto wrong = swmpm::post::compare(run, "top.displacement_y", (dir / "wrong.csv").string(), "displacement_y");
  std::printf("compare: relative L2 %.4f (right), %.4f (wrong)\n", right.rel_l2, wrong.rel_l2);
  EXPECT_EQ(right.points, 11u);
  EXPECT_LT(right.rel_l2, 0.01);
  EXPECT_NEAR(wrong.rel_l2, 1.0 - 1.0 / 1.2, 0.01);
}

TEST(Postprocess, PlotsArePngFiles) {
  const std::string run = column_run("plot");
  const fs::path dir = fs::path(run).parent_path();
  write_reference(dir / "right.csv", 1.0);
  Result r = swmpm_cmd("postprocess " + run + " plot --reference top.displacement_y=" + (dir / "right.csv").string(), dir);
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* m : {"top", "base", "energy"}) EXPECT_TRUE(is_png(fs::path(run) / "plots" / (std::string(m) + ".png"))) << m;
  r = swmpm_cmd("postprocess " + run + " plot --field stress_yy --times 0.5,1", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* t : {"0.5", "1"})
    EXPECT_TRUE(is_png(fs::path(run) / "plots" / ("field_stress_yy_" + std::string(t) + ".png"))) << t;
  r = swmpm_cmd("postprocess " + run + " plot --field displacement_magnitude", dir);  // the last frame
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(is_png(fs::path(run) / "plots" / "field_displacement_magnitude_1.png")) << r.out;
}

TEST(Postprocess, ReportHoldsTheNumbers) {
  const std::string run = column_run("report");
  const fs::path dir = fs::path(run).parent_path();
  write_reference(dir / "right.csv", 1.0);
  const Result r = swmpm_cmd("postprocess " + run + " report --reference top.displacement_y=" + (dir / "right.csv").string(), dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string md = swmpm::testing::read_text(run + "/report.md");
  const json rj = swmpm::testing::load_json(run + "/run.json");
  const auto c = swmpm::post::compare(run, "top.displacement_y", (dir / "right.csv").string());
  std::ostringstream rel;
  rel.precision(4);
  rel << c.rel_l2;
  for (const std::string& s : {std::string("elastic-column"), std::string("gimp"), std::string("linear-elastic"),
                               std::to_string(rj["steps"].get<long>()), std::string("µs per particle-step"),
                               rel.str(), std::string("plots/top.png"), std::string("plots/field_")})
    EXPECT_NE(md.find(s), std::string::npos) << "\"" << s << "\" in report.md:\n" << md;
  EXPECT_TRUE(is_png(fs::path(run) / "plots" / "top.png"));
}

// Single-point two-phase runs write one particle set carrying both phases: --phase fluid reads
// its fluid arrays (velocity_* is fluid_velocity) from the solid frames. A hand-made series of two
// frames stands in for a run, as any tool's VTU files may.
TEST(Postprocess, FluidPhaseOnSinglePointFrames) {
  const fs::path run = swmpm::testing::scratch("post-fluid") / "run";
  fs::create_directories(run / "output");
  std::ofstream(run / "scene.json") << R"({"dimension": 2})";
  std::vector<swmpm::scene::PvdEntry> entries;
  for (int k = 0; k < 2; ++k) {
    swmpm::scene::PointCloud c;
    c.points = {{0.25, 0.25, 0.0}, {0.75, 0.25, 0.0}};
    auto& id = c.add("id", 1);
    auto& half = c.add("half_size", 3);
    auto& v = c.add("velocity", 3);
    auto& vf = c.add("fluid_velocity", 3);
    auto& p = c.add("pore_pressure", 1);
    for (std::size_t i = 0; i < 2; ++i) {
      id.values[i] = static_cast<double>(i);
      half.values[3 * i] = half.values[3 * i + 1] = 0.25;
      v.values[3 * i + 1] = -1.0 * k;   // solid moves down
      vf.values[3 * i + 1] = 2.0 * k;   // water moves up
      p.values[i] = 1000.0 * (k + 1) + static_cast<double>(i);
    }
    const std::string file = "solid_00000" + std::to_string(k) + ".vtu";
    swmpm::scene::write_vtu((run / "output" / file).string(), c);
    entries.push_back({0.5 * k, "solid", 0, file});
  }
  swmpm::scene::write_pvd((run / "output" / "results.pvd").string(), entries);
  swmpm::post::HistoryOptions o;
  o.point = {0.3, 0.3, 0.0};
  o.phase = "fluid";
  o.quantity = "velocity_y";
  auto h = swmpm::post::history(run.string(), o);
  ASSERT_EQ(h.rows.size(), 2u);
  EXPECT_EQ(h.rows[1][1], 2.0);
  o.quantity = "pore_pressure";
  h = swmpm::post::history(run.string(), o);
  EXPECT_EQ(h.rows[0][1], 1000.0);
  EXPECT_EQ(h.rows[1][1], 2000.0);
  o.phase = "solid";
  o.quantity = "velocity_y";
  EXPECT_EQ(swmpm::post::history(run.string(), o).rows[1][1], -1.0);
}

// Each bad input: non-zero status, one line on stderr that says what is wrong.
TEST(Postprocess, ErrorsAreOneClearLine) {
  const std::string run = column_run("errors");
  const fs::path dir = fs::path(run).parent_path();
  fs::create_directories(dir / "empty-run");
  const std::string hist = " history --phase solid --quantity displacement_y --point ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {(dir / "no-such-run").string() + hist + "0.05,1", "not a run directory"},
      {(dir / "empty-run").string() + hist + "0.05,1", "results.pvd"},
      {run + " history --point 0.05,1 --quantity stress_qq", "available: "},
      {run + hist + "5,5", "outside all solid particles"},
      {run + hist + "'0.05;1'", "expected X,Y or X,Y,Z"},
      {run + hist + "0.05", "expected X,Y or X,Y,Z"},
      {run + " profile --from 3,3 --to 4,4 --time 1 --quantity stress_yy", "outside all solid particles"},
      {run + " history --point 0.05,1 --phase fluid --quantity pore_pressure", "no fluid frames"},
      {run + " compare --monitor top.nothing --reference " + (dir / "x.csv").string(), "available: top.displacement_y"},
      {run + " plot --field nothing", "available: "},
  };
  for (const auto& [args, phrase] : cases) {
    const Result r = swmpm_cmd("postprocess " + args, dir);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_EQ(lines(r.err), 1u) << args << ": " << r.err;
    EXPECT_NE(r.err.find(phrase), std::string::npos) << args << ": " << r.err;
  }
  // The available list names the components a user can type.
  const Result r = swmpm_cmd("postprocess " + run + " history --point 0.05,1 --quantity stress_qq", dir);
  for (const char* q : {"stress_yy", "displacement_y", "mean_effective_stress", "volume_ratio"})
    EXPECT_NE(r.err.find(q), std::string::npos) << q << " in " << r.err;
}
