// `swmpm solve RUN_DIR --resume` (issue 23, item 8): a run killed with SIGKILL part-way continues
// from RUN_DIR/checkpoint.bin, and its frames and monitors.csv are bitwise those of a run that was
// never stopped — for dry, explicit-single-point and both semi-implicit variants. A checkpoint of
// another scene or version is refused with what differs.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "support/run_helpers.hpp"
#include "support/slope_scene.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::testing::read_text;
using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

json example(const std::string& file) { return swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/" + file); }

/// A run that was not stopped, and one killed with SIGKILL once `kill_after_checkpoints` checkpoints
/// are on disk (so at a step the test does not choose), then resumed; both from the same scene.
struct Pair {
  fs::path whole, resumed;
  json resumed_run;
  std::string killed_status;
};

Pair run_killed_and_resumed(const json& scene, const std::string& name, int kill_after_checkpoints) {
  const fs::path dir = swmpm::testing::scratch("resume-" + name);
  std::ofstream(dir / "scene.json") << scene.dump(2);
  Pair p{dir / "whole", dir / "resumed", json(), ""};
  EXPECT_EQ(swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + p.whole.string() + " -q --threads 2", dir).status, 0);
  EXPECT_EQ(swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + p.resumed.string() + " -q", dir).status, 0);

  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    const std::string run = p.resumed.string();
    ::execl(SWMPM_EXE, SWMPM_EXE, "solve", run.c_str(), "-q", "--threads", "2", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Count checkpoints by their changes on disk (each is renamed into place whole).
  const fs::path ckpt = p.resumed / "checkpoint.bin";
  fs::file_time_type last{};
  int seen = 0, raw = 0;
  bool exited = false;
  for (int i = 0; i < 20000 && seen < kill_after_checkpoints && !exited; ++i) {
    std::error_code ec;
    const auto t = fs::last_write_time(ckpt, ec);
    if (!ec && t != last) {
      last = t;
      ++seen;
    }
    exited = ::waitpid(pid, &raw, WNOHANG) == pid;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  if (!exited) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &raw, 0);
  }
  p.killed_status = swmpm::testing::load_json((p.resumed / "run.json").string()).value("status", "");
  const Result r = swmpm_cmd("solve " + p.resumed.string() + " --resume -q --threads 2", p.resumed.parent_path());
  EXPECT_EQ(r.status, 0) << r.err;
  p.resumed_run = swmpm::testing::load_json((p.resumed / "run.json").string());
  return p;
}

/// Frames (every VTU and results.pvd) and monitors.csv byte for byte.
void expect_identical(const Pair& p, const std::string& name) {
  EXPECT_EQ(p.killed_status, "running") << name << ": the first run must have been killed part-way";
  EXPECT_GT(p.resumed_run.value("resumed_from_step", 0L), 0L) << name;
  EXPECT_EQ(p.resumed_run["status"], "completed") << name;
  std::size_t frames = 0;
  for (const auto& e : fs::directory_iterator(p.whole / "output")) {
    const std::string f = e.path().filename().string();
    ++frames;
    ASSERT_TRUE(fs::exists(p.resumed / "output" / f)) << name << ": " << f;
    EXPECT_TRUE(read_text(e.path().string()) == read_text((p.resumed / "output" / f).string()))
        << name << ": " << f << " differs";
  }
  EXPECT_GE(frames, 6u) << name;
  std::size_t resumed_frames = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(p.resumed / "output")) ++resumed_frames;
  EXPECT_EQ(resumed_frames, frames) << name << ": no frame of the killed run is left over";
  EXPECT_TRUE(read_text((p.whole / "monitors.csv").string()) == read_text((p.resumed / "monitors.csv").string()))
      << name << ": monitors.csv differs";
  EXPECT_EQ(p.resumed_run["steps"], swmpm::testing::load_json((p.whole / "run.json").string())["steps"]) << name;
  // The stability indicators' record (run.json) too: the checkpoint carries it on.
  const json whole_stability = swmpm::testing::load_json((p.whole / "run.json").string())["stability"];
  EXPECT_EQ(p.resumed_run["stability"]["frames"].dump(), whole_stability["frames"].dump()) << name;
  EXPECT_EQ(p.resumed_run["stability"]["worst"].dump(), whole_stability["worst"].dump()) << name;
  std::size_t solid_frames = 0;
  for (const auto& e : fs::directory_iterator(p.whole / "output")) solid_frames += e.path().filename().string().rfind("solid_", 0) == 0;
  EXPECT_EQ(p.resumed_run["stability"]["frames"]["time"].size(), solid_frames) << name << ": one entry per frame";
  EXPECT_NE(read_text((p.resumed / "log.txt").string()).find("resumed from the checkpoint at step"), std::string::npos);
}

json shortened(json s, double end, int frames) {
  s["time"]["end"] = end;
  s["output"]["interval"] = end / frames;
  return s;
}

}  // namespace

TEST(Resume, DryIsBitwiseTheUninterruptedRun) {
  const Pair p = run_killed_and_resumed(shortened(example("elastic-column/scene.json"), 1.0, 20), "dry", 6);
  expect_identical(p, "dry");
}

TEST(Resume, DryInitialisationWithTheMaterialParametersOfThePhase) {
  // The phase's material models swap in at its start and back at t = 0 (PhaseMaterials,
  // solver/materials/material.hpp); the resumed run, killed after the phase, replays both swaps.
  // A cohesionless slope with c = 1 MPa during a plastic phase: it slides from t = 0.
  json s = swmpm::testing::dry_mc_slope("resume-init", 1.0, 1.0);
  s["materials"][0]["cohesion"] = 0.0;
  s["initialisation"] = {{"duration", 0.6}, {"gravity_ramp", 0.4}, {"damping", 0.3}, {"plasticity", true},
                         {"materials", {{"soil", {{"cohesion", 1e6}}}}}};
  s["time"]["dt"] = 5e-4;
  s["output"]["interval"] = 0.1;
  s["output"]["monitors"] = {{{"name", "crest"}, {"at", {8.5, 6.75}}, {"quantities", {"displacement_y", "plastic_strain"}}}};
  const Pair p = run_killed_and_resumed(s, "dry-init-materials", 9);
  expect_identical(p, "dry-init-materials");
  EXPECT_GT(p.resumed_run.value("resumed_from_time", -1.0), 0.0) << "killed after the phase";
}

TEST(Resume, DryBsplinesWithModifiedFbarBetweenFrames) {
  // Checkpoints between the frames (output.checkpoint_interval), quadratic B-splines, F-bar.
  json s = shortened(example("strip-footing-fbar/scene.json"), 0.1, 6);
  s["output"]["checkpoint_interval"] = 0.0071;
  const Pair p = run_killed_and_resumed(s, "dry-fbar", 5);
  expect_identical(p, "dry-fbar");
}

TEST(Resume, ExplicitSinglePointIsBitwiseTheUninterruptedRun) {
  const Pair p = run_killed_and_resumed(shortened(example("terzaghi/scene.json"), 0.1, 10), "esp", 4);
  expect_identical(p, "explicit-single-point");
}

TEST(Resume, ExplicitSinglePointLargeStrainCellPressure) {
  const Pair p = run_killed_and_resumed(shortened(example("large-strain-consolidation/scene-fast.json"), 0.6, 8), "esp-ls", 4);
  expect_identical(p, "explicit-single-point large strain");
}

TEST(Resume, SemiImplicitSinglePointIsBitwiseTheUninterruptedRun) {
  const Pair p = run_killed_and_resumed(shortened(example("terzaghi-semi-implicit/scene.json"), 0.3, 10), "sisp", 4);
  expect_identical(p, "semi-implicit-single-point");
}

TEST(Resume, SemiImplicitDoublePointWithEscapedWaterBetweenFrames) {
  // The pressure solver's reused factor, removed water points, checkpoints between frames.
  json s = shortened(example("large-strain-consolidation-semi-implicit/scene-double-point.json"), 1.0, 10);
  s["output"]["checkpoint_interval"] = 0.037;
  const Pair p = run_killed_and_resumed(s, "sidp", 8);
  expect_identical(p, "semi-implicit-double-point");
}

TEST(Resume, SemiImplicitDoublePointTerzaghi) {
  const Pair p = run_killed_and_resumed(shortened(example("terzaghi-semi-implicit/scene-double-point.json"), 0.3, 10), "sidp-t", 4);
  expect_identical(p, "semi-implicit-double-point terzaghi");
}

TEST(Resume, MismatchedCheckpointsAreRefused) {
  const fs::path dir = swmpm::testing::scratch("resume-mismatch");
  std::ofstream(dir / "scene.json") << shortened(example("elastic-column/scene.json"), 0.2, 4).dump(2);
  const fs::path run = dir / "run";
  ASSERT_EQ(swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run.string() + " -q", dir).status, 0);
  // No checkpoint yet in a fresh run directory.
  ASSERT_EQ(swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "fresh").string() + " -q", dir).status, 0);
  Result r = swmpm_cmd("solve " + (dir / "fresh").string() + " --resume", dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("no checkpoint to resume from"), std::string::npos) << r.err;
  // The scene changed since the checkpoint: the message names the changed key.
  json s = swmpm::testing::load_json((run / "scene.json").string());
  const std::string original = read_text((run / "scene.json").string());
  s["time"]["end"] = 0.3;
  std::ofstream(run / "scene.json") << s.dump(2) << "\n";
  const std::string monitors = read_text((run / "monitors.csv").string());
  r = swmpm_cmd("solve " + run.string() + " --resume", dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("the scene changed since the checkpoint (/time/end"), std::string::npos) << r.err;
  EXPECT_EQ(read_text((run / "monitors.csv").string()), monitors) << "a refused resume writes nothing";
  std::ofstream(run / "scene.json") << original;
  // Another version's checkpoint: the hash in the header differs.
  std::string ck = read_text((run / "checkpoint.bin").string());
  const auto at = ck.find("\"git_hash\":\"");
  ASSERT_NE(at, std::string::npos);
  ck[at + 12] = ck[at + 12] == 'x' ? 'y' : 'x';
  std::ofstream(run / "checkpoint.bin", std::ios::binary) << ck;
  r = swmpm_cmd("solve " + run.string() + " --resume", dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("a checkpoint resumes only with the version that wrote it"), std::string::npos) << r.err;
  // A damaged one.
  std::ofstream(run / "checkpoint.bin", std::ios::binary) << ck.substr(0, ck.size() / 2);
  r = swmpm_cmd("solve " + run.string() + " --resume", dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("checkpoint.bin"), std::string::npos) << r.err;
}

TEST(Resume, ExplicitDoublePointColumnCollapseBetweenFrames) {
  // Both point sets reordered, liquefied points, free-surface liquid, the lagged Ergun drag
  // (the liquid velocity each solid point keeps), checkpoints between frames.
  json s = shortened(example("column-collapse-double-point/scene.json"), 0.12, 6);
  s["output"]["checkpoint_interval"] = 0.007;
  const Pair p = run_killed_and_resumed(s, "edp", 5);
  expect_identical(p, "explicit-double-point");
}

TEST(Resume, MpmFemTerzaghiBetweenFrames) {
  // The fluid's nodal state (v^L, v^{L-1}, p, phi) and the reused LU factor: a saving run and a
  // resumed one both factorise afresh after the checkpoint.
  json s = shortened(example("terzaghi-mpm-fem/scene.json"), 0.1, 5);
  s["time"]["dt"] = 1e-4;
  s["output"]["checkpoint_interval"] = 0.013;
  const Pair p = run_killed_and_resumed(s, "mpmfem", 3);
  expect_identical(p, "mpm-fem");
}

TEST(Resume, MpmFemMultiRateResumesInsideAGroupOfSoilSteps) {
  // solver.soil_substeps = 3: checkpoints fall inside a group of soil steps (the fluid ahead of
  // the soil); the resumed run continues the group where it was.
  json s = shortened(example("terzaghi-mpm-fem/scene.json"), 0.1, 5);
  s["time"]["dt"] = 5e-5;
  s["solver"]["soil_substeps"] = 3;
  s["output"]["checkpoint_interval"] = 0.0131;
  const Pair p = run_killed_and_resumed(s, "mpmfem-multirate", 3);
  expect_identical(p, "mpm-fem");
}

TEST(Resume, MpmFemDamBreakResumesAfterItsRegionGrew) {
  // The fluid's active region grows with the surge (7 times over the example's 0.2 s): the
  // checkpoint holds the region, and a resumed run solves on the one the saving run had.
  json s = shortened(example("dam-break-mpm-fem/scene.json"), 0.1, 5);
  s["output"]["checkpoint_interval"] = 0.011;
  const Pair p = run_killed_and_resumed(s, "mpmfem-region", 4);
  expect_identical(p, "mpm-fem");
  const json r = swmpm::testing::load_json((p.resumed / "run.json").string());
  EXPECT_GE(r["counters"]["fluid region changes"].get<double>(), 1.0);
}
