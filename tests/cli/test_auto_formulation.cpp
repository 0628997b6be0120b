// `"formulation": "auto"` through the program (issue 26 item 1): `preprocess --explain` prints the
// choice and both single-point estimates and writes nothing; a run's log says it before the first
// step, and RUN_DIR/scene.json and run.json keep it; a key the chosen formulation does not read ends
// every command with exit 2, naming the key and that auto chose, and nothing written.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "scene/auto_formulation.hpp"
#include "scene/budget.hpp"
#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

/// examples/terzaghi with "auto", dt "auto", no formulation-specific switches, ending at `end`.
json terzaghi_auto(double end) {
  json s = json::parse(std::ifstream(SWMPM_SOURCE_DIR "/examples/terzaghi/scene.json"));
  s["formulation"] = "auto";
  s["time"] = {{"end", end}};
  s.erase("solver");
  return s;
}

fs::path write_scene(const json& s, const std::string& name, fs::path& dir) {
  dir = swmpm::testing::scratch("auto-formulation-" + name);
  const fs::path file = dir / "scene.json";
  std::ofstream(file) << s.dump(2);
  return file;
}

std::size_t files_in(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::recursive_directory_iterator(dir)) ++n;
  return n;
}

}  // namespace

TEST(AutoFormulationCli, ExplainPrintsBothEstimatesAndWritesNothing) {
  fs::path dir;
  const json s = terzaghi_auto(1.0);
  const fs::path file = write_scene(s, "explain", dir);
  const Result r = swmpm_cmd("preprocess --explain " + file.string() + " -o " + (dir / "run").string(), dir);
  std::printf("%s", r.out.c_str());
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_FALSE(fs::exists(dir / "run"));
  EXPECT_EQ(files_in(dir), 3u) << "scene.json, stdout.txt, stderr.txt only";
  EXPECT_NE(r.out.find("formulation semi-implicit-single-point (chosen by \"auto\"): "), std::string::npos) << r.out;
  // The printed estimates are the function's, and the chosen one is the cheaper.
  const auto c = swmpm::scene::choose_formulation(swmpm::scene::parse_scene(s, file.string()));
  ASSERT_EQ(c.estimates.size(), 2u);
  for (const auto& e : c.estimates) {
    const std::string line = "estimate " + swmpm::scene::to_string(e.formulation) + ": dt ";
    const auto at = r.out.find(line);
    ASSERT_NE(at, std::string::npos) << line << "\n" << r.out;
    const std::string rest = r.out.substr(at, r.out.find('\n', at) - at);
    EXPECT_NEAR(std::stod(rest.substr(line.size())), e.dt, 4e-3 * e.dt) << rest;  // printed to 3 digits
    EXPECT_NE(rest.find("about " + swmpm::scene::format_duration(e.wall_seconds)), std::string::npos) << rest;
  }
  EXPECT_EQ(c.chosen, swmpm::scene::Formulation::semi_implicit_single_point);
  EXPECT_LT(c.estimates[1].wall_seconds, c.estimates[0].wall_seconds);
}

TEST(AutoFormulationCli, TheRunLogsTheChoiceBeforeTheFirstStepAndKeepsItInRunJson) {
  fs::path dir;
  const fs::path file = write_scene(terzaghi_auto(0.02), "run", dir);
  const std::string run = (dir / "run").string();
  Result r = swmpm_cmd("-q preprocess " + file.string() + " -o " + run, dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const json resolved = swmpm::testing::load_json(run + "/scene.json");
  EXPECT_EQ(resolved["formulation"], "semi-implicit-single-point");
  EXPECT_TRUE(resolved["formulation_choice"]["automatic"].get<bool>());
  EXPECT_EQ(resolved["formulation_choice"]["chosen"], "semi-implicit-single-point");
  r = swmpm_cmd("-q solve " + run + " --threads 1", dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const json rj = swmpm::testing::load_json(run + "/run.json");
  EXPECT_EQ(rj["formulation"], "semi-implicit-single-point");
  EXPECT_EQ(rj["formulation_choice"], resolved["formulation_choice"]);
  ASSERT_EQ(rj["formulation_choice"]["estimates"].size(), 2u);
  // The estimate of the formulation that ran uses its dt at t = 0: the run's first step.
  const json& est = rj["formulation_choice"]["estimates"][1];
  EXPECT_EQ(est["formulation"], "semi-implicit-single-point");
  EXPECT_NEAR(est["dt"].get<double>(), rj["dt_max"].get<double>(), 1e-6 * est["dt"].get<double>());
  const std::string log = swmpm::testing::read_text(run + "/log.txt");
  const auto choice = log.find("formulation semi-implicit-single-point (chosen by \"auto\"): the soil holds pore water only");
  const auto first_dt = log.find("dt auto: ");
  ASSERT_NE(choice, std::string::npos) << log;
  ASSERT_NE(first_dt, std::string::npos) << log;
  EXPECT_LT(choice, first_dt);
  EXPECT_NE(log.find("estimate explicit-single-point: dt "), std::string::npos) << log;
}

TEST(AutoFormulationCli, AKeyTheChosenFormulationDoesNotReadEndsWithExit2AndNothingWritten) {
  fs::path dir;
  json s = terzaghi_auto(0.02);
  s["solver"] = {{"stabilisation", {{"strain_smoothing", true}}}};
  const fs::path file = write_scene(s, "key", dir);
  for (const std::string command : {"preprocess --explain", "preprocess", "run"}) {
    const Result r = swmpm_cmd("-q " + command + " " + file.string() + " -o " + (dir / "run").string(), dir);
    std::printf("swmpm %s: exit %d, stderr: %s", command.c_str(), r.status, r.err.c_str());
    EXPECT_EQ(r.status, 2) << command;
    EXPECT_NE(r.err.find(file.string() + ": /solver/stabilisation/strain_smoothing: got true, but "
                         "semi-implicit-single-point does not read this switch"),
              std::string::npos) << r.err;
    EXPECT_NE(r.err.find("(formulation \"semi-implicit-single-point\" was chosen automatically by \"auto\""),
              std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "run")) << command;
  }
}
