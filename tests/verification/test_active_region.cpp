// Empty space must not change results (issue 26 item 2, the active region): a column run on its
// own grid and on a grid of four times the area (twice as long per axis, from the same min, so
// the node positions and the walls the column touches stay) gives bitwise identical last frames
// and monitors.csv, for every MPM formulation and a mix of shape functions. Every grid loop,
// the pressure system and the outputs work on the step's active box (the nodes the points'
// supports reach, solver/grid/grid.hpp), and node arrays take memory only there
// (solver/grid/node_array.hpp); so the enlarged grid can change nothing but the cost.
// bench/active_region.py measures that cost at 1x, 4x and 16x.
// mpm-fem's fluid (water and air) is solved on its own active region, the box of the water and
// the soil widened by 3 cells, with open faces where the box ends inside the grid
// (solver.air.domain "active"; docs/formulations.md, "Active region"): a column whose own grid
// is that box runs bitwise as on a larger grid, and the dam break, whose region grows with the
// surge, stays with the run that solves the air on the whole grid.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "support/dam_break.hpp"
#include "support/run_helpers.hpp"

namespace {

constexpr double kH = 0.05;                  // m, cell size
constexpr double kWidth = 0.6, kHeight = 1.2;  // m, the column
constexpr int kMargin = 3;                   // empty cells right of and above it on its own grid
                                             // (B-splines: the far end's clamped bases stay out of reach)

/// The column of `formulation` with a grid `scale` times as long per axis as its own.
nlohmann::json column(const std::string& formulation, const std::string& shape, int scale) {
  const bool dry = formulation == "dry";
  const bool edp = formulation == "explicit-double-point";
  const bool esp = formulation == "explicit-single-point";
  // s: the step each formulation's stability allows at h = 0.05 m (E = 10 MPa; explicit-single-
  // point: the undrained P-wave with K_f / n; explicit-double-point: K_L = 21.5 MPa).
  const double dt = esp ? 1e-5 : edp ? 8e-5 : 2e-4;
  nlohmann::json materials =
      dry ? nlohmann::json::array({{{"name", "m"}, {"model", "linear-elastic"}, {"density", 2000.0},
                                    {"youngs_modulus", 1e7}, {"poisson_ratio", 0.3}}})
          : nlohmann::json::array({{{"name", "soil"}, {"model", "linear-elastic"}, {"grain_density", 2650.0},
                                    {"porosity", 0.3}, {"youngs_modulus", 1e7}, {"poisson_ratio", 0.3},
                                    {"hydraulic_conductivity", 1e-3}},
                                   {{"name", "water"}, {"model", "fluid"}, {"density", 1000.0},
                                    {"bulk_modulus", edp ? 2.15e7 : 2.2e9}}});
  nlohmann::json body = {{"name", "column"},
                         {"geometry", {{"type", "box"}, {"min", {0.0, 0.0}}, {"max", {kWidth, kHeight}}}},
                         {"solid", dry ? "m" : "soil"},
                         {"particles_per_cell", 2}};
  if (!dry) {
    body["fluid"] = "water";
    body["initial"] = {{"stress", "geostatic"}, {"k0", 0.5}, {"pore_pressure", "hydrostatic"}};
  }
  nlohmann::json x_min = {{"on", "x_min"}, {"solid", "roller"}}, y_min = {{"on", "y_min"}, {"solid", "fixed"}};
  if (!dry) x_min["fluid"] = y_min["fluid"] = "impermeable";
  const double end = 40 * dt * (1 - 1e-9);
  return {{"name", "active-" + formulation},
          {"dimension", 2},
          {"formulation", formulation},
          {"gravity", {0.0, -9.81}},
          {"grid",
           {{"cell_size", kH},
            {"min", {0.0, 0.0}},
            {"max", {scale * (kWidth + kMargin * kH), scale * (kHeight + kMargin * kH)}},
            {"shape_function", shape}}},
          {"materials", materials},
          {"bodies", {body}},
          {"boundaries", {x_min, y_min}},
          {"time", {{"end", end}, {"dt", dt}}},
          {"output",
           {{"interval", end / 2},
            {"monitor_interval", 0.0},
            {"monitors",
             {{{"name", "crest"}, {"at", {kWidth - 0.5 * kH, kHeight - 0.5 * kH}},
               {"quantities", {"displacement_x", "displacement_y", "stress_yy"}}},
              {{"name", "energy"}, {"quantities", {"kinetic_energy", "strain_energy"}}}}}}}};
}

/// monitors.csv without its comment lines.
std::string monitor_rows(const std::string& run) {
  std::istringstream in(swmpm::testing::read_text(run + "/monitors.csv"));
  std::string line, out;
  while (std::getline(in, line))
    if (!line.starts_with("#")) out += line + "\n";
  return out;
}

/// Same points at bitwise equal positions, and every array bitwise equal.
void expect_identical(const swmpm::scene::PointCloud& a, const swmpm::scene::PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 0u);
  for (std::size_t p = 0; p < a.size(); ++p)
    for (int d = 0; d < 3; ++d) ASSERT_EQ(a.points[p][d], b.points[p][d]) << "point " << p;
  ASSERT_EQ(a.arrays.size(), b.arrays.size());
  for (const auto& arr : a.arrays) {
    const auto& other = b.get(arr.name, "enlarged grid").values;
    ASSERT_EQ(arr.values.size(), other.size()) << arr.name;
    for (std::size_t k = 0; k < other.size(); ++k) ASSERT_EQ(arr.values[k], other[k]) << arr.name << " entry " << k;
  }
}

void expect_same_on_enlarged_grid(const std::string& formulation, const std::string& shape) {
  const std::string tag = formulation + "-" + shape;
  const std::string own = swmpm::testing::run_scene(column(formulation, shape, 1), "active1-" + tag, 1);
  const std::string big = swmpm::testing::run_scene(column(formulation, shape, 2), "active4-" + tag, 1);
  const auto run = swmpm::testing::load_json(own + "/run.json");
  ASSERT_EQ(run["status"], "completed");
  ASSERT_EQ(run["steps"].get<long>(), 40);
  EXPECT_EQ(run["active_cells"], swmpm::testing::load_json(big + "/run.json")["active_cells"]);
  const std::string rows = monitor_rows(own);
  ASSERT_GT(rows.size(), 1000u);
  EXPECT_EQ(rows, monitor_rows(big));
  expect_identical(swmpm::testing::last_frame(own), swmpm::testing::last_frame(big));
  if (formulation.find("double-point") != std::string::npos)
    expect_identical(swmpm::testing::last_frame(own, "fluid"), swmpm::testing::last_frame(big, "fluid"));
  // The column moved: the comparison is not of two resting states.
  EXPECT_GT(std::abs(swmpm::testing::read_monitors(own).column("crest.displacement_y").back()), 0.0);
}

}  // namespace

TEST(ActiveRegion, EmptySpaceLeavesDryBitwiseUnchanged) { expect_same_on_enlarged_grid("dry", "gimp"); }
TEST(ActiveRegion, EmptySpaceLeavesDryBSplineBitwiseUnchanged) { expect_same_on_enlarged_grid("dry", "bspline2"); }
TEST(ActiveRegion, EmptySpaceLeavesExplicitSinglePointBitwiseUnchanged) {
  expect_same_on_enlarged_grid("explicit-single-point", "gimp");
}
TEST(ActiveRegion, EmptySpaceLeavesSemiImplicitSinglePointBitwiseUnchanged) {
  expect_same_on_enlarged_grid("semi-implicit-single-point", "gimp");
  expect_same_on_enlarged_grid("semi-implicit-single-point", "bspline2");
}
TEST(ActiveRegion, EmptySpaceLeavesSemiImplicitDoublePointBitwiseUnchanged) {
  expect_same_on_enlarged_grid("semi-implicit-double-point", "linear");
}
TEST(ActiveRegion, EmptySpaceLeavesExplicitDoublePointBitwiseUnchanged) {
  expect_same_on_enlarged_grid("explicit-double-point", "bspline2");
}

namespace {

/// mpm-fem: a saturated column (0.1 x 0.2 m, h = 0.01 m, 2 x 2 points per cell) in air, on a grid
/// `scale` times as long per axis as its own. Its own grid leaves 5 cells right of and above it:
/// the initial phase field's tail (2 cells to phi = 0.01) and the region's 3-cell halo, so that it
/// is the region a larger grid solves on.
nlohmann::json fem_column(int scale) {
  const double h = 0.01, w = 0.1, ht = 0.2, dt = 1e-4, margin = 5 * h;
  const double end = 30 * dt * (1 - 1e-9);
  return {{"name", "active-mpm-fem"},
          {"dimension", 2},
          {"formulation", "mpm-fem"},
          {"gravity", {0.0, -9.81}},
          {"grid", {{"cell_size", h}, {"min", {0.0, 0.0}}, {"max", {scale * (w + margin), scale * (ht + margin)}},
                    {"shape_function", "bspline2"}}},
          {"materials", {{{"name", "beads"}, {"model", "linear-elastic"}, {"grain_density", 2650.0}, {"porosity", 0.4},
                          {"youngs_modulus", 1e6}, {"poisson_ratio", 0.3}, {"grain_diameter", 0.001}},
                         {{"name", "water"}, {"model", "fluid"}, {"density", 1000.0}, {"dynamic_viscosity", 0.001}}}},
          {"bodies", {{{"name", "column"}, {"geometry", {{"type", "box"}, {"min", {0.0, 0.0}}, {"max", {w, ht}}}},
                       {"solid", "beads"}, {"fluid", "water"}, {"particles_per_cell", 2}}}},
          {"boundaries", {{{"on", "x_min"}, {"solid", "roller"}, {"fluid", "impermeable"}},
                          {{"on", "y_min"}, {"solid", "fixed"}, {"fluid", "impermeable"}}}},
          {"time", {{"end", end}, {"dt", dt}}},
          {"output", {{"interval", end / 2}, {"monitor_interval", 0.0},
                      {"monitors", {{{"name", "crest"}, {"at", {w - 0.5 * h, ht - 0.5 * h}},
                                     {"quantities", {"displacement_x", "displacement_y", "pore_pressure"}}},
                                    {{"name", "probe"}, {"phase", "fluid"}, {"at", {0.5 * w, 0.5 * ht}},
                                     {"quantities", {"pore_pressure", "velocity_y"}}},
                                    {{"name", "energy"}, {"quantities", {"kinetic_energy", "strain_energy"}}}}}}}};
}

}  // namespace

TEST(ActiveRegion, EmptySpaceLeavesMpmFemBitwiseUnchanged) {
  const std::string own = swmpm::testing::run_scene(fem_column(1), "active1-mpm-fem", 1);
  const std::string big = swmpm::testing::run_scene(fem_column(2), "active4-mpm-fem", 1);
  const auto r1 = swmpm::testing::load_json(own + "/run.json"), r4 = swmpm::testing::load_json(big + "/run.json");
  ASSERT_EQ(r1["status"], "completed");
  ASSERT_EQ(r1["steps"].get<long>(), 30);
  // The fluid is solved on the same 15 x 25 cells (17 x 27 nodes), not on the larger grid's 30 x 50.
  const double nodes = r1["counters"]["fluid nodes (active region)"].get<double>();
  EXPECT_EQ(nodes, 17.0 * 27.0);
  EXPECT_EQ(r4["counters"]["fluid nodes (active region)"].get<double>(), nodes);
  EXPECT_EQ(r4["counters"]["fluid region changes"].get<double>(), 0.0);
  const std::string rows = monitor_rows(own);
  ASSERT_GT(rows.size(), 1000u);
  EXPECT_EQ(rows, monitor_rows(big));
  expect_identical(swmpm::testing::last_frame(own), swmpm::testing::last_frame(big));
  const auto mon = swmpm::testing::read_monitors(own);
  EXPECT_GT(std::abs(mon.column("crest.displacement_y").back()), 0.0);  // the column moved
  EXPECT_GT(mon.column("probe.pore_pressure").back(), 0.0);             // the grid's pressure was read
}

// The dam break (examples/dam-break-mpm-fem): the water column starts in the corner of a tank
// 7 times as long, so the region starts small and grows with the surge. Against the same run
// with the air solved on the whole grid (solver.air.domain "grid", seed 004's choice), the front
// stays within a tenth of a cell at every frame from T = 1 and both within 10 % of Martin & Moyce.
// Measured 2026-12-05 (one thread, the two runs side by side): the fronts differ by at most
// 0.004 a (0.04 cells; +9.3 ... -3.6 % against +9.2 ... -3.7 %), the region changed 7 times and
// ended at 1,560 of the grid's 2,160 nodes, and the run took 4.6 s against 10.6 s.
TEST(ActiveRegion, MpmFemDamBreakGrowsItsRegionAndKeepsTheFront) {
  const std::string dir = SWMPM_SOURCE_DIR "/examples/dam-break-mpm-fem/";
  nlohmann::json sc = swmpm::testing::load_json(dir + "scene.json");
  const std::string active = swmpm::testing::run_scene(sc, "active-dam-break", 1);
  sc["solver"]["air"]["domain"] = "grid";
  const std::string whole = swmpm::testing::run_scene(sc, "grid-dam-break", 1);
  const auto ra = swmpm::testing::load_json(active + "/run.json"), rg = swmpm::testing::load_json(whole + "/run.json");
  ASSERT_EQ(ra["status"], "completed");
  ASSERT_EQ(rg["status"], "completed");
  EXPECT_GE(ra["counters"]["fluid region changes"].get<double>(), 1.0);
  EXPECT_LT(ra["counters"]["fluid nodes (active region)"].get<double>(), rg["counters"]["fluid nodes (active region)"].get<double>());
  EXPECT_LT(std::abs(ra["counters"]["water outflow"].get<double>()), 0.01);  // per cent, through the region's open faces
  const auto fa = swmpm::testing::dam_break_front_error(active, dir + "martin-moyce-1952-front.csv", "active region");
  const auto fg = swmpm::testing::dam_break_front_error(whole, dir + "martin-moyce-1952-front.csv", "whole grid");
  EXPECT_GE(fa.compared, 6);
  EXPECT_EQ(fa.compared, fg.compared);
  EXPECT_LT(fa.worst, 0.10);
  EXPECT_LT(fg.worst, 0.10);
  const double a = 0.05715, h = 0.005715;  // m
  for (std::size_t k = 0; k < fa.x_over_a.size() && k < fg.x_over_a.size(); ++k)
    EXPECT_LT(std::abs(fa.x_over_a[k] - fg.x_over_a[k]) * a, 0.1 * h) << "frame " << k;
}

