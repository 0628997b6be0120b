// explicit-double-point (seed 003): the published and analytic cases of issue 24, each from its
// example folder (docs/verification.md, "explicit-double-point").
//   C1  1D consolidation, seed Table 1: double-point against single-point and Terzaghi
//   E3  dam break of free water against Martin & Moyce (1952), Table 2
//   hydrostatics: a soil bed under free water at rest for 10 s
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>

#include "scene/pointcloud.hpp"
#include "support/indicators.hpp"
#include "support/run_helpers.hpp"
#include "support/seepage.hpp"

namespace {

using nlohmann::json;
using swmpm::testing::load_json;
using swmpm::testing::read_monitors;
using swmpm::testing::terzaghi;
using swmpm::testing::run_scene;



}  // namespace

// C1: n = 0.4, kappa = 1.0214e-10 m^2, mu = 1.002e-3 Pa s (k = 1.0e-3 m/s), E = 10 MPa, nu = 0.2,
// K_L = 21.5 MPa, 40 rows of cells, 10 kPa on a drained top, weightless. c_v with the liquid's
// storage: k / (gamma_w (1 / E_oed + n / K_L)) = 0.939 m^2/s (the seed's 1.1 leaves out n / K_L).
TEST(ExplicitDoublePoint, C1ConsolidationMatchesSinglePointAndTerzaghi) {
  const std::string dir = SWMPM_SOURCE_DIR "/examples/consolidation-double-point/";
  const auto dp = read_monitors(run_scene(load_json(dir + "scene.json"), "edp-c1-double"));
  const auto sp = read_monitors(run_scene(load_json(dir + "scene-single-point.json"), "edp-c1-single"));
  const double k = 1.0214e-10 * 1000.0 * 9.81 / 1.002e-3, E = 1.0e7, nu = 0.2, n = 0.4, K_L = 2.15e7, p0 = 1.0e4;
  const double E_oed = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)), c_v = k / (9810.0 * (1 / E_oed + n / K_L));
  const auto& t_dp = dp.column("time");
  const auto& t_sp = sp.column("time");
  ASSERT_EQ(t_dp.size(), t_sp.size());
  const std::pair<const char*, double> gauges[] = {
      {"base", 0.00625}, {"quarter", 0.25625}, {"mid", 0.50625}, {"three_quarters", 0.75625}};
  for (const auto& [name, y] : gauges) {
    const auto& p_dp = dp.column(std::string(name) + ".pore_pressure");
    const auto& p_sp = sp.column(std::string(name) + ".pore_pressure");
    double e_dp = 0, e_sp = 0, diff = 0;
    int count = 0;
    for (std::size_t r = 0; r < t_dp.size(); ++r) {
      const double t = t_dp[r], Tv = c_v * t;
      ASSERT_NEAR(t, t_sp[r], 2e-4);  // the row after each 5 ms mark; the two dt differ
      if (Tv < 0.05) continue;
      const double ref = p0 * terzaghi(1.0 - y, Tv);
      e_dp += std::pow((p_dp[r] - ref) / p0, 2);
      e_sp += std::pow((p_sp[r] - ref) / p0, 2);
      diff = std::max(diff, std::abs(p_dp[r] - p_sp[r]) / p0);
      ++count;
    }
    e_dp = std::sqrt(e_dp / count), e_sp = std::sqrt(e_sp / count);
    std::printf("C1 %s: RMS of p/p0 against Terzaghi double-point %.4f single-point %.4f; max |DP - SP| / p0 %.4f\n",
                name, e_dp, e_sp, diff);
    EXPECT_LT(e_dp, 0.02) << name;
    EXPECT_LT(e_sp, 0.02) << name;
    EXPECT_LT(diff, 0.01) << name;
  }
}

// Hydrostatics: a 0.4 m bed (n = 0.4, k = 1e-3 m/s) under 0.2 m of free water, 10 s at rest.
// p = rho_w g depth within 1 % in both layers (the two cells around the interface apart, whose
// points' pressures alternate by a few per cent about it), no spurious flow, the bed's effective
// stress geostatic.
TEST(ExplicitDoublePoint, SoilUnderFreeWaterStaysHydrostatic) {
  const std::string run =
      run_scene(load_json(SWMPM_SOURCE_DIR "/examples/soil-under-water-double-point/scene.json"), "edp-hydrostatic");
  const auto water = swmpm::testing::last_frame(run, "fluid");
  const auto& p = water.get("pore_pressure", "fluid").values;
  const auto& v = water.get("velocity", "fluid").values;
  const double rho_g = 1000.0 * 9.81, top = 0.6, H = 0.6, h = 0.05;
  double worst = 0.0, worst_interface = 0.0, v_max = 0.0;
  for (std::size_t i = 0; i < water.size(); ++i) {
    const double y = water.points[i][1], expected = rho_g * (top - y);
    const double err = std::abs(p[i] - expected) / (rho_g * H);
    if (std::abs(y - 0.4) < h) worst_interface = std::max(worst_interface, err);
    else worst = std::max(worst, err);
    v_max = std::max(v_max, std::hypot(v[3 * i], v[3 * i + 1]));
  }
  // The error relative to the base pressure (p / rho_w g H), away from the interface and at it.
  std::printf("hydrostatics: max |p - rho g d| / (rho g H) %.4f (interface cells %.4f), max |v_w| %.2e m/s\n", worst,
              worst_interface, v_max);
  const double checker = swmpm::testing::checkerboard_indicator(water, p, 1.6 * h);
  std::printf("hydrostatics: checkerboard indicator of p %.4f\n", checker);
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(worst_interface, 0.06);
  EXPECT_LT(checker, 0.01);
  EXPECT_LT(v_max, 1e-3 * std::sqrt(9.81 * H));
  const auto soil = swmpm::testing::last_frame(run, "solid");
  const auto& s = soil.get("stress", "solid").values;
  const auto& vs = soil.get("velocity", "solid").values;
  double s_err = 0.0, vs_max = 0.0;
  for (std::size_t i = 0; i < soil.size(); ++i) {
    const double y = soil.points[i][1];
    const double expected = -(0.6 * (2650.0 - 1000.0)) * 9.81 * (0.4 - y);  // buoyant weight
    if (y < 0.4 - h) s_err = std::max(s_err, std::abs(s[6 * i + 1] - expected) / (0.6 * 1650.0 * 9.81 * 0.4));
    vs_max = std::max(vs_max, std::hypot(vs[3 * i], vs[3 * i + 1]));
  }
  std::printf("hydrostatics: max |sigma'_yy - geostatic| / sigma'_base %.4f below the top cell, max |v_s| %.2e m/s\n",
              s_err, vs_max);
  EXPECT_LT(s_err, 0.03);
  EXPECT_LT(vs_max, 1e-3 * std::sqrt(9.81 * H));
}

// E3: a column of water a = 57.15 mm wide and 2a high collapses onto a dry floor. The surge front
// (the farthest liquid point) against Martin & Moyce (1952), Table 2, at T = t sqrt(2 g / a) >= 1;
// the liquid's mass is constant by construction, its volume through the pressure within 0.1 %.
TEST(ExplicitDoublePoint, E3DamBreakFrontFollowsMartinAndMoyce) {
  const json scene = load_json(SWMPM_SOURCE_DIR "/examples/dam-break-double-point/scene.json");
  const std::string run = run_scene(scene, "edp-dam-break");
  // Martin & Moyce's front Z = x / a against T (shared/refdata, copied into the example folder with its source).
  const auto mm = swmpm::post::read_reference(SWMPM_SOURCE_DIR "/examples/dam-break-double-point/martin-moyce-1952-front.csv");
  const std::vector<double>& T_ref = mm.t;
  const std::vector<double>& Z_ref = mm.v;
  ASSERT_GE(T_ref.size(), 10u);
  const double a = 0.05715, g = 9.81;
  int compared = 0;
  double worst = 0.0;
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd")) {
    if (e.group != "fluid") continue;
    const double T = e.time * std::sqrt(2 * g / a);
    if (T < 1.0 || T > T_ref.back()) continue;
    const auto f = swmpm::scene::read_vtu(run + "/output/" + e.file);
    double x = 0.0;
    for (std::size_t i = 0; i < f.size(); ++i) x = std::max(x, f.points[i][0]);
    double Z = 0.0;
    for (std::size_t k = 1; k < T_ref.size(); ++k)
      if (T <= T_ref[k]) {
        Z = Z_ref[k - 1] + (Z_ref[k] - Z_ref[k - 1]) * (T - T_ref[k - 1]) / (T_ref[k] - T_ref[k - 1]);
        break;
      }
    const double err = (x / a - Z) / Z;
    std::printf("E3: T = %.2f, x/a = %.3f, Martin & Moyce %.3f (%+.1f %%)\n", T, x / a, Z, 100 * err);
    worst = std::max(worst, std::abs(err));
    ++compared;
  }
  EXPECT_GE(compared, 6);
  EXPECT_LT(worst, 0.10);
  // Volume: the liquid's own, sum m / rho (1 - p / K), and the volume its points occupy, sum V
  // (each point's V follows the liquid's velocity divergence), at the end against the start.
  const auto first = [&] {
    for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd"))
      if (e.group == "fluid") return swmpm::scene::read_vtu(run + "/output/" + e.file);
    return swmpm::scene::PointCloud{};
  }();
  const auto last = swmpm::testing::last_frame(run, "fluid");
  auto volumes = [](const swmpm::scene::PointCloud& f) {
    const auto& m = f.get("mass", "fluid").values;
    const auto& p = f.get("pore_pressure", "fluid").values;
    const auto& V = f.get("volume", "fluid").values;
    double own = 0.0, occupied = 0.0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      own += m[i] / 1000.0 * (1.0 - p[i] / 2.0e6);
      occupied += V[i];
    }
    return std::pair{own, occupied};
  };
  const auto [own0, occ0] = volumes(first);
  const auto [own1, occ1] = volumes(last);
  std::printf("E3: liquid volume %.6g -> %.6g m^2 (%+.3f %%), occupied %.6g -> %.6g m^2 (%+.3f %%)\n", own0, own1,
              100 * (own1 / own0 - 1), occ0, occ1, 100 * (occ1 / occ0 - 1));
  EXPECT_NEAR(own1 / own0, 1.0, 1e-3);
  EXPECT_NEAR(occ1 / occ0, 1.0, 0.02);
}

namespace {

/// Seepage through the fixed gravel layer of examples/seepage-double-point (D = 1 mm:
/// kappa = 1.185e-9 m^2) at cell size `cell`: the pond's fall rate over 0.15-1.2 s against Darcy and
/// against Ergun's root (support/seepage.hpp). Returns {q, q_darcy, q_ergun}.
std::array<double, 3> seepage_flux(const std::string& scene_file, const std::string& name, double cell) {
  json s = load_json(SWMPM_SOURCE_DIR "/examples/seepage-double-point/" + scene_file);
  s["grid"]["cell_size"] = cell;
  s["output"]["monitors"][0]["at"] = {0.1, 0.9 - cell / 4};  // the pond's top row of points
  const auto f = swmpm::testing::seepage_flux(run_scene(s, name), 1e-3, 0.15, 1.2);
  std::printf("seepage %s, h = %g m: q = %.5f m/s, Darcy %.5f (%+.1f %%), Ergun %.5f (%+.1f %%)\n", scene_file.c_str(),
              cell, f.q, f.q_darcy, 100 * (f.q / f.q_darcy - 1), f.q_ergun, 100 * (f.q / f.q_ergun - 1));
  return {f.q, f.q_darcy, f.q_ergun};
}

}  // namespace

// The flux converges to the closed forms with the cell size (the liquid points' volume follows
// the liquid within a cell of the layer's faces): at h = 25 mm Darcy -13 %, Ergun -17 %; at
// 12.5 mm -4 % and -8 % (SlowSeepageConvergesToDarcyAndErgun).
TEST(ExplicitDoublePoint, SeepageThroughAFixedLayerFollowsDarcyAndErgun) {
  const auto darcy = seepage_flux("scene.json", "edp-seepage-darcy", 0.025);
  const auto ergun = seepage_flux("scene-ergun.json", "edp-seepage-ergun", 0.025);
  EXPECT_NEAR(darcy[0] / darcy[1], 1.0, 0.16);
  EXPECT_NEAR(ergun[0] / ergun[2], 1.0, 0.20);
  EXPECT_LT(ergun[0], 0.7 * darcy[0]);  // the inertial term cuts the flux (closed forms: 0.69)
}

TEST(ExplicitDoublePoint, SlowSeepageConvergesToDarcyAndErgun) {
  const auto darcy = seepage_flux("scene.json", "edp-seepage-darcy-fine", 0.0125);
  const auto ergun = seepage_flux("scene-ergun.json", "edp-seepage-ergun-fine", 0.0125);
  EXPECT_NEAR(darcy[0] / darcy[1], 1.0, 0.05);
  EXPECT_NEAR(ergun[0] / ergun[2], 1.0, 0.09);
}

// Settling (examples/settling-double-point): a suspension with n = 0.7 > n_max = 0.5 (D = 0.5 mm,
// Kozeny–Carman, Darcy drag) under 0.1 m of clear water in a closed column. A grain in its middle
// settles at the terminal velocity of the drag balance with zero mixture flux,
// v_s = -(1 - n) (rho_S - rho_L) / rho_L k(n), k = kappa rho_L g / mu; at the bottom the grains
// pack below n_max and carry effective stress again (sedimentation).
TEST(ExplicitDoublePoint, SuspensionSettlesAtTerminalVelocityAndSediments) {
  const std::string run = run_scene(load_json(SWMPM_SOURCE_DIR "/examples/settling-double-point/scene.json"), "edp-settling");
  const auto m = read_monitors(run);
  const auto& time = m.column("time");
  const auto& v_s = m.column("mid_grain.velocity_y");
  const double n = 0.7, D = 5e-4, kappa = D * D / 150 * std::pow(n, 3) / std::pow(1 - n, 2), k = kappa * 1000 * 9.81 / 1e-3;
  const double v_t = -(1 - n) * (2650.0 - 1000.0) / 1000.0 * k;
  double sum = 0.0;
  int count = 0;
  for (std::size_t r = 0; r < time.size(); ++r)
    if (time[r] >= 0.5 && time[r] <= 1.5) sum += v_s[r], ++count;
  const double v_mean = sum / count;
  std::printf("settling: mean v_s %.5f m/s over 0.5-1.5 s, terminal %.5f m/s (%+.2f %%)\n", v_mean, v_t,
              100 * (v_mean / v_t - 1));
  EXPECT_NEAR(v_mean / v_t, 1.0, 0.03);
  const auto soil = swmpm::testing::last_frame(run, "solid");
  const auto& por = soil.get("porosity", "solid").values;
  const auto& liq = soil.get("liquefied", "solid").values;
  const auto& s = soil.get("stress", "solid").values;
  int bottom = 0, packed = 0;
  double syy = 0.0;
  for (std::size_t i = 0; i < soil.size(); ++i) {
    if (soil.points[i][1] > 0.1) continue;
    ++bottom;
    syy += s[6 * i + 1];
    if (por[i] <= 0.5) {
      ++packed;
      EXPECT_EQ(liq[i], 0.0);
    }
  }
  std::printf("settling at 6 s: %d of %d grains in the bottom 0.1 m below n_max, mean sigma'_yy %.0f Pa\n", packed, bottom,
              syy / bottom);
  EXPECT_GE(packed, bottom / 4);
  EXPECT_LT(syy / bottom, -500.0);
}

namespace {

/// C2 (examples/column-collapse-double-point) at time t: the fronts (99th percentile of x) of the
/// solid and the liquid points, the share of liquefied solid points, and the share of solid points
/// with no liquid point in their own or a neighbouring cell (25 mm cells: the dry layer).
struct CollapseState {
  double solid_front = 0, liquid_front = 0, liquefied = 0, dry = 0;
};
CollapseState collapse_state(const std::string& run, double t) {
  auto frame = [&](const std::string& group) {
    swmpm::scene::PointCloud best;
    double dt = 1e300;
    for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd"))
      if (e.group == group && std::abs(e.time - t) < dt) dt = std::abs(e.time - t), best = swmpm::scene::read_vtu(run + "/output/" + e.file);
    return best;
  };
  auto p99 = [](std::vector<double> x) {
    std::sort(x.begin(), x.end());
    return x[std::min(x.size() - 1, static_cast<std::size_t>(0.99 * static_cast<double>(x.size())))];
  };
  CollapseState c;
  const auto s = frame("solid");
  std::vector<double> xs;
  for (std::size_t i = 0; i < s.size(); ++i) xs.push_back(s.points[i][0]);
  c.solid_front = p99(xs);
  const auto* liq = s.find("liquefied");
  if (!liq) return c;
  const auto w = frame("fluid");
  std::vector<double> xw;
  std::set<std::pair<int, int>> cells;
  const double h = 0.025;
  for (std::size_t i = 0; i < w.size(); ++i) {
    xw.push_back(w.points[i][0]);
    cells.insert({static_cast<int>(w.points[i][0] / h), static_cast<int>(w.points[i][1] / h)});
  }
  c.liquid_front = p99(xw);
  int dry = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    c.liquefied += liq->values[i] / static_cast<double>(s.size());
    const int cx = static_cast<int>(s.points[i][0] / h), cy = static_cast<int>(s.points[i][1] / h);
    bool wet = false;
    for (int a = -1; a <= 1 && !wet; ++a)
      for (int b = -1; b <= 1 && !wet; ++b) wet = cells.count({cx + a, cy + b}) > 0;
    dry += !wet;
  }
  c.dry = static_cast<double>(dry) / static_cast<double>(s.size());
  return c;
}

}  // namespace

// C2, recorded (examples/column-collapse-double-point/README.md): both formulations run the 2 s
// collapse; the drag study at d = 7 mm shows the linear drag letting the liquid run ahead as free
// water and leave dry grains, the Ergun term holding it in the soil. The seed's other findings
// (single-point farther, a dry layer at d = 2 mm) are not reproduced: the numbers are printed and
// bounded where they were measured, not asserted as the seed's.
TEST(ExplicitDoublePoint, SlowC2ColumnCollapseAndDragStudy) {
  const std::string dir = SWMPM_SOURCE_DIR "/examples/column-collapse-double-point/";
  const auto sp = collapse_state(run_scene(load_json(dir + "scene-single-point.json"), "edp-c2-sp"), 2.0);
  const auto dp = collapse_state(run_scene(load_json(dir + "scene.json"), "edp-c2-dp"), 2.0);
  std::printf("C2 at 2 s: single-point front %.3f m; double-point solid %.3f m, liquid %.3f m, liquefied %.1f %%, dry %.1f %%\n",
              sp.solid_front, dp.solid_front, dp.liquid_front, 100 * dp.liquefied, 100 * dp.dry);
  EXPECT_GT(sp.solid_front, 3.0);
  EXPECT_GT(dp.solid_front, 3.0);
  EXPECT_LT(std::abs(dp.liquid_front - dp.solid_front), 0.1);
  EXPECT_GT(dp.liquefied, 0.0);
  CollapseState v[3];
  const char* names[3] = {"a", "b", "c"};
  for (int k = 0; k < 3; ++k) {
    v[k] = collapse_state(run_scene(load_json(dir + "scene-drag-" + names[k] + ".json"), std::string("edp-c2-drag-") + names[k]), 0.85);
    std::printf("C2 drag study (%s) at 0.85 s: solid front %.3f m, liquid front %.3f m, dry %.1f %%\n", names[k],
                v[k].solid_front, v[k].liquid_front, 100 * v[k].dry);
  }
  for (int k = 0; k < 2; ++k) {  // linear drag: the liquid runs ahead and leaves dry grains
    EXPECT_GT(v[k].liquid_front, v[k].solid_front + 0.5) << names[k];
    EXPECT_GT(v[k].dry, 0.05) << names[k];
  }
  EXPECT_LT(std::abs(v[2].liquid_front - v[2].solid_front), 0.1);  // Ergun holds the liquid in the soil
  EXPECT_LT(v[2].dry, 0.02);
}

// 3D: the bed under free water of examples/soil-under-water-double-point as a 0.1 x 0.8 x 0.1 m
// column (rollers on the four sides), 1 s at rest; the water_level gauge on its axis.
TEST(ExplicitDoublePoint, SoilUnderFreeWaterStaysHydrostatic3D) {
  json s = load_json(SWMPM_SOURCE_DIR "/examples/soil-under-water-double-point/scene.json");
  s["dimension"] = 3;
  s["gravity"] = {0.0, -9.81, 0.0};
  s["grid"]["min"] = {0.0, 0.0, 0.0};
  s["grid"]["max"] = {0.1, 0.8, 0.1};
  for (auto& b : s["bodies"]) {
    b["geometry"]["min"] = {0.0, b["geometry"]["min"][1], 0.0};
    b["geometry"]["max"] = {0.1, b["geometry"]["max"][1], 0.1};
  }
  s["boundaries"].push_back({{"on", "z_min"}, {"solid", "roller"}, {"fluid", "impermeable"}});
  s["boundaries"].push_back({{"on", "z_max"}, {"solid", "roller"}, {"fluid", "impermeable"}});
  s["time"]["end"] = 1.0;
  s["output"]["monitors"] = json::parse(R"([{"name": "level", "at": [0.05, 0.05], "quantities": ["water_level"]}])");
  const std::string run = run_scene(s, "edp-hydrostatic-3d");
  const auto water = swmpm::testing::last_frame(run, "fluid");
  const auto& p = water.get("pore_pressure", "fluid").values;
  const auto& v = water.get("velocity", "fluid").values;
  double worst = 0.0, v_max = 0.0;
  for (std::size_t i = 0; i < water.size(); ++i) {
    worst = std::max(worst, std::abs(p[i] - 9810.0 * (0.6 - water.points[i][1])) / (9810.0 * 0.6));
    v_max = std::max(v_max, std::sqrt(v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]));
  }
  const auto m = read_monitors(run);
  const double level = m.column("level.water_level").back();
  std::printf("hydrostatics 3D: max |p - rho g d| / (rho g H) %.4f, max |v_w| %.2e m/s, water level %.5f m\n", worst, v_max,
              level);
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(v_max, 1e-3 * std::sqrt(9.81 * 0.6));
  EXPECT_NEAR(level, 0.6, 1e-3);
}
