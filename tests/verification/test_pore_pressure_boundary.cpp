// A prescribed pore pressure on a boundary (`boundaries[].fluid: "pressure"`, explicit-single-point):
// a saturated column under 0.5 m of free water, modelled as the pressure rho_w g 0.5 m on its top
// face, stays hydrostatic at rest: the boundary load -p A n, shared (1 - n) by the skeleton and n by
// the pore fluid, balances the initial state. With the top drained (p = 0) instead, the same
// column's top pressure falls as water flows out: the boundary value is what holds it.
#include <gtest/gtest.h>

#include <cmath>

#include "support/run_helpers.hpp"

namespace {

using nlohmann::json;
constexpr double rho_w = 1000.0, g = 9.81, depth = 0.5;  // free water above the soil, m

json submerged_column(bool with_pressure) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi/scene.json");
  s["gravity"] = {0.0, -g};
  s["grid"]["max"] = {0.1, 1.0};  // the top face is the grid's y_max
  s["bodies"][0]["initial"] = {{"stress", "geostatic"}, {"k0", 1.0},
                               {"pore_pressure", "hydrostatic"}, {"water_table", 1.0 + depth}};
  s["loads"] = json::array();
  json top = {{"on", "y_max"}, {"solid", "free"}, {"fluid", "drained"}};
  if (with_pressure) top = {{"on", "y_max"}, {"solid", "free"}, {"fluid", "pressure"}, {"value", rho_w * g * depth}};
  s["boundaries"].push_back(top);
  s["time"] = {{"end", 0.3}, {"dt", "auto"}, {"cfl", 0.5}};
  s["output"] = {{"interval", 0.3},
                 {"monitor_interval", 0.01},
                 {"monitors", json::array({{{"name", "base"}, {"at", {0.05, 0.0125}}, {"phase", "fluid"},
                                            {"quantities", {"pore_pressure"}}},
                                           {{"name", "top"}, {"at", {0.05, 0.9875}}, {"phase", "fluid"},
                                            {"quantities", {"pore_pressure", "velocity_y"}}}})}};
  return s;
}

}  // namespace

TEST(PorePressureBoundary, SubmergedColumnStaysHydrostatic) {
  const std::string run = swmpm::testing::run_scene(submerged_column(true), "submerged-pressure");
  const auto t = swmpm::post::read_csv(run + "/monitors.csv");
  const auto& base = t.column("base.pore_pressure");
  const auto& top = t.column("top.pore_pressure");
  const double base_exact = rho_w * g * (1.0 + depth - 0.0125), top_exact = rho_w * g * (depth + 0.0125);
  double worst_base = 0, worst_top = 0;
  for (std::size_t k = 0; k < base.size(); ++k) {
    worst_base = std::max(worst_base, std::abs(base[k] / base_exact - 1));
    worst_top = std::max(worst_top, std::abs(top[k] / top_exact - 1));
  }
  const auto f = swmpm::testing::last_frame(run);
  const auto& v = f.get("velocity", "frame").values;
  double v_max = 0;
  for (std::size_t k = 0; k < f.size(); ++k) v_max = std::max(v_max, std::hypot(v[3 * k], v[3 * k + 1]));
  std::printf("submerged column with p = %.0f Pa on top: worst deviation from hydrostatic over 0.3 s: base %.3f %%, "
              "top %.3f %%; max |v_s| at the end %.2e m/s\n",
              rho_w * g * depth, 100 * worst_base, 100 * worst_top, v_max);
  EXPECT_LT(worst_base, 0.01);
  EXPECT_LT(worst_top, 0.02);
  EXPECT_LT(v_max, 1e-3);

  const std::string drained = swmpm::testing::run_scene(submerged_column(false), "submerged-drained");
  const auto td = swmpm::post::read_csv(drained + "/monitors.csv");
  const double top_drained = td.column("top.pore_pressure").back();
  std::printf("the same column with its top drained: top pressure %.0f Pa after 0.3 s (hydrostatic %.0f)\n",
              top_drained, top_exact);
  EXPECT_LT(top_drained, 0.5 * top_exact);
}
