// `mpirun -n N swmpm solve RUN_DIR` (solver/parallel/): the same scene and CLI as one rank, the
// same answers bit for bit (the explicit formulations), one results.pvd over per-rank .pvtu
// pieces, monitors.csv once, run.json with the ranks, particles per rank and communication time.
// CI runs as root: OpenMPI's two variables allow it (mpirun refuses root without them).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "support/run_helpers.hpp"

namespace swmpm::testing {
namespace {

/// `mpirun -n N swmpm ARGS` (oversubscribed: N may exceed the cores), output captured under dir.
/// `env`: more VAR=value words for the ranks' environment.
Result mpirun(int n, const std::string& args, const fs::path& dir, const std::string& env = {}) {
  const std::string out = (dir / "stdout.txt").string(), err = (dir / "stderr.txt").string();
  // `timeout`: a rank that waits for ever in a collective fails the test instead of hanging CI.
  const std::string cmd = "timeout 300 env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
                          "OMPI_MCA_mpi_yield_when_idle=1 " + env + " " +
                          std::string(SWMPM_MPIEXEC) + " -n " + std::to_string(n) + " " + SWMPM_EXE + " " + args +
                          " > " + out + " 2> " + err;
  const int raw = std::system(cmd.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, read_text(out), read_text(err)};
}

/// A frame with its points in increasing id (a .pvtu holds each rank's piece in turn); a grid
/// frame (mpm-fem's nodes, no ids: one file in node order) as it is.
scene::PointCloud sorted_by_id(const scene::PointCloud& c) {
  const auto* id = c.find("id");
  if (!id) return c;
  std::vector<std::size_t> order(c.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](auto a, auto b) { return id->values[a] < id->values[b]; });
  scene::PointCloud s = c;
  for (std::size_t k = 0; k < order.size(); ++k) s.points[k] = c.points[order[k]];
  for (std::size_t a = 0; a < c.arrays.size(); ++a) {
    const auto n = static_cast<std::size_t>(c.arrays[a].components);
    for (std::size_t k = 0; k < order.size(); ++k)
      for (std::size_t j = 0; j < n; ++j) s.arrays[a].values[k * n + j] = c.arrays[a].values[order[k] * n + j];
  }
  return s;
}

/// Calls fn(name, values of a, values of b) for the positions ("position", x y z per point) and
/// each array of two frames of the same particles, matched by id. False (and a test failure) when
/// the frames do not hold the same points and arrays.
template <class Fn>
bool for_each_value_array(const scene::PointCloud& a_in, const scene::PointCloud& b_in, Fn&& fn) {
  const auto a = sorted_by_id(a_in), b = sorted_by_id(b_in);
  EXPECT_EQ(a.size(), b.size());
  EXPECT_EQ(a.arrays.size(), b.arrays.size());
  if (a.size() != b.size()) return false;
  std::vector<double> pa, pb;
  for (std::size_t k = 0; k < a.size(); ++k)
    for (int d = 0; d < 3; ++d) pa.push_back(a.points[k][d]), pb.push_back(b.points[k][d]);
  fn(std::string("position"), pa, pb);
  for (const auto& arr : a.arrays) {
    const auto* other = b.find(arr.name);
    EXPECT_NE(other, nullptr) << arr.name;
    if (!other) return false;
    fn(arr.name, arr.values, other->values);
  }
  return true;
}

/// Number of values that differ (bitwise) between two frames of the same particles, matched by id
/// (NaN equals NaN: a field not defined yet, such as Nor-Sand's state parameter at t = 0).
long differing_values(const scene::PointCloud& a, const scene::PointCloud& b) {
  long differ = 0;
  const bool same_points = for_each_value_array(a, b, [&](const std::string&, const auto& va, const auto& vb) {
    for (std::size_t k = 0; k < va.size(); ++k) differ += !(va[k] == vb[k] || (std::isnan(va[k]) && std::isnan(vb[k])));
  });
  return same_points ? differ : -1;
}

/// A granular column collapsing as it slides to the right at 1.5 m/s over a smooth floor: the
/// slide carries every point across the cut between the ranks (balanced on the column's points at
/// the start), so particles migrate and the cuts move to follow them.
nlohmann::json column_collapse(int dim, const std::string& shape) {
  const bool three = dim == 3;
  nlohmann::json s = {
      {"name", "collapse"},
      {"dimension", dim},
      {"formulation", "dry"},
      {"gravity", three ? nlohmann::json{0.0, -9.81, 0.0} : nlohmann::json{0.0, -9.81}},
      {"grid",
       {{"cell_size", three ? 0.04 : 0.02},
        {"min", three ? nlohmann::json{0.0, 0.0, 0.0} : nlohmann::json{0.0, 0.0}},
        {"max", three ? nlohmann::json{0.8, 0.28, 0.12} : nlohmann::json{0.8, 0.3}},
        {"shape_function", shape}}},
      {"materials",
       {{{"name", "sand"}, {"model", "mohr-coulomb"}, {"density", 1800.0}, {"youngs_modulus", 2e6},
         {"poisson_ratio", 0.3}, {"cohesion", 0.0}, {"friction_angle", 30.0}, {"dilation_angle", 0.0}}}},
      {"bodies",
       {{{"name", "column"},
         {"geometry",
          {{"type", "box"},
           {"min", three ? nlohmann::json{0.0, 0.0, 0.0} : nlohmann::json{0.0, 0.0}},
           {"max", three ? nlohmann::json{0.2, 0.2, 0.12} : nlohmann::json{0.2, 0.2}}}},
         {"solid", "sand"},
         {"particles_per_cell", 2},
         {"initial", {{"velocity", three ? nlohmann::json{1.5, 0.0, 0.0} : nlohmann::json{1.5, 0.0}}}}}}},
      {"boundaries",
       {{{"on", "x_min"}, {"solid", "roller"}}, {{"on", "x_max"}, {"solid", "roller"}},
        {{"on", "y_min"}, {"solid", "roller"}}}},
      {"time", {{"end", three ? 0.25 : 0.3}, {"dt", "auto"}, {"cfl", 0.5}}},
      {"solver", {{"flip", 0.99}, {"damping", 0.0}}},
      {"output",
       {{"interval", 0.1},
        {"monitor_interval", 0.01},
        {"monitors",
         {{{"name", "toe"}, {"at", three ? nlohmann::json{0.19, 0.01, 0.06} : nlohmann::json{0.19, 0.01}},
           {"phase", "solid"}, {"quantities", {"displacement_x", "velocity_x"}}},
          {{"name", "top"}, {"at", three ? nlohmann::json{0.01, 0.19, 0.06} : nlohmann::json{0.01, 0.19}},
           {"phase", "solid"}, {"quantities", {"displacement_y", "stress_yy"}}},
          {{"name", "energy"}, {"quantities", {"kinetic_energy", "strain_energy"}}}}}}}};
  if (three) s["boundaries"].push_back({{"on", "z_min"}, {"solid", "roller"}}), s["boundaries"].push_back({{"on", "z_max"}, {"solid", "roller"}});
  return s;
}

struct Pair {
  fs::path dir;
  std::string one, many;
  Result one_result, many_result;
};

/// Preprocess once; solve the run on one rank (no mpirun) and on `ranks` ranks, one thread each.
Pair solve_both(const nlohmann::json& scene, const std::string& name, int ranks) {
  Pair p;
  p.dir = scratch(name);
  std::ofstream(p.dir / "scene.json") << scene.dump(2);
  p.one = (p.dir / "one").string();
  p.many = (p.dir / "many").string();
  EXPECT_EQ(swmpm_cmd("preprocess " + (p.dir / "scene.json").string() + " -o " + p.one + " -q", p.dir).status, 0);
  EXPECT_EQ(swmpm_cmd("preprocess " + (p.dir / "scene.json").string() + " -o " + p.many + " -q", p.dir).status, 0);
  p.one_result = swmpm_cmd("solve " + p.one + " -q --threads 1", p.dir);
  p.many_result = mpirun(ranks, "solve " + p.many + " -q --threads 1", p.dir);
  EXPECT_EQ(p.one_result.status, 0) << p.one_result.err;
  EXPECT_EQ(p.many_result.status, 0) << p.many_result.err;
  return p;
}

/// run.json's stability record of `many` (each rank measures its share of the sets with copies of
/// the points near it) against the one-rank run's: every indicator of every frame within
/// `tolerance` of its value (relative; absolute below 1: the indicators are ratios, and the
/// energy error a small difference of large sums); with `places`, each worst value found at the same point
/// (position included).
/// A bitwise run differs only in the order of the sums over the ranks (the checkerboard's sum of
/// squares, the energies): round-off.
void expect_same_stability(const Pair& p, double tolerance, bool places) {
  const auto one = load_json(p.one + "/run.json")["stability"], many = load_json(p.many + "/run.json")["stability"];
  ASSERT_EQ(one["frames"]["time"].size(), many["frames"]["time"].size());
  EXPECT_GT(one["frames"]["time"].size(), 1u);
  for (const auto& [key, values] : one["frames"].items()) {
    const auto& other = many["frames"][key];
    ASSERT_EQ(values.size(), other.size()) << key;
    for (std::size_t k = 0; k < values.size(); ++k) {
      EXPECT_EQ(values[k].is_null(), other[k].is_null()) << key << ", frame " << k;
      if (values[k].is_null() || other[k].is_null()) continue;
      const double a = values[k], b = other[k];
      EXPECT_LE(std::abs(a - b), tolerance * std::max(std::abs(a), 1.0)) << key << ", frame " << k;
    }
  }
  for (const auto& [key, worst] : one["worst"].items()) {
    const auto& other = many["worst"][key];
    EXPECT_EQ(worst.is_null(), other.is_null()) << key;
    if (worst.is_null() || other.is_null()) continue;
    // (A run that follows to a tolerance may find a worst value at a mirror point of a symmetric
    // body: equal values to round-off.)
    if (places) {
      EXPECT_EQ(worst["where"].dump(), other["where"].dump()) << key;
    }
    EXPECT_EQ(worst["crossed_frames"], other["crossed_frames"]) << key;
  }
  EXPECT_EQ(one["warnings"].size(), many["warnings"].size());
}

/// Every frame of `many` equals the one-rank frame bit for bit; monitors.csv is the same file;
/// the stability indicators are the one-rank run's to round-off, found at the same points.
void expect_same_answers(const Pair& p) {
  const auto one = scene::read_pvd(p.one + "/output/results.pvd");
  const auto many = scene::read_pvd(p.many + "/output/results.pvd");
  ASSERT_EQ(one.size(), many.size());
  for (std::size_t k = 0; k < one.size(); ++k) {
    EXPECT_EQ(one[k].time, many[k].time);
    EXPECT_EQ(one[k].group, many[k].group);
    const auto a = scene::read_vtu(p.one + "/output/" + one[k].file);
    const auto b = scene::read_vtu(p.many + "/output/" + many[k].file);
    if (one[k].group == "grid") {  // the grid's nodes (mpm-fem), one file from rank 0, in node order
      EXPECT_EQ(a.points, b.points);
      ASSERT_EQ(a.arrays.size(), b.arrays.size());
      for (std::size_t j = 0; j < a.arrays.size(); ++j) EXPECT_EQ(a.arrays[j].values, b.arrays[j].values) << a.arrays[j].name;
      continue;
    }
    EXPECT_EQ(many[k].file.substr(many[k].file.size() - 5), ".pvtu");
    EXPECT_EQ(differing_values(a, b), 0) << "frame " << k << " (t = " << one[k].time << " s)";
  }
  EXPECT_EQ(read_text(p.one + "/monitors.csv"), read_text(p.many + "/monitors.csv"));
  expect_same_stability(p, 1e-12, true);
}

TEST(Mpirun, DryCollapseOnTwoRanksIsBitwiseTheOneRankRun2D) {
  const Pair p = solve_both(column_collapse(2, "bspline2"), "mpirun-dry-2d", 2);
  expect_same_answers(p);
  const auto rj = load_json(p.many + "/run.json");
  EXPECT_EQ(rj["ranks"], 2);
  const long total = rj["particles"]["solid"];
  const long lo = rj["particles_per_rank"]["min"], hi = rj["particles_per_rank"]["max"];
  EXPECT_EQ(total, 400);
  EXPECT_EQ(rj["particles_per_rank"]["each"][0].get<long>() + rj["particles_per_rank"]["each"][1].get<long>(), total);
  EXPECT_GT(lo, 0);
  EXPECT_LE(lo, hi);
  EXPECT_GT(rj["communication_seconds"]["max"].get<double>(), 0.0);
  // The slide crossed the cut (every point at least once), and the cuts moved to follow it: at the
  // end the ranks hold 400 / 2 within the 5 % the rebalancing allows (and the stripes' granularity).
  EXPECT_GT(rj["counters"]["particles migrated"].get<double>(), 400.0);
  EXPECT_GE(rj["counters"]["rebalances"].get<double>(), 2.0);
  EXPECT_LE(hi, 240);
  // One monitors.csv, one results.pvd; each frame's pieces, one per rank.
  EXPECT_TRUE(fs::exists(p.many + "/output/solid_000001_0.vtu"));
  EXPECT_TRUE(fs::exists(p.many + "/output/solid_000001_1.vtu"));
  EXPECT_EQ(load_json(p.one + "/run.json")["ranks"], 1);
}

TEST(Mpirun, DryCollapseOnTwoRanksIsBitwiseTheOneRankRun3D) {
  const Pair p = solve_both(column_collapse(3, "gimp"), "mpirun-dry-3d", 2);
  expect_same_answers(p);
  const auto rj = load_json(p.many + "/run.json");
  EXPECT_GT(rj["counters"]["particles migrated"].get<double>(), 600.0);
  EXPECT_GE(rj["counters"]["rebalances"].get<double>(), 1.0);
}

TEST(Mpirun, DryCollapseOnFourOversubscribedRanksIsBitwiseTheOneRankRun) {
  // Four ranks on two cores: a correctness check only (their speed means nothing here).
  const Pair p = solve_both(column_collapse(2, "linear"), "mpirun-dry-4", 4);
  expect_same_answers(p);
  EXPECT_EQ(load_json(p.many + "/run.json")["particles_per_rank"]["each"].size(), 4u);
}

/// The column of column_collapse saturated with water (explicit-single-point): its pore pressure
/// builds up as the column collapses and slides across the cut.
nlohmann::json saturated_collapse(int dim, const std::string& shape) {
  nlohmann::json s = column_collapse(dim, shape);
  s["name"] = "saturated-collapse";
  s["formulation"] = "explicit-single-point";
  s["materials"] = {{{"name", "sand"}, {"model", "mohr-coulomb"}, {"grain_density", 2650.0}, {"porosity", 0.4},
                     {"youngs_modulus", 2e6}, {"poisson_ratio", 0.3}, {"cohesion", 0.0}, {"friction_angle", 30.0},
                     {"dilation_angle", 0.0}, {"hydraulic_conductivity", 1e-2}},
                    {{"name", "water"}, {"model", "fluid"}, {"density", 1000.0}, {"bulk_modulus", 2e7}}};
  s["bodies"][0]["fluid"] = "water";
  for (auto& b : s["boundaries"]) b["fluid"] = "impermeable";
  s["output"]["monitors"][1]["quantities"] = {"displacement_y", "pore_pressure"};
  s["bodies"][0]["initial"]["velocity"][0] = 0.75;
  s["grid"]["min"][0] = -0.1;  // the column's left side is free: it spreads both ways
  s["boundaries"].erase(0);    // (x_min)
  return s;
}

TEST(Mpirun, ExplicitSinglePointOnTwoRanksIsBitwiseTheOneRankRun2D) {
  // GIMP: a cell's points may have their first node in two stripes, on two ranks (the strain
  // smoothing's cell sums cross the cut); the default mfvp-linear pressure step.
  nlohmann::json s = saturated_collapse(2, "gimp");
  s["time"]["end"] = 0.2;  // later the floor's bottom row of points sinks through the roller (t = 0.245 s)
  const Pair p = solve_both(s, "mpirun-esp-2d", 2);
  expect_same_answers(p);
  const auto rj = load_json(p.many + "/run.json");
  EXPECT_GT(rj["counters"]["particles migrated"].get<double>(), 400.0);
  EXPECT_GE(rj["counters"]["rebalances"].get<double>(), 1.0);
}

/// The lines of a run's log.txt that say what runs: the first (formulation, particle counts) and
/// what each monitor follows.
std::vector<std::string> log_header(const std::string& run) {
  std::vector<std::string> lines;
  std::istringstream in(read_text(run + "/log.txt"));
  for (std::string l; std::getline(in, l);)
    if (l.find("solving") != std::string::npos || l.rfind("monitor ", 0) == 0) lines.push_back(l);
  return lines;
}

TEST(Mpirun, AStartFromSlicesBuildsWhatOneRankBuilds) {
  // Rank 0 reads the particles and deals them out in slices; each rank builds the formulation,
  // the loads and the monitors from its slice before the particles go to their owners. Every setup
  // step that reads the particles must then reduce over the ranks: here two materials (the dry
  // footing has no pore fluid; the pore-fluid table is per material), a load on a named surface
  // (its samples shared among the tagged particles of every rank), a load on an axis face, a
  // prescribed pore pressure (its saturated particles at the face), monitors at a point and on a
  // particle id (the nearest point over the ranks). On two ranks as dealt out (each a half), and
  // on three with every particle dealt to the last rank (SWMPM_START_SLICES=last: ranks 0 and 1
  // build from nothing), the run is the one-rank run bit for bit, and the log says the same.
  nlohmann::json s = saturated_collapse(2, "gimp");
  s["name"] = "sliced-start";
  s["materials"].push_back({{"name", "block"}, {"model", "linear-elastic"}, {"grain_density", 2650.0},
                            {"porosity", 0.3}, {"youngs_modulus", 1e7}, {"poisson_ratio", 0.3}});
  s["bodies"].push_back({{"name", "footing"},
                         {"geometry", {{"type", "footing"}, {"width", 0.1}, {"height", 0.04}, {"center_x", 0.1}, {"on", "column"}}},
                         {"solid", "block"},
                         {"particles_per_cell", 2}});
  s["loads"] = {{{"type", "traction"}, {"body", "footing"}, {"face", "top"}, {"value", {0.0, -3000.0}}},
                {{"type", "pressure"}, {"body", "column"}, {"face", "x_max"}, {"value", 1000.0}}};
  for (auto& b : s["boundaries"])
    if (b["on"] == "y_min") b["fluid"] = "pressure", b["value"] = 500.0;
  s["output"]["monitors"].push_back({{"name", "one"}, {"particle", 7}, {"quantities", {"displacement_y", "pore_pressure"}}});
  // The footing starts unstressed: its mean stress at t = 0 is -0, which the other ranks' part of
  // the row must keep (they add -0, not 0).
  s["output"]["monitors"].push_back({{"name", "block"}, {"at", {0.1, 0.22}}, {"quantities", {"mean_effective_stress"}}});
  s["time"]["end"] = 0.1;
  s["output"]["interval"] = 0.05;
  const Pair p = solve_both(s, "mpirun-sliced-start", 2);
  expect_same_answers(p);
  EXPECT_EQ(log_header(p.many), log_header(p.one));
  ASSERT_EQ(log_header(p.one).size(), 6u);  // the first line and five monitors
  EXPECT_NE(read_text(p.one + "/monitors.csv").find(",-0\n"), std::string::npos);  // the footing's mean stress at t = 0

  Pair last = p;
  last.many = (p.dir / "last").string();
  ASSERT_EQ(swmpm_cmd("preprocess " + (p.dir / "scene.json").string() + " -o " + last.many + " -q", p.dir).status, 0);
  last.many_result = mpirun(3, "solve " + last.many + " -q --threads 1", p.dir, "SWMPM_START_SLICES=last");
  ASSERT_EQ(last.many_result.status, 0) << last.many_result.err;
  expect_same_answers(last);
  EXPECT_EQ(log_header(last.many), log_header(p.one));
}

TEST(Mpirun, ExplicitSinglePointCellPressureConservativeOnTwoRanksIsBitwiseTheOneRankRun3D) {
  nlohmann::json s = saturated_collapse(3, "gimp");
  s["solver"]["continuity"] = "conservative";
  s["solver"]["stabilisation"] = {{"pressure", "cell-constant"}};
  const Pair p = solve_both(s, "mpirun-esp-3d", 2);
  expect_same_answers(p);
  EXPECT_GT(load_json(p.many + "/run.json")["counters"]["particles migrated"].get<double>(), 600.0);
  EXPECT_EQ(load_json(p.many + "/run.json")["status"], "completed");
}

TEST(Mpirun, ExplicitSinglePointQuadraticPressureFitOnThreeRanks) {
  nlohmann::json s = saturated_collapse(2, "bspline2");
  s["solver"]["stabilisation"] = {{"pressure", "mfvp-quadratic"}};
  s["loads"] = {{{"type", "pressure"}, {"body", "column"}, {"face", "y_max"}, {"value", 2000.0}}};
  s["time"]["end"] = 0.12;  // the suction bound stops it at t = 0.16 s
  const Pair p = solve_both(s, "mpirun-esp-3ranks", 3);
  expect_same_answers(p);
  EXPECT_GT(load_json(p.many + "/run.json")["counters"]["particles migrated"].get<double>(), 200.0);
}

TEST(Mpirun, TractionsOnFacePointsOfBothRanksAreTheOneRankLoads) {
  // A traction on the column's top face, which the cut between the two ranks crosses: each face
  // point's force reaches nodes of both ranks, weighed by the rank that holds all its nodes.
  nlohmann::json s = column_collapse(2, "bspline2");
  s["loads"] = {{{"type", "traction"}, {"body", "column"}, {"face", "y_max"}, {"value", {0.0, -5000.0}}}};
  s["time"]["end"] = 0.15;
  const Pair p = solve_both(s, "mpirun-dry-loads", 2);
  expect_same_answers(p);
  // The load did work (the top sinks more than under its weight alone).
  const Pair q = solve_both(column_collapse(2, "bspline2"), "mpirun-dry-unloaded", 2);
  EXPECT_NE(read_text(p.one + "/monitors.csv"), read_text(q.one + "/monitors.csv"));
}

TEST(Mpirun, StandardFbarOnTwoRanksIsBitwiseTheOneRankRun) {
  nlohmann::json dry = column_collapse(2, "bspline2");
  dry["solver"]["stabilisation"] = {{"fbar", "standard"}};
  expect_same_answers(solve_both(dry, "mpirun-fbar-dry", 2));
  nlohmann::json esp = saturated_collapse(3, "gimp");
  esp["solver"]["stabilisation"] = {{"fbar", "standard"}};
  esp["time"]["end"] = 0.15;
  expect_same_answers(solve_both(esp, "mpirun-fbar-esp", 2));
}

TEST(Mpirun, NorSandOnTwoRanksIsBitwiseTheOneRankRun) {
  // Nor-Sand's P-wave modulus grows with the largest pressure of its points: the time step's CFL
  // takes that largest over all ranks, as one rank does (a rank's own largest would give each
  // rank's points another modulus, and another dt, than the one-rank run's).
  nlohmann::json s = saturated_collapse(2, "gimp");
  s["materials"][0] = load_json(SWMPM_SOURCE_DIR "/examples/landslide-nor-sand/scene-loose.json")["materials"][0];
  s["materials"][0]["name"] = "sand";
  s["time"]["end"] = 0.02;  // 460 steps: the build before differed by 1.5e-9 (pore pressure) at the end
  s["output"]["interval"] = 0.01;
  const Pair p = solve_both(s, "mpirun-esp-nor-sand", 2);
  expect_same_answers(p);
  EXPECT_EQ(load_json(p.many + "/run.json")["status"], "completed");
}

TEST(Mpirun, TerzaghiOnTwoRanksIsBitwiseTheOneRankRun) {
  // The column stands along y, the cut across it: the load acts on the upper rank's points.
  nlohmann::json s = load_json(SWMPM_SOURCE_DIR "/examples/terzaghi/scene.json");
  s["time"]["end"] = 0.05;
  s["output"]["interval"] = 0.01;
  const Pair p = solve_both(s, "mpirun-terzaghi", 2);
  expect_same_answers(p);
  EXPECT_EQ(load_json(p.many + "/run.json")["status"], "completed");
}

/// The final frame of `run` (the last entry of results.pvd), or of its particle set `group`
/// ("solid", "fluid": the last entry whose file name starts with it).
scene::PointCloud last_frame(const std::string& run, const std::string& group = {}) {
  const auto frames = scene::read_pvd(run + "/output/results.pvd");
  for (auto f = frames.rbegin(); f != frames.rend(); ++f)
    if (f->file.rfind(group, 0) == 0) return scene::read_vtu(run + "/output/" + f->file);
  ADD_FAILURE() << run << ": no frame of " << group;
  return {};
}

/// A restart test's two run directories of `scene` (preprocessed), the one-rank run solved to the end.
struct RestartRuns {
  fs::path dir;
  std::string one, run;
};
RestartRuns restart_runs(const nlohmann::json& scene, const std::string& name) {
  RestartRuns r;
  r.dir = scratch(name);
  std::ofstream(r.dir / "scene.json") << scene.dump(2);
  r.one = (r.dir / "one").string(), r.run = (r.dir / "run").string();
  EXPECT_EQ(swmpm_cmd("preprocess " + (r.dir / "scene.json").string() + " -o " + r.one + " -q", r.dir).status, 0);
  EXPECT_EQ(swmpm_cmd("preprocess " + (r.dir / "scene.json").string() + " -o " + r.run + " -q", r.dir).status, 0);
  EXPECT_EQ(swmpm_cmd("solve " + r.one + " -q --threads 1", r.dir).status, 0);
  return r;
}

/// `swmpm solve RUN --resume` on `ranks` ranks (one: without mpirun), output under dir.
Result resume(int ranks, const std::string& run, const fs::path& dir) {
  const std::string args = "solve " + run + " --resume -q --threads 1";
  return ranks == 1 ? swmpm_cmd(args, dir) : mpirun(ranks, args, dir);
}

/// `run` (restart_runs) solved on two ranks to its end, then resumed from its last checkpoint (at
/// `step`) on one rank and on three: check(ranks, run.json) after each resume.
template <class Check>
void resume_on_one_and_three(const std::string& run, const fs::path& dir, long step, Check&& check) {
  const Result two = mpirun(2, "solve " + run + " -q --threads 1", dir);
  ASSERT_EQ(two.status, 0) << two.err;
  for (int ranks : {1, 3}) {
    const Result r = resume(ranks, run, dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto rj = load_json(run + "/run.json");
    EXPECT_EQ(rj["resumed_from_step"], step);
    EXPECT_EQ(rj["ranks"], ranks);
    check(ranks, rj);
  }
}

/// The saturated column of saturated_collapse under explicit-double-point (soil points and water
/// points), sliding into a layer of free water on the floor: both sets cross the cut, the water's
/// free surface and a water level gauge follow the wave, and the column's porosity passes the
/// liquefaction bound where it dilates.
nlohmann::json double_point_collapse(int dim, const std::string& shape) {
  nlohmann::json s = saturated_collapse(dim, shape);
  const bool three = dim == 3;
  s["name"] = "double-point-collapse";
  s["formulation"] = "explicit-double-point";
  s["materials"][0]["maximum_porosity"] = 0.45;
  s["materials"][1]["dynamic_viscosity"] = 1e-3;
  s["bodies"][0]["initial"]["pore_pressure"] = "hydrostatic";
  s["bodies"].push_back({{"name", "pool"},
                         {"geometry",
                          {{"type", "box"},
                           {"min", three ? nlohmann::json{0.24, 0.0, 0.0} : nlohmann::json{0.24, 0.0}},
                           {"max", three ? nlohmann::json{0.6, 0.08, 0.12} : nlohmann::json{0.6, 0.08}}}},
                         {"fluid", "water"},
                         {"particles_per_cell", 2},
                         {"initial", {{"pore_pressure", "hydrostatic"}, {"water_table", 0.08}}}});
  s["output"]["monitors"].push_back({{"name", "wave"},
                                     {"at", three ? nlohmann::json{0.25, 0.01, 0.06} : nlohmann::json{0.25, 0.01}},
                                     {"phase", "fluid"},
                                     {"quantities", {"displacement_x", "pore_pressure"}}});
  s["output"]["monitors"].push_back({{"name", "gauge"},
                                     {"at", three ? nlohmann::json{0.45, 0.06} : nlohmann::json{0.45}},
                                     {"quantities", {"water_level"}}});
  return s;
}

TEST(Mpirun, ExplicitDoublePointOnTwoRanksIsBitwiseTheOneRankRun2D) {
  const Pair p = solve_both(double_point_collapse(2, "gimp"), "mpirun-edp-2d", 2);
  expect_same_answers(p);
  const auto rj = load_json(p.many + "/run.json");
  EXPECT_EQ(rj["status"], "completed");
  EXPECT_GT(rj["counters"]["particles migrated"].get<double>(), 400.0);
  EXPECT_GE(rj["counters"]["rebalances"].get<double>(), 1.0);
}

TEST(Mpirun, ExplicitDoublePointOnTwoRanksIsBitwiseTheOneRankRun3D) {
  nlohmann::json s = double_point_collapse(3, "gimp");
  s["time"]["end"] = 0.15;
  const Pair p = solve_both(s, "mpirun-edp-3d", 2);
  expect_same_answers(p);
  const auto rj = load_json(p.many + "/run.json");
  EXPECT_EQ(rj["status"], "completed");
  EXPECT_GT(rj["counters"]["particles migrated"].get<double>(), 600.0);
}

TEST(Mpirun, ExplicitDoublePointTiedInitialisationAndCheckpointResumeOnOneAndThreeRanks) {
  // An initialisation phase ties each water point of the column to its soil point while gravity
  // grows (the partners found over both ranks' points), with its own permeability; the restart
  // file of two ranks (both sets, both schedule orders, the partners) resumes on one rank and on
  // three, each ending bit for bit on the uninterrupted one-rank run.
  nlohmann::json s = double_point_collapse(2, "bspline2");
  s["initialisation"] = {{"duration", 0.05}, {"gravity_ramp", 0.04}, {"tie_water", true}, {"hydraulic_conductivity", 0.1}};
  s["time"]["dt"] = 5e-5;
  s["time"]["end"] = 0.1;
  s["output"]["checkpoint_interval"] = 0.05;
  const Pair tied = solve_both(s, "mpirun-edp-tied", 2);
  expect_same_answers(tied);
  const auto [dir, one, run] = restart_runs(s, "mpirun-edp-restart");
  const auto reference = last_frame(one, "solid"), water = last_frame(one, "fluid");
  const std::string monitors = read_text(one + "/monitors.csv");
  resume_on_one_and_three(run, dir, 2000, [&](int ranks, const nlohmann::json&) {  // 1000 steps of the phase, 1000 after
    EXPECT_EQ(differing_values(reference, last_frame(run, "solid")), 0) << ranks << " ranks";
    EXPECT_EQ(differing_values(water, last_frame(run, "fluid")), 0) << ranks << " ranks";
    EXPECT_EQ(read_text(run + "/monitors.csv"), monitors) << ranks << " ranks";
  });
}

/// The largest difference between two frames of the same particles (matched by id), per array
/// relative to the array's largest magnitude in `a`; positions relative to `length`.
double largest_relative_difference(const scene::PointCloud& a, const scene::PointCloud& b, double length,
                                   std::string& where) {
  double worst = 0.0;
  const bool same_points = for_each_value_array(a, b, [&](const std::string& name, const auto& va, const auto& vb) {
    double scale = length;
    if (name != "position") {
      scale = 0.0;
      for (double v : va) scale = std::max(scale, std::abs(v));
      if (scale == 0.0) scale = 1.0;
    }
    for (std::size_t k = 0; k < va.size(); ++k)
      if (const double e = std::abs(va[k] - vb[k]) / scale; e > worst) worst = e, where = name;
  });
  return same_points ? worst : 1.0;
}

/// Every frame of `many` within `tolerance` of the one-rank frame (largest_relative_difference,
/// positions relative to the cell size h): the semi-implicit pressure solve over the ranks is
/// PETSc's CG to a relative residual of 1e-10, one rank's CHOLMOD's, so they agree to the
/// solver's tolerance, not bit for bit. Returns the largest difference.
double expect_close_answers(const Pair& p, double h, double tolerance) {
  const auto one = scene::read_pvd(p.one + "/output/results.pvd");
  const auto many = scene::read_pvd(p.many + "/output/results.pvd");
  EXPECT_EQ(one.size(), many.size());
  double worst = 0.0;
  for (std::size_t k = 0; k < std::min(one.size(), many.size()); ++k) {
    if (one[k].group == "grid") continue;  // mpm-fem's grid frames: expect_close_grids
    std::string where;
    const double e = largest_relative_difference(scene::read_vtu(p.one + "/output/" + one[k].file),
                                                 scene::read_vtu(p.many + "/output/" + many[k].file), h, where);
    EXPECT_LE(e, tolerance) << "frame " << k << " (t = " << one[k].time << " s): " << where;
    worst = std::max(worst, e);
  }
  expect_same_stability(p, 1e-4, false);
  return worst;
}

/// Two grid frames of mpm-fem (fluid velocity, pressure, phase field, porosity, solid fraction,
/// in node order): the largest difference of each array relative to its largest magnitude in
/// `a`, expected within `tolerance`; the fluid velocity of the air (nodes with phi < 1/2) within
/// `air`: there the momentum equations' scale is rho_a / rho_w = 1/830 of the water's, and
/// BiCGSTAB's test on the whole residual (|b - A x| <= 1e-8 |b|) resolves them the less. Returns
/// the largest difference outside the air.
double expect_close_grid(const scene::PointCloud& a, const scene::PointCloud& b, double tolerance, double air,
                         const std::string& label) {
  EXPECT_EQ(a.points, b.points) << label;
  const auto* phi = a.find("phase_field");
  EXPECT_NE(phi, nullptr) << label;
  EXPECT_EQ(a.arrays.size(), b.arrays.size()) << label;
  if (!phi || a.points != b.points) return 1.0;
  double worst = 0.0;
  for (const auto& arr : a.arrays) {
    const auto* other = b.find(arr.name);
    EXPECT_NE(other, nullptr) << label << ": " << arr.name;
    if (!other) return 1.0;
    double scale = 0.0, water = 0.0, in_air = 0.0;
    for (double v : arr.values) scale = std::max(scale, std::abs(v));
    if (scale == 0.0) scale = 1.0;
    const auto c = static_cast<std::size_t>(arr.components);
    for (std::size_t i = 0; i < arr.values.size(); ++i) {
      const bool air_node = arr.name == "fluid_velocity" && phi->values[i / c] < 0.5;
      double& largest = air_node ? in_air : water;
      largest = std::max(largest, std::abs(arr.values[i] - other->values[i]) / scale);
    }
    EXPECT_LE(water, tolerance) << label << ": " << arr.name;
    EXPECT_LE(in_air, air) << label << ": " << arr.name << " in the air";
    worst = std::max(worst, water);
  }
  return worst;
}

/// Every grid frame of `many` against one rank's (expect_close_grid). Returns the largest difference.
double expect_close_grids(const Pair& p, double tolerance, double air) {
  const auto one = scene::read_pvd(p.one + "/output/results.pvd");
  const auto many = scene::read_pvd(p.many + "/output/results.pvd");
  double worst = 0.0;
  long grids = 0;
  for (std::size_t k = 0; k < std::min(one.size(), many.size()); ++k) {
    if (one[k].group != "grid") continue;
    ++grids;
    const std::string label = "frame " + std::to_string(k) + " (t = " + std::to_string(one[k].time) + " s)";
    worst = std::max(worst, expect_close_grid(scene::read_vtu(p.one + "/output/" + one[k].file),
                                              scene::read_vtu(p.many + "/output/" + many[k].file), tolerance, air, label));
  }
  EXPECT_GT(grids, 1);
  return worst;
}

/// Two monitors.csv of one scene: the same rows and columns, each number within `tolerance` of
/// the first file's, relative to its column's largest magnitude (lines starting with # skipped).
/// Returns the largest difference.
double expect_close_monitors(const std::string& a_path, const std::string& b_path, double tolerance) {
  auto rows = [](const std::string& text) {
    std::vector<std::vector<std::string>> r;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      std::vector<std::string> cells;
      std::istringstream cs(line);
      for (std::string cell; std::getline(cs, cell, ',');) cells.push_back(cell);
      r.push_back(cells);
    }
    return r;
  };
  const auto a = rows(read_text(a_path)), b = rows(read_text(b_path));
  EXPECT_EQ(a.size(), b.size());
  EXPECT_GT(a.size(), 2u);
  if (a.size() != b.size() || a.empty()) return 1.0;
  EXPECT_EQ(a[0], b[0]);  // the header
  std::vector<double> scale(a[0].size(), 0.0);
  for (std::size_t i = 1; i < a.size(); ++i)
    for (std::size_t j = 0; j < a[i].size() && j < scale.size(); ++j) scale[j] = std::max(scale[j], std::abs(std::stod(a[i][j])));
  double worst = 0.0;
  for (std::size_t i = 1; i < a.size(); ++i) {
    EXPECT_EQ(a[i].size(), b[i].size()) << "row " << i;
    for (std::size_t j = 0; j < std::min(a[i].size(), b[i].size()); ++j) {
      const double e = std::abs(std::stod(a[i][j]) - std::stod(b[i][j])) / (scale[j] > 0.0 ? scale[j] : 1.0);
      EXPECT_LE(e, tolerance) << "row " << i << ", " << a[0][j];
      worst = std::max(worst, e);
    }
  }
  return worst;
}

/// solve_both on `ranks` ranks, then expect_close_answers (1e-6) and a completed run; prints the
/// largest difference, labelled `what`.
Pair expect_follows(const nlohmann::json& scene, const std::string& name, int ranks, double h, const std::string& what) {
  Pair p = solve_both(scene, name, ranks);
  const double worst = expect_close_answers(p, h, 1e-6);
  std::cout << "largest relative difference " << ranks << " ranks / 1 rank (" << what << "): " << worst << "\n";
  EXPECT_EQ(load_json(p.many + "/run.json")["status"], "completed");
  return p;
}

/// The saturated column of saturated_collapse under semi-implicit-single-point: the pressure is
/// a Poisson solve over the ranks, with a free surface on every side but the floor.
nlohmann::json semi_implicit_collapse(int dim, const std::string& shape) {
  nlohmann::json s = saturated_collapse(dim, shape);
  s["formulation"] = "semi-implicit-single-point";
  s["time"]["end"] = 0.2;
  return s;
}

TEST(Mpirun, SemiImplicitSinglePointOnTwoRanksFollowsTheOneRankRun2D) {
  // GIMP: the operators are scattered point by point; the free surface's nodes and the fit's
  // inward search read the other rank's columns (ghosts).
  const Pair p = solve_both(semi_implicit_collapse(2, "gimp"), "mpirun-sisp-2d", 2);
  const double worst = expect_close_answers(p, 0.02, 1e-6);
  std::cout << "largest relative difference 2 ranks / 1 rank: " << worst << "\n";
  const auto rj = load_json(p.many + "/run.json");
  EXPECT_EQ(rj["status"], "completed");
  EXPECT_GT(rj["counters"]["pressure_ksp_iterations"].get<double>(), 0.0);
  EXPECT_GT(rj["counters"]["particles migrated"].get<double>(), 400.0);
}

TEST(Mpirun, SemiImplicitSinglePointCellMomentsOnThreeRanksFollowsTheOneRankRun) {
  // Quadratic B-splines: the operators from cell moments, whose rows cross the cuts; a pressure load.
  nlohmann::json s = semi_implicit_collapse(2, "bspline2");
  s["loads"] = {{{"type", "pressure"}, {"body", "column"}, {"face", "y_max"}, {"value", 2000.0}}};
  s["time"]["end"] = 0.15;
  const Pair p = solve_both(s, "mpirun-sisp-3ranks", 3);
  const double worst = expect_close_answers(p, 0.02, 1e-6);
  std::cout << "largest relative difference 3 ranks / 1 rank: " << worst << "\n";
  EXPECT_EQ(load_json(p.many + "/run.json")["status"], "completed");
}

TEST(Mpirun, SemiImplicitSinglePointOnTwoRanksFollowsTheOneRankRun3D) {
  nlohmann::json s = semi_implicit_collapse(3, "gimp");
  s["time"]["end"] = 0.15;
  const Pair p = solve_both(s, "mpirun-sisp-3d", 2);
  const double worst = expect_close_answers(p, 0.04, 1e-6);
  std::cout << "largest relative difference 2 ranks / 1 rank (3D): " << worst << "\n";
  EXPECT_EQ(load_json(p.many + "/run.json")["status"], "completed");
}

TEST(Mpirun, SemiImplicitSinglePointCellMomentsOnTwoRanksFollowsTheOneRankRun3D) {
  // Quadratic B-splines in 3D (the operators from cell moments); some steps' right-hand sides are
  // so much smaller than the last that CG must start from zero (parallel::GridPoisson).
  expect_follows(semi_implicit_collapse(3, "bspline2"), "mpirun-sisp-3d-moments", 2, 0.04, "3D, cell moments");
}

/// The dry column of column_collapse with a fixed dt and checkpoints at 0.1375 and 0.275 s: the
/// last (step 1100) falls just before a step that stores the particles in schedule order (every
/// 10 steps), so a resume uses the restored schedule order at once.
nlohmann::json restart_column() {
  nlohmann::json s = column_collapse(2, "bspline2");
  s["time"]["dt"] = 2.5e-4;
  s["output"]["checkpoint_interval"] = 0.1375;
  return s;
}

/// `run` resumed from step 1100 on `ranks` ranks ends on the uninterrupted one-rank run's last
/// frame (`reference`) and monitors.csv, bit for bit.
void expect_resumes_bitwise(const std::string& run, const fs::path& dir, int ranks, const scene::PointCloud& reference,
                            const std::string& monitors) {
  const Result r = resume(ranks, run, dir);
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rj = load_json(run + "/run.json");
  EXPECT_EQ(rj["resumed_from_step"], 1100) << ranks;
  EXPECT_EQ(rj["ranks"], ranks);
  if (ranks > 1) {
    EXPECT_EQ(rj["particles_per_rank"]["each"].size(), static_cast<std::size_t>(ranks));
  }
  EXPECT_EQ(differing_values(reference, last_frame(run)), 0) << ranks;
  EXPECT_EQ(read_text(run + "/monitors.csv"), monitors) << ranks;
}

/// restart_runs of restart_column, then the run solved on `ranks` ranks to its end; the one-rank
/// run's last frame and monitors.csv, which every resume must end on.
struct ColumnRestart {
  RestartRuns runs;
  scene::PointCloud reference;
  std::string monitors;
};
ColumnRestart column_restart(const std::string& name, int ranks) {
  ColumnRestart c{restart_runs(restart_column(), name), {}, {}};
  c.reference = last_frame(c.runs.one);
  c.monitors = read_text(c.runs.one + "/monitors.csv");
  const Result solved = mpirun(ranks, "solve " + c.runs.run + " -q --threads 1", c.runs.dir);
  EXPECT_EQ(solved.status, 0) << solved.err;
  return c;
}

TEST(Mpirun, ACheckpointOfTwoRanksResumesOnOneAndOnThreeBitForBit) {
  // Two ranks to the end: the last checkpoint (t = 0.275 s) is in pieces, each rank's particles
  // in its own file (nothing gathered), checkpoint.bin the loop's state and the list; the first
  // checkpoint's pieces were removed once the second was in place.
  const ColumnRestart c = column_restart("mpirun-restart", 2);
  const std::string &one = c.runs.one, &run = c.runs.run;
  const fs::path& dir = c.runs.dir;
  const auto& [reference, monitors] = std::tie(c.reference, c.monitors);
  EXPECT_EQ(load_json(run + "/run.json")["checkpoints"], 2);
  for (const char* piece : {"/checkpoint/piece-2-0.bin", "/checkpoint/piece-2-1.bin"}) {
    ASSERT_TRUE(fs::exists(run + piece)) << piece;
    EXPECT_GT(fs::file_size(run + piece), 5 * fs::file_size(run + "/checkpoint.bin")) << piece;  // 54-65 kB, 5.4 kB
  }
  EXPECT_FALSE(fs::exists(run + "/checkpoint/piece-1-0.bin"));
  EXPECT_FALSE(fs::exists(run + "/checkpoint/piece-1-1.bin"));
  // A missing piece is named, and nothing is written (exit 2).
  fs::rename(run + "/checkpoint/piece-2-1.bin", run + "/piece.aside");
  const Result missing = swmpm_cmd("solve " + run + " --resume -q --threads 1", dir);
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.err.find("piece-2-1.bin: missing"), std::string::npos) << missing.err;
  EXPECT_EQ(load_json(run + "/run.json")["ranks"], 2);
  fs::rename(run + "/piece.aside", run + "/checkpoint/piece-2-1.bin");
  // 2 -> 1 (the one rank reads both pieces: the snapshot one rank writes), then the same
  // checkpoint (the resumed run writes none before its end) 2 -> 3: the one-rank run's answers.
  expect_resumes_bitwise(run, dir, 1, reference, monitors);
  expect_resumes_bitwise(run, dir, 3, reference, monitors);
  const auto frames = scene::read_pvd(run + "/output/results.pvd");
  ASSERT_FALSE(frames.empty());
  EXPECT_EQ(frames.back().file.substr(frames.back().file.size() - 5), ".pvtu");
  EXPECT_EQ(scene::read_pvd(one + "/output/results.pvd").size(), frames.size());
}

TEST(Mpirun, ACheckpointOfThreeRanksResumesOnTwoAndOnFourBitForBit) {
  // The pieces are read in blocks (three pieces on two ranks: one reads one, the other two; on
  // four ranks one reads none) and every particle goes to its owner with its place in the
  // schedule order (State::shares): no rank puts the whole run together.
  const ColumnRestart c = column_restart("mpirun-restart-3", 3);
  for (int r = 0; r < 3; ++r)
    EXPECT_TRUE(fs::exists(c.runs.run + "/checkpoint/piece-2-" + std::to_string(r) + ".bin")) << r;
  expect_resumes_bitwise(c.runs.run, c.runs.dir, 2, c.reference, c.monitors);
  expect_resumes_bitwise(c.runs.run, c.runs.dir, 4, c.reference, c.monitors);
}

TEST(Mpirun, SemiImplicitTerzaghiOnTwoRanksFollowsTheOneRankRun) {
  // examples/terzaghi-semi-implicit: the column along y, the cut across it, the drained top face
  // and the traction on the upper rank; the base pore pressure history (monitors.csv) and the
  // frames within 1e-6 of the one-rank run.
  nlohmann::json s = load_json(SWMPM_SOURCE_DIR "/examples/terzaghi-semi-implicit/scene.json");
  s["time"]["end"] = 0.1;
  s["output"]["interval"] = 0.05;
  const Pair p = solve_both(s, "mpirun-terzaghi-si", 2);
  expect_close_answers(p, 0.025, 1e-6);
  const auto one = read_monitors(p.one), many = read_monitors(p.many);
  const auto &a = one.column("base.pore_pressure"), &b = many.column("base.pore_pressure");
  ASSERT_EQ(a.size(), b.size());
  double p_max = 0.0, worst = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) p_max = std::max(p_max, std::abs(a[k])), worst = std::max(worst, std::abs(a[k] - b[k]));
  EXPECT_GT(p_max, 5000.0);  // the load is carried by the water at first (10 kPa)
  EXPECT_LE(worst, 1e-6 * p_max);
  std::cout << "base pore pressure: largest 2-rank difference " << worst << " Pa of " << p_max << " Pa\n";
}

TEST(Mpirun, SemiImplicitCheckpointOfTwoRanksResumesOnOneAndOnThree) {
  // The restart file of a semi-implicit run on two ranks holds the whole run and no pressure-solver
  // state: one rank resumes it with CHOLMOD afresh, three ranks with PETSc; both end within the
  // solver's tolerance of the uninterrupted one-rank run.
  nlohmann::json s = semi_implicit_collapse(2, "gimp");
  s["time"]["dt"] = 2.5e-4;
  s["time"]["end"] = 0.15;
  s["output"]["checkpoint_interval"] = 0.075;
  const auto [dir, one, run] = restart_runs(s, "mpirun-sisp-restart");
  const auto reference = last_frame(one);
  resume_on_one_and_three(run, dir, 300, [&](int ranks, const nlohmann::json&) {
    std::string where;
    const double e = largest_relative_difference(reference, last_frame(run), 0.02, where);
    EXPECT_LE(e, 1e-6) << ranks << " ranks: " << where;
    std::cout << "resumed on " << ranks << " rank(s): largest relative difference " << e << "\n";
  });
}

/// The saturated column of double_point_collapse (without the pool: this formulation models no
/// free water) under semi-implicit-double-point: its soil and water points cross the cut, the
/// pressure is a Poisson solve over the ranks with a free surface on the column's sides and top.
nlohmann::json semi_implicit_double_point_collapse(int dim, const std::string& shape) {
  nlohmann::json s = double_point_collapse(dim, shape);
  s["formulation"] = "semi-implicit-double-point";
  s["materials"][0].erase("maximum_porosity");
  s["materials"][1].erase("dynamic_viscosity");
  s["bodies"].erase(1);
  s["output"]["monitors"].erase(4);  // the gauge
  s["output"]["monitors"][3]["at"][0] = 0.15;  // a water point of the column's toe
  s["time"]["end"] = 0.15;
  return s;
}

TEST(Mpirun, SemiImplicitDoublePointOnTwoRanksFollowsTheOneRankRun2D) {
  const Pair p = expect_follows(semi_implicit_double_point_collapse(2, "gimp"), "mpirun-sidp-2d", 2, 0.02, "double-point, 2D");
  EXPECT_GT(load_json(p.many + "/run.json")["counters"]["particles migrated"].get<double>(), 400.0);
}

TEST(Mpirun, SemiImplicitDoublePointOnTwoRanksFollowsTheOneRankRun3D) {
  expect_follows(semi_implicit_double_point_collapse(3, "gimp"), "mpirun-sidp-3d", 2, 0.04, "double-point, 3D");
}

TEST(Mpirun, SemiImplicitDoublePointEscapedWaterTiedInitialisationAndResumeAcrossRanks) {
  // Escaped water removed (the water squeezed out of the collapsing column leaves the run, point
  // by point, on the rank that holds it), after a tied initialisation; the checkpoint of two
  // ranks resumes on one and on three ranks, within the solver's tolerance of the one-rank run.
  nlohmann::json s = semi_implicit_double_point_collapse(2, "gimp");
  s["solver"]["escaped_water"] = "remove";
  s["materials"][0]["hydraulic_conductivity"] = 0.5;  // the water leaves the column as it collapses
  s["initialisation"] = {{"duration", 0.04}, {"gravity_ramp", 0.03}, {"tie_water", true}};
  s["time"]["dt"] = 2.5e-4;
  s["time"]["end"] = 0.1;
  s["output"]["checkpoint_interval"] = 0.05;
  s["output"]["monitors"].erase(3);  // the toe's water point may leave the run
  const Pair p = solve_both(s, "mpirun-sidp-escaped", 2);
  expect_close_answers(p, 0.02, 1e-6);
  const auto one = load_json(p.one + "/run.json"), many = load_json(p.many + "/run.json");
  EXPECT_GT(one["counters"]["escaped_water_points"].get<double>(), 20.0);  // 29 (2026-12-06)
  EXPECT_EQ(one["counters"]["escaped_water_points"], many["counters"]["escaped_water_points"]);
  const auto [dir, ref, run] = restart_runs(s, "mpirun-sidp-restart");
  const auto reference = last_frame(ref, "solid"), water = last_frame(ref, "fluid");
  resume_on_one_and_three(run, dir, 400, [&](int ranks, const nlohmann::json& rj) {  // t = 0.06 s: the interval counts from the phase's start
    EXPECT_EQ(rj["counters"]["escaped_water_points"], one["counters"]["escaped_water_points"]);
    std::string where;
    EXPECT_LE(largest_relative_difference(reference, last_frame(run, "solid"), 0.02, where), 1e-6) << ranks << ": " << where;
    EXPECT_LE(largest_relative_difference(water, last_frame(run, "fluid"), 0.02, where), 1e-6) << ranks << ": " << where;
  });
}

/// A saturated gravel block launched at 2 m/s through a pool (mpm-fem: the soil on points over the
/// ranks, the pool's water on the grid, its system assembled per rank and solved over the ranks);
/// the block crosses the cut.
/// Monitors: a soil point, a grid probe of the fluid, a grid water-level gauge, the energies.
nlohmann::json mpm_fem_block(int dim) {
  const bool three = dim == 3;
  auto v = [&](double x, double y, double z) { return three ? nlohmann::json{x, y, z} : nlohmann::json{x, y}; };
  nlohmann::json s = {
      {"name", "mpm-fem-block"},
      {"dimension", dim},
      {"formulation", "mpm-fem"},
      {"gravity", v(0.0, -9.81, 0.0)},
      {"grid", {{"cell_size", 0.02}, {"min", v(0, 0, 0)}, {"max", v(0.5, 0.12, 0.06)}, {"shape_function", "bspline2"}}},
      {"materials",
       {{{"name", "gravel"}, {"model", "linear-elastic"}, {"grain_density", 2650}, {"porosity", 0.4},
         {"youngs_modulus", 1e6}, {"poisson_ratio", 0.3}, {"grain_diameter", 0.005}, {"permeability_law", "kozeny-carman"}},
        {{"name", "water"}, {"model", "fluid"}, {"density", 1000}, {"dynamic_viscosity", 0.001}}}},
      {"bodies",
       {{{"name", "pool"}, {"geometry", {{"type", "box"}, {"min", v(0, 0, 0)}, {"max", v(0.5, 0.1, 0.06)}}},
         {"fluid", "water"}, {"particles_per_cell", 2}},
        {{"name", "block"}, {"geometry", {{"type", "box"}, {"min", v(0.06, 0, 0)}, {"max", v(0.2, 0.06, 0.06)}}},
         {"solid", "gravel"}, {"fluid", "water"}, {"particles_per_cell", 2},
         {"initial", {{"stress", "geostatic"}, {"k0", 0.5}, {"velocity", v(2.0, 0.0, 0.0)}}}}}},
      {"boundaries",
       {{{"on", "x_min"}, {"solid", "roller"}, {"fluid", "impermeable"}},
        {{"on", "x_max"}, {"solid", "roller"}, {"fluid", "impermeable"}},
        {{"on", "y_min"}, {"solid", "roller"}, {"fluid", "impermeable"}}}},
      {"time", {{"end", 0.08}, {"dt", "auto"}}},
      {"output",
       {{"interval", 0.02},
        {"monitor_interval", 0.004},
        {"monitors",
         {{{"name", "energy"}, {"quantities", {"kinetic_energy", "total_energy", "external_work"}}},
          {{"name", "block"}, {"at", v(0.13, 0.03, 0.03)}, {"quantities", {"velocity_x", "displacement_x"}}},
          {{"name", "probe"}, {"at", v(0.3, 0.03, 0.03)}, {"phase", "fluid"}, {"quantities", {"pore_pressure", "velocity_x"}}},
          {{"name", "gauge"}, {"at", three ? nlohmann::json{0.4, 0.03} : nlohmann::json{0.4}}, {"quantities", {"water_level"}}}}}}}};
  if (three)
    s["boundaries"].push_back({{"on", "z_min"}, {"solid", "roller"}, {"fluid", "impermeable"}}),
        s["boundaries"].push_back({{"on", "z_max"}, {"solid", "roller"}, {"fluid", "impermeable"}});
  return s;
}

/// The mpm-fem block on `ranks` ranks against one rank: the soil's frames, the grid's and
/// monitors.csv, each within its tolerance; prints the largest differences.
Pair expect_mpm_fem_follows(const nlohmann::json& scene, const std::string& name, int ranks, double h, double soil,
                            double grid, double air, double monitors) {
  Pair p = solve_both(scene, name, ranks);
  const double s = expect_close_answers(p, h, soil), g = expect_close_grids(p, grid, air);
  const double m = expect_close_monitors(p.one + "/monitors.csv", p.many + "/monitors.csv", monitors);
  std::cout << "largest relative difference " << ranks << " ranks / 1 rank (" << name << "): soil " << s << ", grid " << g
            << ", monitors " << m << "\n";
  EXPECT_EQ(load_json(p.many + "/run.json")["status"], "completed");
  return p;
}

TEST(Mpirun, MpmFemOnTwoRanksFollowsTheOneRankRun2D) {
  // The soil's points over the ranks; the fluid's system assembled by each rank on the cells of
  // its node planes and solved by MUMPS's LU and PETSc's BiCGSTAB (one rank: UMFPACK's and
  // Eigen's): the same answers to the Krylov tolerance.
  const Pair p = expect_mpm_fem_follows(mpm_fem_block(2), "mpirun-mpmfem-2d", 2, 0.02, 1e-6, 1e-6, 1e-6, 1e-6);
  long grids = 0;
  for (const auto& e : scene::read_pvd(p.many + "/output/results.pvd")) grids += e.group == "grid";
  EXPECT_EQ(grids, 5);
  const auto rj = load_json(p.many + "/run.json");
  EXPECT_GT(rj["counters"]["particles migrated"].get<double>(), 50.0);  // 90 (2026-12-06)
  EXPECT_GT(rj["counters"]["fluid factorisations"].get<double>(), 1.0);
  EXPECT_GT(rj["counters"]["fluid Krylov iterations per step"].get<double>(), 0.5);  // the factor was reused
}

TEST(Mpirun, MpmFemOnTwoRanksFollowsTheOneRankRun3D) {
  nlohmann::json s = mpm_fem_block(3);
  s["grid"]["cell_size"] = 0.03;  // 3D fluid systems are costly: a coarse grid, a short run
  // The water's surface (y = 0.1 m) two cells below the open top: with the top at 0.12 m the
  // water reached the open face, whose backflow term switches with the sign of the outflow, and
  // one rank's own runs with a direct solve every step and with the reused factor differed by
  // three times the largest pressure at t = 0.03 s.
  s["grid"]["max"] = {0.51, 0.18, 0.06};
  s["time"]["end"] = 0.03;
  // Measured 2026-12-06: soil 3.5e-7, grid 3.5e-5 (the pressure in the air below the top), the
  // air's velocity at the open top 8.0e-4. One rank's own runs with a direct solve every step and
  // with the reused factor differ by 5.3e-7 (soil), 4.9e-6 (pressure) and 8.6e-5 (the air's
  // velocity at the open top).
  expect_mpm_fem_follows(s, "mpirun-mpmfem-3d", 2, 0.03, 1e-5, 1e-3, 1e-2, 1e-5);
}

TEST(Mpirun, MpmFemCheckpointOfTwoRanksResumesOnOneAndOnThree) {
  // The fluid's state is the same on every rank (global restart arrays); the resumed runs
  // factorise afresh, as the saving run does after a checkpoint. Two ranks and three solve the
  // fluid with MUMPS, one with UMFPACK.
  nlohmann::json s = mpm_fem_block(2);
  s["time"]["dt"] = 2.5e-4;
  s["output"]["checkpoint_interval"] = 0.04;
  const auto [dir, one, run] = restart_runs(s, "mpirun-mpmfem-restart");
  const auto reference = last_frame(one, "solid"), grid = last_frame(one, "grid");
  resume_on_one_and_three(run, dir, 160, [&](int ranks, const nlohmann::json&) {
    std::string where;
    const double soil = largest_relative_difference(reference, last_frame(run, "solid"), 0.02, where);
    EXPECT_LE(soil, 1e-6) << ranks << " ranks: " << where;
    const double g = expect_close_grid(grid, last_frame(run, "grid"), 1e-6, 1e-6, std::to_string(ranks) + " ranks");
    const double m = expect_close_monitors(one + "/monitors.csv", run + "/monitors.csv", 1e-6);
    std::cout << "resumed on " << ranks << ": soil " << soil << ", grid " << g << ", monitors " << m << "\n";
  });
}

TEST(Mpirun, ModifiedFbarOnTwoAndThreeRanksIsBitwiseTheOneRankRun) {
  // The patch averages of J^e (h_patch = 2 h here): the patches near a cut hold particles of two
  // ranks (three ranks on this grid: every patch column is near a cut), summed from every rank's
  // records in key order.
  nlohmann::json dry = column_collapse(2, "bspline2");
  dry["solver"]["stabilisation"] = {{"fbar", "modified"}};
  expect_same_answers(solve_both(dry, "mpirun-mfbar-dry", 2));
  expect_same_answers(solve_both(dry, "mpirun-mfbar-dry-3", 3));
  nlohmann::json esp = saturated_collapse(3, "gimp");
  esp["solver"]["stabilisation"] = {{"fbar", "modified"}};
  esp["time"]["end"] = 0.15;
  expect_same_answers(solve_both(esp, "mpirun-mfbar-esp", 2));
}

}  // namespace
}  // namespace swmpm::testing
