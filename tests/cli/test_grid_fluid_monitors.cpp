// Monitors of a fluid on the grid (mpm-fem; solver/output/monitors.hpp): a monitor with
// "phase": "fluid" and `at` is an Eulerian probe that reads Formulation::grid_value at its fixed
// point every row, and a water_level gauge reads Formulation::grid_water_level; the loop reads
// particles/phase_field.vtu into State::phase_field (and refuses a run directory without it).
// A fake formulation with known grid values stands in for the mpm-fem solver: it moves nothing
// and returns closed forms of the point, the quantity and the time.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <string>

#include "postprocess/postprocess.hpp"
#include "preprocess/preprocess.hpp"
#include "scene/scene.hpp"
#include "solver/formulation.hpp"
#include "solver/run.hpp"
#include "support/mpm_fem_scene.hpp"
#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::Formulation;
using swmpm::GridQuantity;
using swmpm::State;
using swmpm::StepContext;

/// The fake's grid values at x and time t: pressure 1e4 + 100 x + 1000 y + t [Pa], velocity
/// component a: (a + 1) (x + t) [m/s]; the water level at x: 0.3 + x + t [m].
double known_value(const std::array<double, 3>& x, GridQuantity q, double t) {
  switch (q) {
    case GridQuantity::pressure: return 1e4 + 100 * x[0] + 1000 * x[1] + t;
    case GridQuantity::velocity_x: return 1 * (x[0] + t);
    case GridQuantity::velocity_y: return 2 * (x[0] + t);
    case GridQuantity::velocity_z: return 3 * (x[0] + t);
    case GridQuantity::phase: return 0.5;
  }
  return NAN;
}
double known_level(double x, double t) { return 0.3 + x + t; }

/// A formulation whose fluid is on the grid with known values; the particles stay where they are.
class GridFluid : public Formulation<2> {
 public:
  GridFluid(const State<2>& st, std::size_t& phase_field_nodes) { phase_field_nodes = st.phase_field.size(); }
  std::string name() const override { return "mpm-fem"; }
  double critical_time_step(const State<2>&, std::string& r) const override {
    r = "the fake's constant";
    return 1.0;
  }
  void step(State<2>&, const StepContext& ctx) override { t_ = ctx.t + ctx.dt; }
  double kinetic_energy(const State<2>&) const override { return 0.0; }
  double strain_energy(const State<2>&) const override { return 0.0; }
  double external_power(const State<2>&, const StepContext&) const override { return 0.0; }
  void set_initialisation(State<2>&, const swmpm::scene::Initialisation*) override {}
  std::size_t active_cells(const State<2>&) const override { return 0; }
  void save(swmpm::Checkpoint&) const override {}
  void restore(const swmpm::Checkpoint&, State<2>&) override {}
  bool fluid_on_grid() const override { return true; }
  double grid_value(const std::array<double, 3>& x, GridQuantity q) const override { return known_value(x, q, t_); }
  double grid_water_level(double x, double /*z*/) const override { return known_level(x, t_); }

 private:
  double t_ = 0.0;  // s, the end of the last step
};

/// Preprocesses `scene` (scene.json, particles/solid.vtu, particles/phase_field.vtu).
std::string write_run_directory(const json& scene, const std::string& name) {
  const fs::path dir = swmpm::testing::scratch(name);
  std::ofstream(dir / "scene.json") << scene.dump(2);
  return swmpm::pre::preprocess((dir / "scene.json").string(), (dir / "run").string(), true);
}

json probed_scene() {
  json s = swmpm::testing::mpm_fem_scene();
  s["time"] = {{"end", 0.05}, {"dt", 0.01}};
  s["output"] = {{"interval", 0.0},
                 {"monitors",
                  {{{"name", "probe"}, {"at", {0.1, 0.25}}, {"phase", "fluid"},
                    {"quantities", {"pore_pressure", "velocity_x", "velocity_y"}}},
                   {{"name", "gauge"}, {"at", {0.15}}, {"quantities", {"water_level"}}},
                   {{"name", "bed"}, {"at", {0.2, 0.05}}, {"quantities", {"displacement_y", "pore_pressure"}}}}}};
  return s;
}

int solve_with_fake(const std::string& run, std::size_t& nodes) {
  swmpm::SolveOptions o;
  o.quiet = true;
  return swmpm::solve(
      run, o, [&](const swmpm::scene::Scene&, const State<2>& st) { return std::make_unique<GridFluid>(st, nodes); }, {});
}

}  // namespace

TEST(GridFluidMonitors, ProbesAndGaugesReadTheFormulationsGridValues) {
  const std::string run = write_run_directory(probed_scene(), "grid-fluid-monitors");
  std::size_t nodes = 0;
  ASSERT_EQ(solve_with_fake(run, nodes), 0);
  EXPECT_EQ(nodes, 10u * 12u);  // the phase field preprocess wrote: 8 + 2 by 10 + 2 bspline2 nodes

  const auto table = swmpm::post::read_csv(run + "/monitors.csv");
  EXPECT_EQ(table.names, (std::vector<std::string>{"time", "probe.pore_pressure", "probe.velocity_x", "probe.velocity_y",
                                                   "gauge.water_level", "bed.displacement_y", "bed.pore_pressure"}));
  const auto& t = table.column("time");
  ASSERT_EQ(t.size(), 6u);  // t = 0 and five steps
  const std::array<double, 3> at{0.1, 0.25, 0.0};
  for (std::size_t r = 0; r < t.size(); ++r) {
    EXPECT_NEAR(t[r], 0.01 * static_cast<double>(r), 1e-12);
    // Rows are written with 10 significant digits.
    auto expect = [&](const std::string& column, double value) {
      EXPECT_NEAR(table.column(column)[r], value, 1e-9 * std::abs(value)) << column << " at t = " << t[r];
    };
    expect("probe.pore_pressure", known_value(at, GridQuantity::pressure, t[r]));
    expect("probe.velocity_x", known_value(at, GridQuantity::velocity_x, t[r]));
    expect("probe.velocity_y", known_value(at, GridQuantity::velocity_y, t[r]));
    expect("gauge.water_level", known_level(0.15, t[r]));
    // A soil point's monitor is as in the other formulations: its own pore pressure (0 here: no
    // initial state given), the displacement of a point the fake does not move.
    EXPECT_EQ(table.column("bed.displacement_y")[r], 0.0);
    EXPECT_EQ(table.column("bed.pore_pressure")[r], 0.0);
  }
  const std::string log = swmpm::testing::read_text(run + "/log.txt");
  EXPECT_NE(log.find("monitor probe: fixed point (0.1, 0.25) of the grid's fluid (Eulerian probe: pore_pressure = the "
                     "fluid's pressure, velocity_x, velocity_y interpolated from the nodes)"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("monitor gauge: water level on the vertical line x = 0.15 (the highest height where the grid's "
                     "phase field phi crosses 1/2)"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("monitor bed: follows solid particle "), std::string::npos) << log;
}

TEST(GridFluidMonitors, RefusedQuantitiesAndAMissingPhaseField) {
  // A probe records the fluid's pressure and velocity only.
  json s = probed_scene();
  s["output"]["monitors"] = {{{"name", "probe"}, {"at", {0.1, 0.25}}, {"phase", "fluid"}, {"quantities", {"stress_yy"}}}};
  std::size_t nodes = 0;
  std::string run = write_run_directory(s, "grid-fluid-refused");
  try {
    solve_with_fake(run, nodes);
    ADD_FAILURE() << "accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/output/monitors/0/quantities: \"stress_yy\" is not available at a fixed "
                                         "point of the grid's fluid"),
              std::string::npos)
        << e.what();
  }
  // The solve needs preprocess's phase field.
  run = write_run_directory(probed_scene(), "grid-fluid-no-phase-field");
  fs::remove(run + "/particles/phase_field.vtu");
  try {
    solve_with_fake(run, nodes);
    ADD_FAILURE() << "accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("particles/phase_field.vtu is missing: mpm-fem starts its water from the "
                                         "phase field preprocess writes there; run swmpm preprocess again"),
              std::string::npos)
        << e.what();
  }
}
