// The time loop's hooks for formulations (issue 23, item 5): grid fields written with every frame
// (output/grid_NNNNNN.vtu, group `grid` of results.pvd, on the ledger, trimmed by --resume), a
// failure at a grid node (exit 3, the node's position in the diagnosis), and a monitor that follows
// a water point of a double-point run. A probe formulation wraps `dry` and adds known grid fields
// and a node failure; everything else is dry's.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "solver/formulation.hpp"
#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::Formulation;
using swmpm::State;
using swmpm::StepContext;

/// `dry`, plus grid fields (each node's flat index; the vector (x, y, t)) on a linear-grid lattice,
/// and, from step `fail_at` on, a failure reported at grid node `fail_node`.
class Probe : public Formulation<2> {
 public:
  Probe(const swmpm::scene::Scene& s, const State<2>& st, long fail_at, long fail_node)
      : inner_(swmpm::make_formulation<2>(s, st)), fail_at_(fail_at), fail_node_(fail_node) {
    h_ = s.grid.cell_size;
    for (int a = 0; a < 2; ++a) {
      min_[a] = s.grid.min[a];
      nodes_[a] = static_cast<int>(std::lround((s.grid.max[a] - s.grid.min[a]) / h_)) + 1;
    }
  }
  std::string name() const override { return inner_->name(); }
  double critical_time_step(const State<2>& s, std::string& r) const override { return inner_->critical_time_step(s, r); }
  void step(State<2>& s, const StepContext& ctx) override {
    inner_->step(s, ctx);
    if (fail_at_ > 0 && s.step + 1 >= fail_at_) s.health.report_node(fail_node_, position(fail_node_), "solid", "velocity is not finite");
  }
  double kinetic_energy(const State<2>& s) const override { return inner_->kinetic_energy(s); }
  double strain_energy(const State<2>& s) const override { return inner_->strain_energy(s); }
  double external_power(const State<2>& s, const StepContext& c) const override { return inner_->external_power(s, c); }
  void set_initialisation(State<2>& s, const swmpm::scene::Initialisation* p) override { inner_->set_initialisation(s, p); }
  std::size_t active_cells(const State<2>& s) const override { return inner_->active_cells(s); }
  void save(swmpm::Checkpoint& c) const override { inner_->save(c); }
  void restore(const swmpm::Checkpoint& c, State<2>& s) override { inner_->restore(c, s); }
  swmpm::GridFields grid_fields(const State<2>& s) const override {
    swmpm::GridFields g;
    g.nodes = {nodes_[0], nodes_[1], 1};
    const std::size_t n = static_cast<std::size_t>(nodes_[0]) * nodes_[1];
    g.cloud.points.resize(n);
    for (std::size_t k = 0; k < n; ++k) g.cloud.points[k] = position(static_cast<long>(k));
    auto& index = g.cloud.add("node_index", 1);
    auto& probe = g.cloud.add("probe", 3);
    for (std::size_t k = 0; k < n; ++k) {
      index.values[k] = static_cast<double>(k);
      probe.values[3 * k] = g.cloud.points[k][0];
      probe.values[3 * k + 1] = g.cloud.points[k][1];
      probe.values[3 * k + 2] = s.time;
    }
    return g;
  }
  std::array<double, 3> position(long k) const {
    return {min_[0] + h_ * static_cast<double>(k % nodes_[0]), min_[1] + h_ * static_cast<double>(k / nodes_[0]), 0.0};
  }

 private:
  std::unique_ptr<Formulation<2>> inner_;
  long fail_at_, fail_node_;
  double h_ = 0.0;
  std::array<double, 2> min_{};
  std::array<int, 2> nodes_{};
};

json column(double end, int frames) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json");
  s["time"]["end"] = end;
  s["output"]["interval"] = end / frames;
  s["grid"]["shape_function"] = "linear";
  return s;
}

/// Preprocesses `scene` and solves it with the probe formulation; returns the run directory.
std::string run_probe(const json& scene, const std::string& name, long fail_at, long fail_node, int& status,
                      bool resume = false, const std::string& existing = "") {
  std::string run_dir = existing;
  if (run_dir.empty()) {
    const fs::path dir = swmpm::testing::scratch(name);
    std::ofstream(dir / "scene.json") << scene.dump(2);
    run_dir = swmpm::pre::preprocess((dir / "scene.json").string(), (dir / "run").string(), true);
  }
  swmpm::SolveOptions o;
  o.quiet = true;
  o.resume = resume;
  status = swmpm::solve(
      run_dir, o,
      [&](const swmpm::scene::Scene& s, const State<2>& st) { return std::make_unique<Probe>(s, st, fail_at, fail_node); },
      {});
  return run_dir;
}

std::vector<swmpm::scene::PvdEntry> group(const std::string& run_dir, const std::string& g) {
  std::vector<swmpm::scene::PvdEntry> out;
  for (const auto& e : swmpm::scene::read_pvd(run_dir + "/output/results.pvd"))
    if (e.group == g) out.push_back(e);
  return out;
}

/// The probe's fields read back from every grid file of results.pvd: node positions, each node's
/// index, and (x, y, t) with t the frame's time.
void expect_probe_frames(const std::string& run_dir, std::size_t frames) {
  const auto grid = group(run_dir, "grid"), solid = group(run_dir, "solid");
  ASSERT_EQ(grid.size(), frames);
  ASSERT_EQ(solid.size(), frames);
  for (std::size_t f = 0; f < frames; ++f) {
    EXPECT_EQ(grid[f].time, solid[f].time);
    EXPECT_EQ(grid[f].part, 2);
    char name[32];
    std::snprintf(name, sizeof name, "grid_%06zu.vtu", f);
    EXPECT_EQ(grid[f].file, name);
    const auto c = swmpm::scene::read_vtu(run_dir + "/output/" + grid[f].file);
    ASSERT_EQ(c.size(), 3u * 23u);  // 0.1 x 1.1 m in cells of 0.05 m: 3 x 23 nodes
    const auto& index = c.get("node_index", "grid");
    const auto& probe = c.get("probe", "grid");
    ASSERT_EQ(probe.components, 3);
    for (std::size_t k = 0; k < c.size(); ++k) {
      const double x = 0.05 * static_cast<double>(k % 3), y = 0.05 * static_cast<double>(k / 3);
      EXPECT_EQ(index.values[k], static_cast<double>(k));
      EXPECT_NEAR(c.points[k][0], x, 1e-15);
      EXPECT_NEAR(c.points[k][1], y, 1e-15);
      EXPECT_EQ(probe.values[3 * k], c.points[k][0]);
      EXPECT_EQ(probe.values[3 * k + 1], c.points[k][1]);
      EXPECT_EQ(probe.values[3 * k + 2], grid[f].time);
    }
  }
}

TEST(LoopHooks, GridFieldsAreWrittenWithEveryFrameListedAndOnTheLedger) {
  int status = -1;
  const std::string run = run_probe(column(0.1, 4), "hooks-grid", 0, 0, status);
  ASSERT_EQ(status, 0);
  expect_probe_frames(run, 5);  // t = 0, 0.025, 0.05, 0.075, 0.1
  const std::string ledger = swmpm::testing::read_text(run + "/.swmpm-files");
  for (int f = 0; f < 5; ++f)
    EXPECT_NE(ledger.find("output/grid_00000" + std::to_string(f) + ".vtu"), std::string::npos) << ledger;

  // --resume from the last checkpoint (the frame at t = 0.075): the grid files after it are
  // removed and written again, results.pvd lists each frame's three groups once.
  fs::remove(run + "/output/grid_000004.vtu");
  const auto before = fs::last_write_time(run + "/output/grid_000003.vtu");
  run_probe(json(), "", 0, 0, status, true, run);
  ASSERT_EQ(status, 0);
  expect_probe_frames(run, 5);
  EXPECT_TRUE(fs::exists(run + "/output/grid_000004.vtu"));
  EXPECT_EQ(fs::last_write_time(run + "/output/grid_000003.vtu"), before) << "a frame the checkpoint covers was rewritten";
}

TEST(LoopHooks, ANodeFailureStopsTheRunWithStatus3AndNamesTheNodePosition) {
  json s = column(0.1, 2);
  s["solver"]["checkpoint_every"] = 5;
  int status = -1;
  const long node = 3 * 13 + 1;  // (0.05, 0.65)
  const std::string run = run_probe(s, "hooks-node", 8, node, status);
  EXPECT_EQ(status, 3);
  const json rj = swmpm::testing::load_json(run + "/run.json");
  EXPECT_EQ(rj["status"], "diverged");
  EXPECT_EQ(rj["steps"], 7);  // the step that failed does not count
  const std::string d = rj["diagnosis"];
  EXPECT_NE(d.find("solid grid node 40 at (0.05, 0.65) velocity is not finite in the step from t = "), std::string::npos)
      << d;
  EXPECT_NE(d.find("(step 8, dt = "), std::string::npos) << d;
  EXPECT_EQ(rj["failed_node"]["index"], node);
  EXPECT_DOUBLE_EQ(rj["failed_node"]["position"][0].get<double>(), 0.05);
  EXPECT_DOUBLE_EQ(rj["failed_node"]["position"][1].get<double>(), 0.65);
  // The last frame is the last good state: the snapshot of step 5 (checkpoint_every), restored
  // through Formulation::restore, particles only (its grid fields are gone).
  const auto solid = group(run, "solid"), grid = group(run, "grid");
  ASSERT_EQ(solid.size(), 2u);
  ASSERT_EQ(grid.size(), 1u);
  EXPECT_GT(solid.back().time, 0.0);
  EXPECT_EQ(rj["last_good_frame_time"].get<double>(), solid.back().time);
  const std::string log = swmpm::testing::read_text(run + "/log.txt");
  EXPECT_NE(log.find("DIVERGED: solid grid node 40 at (0.05, 0.65)"), std::string::npos);
}

/// A monitor with `points: "water"` follows a water point of a double-point run (here one at the
/// free surface) and records its own values: those of the water frames at the same time.
TEST(LoopHooks, AMonitorFollowsAWaterPointOfADoublePointRun) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene-double-point.json");
  s["time"]["end"] = 0.005;
  s["output"]["interval"] = 0.005;
  s["output"]["monitor_interval"] = 0.0;
  s["output"]["monitors"] = json::array(
      {{{"name", "surface"},
        {"at", {0.05, 1.0}},
        {"points", "water"},
        {"quantities", {"displacement_y", "velocity_y", "pore_pressure", "porosity"}}},
       {{"name", "soil"}, {"at", {0.05, 1.0}}, {"phase", "fluid"}, {"quantities", {"velocity_y"}}}});
  const std::string run = swmpm::testing::run_scene(s, "hooks-water-monitor");
  const std::string log = swmpm::testing::read_text(run + "/log.txt");
  const auto at = log.find("monitor surface: follows water point ");
  ASSERT_NE(at, std::string::npos) << log;
  const long id = std::stol(log.substr(at + 37));

  // The last row of monitors.csv against the last water frame.
  std::ifstream in(run + "/monitors.csv");
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty() && line[0] != '#') last = line;
  std::vector<double> row;
  std::stringstream ss(last);
  for (std::string cell; std::getline(ss, cell, ',');) row.push_back(std::stod(cell));
  ASSERT_EQ(row.size(), 6u);
  const auto water = swmpm::testing::last_frame(run, "fluid");
  const auto& ids = water.get("id", "fluid").values;
  std::size_t p = 0;
  while (p < ids.size() && ids[p] != static_cast<double>(id)) ++p;
  ASSERT_LT(p, ids.size());
  EXPECT_NEAR(row[0], 0.005, 1e-12);
  auto expect_value = [&](double monitored, double framed, const char* what) {
    EXPECT_NEAR(monitored, framed, 1e-9 * std::max(1.0, std::abs(framed))) << what;
  };
  expect_value(row[1], water.get("displacement", "fluid").values[3 * p + 1], "displacement_y");
  expect_value(row[2], water.get("velocity", "fluid").values[3 * p + 1], "velocity_y");
  expect_value(row[3], water.get("pore_pressure", "fluid").values[p], "pore_pressure");
  expect_value(row[4], water.get("porosity", "fluid").values[p], "porosity");
  EXPECT_GT(row[4], 0.0);
  EXPECT_LT(row[4], 1.0);
  EXPECT_NE(row[2], 0.0);  // the water at the surface moves
  EXPECT_NE(row[2], row[5]) << "the water point's own velocity, not the water velocity at a soil point";
}

TEST(LoopHooks, WaterPointMonitorsNeedADoublePointFormulation) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi/scene.json");
  s["output"]["monitors"] = json::array({{{"name", "w"}, {"at", {0.05, 1.0}}, {"points", "water"}, {"quantities", {"pore_pressure"}}}});
  try {
    swmpm::scene::parse_scene(s, "scene.json");
    ADD_FAILURE() << "accepted";
  } catch (const swmpm::scene::SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("/output/monitors/0/points: got \"water\", but only the double-point"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
