// --threads must not change results: a 2D block under a ramped gravity and a partial traction,
// with friction at the base, run with 1 and 2 threads, gives bitwise identical monitors.csv and
// final frames. The block has 8000 particles (above solver/common.hpp's parallel_threshold) on a
// grid 120 cells wide, so the scatter schedule has many stripes to share between the threads.
#include <gtest/gtest.h>

#include <initializer_list>

#include "support/run_helpers.hpp"

namespace {

nlohmann::json block_scene() {
  return nlohmann::json::parse(R"({
    "name": "threads", "dimension": 2, "formulation": "dry",
    "gravity": [0.0, -9.81], "gravity_ramp": 0.05,
    "grid": { "cell_size": 0.05, "min": [0.0, 0.0], "max": [6.0, 1.5], "shape_function": "gimp" },
    "materials": [ { "name": "m", "model": "hencky", "density": 2000.0,
                     "youngs_modulus": 5.0e6, "poisson_ratio": 0.3 } ],
    "bodies": [ { "name": "block", "geometry": { "type": "box", "min": [0.5, 0.0], "max": [5.5, 1.0] },
                  "solid": "m", "particles_per_cell": 2 } ],
    "boundaries": [ { "on": "y_min", "solid": "friction", "coefficient": 0.3 },
                    { "on": "x_min", "solid": "roller" }, { "on": "x_max", "solid": "roller" } ],
    "loads": [ { "type": "traction", "body": "block", "face": "y_max", "value": [2.0e3, -2.0e4],
                 "region": { "min": [1.0, 0.9], "max": [2.0, 1.0] }, "ramp": 0.05 } ],
    "time": { "end": 0.06, "dt": "auto", "cfl": 0.5 },
    "output": { "interval": 0.03, "monitors": [
      { "name": "p", "at": [1.5, 1.0], "phase": "solid", "quantities": ["displacement_x", "displacement_y", "stress_yy"] },
      { "name": "energy", "quantities": ["kinetic_energy", "strain_energy", "external_work"] } ] }
  })");
}

/// Two frames hold the same points at bitwise equal positions and `arrays` bitwise equal.
void expect_identical_frames(const swmpm::scene::PointCloud& f1, const swmpm::scene::PointCloud& f2,
                             std::initializer_list<const char*> arrays) {
  ASSERT_EQ(f1.size(), f2.size());
  for (std::size_t p = 0; p < f1.size(); ++p)
    for (int a = 0; a < 3; ++a) ASSERT_EQ(f1.points[p][a], f2.points[p][a]) << "point " << p;
  for (const char* field : arrays) {
    const auto& a1 = f1.get(field, "1").values;
    const auto& a2 = f2.get(field, "2").values;
    ASSERT_EQ(a1.size(), a2.size()) << field;
    for (std::size_t k = 0; k < a1.size(); ++k) ASSERT_EQ(a1[k], a2[k]) << field << " entry " << k;
  }
}

}  // namespace

TEST(Threads, OneAndTwoThreadsGiveIdenticalResults) {
  const std::string one = swmpm::testing::run_scene(block_scene(), "threads1", 1);
  const std::string two = swmpm::testing::run_scene(block_scene(), "threads2", 2);
  const std::string m1 = swmpm::testing::read_text(one + "/monitors.csv");
  const std::string m2 = swmpm::testing::read_text(two + "/monitors.csv");
  ASSERT_GT(m1.size(), 1000u);
  EXPECT_EQ(m1, m2);
  expect_identical_frames(swmpm::testing::last_frame(one), swmpm::testing::last_frame(two), {"stress"});
  // The run did something: the loaded area moved.
  const auto run = swmpm::testing::load_json(one + "/run.json");
  EXPECT_EQ(run["status"], "completed");
  EXPECT_GT(run["steps"].get<long>(), 50);
  EXPECT_EQ(run["particles"]["solid"].get<long>(), 8000);
}

namespace {

/// explicit-single-point on A5 (the soft saturated block slumping under a gravity ramp) at twice the
/// resolution (4096 particles, above the parallel threshold) with `solver` merged into the scene's
/// solver keys: monitors and the last frame's positions and `arrays` bitwise equal on 1 and 2 threads,
/// and the run did something (the block is slumping and the pore pressure rising).
void expect_explicit_a5_thread_invariant(const nlohmann::json& solver, const std::string& name,
                                         std::initializer_list<const char*> arrays) {
  nlohmann::json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/self-weight-consolidation/scene.json");
  s["grid"]["cell_size"] = 0.0625;
  s["time"]["end"] = 0.006;
  s["output"]["interval"] = 0.006;
  s["output"]["monitor_interval"] = 0.0002;
  s["solver"].merge_patch(solver);
  const std::string one = swmpm::testing::run_scene(s, name + "-1", 1);
  const std::string two = swmpm::testing::run_scene(s, name + "-2", 2);
  EXPECT_EQ(swmpm::testing::read_text(one + "/monitors.csv"), swmpm::testing::read_text(two + "/monitors.csv"));
  const auto f1 = swmpm::testing::last_frame(one);
  const auto f2 = swmpm::testing::last_frame(two);
  ASSERT_EQ(f1.size(), 4096u);
  expect_identical_frames(f1, f2, arrays);
  double p_max = 0;
  for (double p : f1.get("pore_pressure", "1").values) p_max = std::max(p_max, p);
  EXPECT_GT(p_max, 100.0);
}

}  // namespace

// The default stabilisation (strain smoothing + linear MFVP).
TEST(Threads, ExplicitSinglePointOneAndTwoThreadsGiveIdenticalResults) {
  expect_explicit_a5_thread_invariant(nlohmann::json::object(), "threads-esp", {"pore_pressure", "stress"});
}

// The cell-constant pressure with the conservative continuity (cell sums and the nodal porosity go
// through the scatter schedule).
TEST(Threads, ExplicitCellConstantPressureOneAndTwoThreadsGiveIdenticalResults) {
  expect_explicit_a5_thread_invariant(
      {{"continuity", "conservative"}, {"stabilisation", {{"pressure", "cell-constant"}}}}, "threads-cc",
      {"pore_pressure", "stress", "porosity"});
}

// The F-bar stage (solver/transfer/fbar.hpp) keeps this: its nodal sums go through the scatter
// schedule and its patch sums through a schedule of patch rows. The dry block with the modified
// F-bar, cell-wise on GIMP and patch-wise (1.5 h) on quadratic B-splines (which includes the standard F-bar
// on B-splines; and A5 (explicit-single-point, strain smoothing on) with the modified F-bar.
TEST(Threads, FBarOneAndTwoThreadsGiveIdenticalResults) {
  struct Variant {
    const char* shape;
    const char* fbar;
    double patch;
  };
  for (const Variant v : {Variant{"gimp", "modified", 1.0}, Variant{"bspline2", "modified", 1.5}}) {
    nlohmann::json s = block_scene();
    s["grid"]["shape_function"] = v.shape;
    s["solver"]["stabilisation"] = {{"fbar", v.fbar}};
    if (v.patch > 0.0) s["solver"]["stabilisation"]["fbar_patch"] = v.patch;
    const std::string tag = std::string("threads-fbar-") + v.shape + "-" + v.fbar;
    const std::string one = swmpm::testing::run_scene(s, tag + "-1", 1);
    const std::string two = swmpm::testing::run_scene(s, tag + "-2", 2);
    const std::string m1 = swmpm::testing::read_text(one + "/monitors.csv");
    ASSERT_GT(m1.size(), 1000u);
    EXPECT_EQ(m1, swmpm::testing::read_text(two + "/monitors.csv")) << tag;
    const auto f1 = swmpm::testing::last_frame(one);
    const auto f2 = swmpm::testing::last_frame(two);
    ASSERT_EQ(f1.size(), f2.size());
    for (const char* field : {"stress", "volume_ratio", "displacement"}) {
      const auto& a1 = f1.get(field, "1").values;
      const auto& a2 = f2.get(field, "2").values;
      for (std::size_t k = 0; k < a1.size(); ++k) ASSERT_EQ(a1[k], a2[k]) << tag << " " << field << " entry " << k;
    }
    const auto run = swmpm::testing::load_json(one + "/run.json");
    EXPECT_TRUE(run["stage_seconds"].contains("f-bar")) << tag;
  }
  nlohmann::json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/self-weight-consolidation/scene.json");
  s["grid"]["cell_size"] = 0.0625;
  s["time"]["end"] = 0.006;
  s["output"]["interval"] = 0.006;
  s["output"]["monitor_interval"] = 0.0002;
  s["solver"]["stabilisation"]["fbar"] = "modified";
  const std::string one = swmpm::testing::run_scene(s, "threads-fbar-esp-1", 1);
  const std::string two = swmpm::testing::run_scene(s, "threads-fbar-esp-2", 2);
  EXPECT_EQ(swmpm::testing::read_text(one + "/monitors.csv"), swmpm::testing::read_text(two + "/monitors.csv"));
  const auto f1 = swmpm::testing::last_frame(one);
  const auto f2 = swmpm::testing::last_frame(two);
  ASSERT_EQ(f1.size(), 4096u);
  for (const char* field : {"pore_pressure", "stress", "porosity"}) {
    const auto& a1 = f1.get(field, "1").values;
    const auto& a2 = f2.get(field, "2").values;
    for (std::size_t k = 0; k < a1.size(); ++k) ASSERT_EQ(a1[k], a2[k]) << field << " entry " << k;
  }
}

// Double-point with `solver.escaped_water: remove`: B2's column widened to 0.8 m (5120 soil and
// 5120 water points, above the parallel threshold), 0.1 s, while the squeezed-out water leaves the
// top: the removal (a parallel test per point, a serial order-keeping compaction) and everything
// after it are bitwise equal on 1 and 2 threads.
TEST(Threads, DoublePointEscapedWaterOneAndTwoThreadsGiveIdenticalResults) {
  nlohmann::json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR
                                               "/examples/large-strain-consolidation-semi-implicit/scene-double-point.json");
  s["grid"]["max"][0] = 0.8;
  s["bodies"][0]["geometry"]["max"][0] = 0.8;
  s["time"]["end"] = 0.1;
  s["output"]["interval"] = 0.05;
  const std::string one = swmpm::testing::run_scene(s, "threads-dp-escaped-1", 1);
  const std::string two = swmpm::testing::run_scene(s, "threads-dp-escaped-2", 2);
  EXPECT_EQ(swmpm::testing::read_text(one + "/monitors.csv"), swmpm::testing::read_text(two + "/monitors.csv"));
  const auto r1 = swmpm::testing::load_json(one + "/run.json");
  const auto r2 = swmpm::testing::load_json(two + "/run.json");
  EXPECT_EQ(r1["status"], "completed");
  EXPECT_GT(r1["counters"]["escaped_water_points"].get<double>(), 0.0);  // the removal happened
  EXPECT_EQ(r1["counters"], r2["counters"]);
  EXPECT_EQ(r1["particles"], r2["particles"]);
  expect_identical_frames(swmpm::testing::last_frame(one, "fluid"), swmpm::testing::last_frame(two, "fluid"),
                          {"pore_pressure", "velocity"});
}

// explicit-double-point: the column collapse (3200 solid and 3200 liquid points, above the
// parallel threshold), 0.15 s: both scatters through their schedules, the liquid's pressure-rate
// projection, the per-material stress lists that leave liquefied points out.
TEST(Threads, ExplicitDoublePointOneAndTwoThreadsGiveIdenticalResults) {
  nlohmann::json s =
      swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/column-collapse-double-point/scene.json");
  s["time"]["end"] = 0.15;
  s["output"]["interval"] = 0.05;
  const std::string one = swmpm::testing::run_scene(s, "threads-edp-1", 1);
  const std::string two = swmpm::testing::run_scene(s, "threads-edp-2", 2);
  EXPECT_EQ(swmpm::testing::read_text(one + "/monitors.csv"), swmpm::testing::read_text(two + "/monitors.csv"));
  expect_identical_frames(swmpm::testing::last_frame(one, "fluid"), swmpm::testing::last_frame(two, "fluid"),
                          {"pore_pressure", "velocity", "porosity", "free_surface"});
  expect_identical_frames(swmpm::testing::last_frame(one, "solid"), swmpm::testing::last_frame(two, "solid"),
                          {"stress", "velocity", "porosity", "liquefied", "pore_pressure"});
}

// mpm-fem: D1 for 0.02 s (2400 soil points with 4 x 4 per cell, above the parallel threshold): the
// fluid's and the phase field's cell assembly in colours, the soil forces per cell, the Krylov
// solve with the reused factor.
TEST(Threads, MpmFemOneAndTwoThreadsGiveIdenticalResults) {
  nlohmann::json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-mpm-fem/scene.json");
  s["bodies"][0]["particles_per_cell"] = 4;
  s["time"]["dt"] = 1e-4;
  s["time"]["end"] = 0.02;
  s["output"]["interval"] = 0.02;
  const std::string one = swmpm::testing::run_scene(s, "threads-mpmfem-1", 1);
  const std::string two = swmpm::testing::run_scene(s, "threads-mpmfem-2", 2);
  EXPECT_EQ(swmpm::testing::read_text(one + "/monitors.csv"), swmpm::testing::read_text(two + "/monitors.csv"));
  expect_identical_frames(swmpm::testing::last_frame(one, "solid"), swmpm::testing::last_frame(two, "solid"),
                          {"stress", "velocity", "pore_pressure"});
  expect_identical_frames(swmpm::testing::last_frame(one, "grid"), swmpm::testing::last_frame(two, "grid"),
                          {"fluid_velocity", "pressure", "phase_field", "porosity"});
}

// The semi-implicit formulations with quadratic B-splines: the pressure operators come from cell
// moments (transfer/cell_moments.hpp: points add to their cell through the schedule, cells are
// reduced in two colours of stripes), the node fits and the F-bar through the schedule. B4's slope
// at cell 1.0 m and 3 x 3 points per cell (6003 soil points, above the parallel threshold; 45
// cells across: 8 stripes of cells per colour), 0.1 s, single- and double-point.
TEST(Threads, SemiImplicitBSplineOneAndTwoThreadsGiveIdenticalResults) {
  for (const char* formulation : {"semi-implicit-single-point", "semi-implicit-double-point"}) {
    nlohmann::json s = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/slope-stability-mohr-coulomb/scene.json");
    s["formulation"] = formulation;
    s["grid"]["cell_size"] = 1.0;
    s["grid"]["shape_function"] = "bspline2";
    s["bodies"][0]["particles_per_cell"] = 3;
    s["time"]["dt"] = 0.004;
    s["time"]["end"] = 0.1;
    s["output"]["interval"] = 0.1;
    s["output"]["monitor_interval"] = 0.004;
    const std::string tag = std::string("threads-") + formulation;
    const std::string one = swmpm::testing::run_scene(s, tag + "-1", 1);
    const std::string two = swmpm::testing::run_scene(s, tag + "-2", 2);
    const std::string m1 = swmpm::testing::read_text(one + "/monitors.csv");
    ASSERT_GT(m1.size(), 1000u) << tag;
    EXPECT_EQ(m1, swmpm::testing::read_text(two + "/monitors.csv")) << tag;
    const auto r1 = swmpm::testing::load_json(one + "/run.json");
    const auto r2 = swmpm::testing::load_json(two + "/run.json");
    ASSERT_EQ(r1["status"], "completed") << tag;
    ASSERT_EQ(r2["status"], "completed") << tag;
    EXPECT_EQ(r2["threads"], 2) << tag;
    EXPECT_GT(r1["particles"]["solid"].get<double>(), 2048.0) << tag;
    EXPECT_EQ(r1["counters"], r2["counters"]) << tag;
    expect_identical_frames(swmpm::testing::last_frame(one), swmpm::testing::last_frame(two),
                            {"pore_pressure", "stress", "velocity", "porosity"});
    if (std::string(formulation) == "semi-implicit-double-point")
      expect_identical_frames(swmpm::testing::last_frame(one, "fluid"), swmpm::testing::last_frame(two, "fluid"),
                              {"pore_pressure", "velocity", "porosity"});
  }
}
