// A prescribed pore pressure on a boundary (`boundaries[].fluid: "pressure"`). Explicit-single-point:
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

// The semi-implicit formulations take a prescribed pore pressure as the Dirichlet value of their
// pressure equation on the face; their pressure force is the strong gradient -grad p of the nodal
// field, whose integration by parts already holds the boundary term, so no load is added (until
// 2026-12-02 the load -p A n was added as well: a weightless column under p = 10 kPa took 20.0 kPa
// inside, and double-point rejected the boundary because its soil points carry no pore fluid).
namespace {

json semi_implicit_column(const std::string& formulation, double gravity, double p_top) {
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  s["formulation"] = formulation;
  s["gravity"] = {0.0, -gravity};
  s["grid"]["max"] = {0.1, 1.0};  // the top face is the grid's y_max
  s["bodies"][0]["initial"] = json::object();
  if (gravity > 0.0)
    s["bodies"][0]["initial"] = {{"stress", "geostatic"}, {"k0", 1.0},
                                 {"pore_pressure", "hydrostatic"}, {"water_table", 1.0 + p_top / (rho_w * gravity)}};
  s["loads"] = json::array();
  s["boundaries"].push_back({{"on", "y_max"}, {"solid", "free"}, {"fluid", "pressure"}, {"value", p_top}});
  s["time"] = {{"end", 0.1}, {"dt", 1e-4}};
  s["output"] = {{"interval", 0.1},
                 {"monitor_interval", 0.01},
                 {"monitors", json::array({{{"name", "base"}, {"at", {0.05, 0.00625}}, {"phase", "fluid"},
                                            {"quantities", {"pore_pressure"}}},  // the lowest points' row
                                           {{"name", "mid"}, {"at", {0.05, 0.5}}, {"phase", "solid"},
                                            {"quantities", {"stress_yy"}}},
                                           {{"name", "top"}, {"at", {0.05, 0.9875}}, {"phase", "solid"},
                                            {"quantities", {"displacement_y"}}}})}};
  return s;
}

class SemiImplicitPorePressureBoundary : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(SemiImplicitPorePressureBoundary, PrescribedPressureIsNoLoad) {
  const std::string& formulation = GetParam();
  // Weightless: p = 10 kPa on top and nothing else; incompressible constituents, so p = 10 kPa
  // throughout from the first step, the skeleton unloaded and at rest.
  const double p_top = 1e4;
  const auto t = swmpm::post::read_csv(
      swmpm::testing::run_scene(semi_implicit_column(formulation, 0.0, p_top), formulation + "-p-top") + "/monitors.csv");
  double worst_p = 0, worst_s = 0, worst_u = 0;
  for (std::size_t k = 1; k < t.column("base.pore_pressure").size(); ++k) {  // row 0: the initial p = 0
    worst_p = std::max(worst_p, std::abs(t.column("base.pore_pressure")[k] / p_top - 1));
    worst_s = std::max(worst_s, std::abs(t.column("mid.stress_yy")[k]));
    worst_u = std::max(worst_u, std::abs(t.column("top.displacement_y")[k]));
  }
  std::printf("%s, weightless column, p = %.0f Pa on top: base p deviation %.2e, |sigma'_yy| at mid-height %.2e Pa, "
              "|u_y| at the top %.2e m\n",
              formulation.c_str(), p_top, worst_p, worst_s, worst_u);
  EXPECT_LT(worst_p, 1e-6);
  EXPECT_LT(worst_s, 1e-3);   // Pa (against 1e4 Pa of pore pressure)
  EXPECT_LT(worst_u, 1e-9);   // m

  // Under gravity and 0.5 m of free water (p = rho_w g 0.5 on top), hydrostatic at rest.
  const double p_sub = rho_w * g * depth;
  const auto h = swmpm::post::read_csv(
      swmpm::testing::run_scene(semi_implicit_column(formulation, g, p_sub), formulation + "-submerged") +
      "/monitors.csv");
  const double base_exact = rho_w * g * (1.0 + depth - 0.00625);
  double worst_base = 0, worst_top_u = 0;
  for (std::size_t k = 0; k < h.column("base.pore_pressure").size(); ++k) {
    worst_base = std::max(worst_base, std::abs(h.column("base.pore_pressure")[k] / base_exact - 1));
    worst_top_u = std::max(worst_top_u, std::abs(h.column("top.displacement_y")[k]));
  }
  std::printf("%s, submerged column (p = %.0f Pa on top): base p deviation from hydrostatic %.2e, |u_y| at the top "
              "%.2e m\n",
              formulation.c_str(), p_sub, worst_base, worst_top_u);
  EXPECT_LT(worst_base, 1e-9);
  EXPECT_LT(worst_top_u, 1e-9);  // m
}

namespace {
std::string variant_name(const ::testing::TestParamInfo<std::string>& param) {
  return param.param == "semi-implicit-single-point" ? "SinglePoint" : "DoublePoint";
}
}  // namespace

INSTANTIATE_TEST_SUITE_P(BothVariants, SemiImplicitPorePressureBoundary,
                         ::testing::Values("semi-implicit-single-point", "semi-implicit-double-point"), variant_name);

// A prescribed pore pressure drives flow: a weightless column, nearly rigid (E = 1 GPa, so the
// consolidation transient is over within milliseconds), p = 10 kPa on its base and drained on top.
// Steady state: p = p_bar (1 - y / L) and the Darcy flux n (v_w - v_s) = k p_bar / (rho_w g L).
// The energy check counts the work p_bar does on the face (before 2026-12-02 it counted none and
// stopped this run at step 10 as "creating energy").
TEST_P(SemiImplicitPorePressureBoundary, PressureDrivenSeepageMatchesDarcy) {
  const std::string& formulation = GetParam();
  const double p_bar = 1e4, L = 1.0, k = 1e-3, n0 = 0.3, y_mid = 0.50625;  // y_mid: a row of points
  json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  s["formulation"] = formulation;
  s["gravity"] = {0.0, 0.0};
  s["grid"]["max"] = {0.1, L};
  s["materials"][0]["youngs_modulus"] = 1e9;
  s["loads"] = json::array();
  s["boundaries"] = json::array(
      {{{"on", "x_min"}, {"solid", "roller"}, {"fluid", "impermeable"}},
       {{"on", "x_max"}, {"solid", "roller"}, {"fluid", "impermeable"}},
       {{"on", "y_min"}, {"solid", "fixed"}, {"fluid", "pressure"}, {"value", p_bar}},
       {{"on", "y_max"}, {"solid", "free"}, {"fluid", "drained"}}});
  s["time"] = {{"end", 0.05}, {"dt", 2e-5}};
  s["output"] = {{"interval", 0.05},
                 {"monitor_interval", 0.01},
                 {"monitors", json::array({{{"name", "w"}, {"at", {0.05, y_mid}}, {"phase", "fluid"},
                                            {"quantities", {"pore_pressure", "velocity_y"}}},
                                           {{"name", "s"}, {"at", {0.05, y_mid}}, {"phase", "solid"},
                                            {"quantities", {"velocity_y"}}}})}};
  for (const std::string shape : {"gimp", "bspline2"}) {
    s["grid"]["shape_function"] = shape;
    const std::string run = swmpm::testing::run_scene(s, formulation + "-seepage-" + shape);
    const auto t = swmpm::post::read_csv(run + "/monitors.csv");
    const double p = t.column("w.pore_pressure").back();
    const double q = n0 * (t.column("w.velocity_y").back() - t.column("s.velocity_y").back());
    const double p_exact = p_bar * (1.0 - y_mid / L), q_exact = k * p_bar / (1000.0 * 9.81 * L);
    std::printf("%s, %s, seepage driven by p = %.0f Pa on the base: p at y = %.4f m %.1f Pa (exact %.1f), Darcy "
                "flux %.4e m/s (exact %.4e)\n",
                formulation.c_str(), shape.c_str(), p_bar, y_mid, p, p_exact, q, q_exact);
    EXPECT_NEAR(p / p_exact, 1.0, 0.01) << shape;
    EXPECT_NEAR(q / q_exact, 1.0, 0.02) << shape;
  }
}
