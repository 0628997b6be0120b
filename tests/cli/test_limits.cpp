// Up-front resource limits (issue 27, items 4 and 5): a small scene file that asks for more memory
// than the process may use, an index that would overflow, a geometry file whose header declares
// more than its bytes hold, a .geo whose mesh size would never finish meshing, and runs that would
// never end or would fill the disk. Each is refused before anything is written, exit 2, one line
// naming the file and the key; each used to end in std::bad_alloc, a gmsh abort, a wrong cell
// count or a run that never ended.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <functional>
#include <string>

#include "scene/pointcloud.hpp"
#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

json column_scene() { return swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json"); }

/// The column's scene in 3D with its body a surface mesh read from `file`.
json surface_mesh_scene(const std::string& file, double cell_size, const json& max) {
  json s = column_scene();
  s["dimension"] = 3;
  s["grid"] = {{"cell_size", cell_size}, {"min", {0, 0, 0}}, {"max", max}, {"shape_function", "gimp"}};
  s["gravity"] = {0.0, -9.81, 0.0};
  s["bodies"][0]["geometry"] = {{"type", "surface-mesh"}, {"file", file}};
  s["boundaries"] = json::array();
  s["output"]["monitors"] = json::array();
  return s;
}

void write(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

struct Probe {
  fs::path dir;
  Result r;
  double seconds;
};

/// `swmpm preprocess` of `scene` (written as scene.json in a scratch folder with `files` beside it).
Probe preprocess(const std::string& name, const json& scene, const std::string& flags = "",
                 const std::vector<std::pair<std::string, std::string>>& files = {}) {
  const fs::path dir = swmpm::testing::scratch("limits-" + name);
  for (const auto& [file, text] : files) write(dir / file, text);
  write(dir / "scene.json", scene.dump(2));
  const auto t0 = std::chrono::steady_clock::now();
  const Result r = swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string() + " " +
                                 flags,
                             dir);
  return {dir, r, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
}

/// Refused at once: exit 2, one line naming scene.json (or `file`) and `key`, nothing written.
void expect_refused(const Probe& p, const std::string& key, const std::string& says) {
  EXPECT_EQ(p.r.status, 2) << p.r.err;
  EXPECT_NE(p.r.err.find("scene.json: " + key), std::string::npos) << "names the file and " << key << ": " << p.r.err;
  EXPECT_NE(p.r.err.find(says), std::string::npos) << p.r.err;
  EXPECT_EQ(std::count(p.r.err.begin(), p.r.err.end(), '\n'), 1) << p.r.err;
  EXPECT_FALSE(fs::exists(p.dir / "run")) << "nothing may be written";
  EXPECT_LT(p.seconds, 20.0) << "refused up front, not after trying";
}

}  // namespace

// cell_size 1e-4 on the 0.1 x 1 m column: 4e7 particles. Before: 2.4-7.9 GB, then std::bad_alloc,
// exit 1, no path.
TEST(ResourceLimits, TooManyParticlesAreRefusedNamingTheCellSize) {
  json s = column_scene();
  s["grid"]["cell_size"] = 1e-4;
  const Probe p = preprocess("particles", s);
  expect_refused(p, "/grid/cell_size", "4e+07 particles");
  EXPECT_NE(p.r.err.find("/bodies/0/particles_per_cell"), std::string::npos) << p.r.err;
}

// A 2.5e-8 m cell: 1.8e14 nodes.
TEST(ResourceLimits, AnAbsurdCellSizeIsRefusedBeforeSeeding) {
  json s = column_scene();
  s["grid"]["cell_size"] = 2.5e-8;
  expect_refused(preprocess("tiny-cell", s), "/grid/cell_size", "would need at least");
}

// Grid max 1e6 m around 160 particles: 6e7 nodes, 5 GB when it ran. Refused under --max-memory,
// naming the grid's box; --max-memory itself is checked.
TEST(ResourceLimits, AHugeGridBoxIsRefusedUnderMaxMemory) {
  json s = column_scene();
  s["grid"]["max"] = {0.1, 1e6};
  const Probe p = preprocess("box", s, "--max-memory 1G");
  expect_refused(p, "/grid/max", "more than --max-memory 1 GB");
  const Probe bad = preprocess("bad-size", column_scene(), "--max-memory lots");
  EXPECT_EQ(bad.r.status, 2);
  EXPECT_NE(bad.r.err.find("--max-memory: got \"lots\""), std::string::npos) << bad.r.err;
}

// The solve checks again with the points preprocess wrote (a run directory prepared elsewhere, or
// a smaller --max-memory at solve).
TEST(ResourceLimits, SolveChecksTheMemoryOfTheRunDirectory) {
  json s = column_scene();
  s["grid"]["max"] = {0.1, 2e4};  // 1.2e6 nodes, about 72 MB of grid
  const Probe p = preprocess("solve", s, "-q");
  ASSERT_EQ(p.r.status, 0) << p.r.err;
  const Result r = swmpm_cmd("solve " + (p.dir / "run").string() + " --max-memory 20M", p.dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("run/scene.json: /grid/max"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(p.dir / "run" / "run.json"));
  EXPECT_FALSE(fs::exists(p.dir / "run" / "output"));
}

// Grid max 1e12 m: 2e13 cells along y overflowed the 32-bit count (8 particles seeded instead of 160,
// then "needs at least 2 cells" at solve).
TEST(ResourceLimits, ACellCountThatWouldOverflowIsRefused) {
  json s = column_scene();
  s["grid"]["max"] = {0.1, 1e12};
  expect_refused(preprocess("overflow", s), "/grid/max", "cells along axis 1");
}

// A 76-byte .msh that declares 1e8 nodes: gmsh reserved 2.4 GB before failing.
TEST(ResourceLimits, AMeshFileDeclaringMoreThanItHoldsIsRefused) {
  json s = column_scene();
  s["bodies"][0]["geometry"] = {{"type", "gmsh"}, {"file", "tiny.msh"}};
  const std::string msh = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 100000000 1 100000000\n$EndNodes\n";
  const Probe p = preprocess("msh", s, "", {{"tiny.msh", msh}});
  EXPECT_EQ(p.r.status, 2) << p.r.err;
  EXPECT_NE(p.r.err.find("/bodies/0/geometry/file"), std::string::npos) << p.r.err;
  EXPECT_NE(p.r.err.find("declares 100000000 nodes"), std::string::npos) << p.r.err;
  EXPECT_FALSE(fs::exists(p.dir / "run"));
}

// An .off surface whose header declares 1e9 vertices in a few bytes.
TEST(ResourceLimits, ASurfaceFileDeclaringMoreThanItHoldsIsRefused) {
  const json s = surface_mesh_scene("huge.off", 0.05, {0.1, 1.1, 0.1});
  const Probe p = preprocess("off", s, "", {{"huge.off", "OFF\n1000000000 1000000000 0\n0 0 0\n"}});
  EXPECT_EQ(p.r.status, 2) << p.r.err;
  EXPECT_NE(p.r.err.find("/bodies/0/geometry/file"), std::string::npos) << p.r.err;
  EXPECT_NE(p.r.err.find("declares 2000000000 vertices and faces"), std::string::npos) << p.r.err;
  EXPECT_LT(p.seconds, 20.0);
}

// Found by FuzzSlow: sphere.off with one face of "1e12" corners. CGAL reserved them:
// std::bad_alloc, exit 1, no path.
TEST(ResourceLimits, ASurfaceFaceWithAbsurdCornersIsRefused) {
  const json s = surface_mesh_scene("sphere.off", 0.1, {1, 1, 1});
  std::string off = swmpm::testing::read_text(SWMPM_SOURCE_DIR "/geometries/sphere.off");
  const std::size_t face = off.find("\n3 ", off.find("\n3 ") + 1);  // the second face line
  off.replace(face + 1, 1, "1e12");
  const Probe p = preprocess("off-face", s, "", {{"sphere.off", off}});
  EXPECT_EQ(p.r.status, 2) << p.r.err;
  EXPECT_NE(p.r.err.find("/bodies/0/geometry/file"), std::string::npos) << p.r.err;
  EXPECT_NE(p.r.err.find("has 1e12 corners, expected 3 to 162"), std::string::npos) << p.r.err;
  EXPECT_FALSE(fs::exists(p.dir / "run"));
}

// A .geo with a mesh size of 1e-5 m on the 0.1 x 1 m column: 2e10 triangles, meshed for ever. The
// mesh is now no finer than an eighth of the particle spacing, and the body seeds as the box does.
TEST(ResourceLimits, AGeoMeshSizeFarBelowTheParticleSpacingMeshesQuickly) {
  json s = column_scene();
  s["bodies"][0]["geometry"] = {{"type", "gmsh"}, {"file", "fine.geo"}};
  const std::string geo =
      "lc = 1e-5;\n"
      "Point(1) = {0, 0, 0, lc}; Point(2) = {0.1, 0, 0, lc}; Point(3) = {0.1, 1, 0, lc}; Point(4) = {0, 1, 0, lc};\n"
      "Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n"
      "Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n";
  const Probe p = preprocess("geo", s, "-q", {{"fine.geo", geo}});
  EXPECT_EQ(p.r.status, 0) << p.r.err;
  EXPECT_LT(p.seconds, 30.0);
  const auto solid = swmpm::scene::read_vtu((p.dir / "run" / "particles" / "solid.vtu").string());
  EXPECT_EQ(solid.size(), 160u) << "the same particles as the box";
}

// time.end 1e12 s, dt 1e-30 s, density 1e-300 (dt auto 2e-155 s), E = 1e300: runs that would never
// end, started without a word. Refused before anything is written, naming the key.
TEST(ResourceLimits, RunsThatWouldNeverEndAreRefusedNamingTheKey) {
  struct Case {
    const char* name;
    std::function<void(json&)> set;
    const char* key;
  };
  const std::vector<Case> cases = {
      {"end", [](json& s) { s["time"]["end"] = 1e12; }, "/time/end"},
      {"dt", [](json& s) { s["time"]["dt"] = 1e-30; }, "/time/dt"},
      {"density", [](json& s) { s["materials"][0]["density"] = 1e-300; }, "/materials"},
      {"stiffness", [](json& s) { s["materials"][0]["youngs_modulus"] = 1e300; }, "/materials"},
  };
  for (const Case& c : cases) {
    json s = column_scene();
    c.set(s);
    const Probe p = preprocess(std::string("never-") + c.name, s, "-q");
    ASSERT_EQ(p.r.status, 0) << c.name << ": " << p.r.err;
    const auto t0 = std::chrono::steady_clock::now();
    const Result r = swmpm_cmd("solve " + (p.dir / "run").string() + " -q", p.dir);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 20.0) << c.name;
    EXPECT_EQ(r.status, 2) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(std::string("run/scene.json: ") + c.key + ": the run would take"), std::string::npos)
        << c.name << ": " << r.err;
    EXPECT_NE(r.err.find("more than a year"), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(p.dir / "run" / "run.json")) << c.name;
  }
}

// A long but finite run starts, with the estimate in the log and a warning naming the key.
TEST(ResourceLimits, ALongRunStartsWithItsEstimateAndAWarning) {
  json s = column_scene();
  s["time"]["end"] = 1e7;  // 1.1e10 steps, days
  s["output"]["interval"] = 1e4;
  s["output"]["monitor_interval"] = 1.0;
  const Probe p = preprocess("long", s, "-q");
  ASSERT_EQ(p.r.status, 0) << p.r.err;
  // Stopped after two seconds: SIGTERM is an interrupt that keeps the state.
  const fs::path err = p.dir / "solve-stderr.txt";
  const std::string cmd = std::string(SWMPM_EXE) + " solve " + (p.dir / "run").string() + " -q 2> " + err.string() +
                          " & pid=$!; sleep 2; kill $pid; wait $pid";
  EXPECT_EQ(WEXITSTATUS(std::system(cmd.c_str())), 4) << "interrupted";
  const Result r{0, "", swmpm::testing::read_text(err.string())};
  const std::string log = swmpm::testing::read_text((p.dir / "run" / "log.txt").string());
  EXPECT_NE(log.find("estimate: 1.09e+10 steps"), std::string::npos) << log.substr(0, 2000);
  EXPECT_NE(log.find("warning: " + (p.dir / "run" / "scene.json").string() + ": /time/end: the run would take"),
            std::string::npos)
      << log.substr(0, 2000);
  EXPECT_NE(r.err.find("/time/end: the run would take"), std::string::npos) << "shown even with -q: " << r.err;
}

// A disk that cannot hold the run's estimated output (a lower bound: 2.3 MB for a frame every step
// of the column) is refused before the first step, naming the output interval; before, the run
// started and failed when the disk filled (FullDisk.*). A 400 KiB tmpfs in a private mount
// namespace (root only; skipped elsewhere).
TEST(ResourceLimits, OutputLargerThanTheFreeDiskIsRefusedUpFront) {
  json s = column_scene();
  s["time"]["end"] = 0.5;
  s["time"]["dt"] = 9e-4;
  s["output"]["interval"] = 9e-4;
  const fs::path dir = swmpm::testing::scratch("limits-disk");
  write(dir / "scene.json", s.dump(2));
  const fs::path mnt = dir / "disk";
  fs::create_directories(mnt);
  const std::string script = "set -e; mount -t tmpfs -o size=400k tmpfs " + mnt.string() + "; cd " + dir.string() +
                             "; " + SWMPM_EXE + " preprocess scene.json -o " + (mnt / "run").string() + " -q; set +e; " +
                             SWMPM_EXE + " solve " + (mnt / "run").string() + " -q 2> err.txt; echo $? > status.txt; " +
                             "ls -A " + (mnt / "run").string() + " > listing.txt";
  const int raw = std::system(("unshare -m sh -c '" + script + "' 2> " + (dir / "unshare.txt").string()).c_str());
  if (WEXITSTATUS(raw) != 0 && !fs::exists(dir / "status.txt"))
    GTEST_SKIP() << "cannot mount a tmpfs here: " << swmpm::testing::read_text((dir / "unshare.txt").string());
  const std::string err = swmpm::testing::read_text((dir / "err.txt").string());
  EXPECT_EQ(std::stoi(swmpm::testing::read_text((dir / "status.txt").string())), 2) << err;
  EXPECT_NE(err.find("run/scene.json: /output/interval: the run would write at least 2.26 MB"), std::string::npos) << err;
  EXPECT_NE(err.find("free on the run directory's disk"), std::string::npos) << err;
  EXPECT_EQ(swmpm::testing::read_text((dir / "listing.txt").string()).find("run.json"), std::string::npos)
      << "the solve wrote nothing";
}
