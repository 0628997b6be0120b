// Free water in semi-implicit-double-point (issue 27, item 8): refused up front.
//
// Before: a scene whose only body is free water failed at solve with "particles/solid.vtu: cannot
// open file" (after preprocess had written its run directory), and a dam break (0.1 x 0.2 m of water
// on a 2 cm saturated bed, bspline2) followed Martin & Moyce within 5-13 % up to T = 1.95, then
// stopped at t = 0.14 s "creating energy". Now the scene is refused when it is read: exit 2, one
// line naming the scene file and the free-water body's JSON path, pointing to the formulations that
// model free water (explicit-double-point, mpm-fem); nothing is written.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

/// A 0.1 m wide, 0.2 m high column of water at the left wall of a 0.5 x 0.3 m tank (bspline2, cells
/// 5 mm); with `bed`, on a 2 cm saturated sand bed across the tank (the water column then 0.02-0.22 m).
json dam_break(bool bed) {
  const double y0 = bed ? 0.02 : 0.0;
  json s = {{"name", bed ? "dam-break-on-bed" : "free-water-only"},
            {"dimension", 2},
            {"formulation", "semi-implicit-double-point"},
            {"gravity", {0.0, -9.81}},
            {"grid", {{"cell_size", 0.005}, {"min", {0.0, 0.0}}, {"max", {0.5, 0.3}}, {"shape_function", "bspline2"}}},
            {"materials",
             {{{"name", "sand"}, {"model", "linear-elastic"}, {"grain_density", 2650.0}, {"porosity", 0.4},
               {"youngs_modulus", 1e7}, {"poisson_ratio", 0.3}, {"hydraulic_conductivity", 1e-3}},
              {{"name", "water"}, {"model", "fluid"}, {"density", 1000.0}, {"bulk_modulus", 2.2e6}}}},
            {"bodies", json::array()},
            {"boundaries",
             {{{"on", "x_min"}, {"solid", "roller"}, {"fluid", "impermeable"}},
              {{"on", "x_max"}, {"solid", "roller"}, {"fluid", "impermeable"}},
              {{"on", "y_min"}, {"solid", "fixed"}, {"fluid", "impermeable"}}}},
            {"time", {{"end", 0.3}}},
            {"output", {{"interval", 0.05}}}};
  if (bed)
    s["bodies"].push_back({{"name", "bed"},
                           {"geometry", {{"type", "box"}, {"min", {0.0, 0.0}}, {"max", {0.5, y0}}}},
                           {"solid", "sand"},
                           {"fluid", "water"},
                           {"particles_per_cell", 2},
                           {"initial", {{"pore_pressure", "hydrostatic"}, {"water_table", y0}}}});
  s["bodies"].push_back({{"name", "column"},
                         {"geometry", {{"type", "box"}, {"min", {0.0, y0}}, {"max", {0.1, y0 + 0.2}}}},
                         {"fluid", "water"},
                         {"particles_per_cell", 2},
                         {"initial", {{"pore_pressure", "hydrostatic"}}}});
  return s;
}

/// `swmpm COMMAND scene.json -o run` on `scene`: exit 2, one line on stderr naming the scene file and
/// /bodies/`body`, the formulations that model free water; no run directory.
void expect_refused(const json& scene, const std::string& name, const std::string& command, int body) {
  const fs::path dir = swmpm::testing::scratch("free-water-si-" + name + "-" + command);
  const fs::path file = dir / "scene.json";
  std::ofstream(file) << scene.dump(2);
  const Result r = swmpm_cmd("-q " + command + " " + file.string() + " -o " + (dir / "run").string(), dir);
  std::printf("%s, swmpm %s: exit %d, stderr: %s", name.c_str(), command.c_str(), r.status, r.err.c_str());
  EXPECT_EQ(r.status, 2) << r.err;
  const std::string where = file.string() + ": /bodies/" + std::to_string(body) + ": body \"column\" is free water";
  EXPECT_NE(r.err.find(where), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("semi-implicit-double-point does not model"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("\"explicit-double-point\" or \"mpm-fem\""), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir / "run")) << "nothing may be written";
}

}  // namespace

TEST(FreeWaterInSemiImplicitDoublePoint, FreeWaterOnlyIsRefusedUpFront) {
  for (const char* command : {"run", "preprocess"}) expect_refused(dam_break(false), "free-water-only", command, 0);
}

TEST(FreeWaterInSemiImplicitDoublePoint, DamBreakOnASaturatedBedIsRefusedUpFront) {
  for (const char* command : {"run", "preprocess"}) expect_refused(dam_break(true), "dam-break", command, 1);
}

// The same scenes are accepted by the formulation the message points to (preprocess only: the
// refusal is about the formulation, not the scene).
TEST(FreeWaterInSemiImplicitDoublePoint, ExplicitDoublePointTakesTheSameScenes) {
  for (const bool bed : {false, true}) {
    json s = dam_break(bed);
    s["formulation"] = "explicit-double-point";
    const fs::path dir = swmpm::testing::scratch(std::string("free-water-edp-") + (bed ? "bed" : "only"));
    std::ofstream(dir / "scene.json") << s.dump(2);
    const Result r = swmpm_cmd("-q preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir / "run" / "particles" / "fluid.vtu"));
  }
}
