// The first run a user makes (README's first command, examples/saturated-slope) ends with a
// one-page report in report.md and report.html (issue 26, item 6). Checked as a reader sees it:
// the sections are there (setup, the formulation "auto" chose and why, cost, stability, monitors,
// the last frame's displacement and pore pressure), report.html embeds every picture (no file
// beside it is needed), and headless Chromium renders it with every image decoded and the tables
// present.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "support/run_helpers.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t k = text.find(what); k != std::string::npos; k = text.find(what, k + what.size())) ++n;
  return n;
}

/// The saturated slope of the README's first command, cut short: 0.2 s of initialisation and
/// 0.1 s of run (the gmsh geometry, "auto", the monitors and the outputs as in the example).
fs::path run_short_slope(const std::string& name) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/saturated-slope/scene.json");
  s["bodies"][0]["geometry"]["file"] = SWMPM_SOURCE_DIR "/geometries/slope.geo";
  s["initialisation"]["duration"] = 0.2;
  s["initialisation"]["gravity_ramp"] = 0.1;
  s["time"]["end"] = 0.1;
  s["output"]["interval"] = 0.05;
  const fs::path dir = swmpm::testing::scratch(name);
  std::ofstream(dir / "scene.json") << s.dump(2);
  const fs::path run = dir / "run";
  const Result r = swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run.string(), dir);
  EXPECT_EQ(r.status, 0) << r.err;
  return run;
}

}  // namespace

TEST(ReportHtml, SaturatedSlopeReportHoldsEverySectionAndEmbedsEveryPicture) {
  const fs::path run = run_short_slope("report-html-sections");
  const std::string md = swmpm::testing::read_text((run / "report.md").string());
  const std::string html = swmpm::testing::read_text((run / "report.html").string());
  for (const char* section : {"## Setup", "## Formulation", "## Cost", "## Stability", "## Monitors", "## Fields"})
    EXPECT_NE(md.find(std::string(section) + "\n"), std::string::npos) << section << "\n" << md;
  // "auto" chose a single-point formulation (pore water only) and the report says why, with both estimates.
  EXPECT_NE(md.find("chosen by `\"formulation\": \"auto\"`"), std::string::npos) << md;
  EXPECT_NE(md.find("| explicit-single-point |"), std::string::npos) << md;
  EXPECT_NE(md.find("| semi-implicit-single-point |"), std::string::npos) << md;
  // Every indicator is listed with its verdict.
  for (const char* indicator : {"pressure checkerboard", "mean stress checkerboard", "energy error", "porosity min", "J max"})
    EXPECT_NE(md.find("| " + std::string(indicator) + " |"), std::string::npos) << indicator << "\n" << md;
  // The last frame's displacement and pore pressure, and the three monitors.
  const std::regex field(R"(!\[(displacement_magnitude|pore_pressure) at t = 0\.1 s\]\(plots/field_\w+_0\.1\.png\))");
  EXPECT_EQ(std::distance(std::sregex_iterator(md.begin(), md.end(), field), std::sregex_iterator()), 2) << md;
  for (const char* m : {"crest", "toe", "toe_water"})
    EXPECT_NE(md.find("](plots/" + std::string(m) + ".png)"), std::string::npos) << m;
  // report.html: the same pictures, each embedded as a PNG (base64 of the PNG signature starts
  // "iVBORw0KGgo"), and no reference to any file.
  const std::size_t pictures = count(md, "![");
  EXPECT_GE(pictures, 5u);
  EXPECT_EQ(count(html, "<img "), pictures);
  EXPECT_EQ(count(html, "src=\"data:image/png;base64,iVBORw0KGgo"), pictures);
  EXPECT_EQ(count(html, "src=\""), pictures);
  EXPECT_EQ(count(html, "href="), 0u);
  EXPECT_GE(count(html, "<table>"), 6u);  // setup, materials, bodies, estimates, cost, stages, stability
}

// Rendered by Chromium as a reader opens it: a script added to a copy of the page reports, once
// the page has loaded, how many images decoded (naturalWidth > 0) and how many tables have rows;
// a screenshot of the page is written beside it.
TEST(ReportHtml, SaturatedSlopeReportRendersInHeadlessChromium) {
  ASSERT_EQ(std::system("command -v chromium >/dev/null 2>&1"), 0)
      << "chromium is not installed: scripts/install-deps.sh installs it (Debian package chromium)";
  const fs::path run = run_short_slope("report-html-chromium");
  std::string html = swmpm::testing::read_text((run / "report.html").string());
  const std::size_t images = count(html, "<img ");
  const std::size_t tables = count(html, "<table>");
  const std::string probe =
      "<script>window.addEventListener('load', () => {"
      " const im = [...document.images];"
      " const ok = im.filter(i => i.complete && i.naturalWidth > 0 && i.naturalHeight > 0).length;"
      " const t = [...document.querySelectorAll('table')].filter(t => t.rows.length > 0).length;"
      " document.body.setAttribute('data-probe', 'images ' + ok + ' of ' + im.length + ', tables ' + t); });</script>";
  html.insert(html.rfind("</body>"), probe);
  const fs::path page = run / "probe.html";
  std::ofstream(page) << html;
  const std::string chromium = "chromium --headless --no-sandbox --disable-gpu --disable-dev-shm-usage "
                               "--virtual-time-budget=5000 ";
  const fs::path dump = run / "dom.html";
  ASSERT_EQ(std::system((chromium + "--dump-dom file://" + page.string() + " > " + dump.string() + " 2>/dev/null").c_str()), 0);
  const std::string rendered = swmpm::testing::read_text(dump.string());
  const std::string expected = "images " + std::to_string(images) + " of " + std::to_string(images) + ", tables " +
                               std::to_string(tables);
  EXPECT_NE(rendered.find("data-probe=\"" + expected + "\""), std::string::npos)
      << "expected " << expected << "; the rendered body begins: " << rendered.substr(rendered.find("<body"), 300);
  const fs::path shot = run / "report.png";
  ASSERT_EQ(std::system((chromium + "--window-size=1280,4000 --screenshot=" + shot.string() + " file://" +
                         (run / "report.html").string() + " >/dev/null 2>&1")
                            .c_str()),
            0);
  ASSERT_TRUE(fs::exists(shot));
  EXPECT_GT(fs::file_size(shot), 50'000u) << "a page of tables and plots is more than a blank screenshot";
}

// A run of free water only in mpm-fem (the dam break, cut to 0.02 s): no soil points and no water
// points, the water lives on the grid. `swmpm run` used to fail in its report ("the frames have
// neither half_size nor volume"); the report now shows the grid's phase field and pressure.
TEST(ReportHtml, FreeWaterOnTheGridReportShowsThePhaseFieldAndPressure) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/dam-break-mpm-fem/scene.json");
  s["time"]["end"] = 0.02;
  s["output"]["interval"] = 0.01;
  const fs::path dir = swmpm::testing::scratch("report-html-free-water");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const fs::path run = dir / "run";
  const Result r = swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run.string() + " -q", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string md = swmpm::testing::read_text((run / "report.md").string());
  for (const char* f : {"phase_field", "pressure"})
    EXPECT_NE(md.find("](plots/field_" + std::string(f) + "_0.02.png)"), std::string::npos) << f << "\n" << md;
  const std::string html = swmpm::testing::read_text((run / "report.html").string());
  EXPECT_EQ(count(html, "src=\"data:image/png;base64,iVBORw0KGgo"), count(md, "!["));
}
