// The water_level gauge (solver/output/monitors.hpp): a pond of free water at rest in
// explicit-double-point, 0.2 m wide and H = 0.3 m deep in a 0.2 x 0.5 m grid of 0.05 m cells, two
// points per cell and direction, hydrostatic from t = 0, impermeable walls and floor. The level on
// every vertical line is H: the topmost points' centres lie a quarter cell below the surface and
// their domains reach it; the liquid's compression under its own weight is already in the
// hydrostatic start (p = K ΔV/V), so the surface stays put but for the start's small transient.
// Gauges on a line through nodes (x = 0.1: the points on both sides at h/2), through cell centres
// (x = 0.025) and on the wall (x = 0); 3D the same with z.
// Moving surface: the dam break of examples/dam-break-double-point (a = 57.15 mm, a column 2a high
// collapsing), gauges at x = a (the column's edge) and 2a (dry until the surge passes): each row at
// a frame's time equals the definition evaluated on that frame's liquid points, read back from
// output/fluid_*.vtu (positions and half_size), NaN where the definition finds no point.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "scene/pointcloud.hpp"
#include "support/pond_scene.hpp"
#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;
using swmpm::testing::load_json;
using swmpm::testing::read_monitors;
using swmpm::testing::run_scene;

constexpr double H = 0.3;          // m, depth of the pond
constexpr double tolerance = 1e-3;  // m

/// The pond (support/pond_scene.hpp) with three gauges: on a node line, on cell centres, on the wall.
json pond(int dim) {
  json j = swmpm::testing::pond_scene(dim);
  j["output"] = json::parse(R"json({ "interval": 0.2, "monitor_interval": 0.01, "monitors": [
      { "name": "middle", "at": [0.1], "quantities": ["water_level"] },
      { "name": "cell", "at": [0.025], "quantities": ["water_level"] },
      { "name": "wall", "at": [0.0], "quantities": ["water_level"] } ] })json");
  if (dim == 3) {
    auto& m = j["output"]["monitors"];
    m[0]["at"] = {0.1, 0.05};
    m[1]["at"] = {0.025, 0.025};
    m[2]["at"] = {0.0, 0.1};
  }
  return j;
}


void pond_at_rest_reads_its_depth(int dim) {
  const std::string run = run_scene(pond(dim), "water-level-" + std::to_string(dim) + "d");
  const auto t = read_monitors(run);
  ASSERT_EQ(t.names.size(), 4u);
  EXPECT_EQ(t.names[1], "middle.water_level");
  const auto& time = t.columns[0];
  ASSERT_GE(time.size(), 20u);
  for (std::size_t c = 1; c < t.names.size(); ++c) {
    const auto& level = t.columns[c];
    double worst = 0.0;
    for (std::size_t r = 0; r < level.size(); ++r) {
      ASSERT_TRUE(std::isfinite(level[r])) << t.names[c] << " at t = " << time[r];
      worst = std::max(worst, std::abs(level[r] - H));
    }
    std::printf("water level %dD %s: t = 0 %.6f m, t = %.2f s %.6f m, max |level - H| %.4f mm\n", dim,
                t.names[c].c_str(), level.front(), time.back(), level.back(), 1e3 * worst);
    EXPECT_NEAR(level.front(), H, 1e-12) << t.names[c];  // the domains' tops at t = 0
    EXPECT_LT(worst, tolerance) << t.names[c];
  }
}

}  // namespace

TEST(WaterLevel, PondAtRestReadsItsDepth2D) { pond_at_rest_reads_its_depth(2); }
TEST(WaterLevel, PondAtRestReadsItsDepth3D) { pond_at_rest_reads_its_depth(3); }

TEST(WaterLevel, DamBreakGaugesReadTheFrames) {
  const json scene = load_json(SWMPM_SOURCE_DIR "/examples/dam-break-double-point/scene.json");
  const std::string run = run_scene(scene, "water-level-dam-break");
  const auto t = read_monitors(run);
  const double a = 0.05715, h = scene["grid"]["cell_size"].get<double>();  // m
  ASSERT_TRUE(t.has("gauge_a.water_level") && t.has("gauge_2a.water_level")) << "the example's gauges";
  const auto& time = t.column("time");
  const auto& at_a = t.column("gauge_a.water_level");
  const auto& at_2a = t.column("gauge_2a.water_level");
  EXPECT_NEAR(at_a.front(), 2 * a, 1e-12);  // the column's top
  EXPECT_TRUE(std::isnan(at_2a.front()));   // dry at t = 0
  // The half-heights l_p,y: frames do not carry them, the particle file does; one body, one size.
  const auto initial = swmpm::scene::read_vtu(run + "/particles/fluid.vtu");
  const auto& half = initial.get("half_size", "fluid").values;
  const double l_y = half[1];  // m
  for (std::size_t p = 0; p < initial.size(); ++p) ASSERT_EQ(half[3 * p + 1], l_y);
  // The definition (monitors.hpp) on a frame.
  const auto level = [h, l_y](const swmpm::scene::PointCloud& f, double x) {
    double top = -INFINITY;
    for (std::size_t p = 0; p < f.size(); ++p)
      if (std::abs(f.points[p][0] - x) <= 0.5 * h * (1 + 1e-9)) top = std::max(top, f.points[p][1] + l_y);
    return std::isfinite(top) ? top : NAN;
  };
  int compared = 0, wet_2a = 0;
  double worst = 0.0;
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd")) {
    if (e.group != "fluid") continue;
    const auto row = std::find_if(time.begin(), time.end(), [&](double tr) { return std::abs(tr - e.time) < 1e-9; });
    if (row == time.end()) continue;
    const auto r = static_cast<std::size_t>(row - time.begin());
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    for (const auto& [gauge, x] : {std::pair{&at_a, a}, std::pair{&at_2a, 2 * a}}) {
      const double expected = level(f, x), got = (*gauge)[r];
      const char* name = gauge == &at_a ? "gauge_a" : "gauge_2a";
      if (std::isnan(expected)) {
        EXPECT_TRUE(std::isnan(got)) << name << " at t = " << e.time;
        continue;
      }
      EXPECT_NEAR(got, expected, 1e-9) << name << " at t = " << e.time;
      worst = std::max(worst, std::abs(got - expected));
      wet_2a += gauge == &at_2a;
    }
    ++compared;
  }
  std::printf("dam break: %d frames compared, max |gauge - frame| %.2e m, %d wet at 2a; t = %.3f s: level at a %.4f m "
              "(2a = %.4f m at t = 0), at 2a %.4f m\n",
              compared, worst, wet_2a, time.back(), at_a.back(), 2 * a, at_2a.back());
  EXPECT_GE(compared, 15);
  EXPECT_GE(wet_2a, 5);                 // the surge has passed 2a
  EXPECT_LT(at_a.back(), 0.5 * 2 * a);  // the column has collapsed
}
