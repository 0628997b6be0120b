// Hard cases for explicit-double-point (seed 003), each asserting bounds and an indicator:
//   (a) a porosity jump from soil (n = 0.4) to free water (n = 1) across an inclined surface, at rest;
//   (b) flow fast enough that the Ergun term dominates the drag;
//   (c) kappa = 1e-14 m^2 at the default dt (the drag is implicit per node);
//   (d) a liquid pulled into tension, bounded by its cavitation threshold.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "support/indicators.hpp"
#include "support/run_helpers.hpp"
#include "support/seepage.hpp"

namespace {

using nlohmann::json;
using swmpm::testing::load_json;
using swmpm::testing::run_scene;

/// Every frame of a group: fn(frame cloud, time).
template <class Fn>
void for_each_frame(const std::string& run, const std::string& group, Fn&& fn) {
  for (const auto& e : swmpm::scene::read_pvd(run + "/output/results.pvd"))
    if (e.group == group) fn(swmpm::scene::read_vtu(run + "/output/" + e.file), e.time);
}

}  // namespace

// (a) A soil wedge (surface from y = 0.4 m at x = 0 down to 0.1 m at x = 0.6 m, E = 10 MPa) under
// free water to y = 0.5 m, hydrostatic, 1 s (local damping 0.2 removes the wedge's elastic
// adjustment from its K0 state). The liquid's pressure averaged per cell (the two rows of points
// of a cell) within 3 % of rho g H of hydrostatic (also in the two cells where the interface meets
// a wall, kept apart because a switch of the liquid points' volume at the soil's half volume
// fraction put 14 % there), no cell checkerboard, no flow. Point by point the bottom cells keep a
// mode of about +-0.9 kPa between their two rows of points that the nodes do not see (19 % of
// rho g H; with mfvp-constant it goes, but a flat bed's pressure is then 1 % off instead of 0.5 %):
// bounded here at 25 %, recorded in docs/verification.md.
TEST(DoublePointHardCases, InclinedSoilWaterInterfaceStaysAtRest) {
  const json s = json::parse(R"json({
    "name": "inclined-interface", "dimension": 2, "formulation": "explicit-double-point", "gravity": [0, -9.81],
    "grid": {"cell_size": 0.025, "min": [0, 0], "max": [0.6, 0.6], "shape_function": "gimp"},
    "materials": [
      {"name": "sand", "model": "linear-elastic", "grain_density": 2650, "porosity": 0.4, "youngs_modulus": 1e7,
       "poisson_ratio": 0.3, "hydraulic_conductivity": 1e-3},
      {"name": "water", "model": "fluid", "density": 1000, "bulk_modulus": 2e7}],
    "bodies": [
      {"name": "pond", "geometry": {"type": "box", "min": [0, 0], "max": [0.6, 0.5]}, "fluid": "water",
       "initial": {"pore_pressure": "hydrostatic", "water_table": 0.5}},
      {"name": "wedge", "geometry": {"type": "polygon", "vertices": [[0, 0], [0.6, 0], [0.6, 0.1], [0, 0.4]]},
       "solid": "sand", "fluid": "water",
       "initial": {"stress": "geostatic", "k0": 0.43, "pore_pressure": "hydrostatic", "water_table": 0.5}}],
    "boundaries": [
      {"on": "x_min", "solid": "roller", "fluid": "impermeable"},
      {"on": "x_max", "solid": "roller", "fluid": "impermeable"},
      {"on": "y_min", "solid": "fixed", "fluid": "impermeable"}],
    "solver": {"damping": 0.2},
    "time": {"end": 1.0},
    "output": {"interval": 0.25}
  })json");
  const std::string run = run_scene(s, "dp-hard-inclined");
  const double rho_g = 9810.0, H = 0.5, h = 0.025;
  double worst_point = 0.0, worst_cell = 0.0, worst_corner = 0.0, v_max = 0.0, checker = 0.0;
  for_each_frame(run, "fluid", [&](const swmpm::scene::PointCloud& f, double t) {
    if (t < 0.2) return;
    const auto& p = f.get("pore_pressure", "fluid").values;
    const auto& v = f.get("velocity", "fluid").values;
    std::vector<double> excess(f.size());
    std::map<std::pair<int, int>, std::pair<double, int>> cells;
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double x = f.points[i][0], y = f.points[i][1];
      excess[i] = p[i] - rho_g * (0.5 - y);
      worst_point = std::max(worst_point, std::abs(excess[i]) / (rho_g * H));
      auto& c = cells[{static_cast<int>(x / h), static_cast<int>(y / h)}];
      c.first += excess[i], c.second += 1;
      v_max = std::max(v_max, std::hypot(v[3 * i], v[3 * i + 1]));
    }
    for (const auto& [key, c] : cells) {
      // The two cells where the interface meets a wall (the wedge's edges) stand apart.
      const double xc = (key.first + 0.5) * h, yc = (key.second + 0.5) * h;
      const bool corner = (xc < h || xc > 0.6 - h) && std::abs(yc - (0.4 - 0.5 * xc)) < 1.5 * h;
      double& worst = corner ? worst_corner : worst_cell;
      worst = std::max(worst, std::abs(c.first / c.second) / (rho_g * H));
    }
    checker = std::max(checker, swmpm::testing::cell_checkerboard_indicator(f, p, h, 0.0, 0.0));
  });
  std::printf("inclined interface: cell-averaged |p - rho g d| / (rho g H) %.4f (the two wall corners %.4f), point-wise "
              "%.4f, cell checkerboard %.4f, |v_w| %.2e m/s\n", worst_cell, worst_corner, worst_point, checker, v_max);
  EXPECT_LT(worst_cell, 0.03);
  EXPECT_LT(worst_corner, 0.03);
  EXPECT_LT(worst_point, 0.25);
  EXPECT_LT(checker, 0.02);
  EXPECT_LT(v_max, 1e-2 * std::sqrt(9.81 * H));
}

// (b) The seepage layer of examples/seepage-double-point with 4 mm grains under the same pond:
// kappa = 1.9e-8 m^2, and at the flux the inertial term beta rho q (~2e5) is 4x the viscous mu / kappa
// (5e4). The run stays bounded (pressure in [0, rho g (H + L)]), and the flux follows Ergun's root,
// 2.6x below Darcy's.
TEST(DoublePointHardCases, ErgunDominatedSeepageStaysBoundedAndFollowsErgun) {
  json s = load_json(SWMPM_SOURCE_DIR "/examples/seepage-double-point/scene-ergun.json");
  s["materials"][0]["grain_diameter"] = 0.004;
  s["time"]["end"] = 0.6;
  s["output"]["interval"] = 0.1;
  const std::string run = run_scene(s, "dp-hard-ergun");
  const auto flux = swmpm::testing::seepage_flux(run, 0.004, 0.1, 0.6);
  const double q = flux.q, q_ergun = flux.q_ergun, q_darcy = flux.q_darcy, rho = 1000, g = 9.81;
  double p_min = 1e300, p_max = -1e300;
  for_each_frame(run, "fluid", [&](const swmpm::scene::PointCloud& f, double) {
    const auto& p = f.get("pore_pressure", "fluid").values;
    for (std::size_t k = 0; k < f.size(); ++k)  // the layer and the pond (below: the drops hit the floor)
      if (f.points[k][1] > 0.3) p_min = std::min(p_min, p[k]), p_max = std::max(p_max, p[k]);
  });
  std::printf("Ergun-dominated seepage: q %.4f m/s, Ergun %.4f (%+.1f %%), Darcy %.4f; beta rho q / (mu / kappa) = %.1f; "
              "p in the layer and pond in [%.0f, %.0f] Pa\n", q, q_ergun, 100 * (q / q_ergun - 1), q_darcy, flux.inertial_over_viscous, p_min, p_max);
  EXPECT_GT(flux.inertial_over_viscous, 2.0);
  EXPECT_NEAR(q / q_ergun, 1.0, 0.25);
  EXPECT_LT(q, 0.6 * q_darcy);
  EXPECT_GE(p_min, 0.0);
  // The layer opens from a hydrostatic start: the rarefaction and the pond's rebound overshoot the
  // hydrostatic 5.9 kPa to about twice it, then settle.
  EXPECT_LT(p_max, 2.5 * rho * g * 0.6);
}

// (c) C1's column with kappa = 1e-14 m^2 (k = 1e-7 m/s): the auto dt is that of kappa = 1.0214e-10
// (the drag is implicit per node and sets no limit), and the response stays undrained and bounded.
TEST(DoublePointHardCases, VeryLowPermeabilityRunsAtTheDefaultStep) {
  json s = load_json(SWMPM_SOURCE_DIR "/examples/consolidation-double-point/scene.json");
  s["time"]["end"] = 0.1;
  const std::string ref = run_scene(s, "dp-hard-kappa-ref");
  s["materials"][0]["intrinsic_permeability"] = 1e-14;
  const std::string run = run_scene(s, "dp-hard-kappa-low");
  const auto j_ref = load_json(ref + "/run.json"), j = load_json(run + "/run.json");
  std::printf("kappa 1e-14: dt %.4e s (kappa 1.02e-10: %.4e s), steps %d\n", j.at("dt").get<double>(),
              j_ref.at("dt").get<double>(), j.at("steps").get<int>());
  EXPECT_EQ(j.at("status"), "completed");
  EXPECT_NEAR(j.at("dt").get<double>() / j_ref.at("dt").get<double>(), 1.0, 1e-6);
  // Undrained: below the top 0.1 m the pressure stays at p0 = 10 kPa.
  const auto f = swmpm::testing::last_frame(run, "fluid");
  const auto& p = f.get("pore_pressure", "fluid").values;
  double worst = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i)
    if (f.points[i][1] < 0.9) worst = std::max(worst, std::abs(p[i] - 1e4) / 1e4);
  std::printf("kappa 1e-14: max |p - p0| / p0 below 0.9 m %.4f\n", worst);
  EXPECT_LT(worst, 0.02);
}

// (d) A free-water column (0.2 x 0.4 m, K_L = 2 MPa) whose upper half starts at +1 m/s and lower
// half at -1 m/s: the split would put ~45 kPa of tension in the middle (rho c dv / 2). With
// cavitation_threshold = 5 kPa the pressure never falls below -5 kPa, the bound is reached, and the
// run stays bounded (energy check).
TEST(DoublePointHardCases, TensionIsBoundedByTheCavitationThreshold) {
  const json s = json::parse(R"json({
    "name": "tension", "dimension": 2, "formulation": "explicit-double-point", "gravity": [0, 0],
    "grid": {"cell_size": 0.025, "min": [0, 0], "max": [0.2, 0.4], "shape_function": "gimp"},
    "materials": [{"name": "water", "model": "fluid", "density": 1000, "bulk_modulus": 2e6, "cavitation_threshold": 5000}],
    "bodies": [{"name": "column", "geometry": {"type": "box", "min": [0, 0], "max": [0.2, 0.4]}, "fluid": "water",
                "initial": {"velocity": ["0", "y > 0.2 ? 1 : -1"]}}],
    "boundaries": [{"on": "x_min", "fluid": "impermeable"}, {"on": "x_max", "fluid": "impermeable"}],
    "time": {"end": 0.02},
    "output": {"interval": 0.002}
  })json");
  const std::string run = run_scene(s, "dp-hard-tension");
  double p_min = 1e300, p_max = -1e300;
  for_each_frame(run, "fluid", [&](const swmpm::scene::PointCloud& f, double) {
    for (double p : f.get("pore_pressure", "fluid").values) p_min = std::min(p_min, p), p_max = std::max(p_max, p);
  });
  const auto j = load_json(run + "/run.json");
  std::printf("tension: p in [%.1f, %.1f] Pa (threshold -5000), status %s\n", p_min, p_max,
              j.at("status").get<std::string>().c_str());
  EXPECT_EQ(j.at("status"), "completed");
  EXPECT_GE(p_min, -5000.0 - 1e-9);
  EXPECT_LT(p_min, -4000.0);  // the bound is reached
}
