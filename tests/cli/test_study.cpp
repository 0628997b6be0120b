// `swmpm study` (issue 26, item 5) on cases with a known answer: its Richardson estimate of the
// discretisation error must bracket the true error (against the analytic solution) within a
// factor of 2. And the command as a user meets it: bad options and scenes exit 2 writing nothing,
// an earlier study is refused without --overwrite and only swmpm's files are replaced, a budget
// too small is refused with what it would need, and the report pages hold the table and the chart.
// Numbers: docs/verification.md, "swmpm study against known answers".
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

json example(const std::string& folder) {
  return swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/" + folder + "/scene.json");
}

/// Writes `scene` to DIR/scene.json and runs `swmpm -q study` on it into DIR/study.
Result study(const json& scene, const fs::path& dir, const std::string& options) {
  std::ofstream(dir / "scene.json") << scene.dump(2);
  return swmpm_cmd("-q study " + (dir / "scene.json").string() + " -o " + (dir / "study").string() + " " + options, dir);
}

/// The estimate of `column` under `metric` in study.json.
json estimate(const json& st, const std::string& column, const std::string& metric) {
  for (const auto& e : st["estimates"])
    if (e["column"] == column && e["metric"] == metric) return e;
  ADD_FAILURE() << "no estimate of " << column << " (" << metric << ")";
  return json::object();
}

/// The finest estimated level's value of `column` at the end time.
double finest_end(const fs::path& study_dir, const json& st, const std::string& column) {
  const std::string label = st["estimated_levels"].back();
  const auto t = swmpm::testing::read_monitors((study_dir / "runs" / label).string());
  return t.column(column).back();
}

/// Asserts that the estimated absolute error of the finest level is within a factor of 2 of the
/// true one, and prints both (the numbers docs/verification.md records).
void expect_brackets(const json& e, double true_error, const std::string& what) {
  const double estimated = e["error"].back().get<double>();
  std::printf("study %s: order %.3f (%s), estimated error %.4g, true error %.4g, ratio %.3f\n", what.c_str(),
              e["order"].is_null() ? NAN : e["order"].get<double>(), e["asymptotic"].get<bool>() ? "asymptotic" : "flagged",
              estimated, true_error, estimated / true_error);
  EXPECT_TRUE(e["asymptotic"].get<bool>()) << what << ": " << e["flag"];
  EXPECT_GE(estimated, 0.5 * true_error) << what;
  EXPECT_LE(estimated, 2.0 * true_error) << what;
}

/// Terzaghi's average degree of consolidation U(Tv) (drained top, impermeable base).
double degree_of_consolidation(double Tv) {
  if (Tv <= 0.0) return 0.0;  // the series converges slowly there
  double sum = 0.0;
  for (int m = 0; m < 400; ++m) {
    const double M = (2 * m + 1) * M_PI / 2;
    sum += 2.0 / (M * M) * std::exp(-M * M * Tv);
  }
  return 1.0 - sum;
}

/// A1 (examples/terzaghi) to t_end, its column widened to 0.2 m (roller sides keep it 1D) so that
/// a 0.1 m cell still leaves the two cells per axis the grid needs.
json terzaghi(double t_end, double width) {
  json s = example("terzaghi");
  s["grid"]["max"][0] = width;
  s["bodies"][0]["geometry"]["max"][0] = width;
  for (auto& m : s["output"]["monitors"]) m["at"][0] = width / 2;
  s["time"]["end"] = t_end;
  s["output"]["interval"] = t_end / 2;
  return s;
}

/// A1's consolidation coefficient and settlement scale (examples/terzaghi/README.md).
constexpr double kCv = 1.0e-3 / (1000.0 * 9.81 * (1.0 / 1.0e7 + 0.3 / 2.2e9));  // m^2/s
constexpr double kFinalSettlement = 1.0e4 * 1.0 / 1.0e7;                           // m, q H / E_oed

void check_terzaghi(const fs::path& dir, double t_end, const std::string& what) {
  const json st = swmpm::testing::load_json((dir / "study" / "study.json").string());
  const double Tv = kCv * t_end;
  // The top settlement, asked at the top (0.05 or 0.1, 1.0): the exact value there.
  const double u_exact = -degree_of_consolidation(Tv) * kFinalSettlement;
  const json top = estimate(st, "top.displacement_y", "end");
  expect_brackets(top, std::abs(finest_end(dir / "study", st, "top.displacement_y") - u_exact), what + " top settlement");
  EXPECT_NEAR(top["order"].get<double>(), 1.0, 0.2) << "the top particle sits h/4 below the top: first order";
  // Its history: RMS over the coarsest level's monitor times of the finest level's error.
  {
    const auto coarse = swmpm::testing::read_monitors((dir / "study" / "runs" / st["estimated_levels"].front().get<std::string>()).string());
    const auto fine = swmpm::testing::read_monitors((dir / "study" / "runs" / st["estimated_levels"].back().get<std::string>()).string());
    const auto& tf = fine.column("time");
    const auto& uf = fine.column("top.displacement_y");
    double sum = 0.0;
    const auto& times = coarse.column("time");
    for (double t : times) {
      std::size_t i = 1;
      while (i + 1 < tf.size() && tf[i] < t) ++i;
      const double w = std::clamp((t - tf[i - 1]) / (tf[i] - tf[i - 1]), 0.0, 1.0);
      const double u = (1.0 - w) * uf[i - 1] + w * uf[i];
      sum += std::pow(u + degree_of_consolidation(kCv * t) * kFinalSettlement, 2);
    }
    expect_brackets(estimate(st, "top.displacement_y", "history"), std::sqrt(sum / static_cast<double>(times.size())),
                    what + " top settlement history");
  }
  // The base pressure converges at second order, but to a value 0.08 % above Terzaghi's: the
  // MPM solves the dynamic equations, and drainage starts one undrained wave transit later (H/c =
  // 0.54 ms). The study sees only the discretisation error (docs/verification.md).
  const json base = estimate(st, "base.pore_pressure", "end");
  const double p_exact = 1.0e4 * swmpm::testing::terzaghi(1.0, Tv);
  const double p_run = finest_end(dir / "study", st, "base.pore_pressure");
  std::printf("study %s base pressure: order %.3f, estimated error %.4g Pa, true error %.4g Pa (extrapolated %.2f, "
              "Terzaghi %.2f)\n",
              what.c_str(), base["order"].get<double>(), base["error"].back().get<double>(), std::abs(p_run - p_exact),
              base["extrapolated"].get<double>(), p_exact);
  EXPECT_TRUE(base["asymptotic"].get<bool>());
  EXPECT_NEAR(base["extrapolated"].get<double>(), p_exact, 2e-3 * p_exact) << "within 0.2 % of Terzaghi";
}

}  // namespace

// A1 at 0.1, 0.05 and 0.025 m to t = 0.1 s (Tv = 0.10): ~15 s on one core.
TEST(Study, TerzaghiSettlementEstimateBracketsTheTrueError) {
  const fs::path dir = swmpm::testing::scratch("study-terzaghi");
  const Result r = study(terzaghi(0.1, 0.2), dir, "--cell-sizes 0.1,0.05,0.025 --budget 20");
  ASSERT_EQ(r.status, 0) << r.err;
  check_terzaghi(dir, 0.1, "A1 h 0.1-0.025");
}

// The example's own column (0.1 m wide) at its own cell size and two refinements.
TEST(Study, SlowTerzaghiAtTheExampleResolution) {
  const fs::path dir = swmpm::testing::scratch("study-terzaghi-example");
  const Result r = study(terzaghi(0.1, 0.1), dir, "--budget 30");
  ASSERT_EQ(r.status, 0) << r.err;
  check_terzaghi(dir, 0.1, "A1 h 0.05-0.0125");
}

// The elastic column (examples/elastic-column) as it is, planned by the study itself: its grid is
// two cells wide, so the levels are h0 = 0.05 m and two refinements. The base stresses bracket
// the closed form at y = 0. The settlement converges to 0.49 % below the small-strain closed form:
// at E = 1 MPa the column shortens by 1.3 % at its base, a finite-strain effect that refining
// does not remove (the next test stiffens the soil).
TEST(Study, ElasticColumnPlansItsLevelsAndBracketsTheBaseStress) {
  const fs::path dir = swmpm::testing::scratch("study-column");
  const json s = example("elastic-column");
  Result r = study(s, dir, "--budget 5");
  ASSERT_EQ(r.status, 0) << r.err;
  const json st = swmpm::testing::load_json((dir / "study" / "study.json").string());
  ASSERT_EQ(st["levels"].size(), 3u);
  EXPECT_EQ(st["levels"][0]["label"], "h0.05");
  EXPECT_EQ(st["levels"][2]["label"], "h0.0125");
  constexpr double rho_g_H = 1800.0 * 9.81 * 1.0, k0 = 0.3 / 0.7;  // Pa; nu / (1 - nu)
  expect_brackets(estimate(st, "base.stress_yy", "end"),
                  std::abs(finest_end(dir / "study", st, "base.stress_yy") + rho_g_H), "column stress_yy");
  expect_brackets(estimate(st, "base.stress_xx", "end"),
                  std::abs(finest_end(dir / "study", st, "base.stress_xx") + k0 * rho_g_H), "column stress_xx");

  // The pages: the verdict, the runs with their stability, the error table, the chart embedded.
  const std::string md = swmpm::testing::read_text((dir / "study" / "report.md").string());
  const std::string html = swmpm::testing::read_text((dir / "study" / "report.html").string());
  for (const std::string& text : {std::string("## Verdict"), std::string("## Runs"), std::string("## Estimated error"),
                                  std::string("cost-error.png"), std::string("no threshold crossed")})
    EXPECT_NE(md.find(text), std::string::npos) << text;
  EXPECT_NE(html.find("<img alt=\"Wall time against estimated relative error"), std::string::npos);
  EXPECT_NE(html.find("src=\"data:image/png;base64,iVBORw0KGgo"), std::string::npos) << "a PNG, embedded";
  EXPECT_EQ(html.find("src=\"cost-error.png"), std::string::npos) << "self-contained";
  EXPECT_NE(html.find("<th>level</th>"), std::string::npos);
  EXPECT_GT(fs::file_size(dir / "study" / "cost-error.png"), 1000u);

  // An earlier study is refused without --overwrite; with it, only swmpm's files are replaced.
  r = study(s, dir, "--budget 5");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--overwrite"), std::string::npos) << r.err;
  std::ofstream(dir / "study" / "notes.txt") << "mine\n";
  std::ofstream(dir / "study" / "runs" / "h0.05" / "mine.csv") << "1\n";
  r = study(s, dir, "--budget 5 --overwrite --cell-sizes 0.05,0.025,0.0125");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "study" / "notes.txt"));
  EXPECT_TRUE(fs::exists(dir / "study" / "runs" / "h0.05" / "mine.csv"));
  EXPECT_TRUE(fs::exists(dir / "study" / "report.html"));
}

// The column stiffened to E = 100 MPa (strain 0.013 % at the base), 0.2 m wide: the small-strain
// closed form is then its continuum limit, and the settlement is bracketed too.
TEST(Study, StiffElasticColumnBracketsSettlementAndStress) {
  const fs::path dir = swmpm::testing::scratch("study-stiff-column");
  json s = example("elastic-column");
  s["materials"][0]["youngs_modulus"] = 1.0e8;
  s["grid"]["max"][0] = 0.2;
  s["bodies"][0]["geometry"]["max"][0] = 0.2;
  for (auto& m : s["output"]["monitors"])
    if (m.contains("at")) m["at"][0] = 0.1;
  const Result r = study(s, dir, "--cell-sizes 0.1,0.05,0.025 --budget 10 --monitor top.displacement_y --monitor base");
  ASSERT_EQ(r.status, 0) << r.err;
  const json st = swmpm::testing::load_json((dir / "study" / "study.json").string());
  constexpr double rho_g_H = 1800.0 * 9.81 * 1.0, k0 = 0.3 / 0.7;
  const double M = 1.0e8 * 0.7 / (1.3 * 0.4);  // Pa, constrained modulus
  expect_brackets(estimate(st, "top.displacement_y", "end"),
                  std::abs(finest_end(dir / "study", st, "top.displacement_y") + rho_g_H / (2.0 * M)),
                  "stiff column settlement");
  expect_brackets(estimate(st, "base.stress_yy", "end"),
                  std::abs(finest_end(dir / "study", st, "base.stress_yy") + rho_g_H), "stiff column stress_yy");
  expect_brackets(estimate(st, "base.stress_xx", "end"),
                  std::abs(finest_end(dir / "study", st, "base.stress_xx") + k0 * rho_g_H), "stiff column stress_xx");
  for (const auto& e : st["estimates"])  // --monitor chose these three (and their histories)
    EXPECT_NE(e["column"], "energy.kinetic_energy");
}

// Bad options and scenes: exit 2, one line naming the option or the JSON path, nothing written.
TEST(Study, BadInputWritesNothing) {
  const fs::path dir = swmpm::testing::scratch("study-bad");
  const json s = example("elastic-column");
  struct Case {
    std::string options, phrase;
  };
  for (const Case& c : {Case{"--tolerance 2", "--tolerance: got 2"}, Case{"--budget 0", "--budget: got 0"},
                        Case{"--levels 2", "--levels: got 2"}, Case{"--monitor nowhere", "--monitor: got \"nowhere\""},
                        Case{"--cell-sizes 0.05,0.025,0.0124", "--cell-sizes: the ratio"},
                        Case{"--cell-sizes 0.1,0.05,0.025", "fewer than 2 cells"}, Case{"--metric peak", "--metric"}}) {
    const Result r = study(s, dir, c.options);
    EXPECT_EQ(r.status, 2) << c.options << ": " << r.err;
    EXPECT_NE(r.err.find(c.phrase), std::string::npos) << c.options << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(dir / "study")) << c.options;
  }
  json bad = s;
  bad["materials"][0]["poisson_ratio"] = 0.7;
  const Result r = study(bad, dir, "");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("/materials/0/poisson_ratio"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "study"));
}

// A budget the fewest levels cannot keep: refused after the first (cheapest) run measured the
// cost, saying what budget would do.
TEST(Study, BudgetTooSmallIsRefusedWithWhatItWouldNeed) {
  const fs::path dir = swmpm::testing::scratch("study-budget");
  json s = example("elastic-column");
  s["time"]["end"] = 0.3;
  const Result r = study(s, dir, "--budget 0.0005");
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("--budget 0.0005 min is too small"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("expected --budget"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "study" / "report.md"));
}
