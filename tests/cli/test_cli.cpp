// The `swmpm` command as a user meets it: bad scenes give one line per problem naming the JSON
// path, a non-zero status and no run directory; a diverging run stops with a diagnosis, status 3,
// and leaves the last good state as a finite final frame.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

json good_scene() { return swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json"); }

/// Runs preprocess on a broken scene; expects failure naming `path`, one line, nothing written.
void expect_rejected(const json& scene, const std::string& name, const std::string& path, const std::string& phrase) {
  const fs::path dir = swmpm::testing::scratch("bad-" + name);
  std::ofstream(dir / "scene.json") << scene.dump(2);
  const fs::path run = dir / "run";
  const Result r = swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + run.string(), dir);
  EXPECT_EQ(r.status, 2) << name << ": an invalid scene exits 2 (docs/architecture.md)";
  EXPECT_NE(r.err.find(path), std::string::npos) << name << ": stderr was: " << r.err;
  EXPECT_NE(r.err.find(phrase), std::string::npos) << name << ": stderr was: " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << name << ": expected one line: " << r.err;
  EXPECT_NE(r.err.find("scene.json"), std::string::npos) << name << ": the line names the file";
  EXPECT_FALSE(fs::exists(run)) << name << ": nothing may be written";
}

}  // namespace

TEST(BadInput, UnknownKeyWithSuggestion) {
  json s = good_scene();
  s["materials"][0].erase("youngs_modulus");
  s["materials"][0]["youngs_modulu"] = 1e6;
  // Two problems (unknown key, missing required key) -> checked separately below; here only the typo.
  const fs::path dir = swmpm::testing::scratch("bad-unknown");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const Result r = swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("/materials/0/youngs_modulu"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("did you mean \"youngs_modulus\""), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "run"));
}

TEST(BadInput, UnknownTopLevelKey) {
  json s = good_scene();
  s["gravty"] = {0, -9.81};
  expect_rejected(s, "toplevel", "/gravty", "did you mean \"gravity\"");
}

TEST(BadInput, WrongType) {
  json s = good_scene();
  s["grid"]["cell_size"] = "0.05";
  expect_rejected(s, "type", "/grid/cell_size", "0.05");
}

TEST(BadInput, WrongVectorLength) {
  json s = good_scene();
  s["gravity"] = {0.0, -9.81, 0.0};
  expect_rejected(s, "veclen", "/gravity", "2");
}

TEST(BadInput, OutOfRange) {
  json s = good_scene();
  s["materials"][0]["poisson_ratio"] = 0.7;
  expect_rejected(s, "range", "/materials/0/poisson_ratio", "0.7");
}

TEST(BadInput, DanglingMaterialName) {
  json s = good_scene();
  s["bodies"][0]["solid"] = "sand";
  expect_rejected(s, "dangling", "/bodies/0/solid", "soil");
}

TEST(BadInput, BodyOutsideTheGrid) {
  json s = good_scene();
  s["bodies"][0]["geometry"]["max"] = {0.1, 1.5};
  expect_rejected(s, "outside", "/bodies/0/geometry", "grid");
}

TEST(BadInput, UnknownEnumValue) {
  json s = good_scene();
  s["grid"]["shape_function"] = "cubic";
  expect_rejected(s, "enum", "/grid/shape_function", "bspline3");
}

TEST(BadInput, SwitchesTheFormulationDoesNotUseAreRejected) {
  json s = good_scene();
  s["solver"]["stabilisation"] = {{"pressure", "mfvp-linear"}};
  expect_rejected(s, "unused-switch", "/solver/stabilisation", "dry");
  s = good_scene();
  s["materials"][0]["model"] = "hencky";
  s["bodies"][0]["initial"] = {{"stress", {-1e3, -1e3, -1e3, 0, 0, 0}}};
  expect_rejected(s, "hencky-stress", "/bodies/0/initial/stress", "hencky");
}

TEST(BadInput, SeveralProblemsAreAllListed) {
  json s = good_scene();
  s["grid"]["cell_size"] = -1.0;
  s["materials"][0]["poisson_ratio"] = 0.5;
  s["time"]["end"] = 0.0;
  const fs::path dir = swmpm::testing::scratch("bad-several");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const Result r = swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
  EXPECT_NE(r.status, 0);
  for (const char* path : {"/grid/cell_size", "/materials/0/poisson_ratio", "/time/end"})
    EXPECT_NE(r.err.find(path), std::string::npos) << path << " in " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 3) << r.err;
}

TEST(BadInput, MissingFileAndInvalidJson) {
  const fs::path dir = swmpm::testing::scratch("bad-file");
  Result r = swmpm_cmd("preprocess " + (dir / "nope.json").string(), dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("nope.json"), std::string::npos) << r.err;
  std::ofstream(dir / "broken.json") << "{ \"name\": \"x\", ";
  r = swmpm_cmd("preprocess " + (dir / "broken.json").string(), dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("broken.json"), std::string::npos) << r.err;
  r = swmpm_cmd("solve " + (dir / "not-a-run").string(), dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("not a run directory"), std::string::npos) << r.err;
}

TEST(Cli, VersionAndHelp) {
  const fs::path dir = swmpm::testing::scratch("cli");
  Result r = swmpm_cmd("--version", dir);
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("swmpm 0."), std::string::npos) << r.out;
  for (const char* sub : {"preprocess", "solve", "postprocess", "run", "element"}) {
    r = swmpm_cmd(std::string(sub) + " --help", dir);
    EXPECT_EQ(r.status, 0) << sub;
    EXPECT_FALSE(r.out.empty()) << sub;
  }
}

TEST(Divergence, StopsWithDiagnosisAndKeepsLastGoodState) {
  // The column with dt 20x its CFL limit (~9e-4 s): it blows up within a few dozen steps.
  json s = good_scene();
  s["time"]["dt"] = 2.0e-2;
  s["output"]["interval"] = 0.1;  // frames at t = 0 and every 5 steps; snapshots every 50 (default)
  s["output"]["monitor_interval"] = 2.0e-2;  // a row every step (an interval below dt is refused)
  const fs::path dir = swmpm::testing::scratch("diverge");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const fs::path run = dir / "run";
  const Result r = swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run.string(), dir);
  EXPECT_EQ(r.status, 3) << r.out << r.err;
  const json rj = swmpm::testing::load_json((run / "run.json").string());
  EXPECT_EQ(rj["status"], "diverged");
  const std::string why = rj["diagnosis"];
  EXPECT_NE(why.find("particle"), std::string::npos) << why;
  EXPECT_NE(why.find("t = "), std::string::npos) << why;
  EXPECT_NE(swmpm::testing::read_text((run / "log.txt").string()).find("DIVERGED"), std::string::npos);
  // The series stays in time order and its last frame is the last good state: finite, in the grid.
  const auto entries = swmpm::scene::read_pvd((run / "output" / "results.pvd").string());
  for (std::size_t k = 1; k < entries.size(); ++k) EXPECT_GT(entries[k].time, entries[k - 1].time);
  EXPECT_EQ(rj["last_good_frame_time"].get<double>(), entries.back().time);
  EXPECT_GT(rj["steps"].get<long>(), 0);
  const auto frame = swmpm::testing::last_frame(run.string());
  ASSERT_GT(frame.size(), 0u);
  for (const auto& x : frame.points) {
    EXPECT_TRUE(std::isfinite(x[0]) && std::isfinite(x[1]));
    EXPECT_GE(x[1], 0.0);
    EXPECT_LE(x[1], 1.1);
  }
  for (double v : frame.get("stress", "frame").values) ASSERT_TRUE(std::isfinite(v));
  // interface.md §1: a failing command says why in one line on stderr, also when quiet.
  EXPECT_NE(r.err.find("swmpm: DIVERGED: "), std::string::npos) << r.err;
  const Result quiet = swmpm_cmd("-q solve " + run.string(), dir);
  EXPECT_EQ(quiet.status, 3);
  EXPECT_TRUE(quiet.out.empty()) << quiet.out;
  EXPECT_EQ(std::count(quiet.err.begin(), quiet.err.end(), '\n'), 1) << quiet.err;
  EXPECT_EQ(quiet.err.rfind("swmpm: DIVERGED: solid particle", 0), 0u) << quiet.err;
}

// The time loop lands on time.end: 1e5 steps of 1e-5 s are 1e5 steps (the plain running sum of
// the steps falls 2e-12 s short of 1 s, and a stray 2e-12 s step used to follow), and monitors
// fall on their interval (0.9, not 0.90001).
TEST(TimeLoop, LandsOnTheEndTimeAndOnTheMonitorTimes) {
  json s = good_scene();
  s["time"]["dt"] = 1e-5;
  s["time"]["end"] = 1.0;
  s["output"]["interval"] = 1.0;
  s["output"]["monitor_interval"] = 0.1;
  const fs::path dir = swmpm::testing::scratch("time-loop-lands");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const fs::path run = dir / "run";
  const Result r = swmpm_cmd("-q run " + (dir / "scene.json").string() + " -o " + run.string() + " --threads 1", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const json rj = swmpm::testing::load_json((run / "run.json").string());
  EXPECT_EQ(rj["steps"].get<long>(), 100000);
  EXPECT_EQ(rj["end_time"].get<double>(), 1.0);
  EXPECT_EQ(rj["dt"].get<double>(), 1e-5);
  const auto t = swmpm::post::read_csv((run / "monitors.csv").string()).column("time");
  ASSERT_EQ(t.size(), 11u);
  for (std::size_t k = 0; k < t.size(); ++k) EXPECT_NEAR(t[k], 0.1 * static_cast<double>(k), 1e-9) << k;
}

TEST(Divergence, ParticleLeavingTheGridIsDiagnosed) {
  // A block thrown upward at 20 m/s towards the free top of a grid that ends 0.3 m above it.
  json s = good_scene();
  s["grid"]["max"] = {0.1, 1.3};
  s["bodies"][0]["initial"] = {{"velocity", {"0", "20"}}};
  s["gravity"] = {0.0, 0.0};
  s.erase("gravity_ramp");
  s["boundaries"] = json::array({{{"on", "x_min"}, {"solid", "roller"}}, {{"on", "x_max"}, {"solid", "roller"}}});
  s["output"]["monitors"] = json::array();
  const fs::path dir = swmpm::testing::scratch("leave");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const fs::path run = dir / "run";
  const Result r = swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run.string(), dir);
  EXPECT_EQ(r.status, 3) << r.out << r.err;
  const json rj = swmpm::testing::load_json((run / "run.json").string());
  EXPECT_EQ(rj["status"], "diverged");
  EXPECT_NE(rj["diagnosis"].get<std::string>().find("left the grid"), std::string::npos) << rj["diagnosis"];
}

// F-bar: the dry formulation accepts solver.stabilisation.fbar (and fbar_patch with "modified"),
// rejects the pore-pressure and smoothing switches, and any formulation rejects a patch size the
// chosen F-bar does not read; an out-of-range patch is a schema error.
TEST(BadInput, FBarSwitches) {
  json s = good_scene();
  s["solver"]["stabilisation"] = {{"fbar", "modified"}, {"fbar_patch", 1.5}};
  const fs::path dir = swmpm::testing::scratch("fbar-dry");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const Result ok = swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
  EXPECT_EQ(ok.status, 0) << ok.err;
  const json resolved = swmpm::testing::load_json((dir / "run" / "scene.json").string());
  EXPECT_EQ(resolved["solver"]["stabilisation"]["fbar_patch"].get<double>(), 1.5);
  s["solver"]["stabilisation"] = {{"fbar", "standard"}, {"fbar_patch", 1.5}};
  expect_rejected(s, "fbar-patch", "/solver/stabilisation/fbar_patch", "modified");
  s["solver"]["stabilisation"] = {{"fbar", "standard"}, {"strain_smoothing", true}};
  expect_rejected(s, "fbar-smoothing", "/solver/stabilisation/strain_smoothing", "dry");
  s["solver"]["stabilisation"] = {{"fbar", "modified"}, {"fbar_patch", 0.5}};
  expect_rejected(s, "fbar-range", "/solver/stabilisation/fbar_patch", "0.5");
  // The default patch follows the shape function: 1 for GIMP, 1.5 for the B-splines.
  for (const char* shape : {"gimp", "bspline2"}) {
    json d = good_scene();
    d["grid"]["shape_function"] = shape;
    d["solver"]["stabilisation"] = {{"fbar", "modified"}};
    const fs::path dd = swmpm::testing::scratch(std::string("fbar-default-") + shape);
    std::ofstream(dd / "scene.json") << d.dump(2);
    ASSERT_EQ(swmpm_cmd("preprocess " + (dd / "scene.json").string() + " -o " + (dd / "run").string(), dd).status, 0);
    EXPECT_EQ(swmpm::testing::load_json((dd / "run" / "scene.json").string())["solver"]["stabilisation"]["fbar_patch"]
                  .get<double>(),
              std::string(shape) == "gimp" ? 1.0 : 1.5);
  }
}

// RUN_DIR/scene.json is "reproducible input" (interface.md): preprocessing it again succeeds and
// resolves to the same scene, in every formulation. (It used to write every solver switch, and
// preprocess then refused the ones the formulation does not read: strain_smoothing in the
// semi-implicit and dry formulations, pressure and kinematics in dry, fbar_patch without the
// modified F-bar.)
TEST(ResolvedScene, IsValidInputAgainInEveryFormulation) {
  std::vector<std::pair<std::string, json>> scenes = {{"dry", good_scene()}};
  for (const char* example : {"terzaghi", "terzaghi-semi-implicit", "landslide-nor-sand"}) {
    const std::string file = std::string(example) == "landslide-nor-sand" ? "/scene-dense.json" : "/scene.json";
    scenes.emplace_back(example, swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/" + std::string(example) + file));
  }
  scenes.emplace_back("dry-standard-fbar", good_scene());
  scenes.back().second["solver"]["stabilisation"] = {{"fbar", "standard"}};
  for (const auto& [name, scene] : scenes) {
    const fs::path dir = swmpm::testing::scratch("resolved-again-" + name);
    std::ofstream(dir / "scene.json") << scene.dump(2);
    const Result first = swmpm_cmd("-q preprocess " + (dir / "scene.json").string() + " -o " + (dir / "a").string(), dir);
    ASSERT_EQ(first.status, 0) << name << ": " << first.err;
    const Result again =
        swmpm_cmd("-q preprocess " + (dir / "a" / "scene.json").string() + " -o " + (dir / "b").string(), dir);
    ASSERT_EQ(again.status, 0) << name << ": " << again.err;
    const json a = swmpm::testing::load_json((dir / "a" / "scene.json").string());
    const json b = swmpm::testing::load_json((dir / "b" / "scene.json").string());
    EXPECT_EQ(a, b) << name;
    EXPECT_EQ(a["solver"]["stabilisation"].contains("strain_smoothing"), a["formulation"] == "explicit-single-point")
        << name;
  }
}

// B-splines with one point per cell and axis diverge in the semi-implicit formulations (B1: within
// 4-9 steps at every cell size): the formulation's row refuses the scene (exit 2, the body's key,
// nothing written).
TEST(BadInput, SemiImplicitBsplinesNeedTwoPointsPerCell) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  s["grid"]["shape_function"] = "bspline2";
  s["bodies"][0]["particles_per_cell"] = 1;
  s["time"]["end"] = 0.001;
  const fs::path dir = swmpm::testing::scratch("bad-si-bspline-ppc1");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const Result r = swmpm_cmd("-q run " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("/bodies/0/particles_per_cell: got 1, which is not available with bspline2"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "run" / "particles"));
}

// The semi-implicit formulations take a prescribed pore pressure as the face nodes' value in their
// pressure equation: a face that no water reaches would silently do nothing, so the run is refused.
TEST(BadInput, PorePressureFaceThatNoWaterReachesIsRejected) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  s["formulation"] = "semi-implicit-double-point";
  s["grid"]["max"] = {0.1, 1.1};  // the column's top (y = 1.0) is a cell below the grid face
  s["loads"] = json::array();
  s["boundaries"].push_back({{"on", "y_max"}, {"fluid", "pressure"}, {"value", 1e4}});
  const fs::path dir = swmpm::testing::scratch("bad-pore-pressure-face");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const Result r = swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + (dir / "run").string() + " -q", dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("boundaries/3/fluid"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no water lies on \"y_max\""), std::string::npos) << r.err;
}

// Switches a formulation or material does not take are scene errors at preprocess (exit 2, the
// JSON path, nothing written), not a late exit 1 from the solver (issue 23, item 4).
TEST(BadInput, SwitchesNoMaterialOrFormulationReads) {
  json si = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  si["solver"]["kinematics"] = "small-strain";  // linear-elastic only: nothing reads it
  expect_rejected(si, "kinematics-unread", "/solver/kinematics", "no material of the scene reads it");

  json esp = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi/scene.json");
  esp["solver"]["stabilisation"]["pressure"] = "node-remap";
  expect_rejected(esp, "node-remap-explicit", "/solver/stabilisation/pressure", "explicit-single-point does not have");

  json sic = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  sic["solver"]["stabilisation"]["pressure"] = "cell-constant";
  expect_rejected(sic, "cell-constant-semi-implicit", "/solver/stabilisation/pressure", "expected one of node-remap");

  json ns = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/landslide-nor-sand/scene-loose.json");
  ns["solver"]["kinematics"] = "small-strain";
  expect_rejected(ns, "nor-sand-small-strain", "/solver/kinematics", "is nor-sand, a finite-strain model");
}

// The README's main job: `swmpm run` leaves frames, monitors, plots of every monitor and report.md.
TEST(RunCommand, LeavesFramesMonitorsPlotsAndAReport) {
  json s = good_scene();
  s["time"]["end"] = 0.05;
  const fs::path dir = swmpm::testing::scratch("run-report");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const fs::path run = dir / "run";
  const Result r = swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run.string(), dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_GE(swmpm::scene::read_pvd((run / "output" / "results.pvd").string()).size(), 2u);
  EXPECT_TRUE(fs::exists(run / "monitors.csv"));
  for (const char* png : {"top.png", "base.png", "energy.png"}) EXPECT_TRUE(fs::exists(run / "plots" / png)) << png;
  const std::string report = swmpm::testing::read_text((run / "report.md").string());
  EXPECT_NE(report.find("# Run report: elastic-column"), std::string::npos) << report.substr(0, 200);
  EXPECT_NE(r.out.find("report: " + (run / "report.md").string() + " and " + (run / "report.html").string()),
            std::string::npos)
      << r.out;
}

// A run of free water only (explicit-double-point, no soil body) has empty solid frames: its
// report draws the water points' speed at the last frame (the report step used to fail, exit 1,
// "the frames have neither half_size nor volume").
TEST(RunCommand, FreeWaterOnlyRunEndsWithAReportOfTheWaterPoints) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/dam-break-double-point/scene.json");
  s["time"]["end"] = 0.01;
  s["output"]["interval"] = 0.005;
  const fs::path dir = swmpm::testing::scratch("run-report-free-water");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const fs::path run = dir / "run";
  const Result r = swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run.string() + " --threads 1", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(run / "plots" / "field_velocity_magnitude_0.01.png"));
  const std::string report = swmpm::testing::read_text((run / "report.md").string());
  EXPECT_NE(report.find("![velocity_magnitude at t = 0.01 s](plots/field_velocity_magnitude_0.01.png)"), std::string::npos) << report;
}
