// Empty space must not change results (issue 26 item 2, the active region): a column run on its
// own grid and on a grid of four times the area (twice as long per axis, from the same min, so
// the node positions and the walls the column touches stay) gives bitwise identical last frames
// and monitors.csv, for every MPM formulation and a mix of shape functions. Every grid loop,
// the pressure system and the outputs work on the step's active box (the nodes the points'
// supports reach, solver/grid/grid.hpp), and node arrays take memory only there
// (solver/grid/node_array.hpp); so the enlarged grid can change nothing but the cost.
// bench/active_region.py measures that cost at 1x, 4x and 16x.
// mpm-fem is not here: its fluid (water and air) lives on the whole grid, so a larger grid is a
// larger air domain with its top, where p = 0, higher up (docs/architecture.md, "Active region").
#include <gtest/gtest.h>

#include <sstream>
#include <string>

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
