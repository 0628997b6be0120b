// Issue 26 item 3, water only where there is water: a body given a water table
// (initial.pore_pressure "hydrostatic" with water_table) is saturated below the table and dry
// skeleton above it (docs/scene-format.md, "Pore pressure"; docs/formulations.md, "Dry soil above
// a water table").
//
// The scene: a soil column 0.125 m wide and 1 m high, geostatic and hydrostatic, under a 10 kPa
// surface traction, in three layouts:
//   table      one body with water_table 0.625 m
//   stacked    a saturated body 0..0.625 m (table 0.625 m) under a dry body 0.625..1 m (no fluid)
//   saturated  one body saturated to its top (the default table)
// The cell (0.0625 m) and the lattice spacing (0.03125 m) are powers of two, so every lattice
// coordinate is exact in binary and both first layouts seed the same points in the same order:
// the table body must then give the stacked pair's particle state bit for bit (every array but
// `body` and `faces`, which name the bodies and their boundaries: faces only place loads, and the
// load names the top body in both). The cost: the table body carries water on the points below the
// table only (single-point: fluid_mass > 0; double-point: points in fluid.vtu), 80 of 128 where
// the saturated column has 128. Wall times are printed, not asserted.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::scene::PointCloud;

constexpr double kCell = 0.0625;   // m
constexpr double kTable = 0.625;   // m, 10 cells: on a lattice face
constexpr double kTop = 1.0;       // m
constexpr double kWidth = 0.125;   // m
constexpr std::size_t kPoints = 4 * 32, kWetPoints = 4 * 20;  // 4 per row, 32 rows, 20 below the table

enum class Layout { table, stacked, saturated };

const char* name_of(Layout l) { return l == Layout::table ? "table" : l == Layout::stacked ? "stacked" : "saturated"; }

json box(double y0, double y1) { return {{"type", "box"}, {"min", {0.0, y0}}, {"max", {kWidth, y1}}}; }

json soil_body(const std::string& name, double y0, double y1, bool fluid, double table) {
  json b = {{"name", name}, {"geometry", box(y0, y1)}, {"solid", "sand"}, {"particles_per_cell", 2},
            {"initial", {{"stress", "geostatic"}, {"k0", 0.3 / 0.7}}}};
  if (fluid) {
    b["fluid"] = "water";
    b["initial"]["pore_pressure"] = "hydrostatic";
    if (table > 0.0) b["initial"]["water_table"] = table;
  }
  return b;
}

/// The column in `layout` for `formulation`, run to `end` seconds.
json column(const std::string& formulation, Layout layout, double end) {
  json s = {
      {"name", std::string("water-table-") + name_of(layout)},
      {"dimension", 2},
      {"formulation", formulation},
      {"gravity", {0.0, -9.81}},
      {"grid", {{"cell_size", kCell}, {"min", {0.0, 0.0}}, {"max", {kWidth, kTop + 2 * kCell}},
                {"shape_function", formulation == "mpm-fem" ? "bspline2" : "gimp"}}},
      {"materials",
       {{{"name", "sand"}, {"model", "linear-elastic"}, {"grain_density", 2650.0}, {"porosity", 0.4},
         {"youngs_modulus", 1e7}, {"poisson_ratio", 0.3}, {"hydraulic_conductivity", 1e-4}},
        {{"name", "water"}, {"model", "fluid"}, {"density", 1000.0}, {"bulk_modulus", 2e8},
         {"dynamic_viscosity", 1e-3}}}},
      {"boundaries",
       {{{"on", "x_min"}, {"solid", "roller"}, {"fluid", "impermeable"}},
        {{"on", "x_max"}, {"solid", "roller"}, {"fluid", "impermeable"}},
        {{"on", "y_min"}, {"solid", "fixed"}, {"fluid", "impermeable"}}}},
      {"loads", {{{"type", "traction"}, {"body", "column"}, {"face", "y_max"}, {"value", {0.0, -1e4}}}}},
      {"time", {{"end", end}}},
      {"output", {{"interval", end}}}};
  if (formulation == "mpm-fem") s["materials"][1].erase("bulk_modulus");
  if (layout == Layout::table) s["bodies"] = {soil_body("column", 0.0, kTop, true, kTable)};
  if (layout == Layout::saturated) s["bodies"] = {soil_body("column", 0.0, kTop, true, -1.0)};
  if (layout == Layout::stacked)
    s["bodies"] = {soil_body("saturated", 0.0, kTable, true, kTable), soil_body("column", kTable, kTop, false, -1.0)};
  return s;
}

struct Timed {
  std::string dir;
  double seconds;  // wall time of preprocess + solve
};

Timed run(const std::string& formulation, Layout layout, double end) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string dir = swmpm::testing::run_scene(column(formulation, layout, end),
                                                    "water-table-" + formulation + "-" + name_of(layout));
  return {dir, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
}

/// Arrays (but `body` and `faces`) and positions of two frames that differ, with the largest
/// difference; 0 when they are the same bit for bit.
std::size_t differences(const PointCloud& a, const PointCloud& b, const std::string& what) {
  if (a.size() != b.size() || a.arrays.size() != b.arrays.size()) {
    ADD_FAILURE() << what << ": " << a.size() << " and " << b.size() << " points, " << a.arrays.size() << " and "
                  << b.arrays.size() << " arrays";
    return 1;
  }
  std::size_t differ = 0;
  for (std::size_t p = 0; p < a.size(); ++p)
    for (int k = 0; k < 3; ++k) differ += a.points[p][k] != b.points[p][k];
  if (differ) std::printf("  %s: %zu position components differ\n", what.c_str(), differ);
  for (std::size_t k = 0; k < a.arrays.size(); ++k) {
    const auto& x = a.arrays[k];
    if (x.name == "body" || x.name == "faces") continue;
    const auto& y = b.get(x.name, what);
    std::size_t n = 0;
    double worst = 0.0;
    for (std::size_t i = 0; i < x.values.size(); ++i)
      if (x.values[i] != y.values[i]) ++n, worst = std::max(worst, std::abs(x.values[i] - y.values[i]));
    if (n) std::printf("  %s: %s differs in %zu values (largest %.3e)\n", what.c_str(), x.name.c_str(), n, worst);
    differ += n;
  }
  return differ;
}

/// Points that carry water in the run's particle files.
std::size_t water_points(const std::string& dir, bool double_point) {
  if (double_point) return swmpm::scene::read_vtu(dir + "/particles/fluid.vtu").size();
  const PointCloud c = swmpm::scene::read_vtu(dir + "/particles/solid.vtu");
  std::size_t n = 0;
  for (const double m : c.get("fluid_mass", "solid.vtu").values) n += m > 0.0;
  return n;
}

/// The largest downward displacement of the frame's points [m].
double largest_settlement(const PointCloud& c) {
  double u = 0.0;
  const auto& d = c.get("displacement", "solid").values;
  for (std::size_t k = 0; k < c.size(); ++k) u = std::max(u, -d[3 * k + 1]);
  return u;
}

/// The table body against the stacked pair and the saturated column (see the file's comment).
void expect_dry_above_the_table(const std::string& formulation, double end) {
  const bool double_point = formulation.find("double-point") != std::string::npos;
  const Timed table = run(formulation, Layout::table, end), stacked = run(formulation, Layout::stacked, end),
            saturated = run(formulation, Layout::saturated, end);
  std::size_t differ = differences(swmpm::testing::last_frame(table.dir), swmpm::testing::last_frame(stacked.dir),
                                   formulation + " soil");
  if (double_point)
    differ += differences(swmpm::testing::last_frame(table.dir, "fluid"),
                          swmpm::testing::last_frame(stacked.dir, "fluid"), formulation + " water");
  const std::size_t wet = water_points(table.dir, double_point), wet_stacked = water_points(stacked.dir, double_point),
                    wet_saturated = water_points(saturated.dir, double_point);
  std::printf("%s, %.3g s: table vs stacked %zu values differ; points with water: table %zu, stacked %zu, saturated "
              "%zu of %zu; wall time table %.2f s, stacked %.2f s, saturated %.2f s\n",
              formulation.c_str(), end, differ, wet, wet_stacked, wet_saturated, kPoints, table.seconds,
              stacked.seconds, saturated.seconds);
  EXPECT_EQ(differ, 0u) << formulation << ": the table body and the stacked pair differ";
  EXPECT_EQ(wet, kWetPoints);
  EXPECT_EQ(wet_stacked, kWetPoints);
  EXPECT_EQ(wet_saturated, kPoints);

  // Above the table the soil stays dry skeleton: dry mass, no pore water, no pore pressure.
  const PointCloud last = swmpm::testing::last_frame(table.dir);
  const auto& mass = last.get("mass", "solid").values;
  const auto& volume = last.get("volume", "solid").values;
  const auto& p = last.get("pore_pressure", "solid").values;
  const auto* fluid_mass = last.find("fluid_mass");
  const double V0 = 0.03125 * 0.03125, m_dry = 0.6 * 2650.0 * V0;  // m^2 per metre, kg per metre
  std::size_t dry = 0;
  for (std::size_t k = 0; k < last.size(); ++k) {
    if (last.points[k][1] < kTable + 0.01) continue;  // the soil above the table (it settles by less than 1 cm)
    ++dry;
    EXPECT_DOUBLE_EQ(mass[k], m_dry) << "point " << k;
    EXPECT_GT(volume[k], 0.0);
    if (!double_point) {
      EXPECT_EQ(p[k], 0.0) << "point " << k << " above the table carries a pore pressure";
      EXPECT_EQ(fluid_mass->values[k], 0.0) << "point " << k << " above the table carries water";
    }
  }
  EXPECT_EQ(dry, kPoints - kWetPoints);

  // The load moved the column (the frames compared are not two states at rest), and the dry crust
  // changes the result: the saturated column settles otherwise.
  const double settled = largest_settlement(last), settled_saturated = largest_settlement(swmpm::testing::last_frame(saturated.dir));
  std::printf("  largest settlement: table %.4g mm, saturated %.4g mm\n", 1e3 * settled, 1e3 * settled_saturated);
  EXPECT_GT(settled, 1e-5);  // m
  EXPECT_NE(settled, settled_saturated);
}

}  // namespace

TEST(WaterTable, ExplicitSinglePointDryAboveTheTableAsADryBodyOnASaturatedOne) {
  expect_dry_above_the_table("explicit-single-point", 0.02);
}

TEST(WaterTable, SemiImplicitSinglePointDryAboveTheTableAsADryBodyOnASaturatedOne) {
  expect_dry_above_the_table("semi-implicit-single-point", 0.05);
}

TEST(WaterTable, SemiImplicitDoublePointDryAboveTheTableAsADryBodyOnASaturatedOne) {
  expect_dry_above_the_table("semi-implicit-double-point", 0.05);
}

TEST(WaterTable, ExplicitDoublePointDryAboveTheTableAsADryBodyOnASaturatedOne) {
  expect_dry_above_the_table("explicit-double-point", 0.02);
}

// mpm-fem models the water on the grid: the soil's pores hold water where the initial phase field
// has it. Above the table the phase field is air (phi = 0) and below it water, the same field as
// the stacked pair's, and the run is the stacked pair's bit for bit. The cost does not change: the
// fluid is solved on the whole grid whatever the phase field.
TEST(WaterTable, MpmFemPhaseFieldIsWaterOnlyBelowTheTable) {
  const Timed table = run("mpm-fem", Layout::table, 0.01), stacked = run("mpm-fem", Layout::stacked, 0.01);
  const PointCloud phi = swmpm::scene::read_vtu(table.dir + "/particles/phase_field.vtu");
  EXPECT_EQ(differences(phi, swmpm::scene::read_vtu(stacked.dir + "/particles/phase_field.vtu"), "mpm-fem phase field"), 0u);
  EXPECT_EQ(differences(swmpm::testing::last_frame(table.dir), swmpm::testing::last_frame(stacked.dir), "mpm-fem soil"),
            0u);
  const auto& f = phi.get("phi", "phase_field.vtu").values;
  double above = 0.0, below = 1.0;  // largest phi above the table + 1.5 cells, smallest below it - 1.5 cells
  for (std::size_t i = 0; i < phi.size(); ++i) {
    const double y = phi.points[i][1];
    if (y > kTable + 1.5 * kCell) above = std::max(above, f[i]);
    if (y < kTable - 1.5 * kCell) below = std::min(below, f[i]);
  }
  std::printf("mpm-fem, 0.01 s: phi above the table <= %.3g, below it >= 1 - %.3g; wall time table %.2f s, stacked "
              "%.2f s\n", above, 1.0 - below, table.seconds, stacked.seconds);
  EXPECT_EQ(above, 0.0);
  EXPECT_GT(below, 1.0 - 1e-12);  // the exact integrals of the basis, to round-off
}

// A table at or below every point of its body would leave the body without water: refused when
// preprocess seeds it (exit 2, one line naming the file and the table's JSON path, nothing written).
TEST(WaterTable, TableBelowTheWholeBodyIsRejected) {
  json s = column("explicit-single-point", Layout::table, 0.01);
  s["bodies"][0]["geometry"] = box(0.25, kTop);
  s["bodies"][0]["initial"]["water_table"] = 0.2;
  const fs::path dir = swmpm::testing::scratch("water-table-below-body");
  std::ofstream(dir / "scene.json") << s.dump(2);
  const fs::path run = dir / "run";
  const auto r = swmpm::testing::swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + run.string(), dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("scene.json: /bodies/0/initial/water_table: got 0.2, at or below every point of body \"column\""),
            std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(run));
}
