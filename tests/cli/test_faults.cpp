// Faults a demanding user or a security reviewer meets (issue 27, items 1-3), through the `swmpm`
// command: a geometry script that would run commands, write or read files; a full disk; run
// directories that hold a user's files or an earlier run; SIGTERM.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using swmpm::testing::read_text;
using swmpm::testing::Result;
using swmpm::testing::swmpm_cmd;

json column_scene() { return swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json"); }

void write(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

/// A 2D unit square as a .geo script, with `extra` lines after the geometry.
std::string square_geo(const std::string& extra) {
  return "DefineConstant[ s = 0.1 ];\n"
         "Point(1) = {0, 0, 0}; Point(2) = {s, 0, 0}; Point(3) = {s, 1, 0}; Point(4) = {0, 1, 0};\n"
         "Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n"
         "Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n" +
         extra + "\n";
}

/// The elastic column with its body read from `geo` (a file name in the scene's folder).
json gmsh_column(const std::string& geo, const json& parameters = json()) {
  json s = column_scene();
  s["bodies"][0]["geometry"] = {{"type", "gmsh"}, {"file", geo}};
  if (!parameters.is_null()) s["bodies"][0]["geometry"]["parameters"] = parameters;
  return s;
}

struct Probe {
  fs::path dir;
  Result r;
};

/// Preprocesses `scene` with `geo_text` as geometry.geo beside it; `flags` go to the command line.
Probe preprocess_geo(const std::string& name, const std::string& geo_text, const std::string& flags = "",
                     const json& parameters = json()) {
  const fs::path dir = swmpm::testing::scratch("faults-" + name);
  write(dir / "geometry.geo", geo_text);
  write(dir / "scene.json", gmsh_column("geometry.geo", parameters).dump(2));
  const Result r = swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string() + " " + flags, dir);
  return {dir, r};
}

/// The scene's run directory is refused: exit 2, one line naming the .geo, its line and `construct`.
void expect_refused(const std::string& name, const std::string& extra, const std::string& construct, int line = 5) {
  const Probe p = preprocess_geo(name, square_geo(extra));
  EXPECT_EQ(p.r.status, 2) << name << ": " << p.r.err;
  EXPECT_NE(p.r.err.find("geometry.geo:" + std::to_string(line) + ": `" + construct), std::string::npos)
      << name << ": the message names the file, the line and the construct: " << p.r.err;
  EXPECT_NE(p.r.err.find("/bodies/0/geometry/file"), std::string::npos) << p.r.err;
  EXPECT_NE(p.r.err.find("--trust-geometry"), std::string::npos) << p.r.err;
  EXPECT_EQ(std::count(p.r.err.begin(), p.r.err.end(), '\n'), 1) << p.r.err;
  EXPECT_FALSE(fs::exists(p.dir / "run")) << name << ": nothing may be written";
}

}  // namespace

TEST(GeometryScript, CommandsAreRefusedAndDoNotRun) {
  const fs::path marker = swmpm::testing::scratch("faults-marker") / "touched";
  expect_refused("systemcall", "SystemCall \"touch " + marker.string() + "\";", "SystemCall");
  expect_refused("system", "System \"touch " + marker.string() + "\";", "System");
  expect_refused("nonblocking", "NonBlockingSystemCall \"touch " + marker.string() + "\";", "NonBlockingSystemCall");
  expect_refused("onelab", "OnelabRun(\"x\", \"touch " + marker.string() + "\");", "OnelabRun");
  EXPECT_FALSE(fs::exists(marker)) << "a refused script must not have run";
}

TEST(GeometryScript, WritesAndProcessControlAreRefused) {
  const fs::path victim = swmpm::testing::scratch("faults-victim") / "victim.txt";
  expect_refused("printf", "Printf(\"owned\") > \"" + victim.string() + "\";", "Printf(...) >");
  expect_refused("printf-append", "Printf(\"s = %g\", s) >> \"" + victim.string() + "\";", "Printf(...) >>");
  expect_refused("save", "Save \"" + victim.string() + "\";", "Save");
  expect_refused("print", "Print \"" + victim.string() + "\";", "Print");
  expect_refused("createdir", "CreateDir \"" + victim.string() + "\";", "CreateDir");
  expect_refused("exit", "Exit;", "Exit");
  expect_refused("sleep", "Sleep 1000;", "Sleep");
  expect_refused("general-option", "General.OptionsFileName = \"" + victim.string() + "\";", "General.OptionsFileName");
  expect_refused("solver-option", "Solver.Executable0 = \"/bin/sh\";", "Solver.Executable0");
  EXPECT_FALSE(fs::exists(victim));
}

TEST(GeometryScript, FilesOutsideTheScenesFoldersAreRefused) {
  expect_refused("include-passwd", "Include \"/etc/passwd\";", "Include \"/etc/passwd\"");
  expect_refused("include-up", "Include \"../elsewhere.geo\";", "Include \"../elsewhere.geo\"");
  expect_refused("include-expression", "Include StrCat(\"/etc/\", \"passwd\");", "Include");
  expect_refused("merge-script", "Merge \"helper.py\";", "Merge \"");
}

TEST(GeometryScript, OrdinaryScriptsStillMesh) {
  // Words in comments and strings are not commands; Mesh.* options, messages to the terminal and an
  // Include beside the file are what geometry scripts use.
  const fs::path dir = swmpm::testing::scratch("faults-ordinary");
  write(dir / "sizes.geo", "Mesh.MeshSizeMax = 0.05; // no SystemCall here\n");
  write(dir / "geometry.geo", square_geo("Include \"sizes.geo\";\n/* Exit; */ Printf(\"SystemCall %g\", s);\n"
                                          "Geometry.Tolerance = 1e-9;"));
  write(dir / "scene.json", gmsh_column("geometry.geo", {{"s", 0.1}}).dump(2));
  const Result r = swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
  EXPECT_EQ(r.status, 0) << r.err;
  const auto solid = swmpm::scene::read_vtu((dir / "run" / "particles" / "solid.vtu").string());
  EXPECT_EQ(solid.size(), 2u * 20u * 4u) << "0.1 x 1 m at 2 x 2 particles per 0.05 m cell";
}

TEST(GeometryScript, TrustGeometryLiftsTheCheck) {
  const fs::path marker = swmpm::testing::scratch("faults-trusted-marker") / "touched";
  const Probe p = preprocess_geo("trusted", square_geo("SystemCall \"touch " + marker.string() + "\";"), "--trust-geometry");
  EXPECT_EQ(p.r.status, 0) << p.r.err;
  EXPECT_TRUE(fs::exists(marker)) << "--trust-geometry meshes the script as it is";
}

TEST(GeometryScript, ParameterPreludeIsPrivate) {
  // Before: the prelude went to /tmp/swmpm-gmsh-<pid>-0.geo, opened with O_TRUNC through symlinks.
  // A symlink planted at every such name for the next pids must keep its victim intact.
  const fs::path dir = swmpm::testing::scratch("faults-prelude-victim");
  write(dir / "victim.txt", "precious\n");
  std::vector<fs::path> planted;
  const pid_t next = ::getpid();
  for (pid_t pid = next; pid < next + 200; ++pid) {
    const fs::path link = fs::temp_directory_path() / ("swmpm-gmsh-" + std::to_string(pid) + "-0.geo");
    std::error_code ec;
    fs::create_symlink(dir / "victim.txt", link, ec);
    if (!ec) planted.push_back(link);
  }
  const Probe p = preprocess_geo("prelude", square_geo(""), "", {{"s", 0.1}});
  for (const auto& link : planted) fs::remove(link);
  EXPECT_EQ(p.r.status, 0) << p.r.err;
  EXPECT_EQ(read_text((dir / "victim.txt").string()), "precious\n");
  // No prelude is left behind in the temporary folder.
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))
    EXPECT_FALSE(fs::exists(e.path() / "geometry-parameters.geo")) << e.path();
}

// ---------------------------------------------------------------------------------------------
// Run directories

namespace {

/// Every file under `dir` with its content, for before/after comparisons.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out[fs::relative(e.path(), dir).string()] = read_text(e.path().string());
  return out;
}

/// The column, short: 0.1 s, frames every 0.05 s.
json short_column() {
  json s = column_scene();
  s["time"]["end"] = 0.1;
  return s;
}

}  // namespace

TEST(RunDirectory, DotWithTheUsersFilesIsRefusedAndNothingChanges) {
  const fs::path dir = swmpm::testing::scratch("faults-dot");
  write(dir / "scene.json", short_column().dump(2));
  fs::create_directories(dir / "output");
  write(dir / "output" / "notes.txt", "mine\n");
  const auto before = snapshot(dir);
  const std::string cmd = "cd " + dir.string() + " && " + SWMPM_EXE + " run scene.json -o . > out.txt 2> err.txt";
  const int raw = std::system(cmd.c_str());
  const std::string err = read_text((dir / "err.txt").string());
  EXPECT_EQ(WEXITSTATUS(raw), 2) << err;
  EXPECT_NE(err.find("scene.json exists and swmpm did not write it"), std::string::npos) << err;
  fs::remove(dir / "out.txt");
  fs::remove(dir / "err.txt");
  EXPECT_EQ(snapshot(dir), before) << "the user's scene.json and output/notes.txt are as they were";
}

TEST(RunDirectory, AnEarlierRunIsReplacedOnlyWithOverwriteAndOnlyItsOwnFiles) {
  const fs::path dir = swmpm::testing::scratch("faults-rerun");
  write(dir / "scene.json", short_column().dump(2));
  const std::string run = (dir / "run").string();
  ASSERT_EQ(swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run + " -q", dir).status, 0);
  ASSERT_TRUE(fs::exists(dir / "run" / "plots" / "top.png"));
  write(dir / "run" / "output" / "my-notes.txt", "mine\n");
  write(dir / "run" / "plots" / "my-sketch.png", "not a png\n");

  // A second scene into the same folder: refused, the earlier run untouched.
  json other = short_column();
  other["output"]["monitors"] = json::array({other["output"]["monitors"][0]});
  write(dir / "other.json", other.dump(2));
  const auto before = snapshot(dir / "run");
  Result r = swmpm_cmd("preprocess " + (dir / "other.json").string() + " -o " + run, dir);
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("holds an earlier swmpm run (status completed)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--overwrite"), std::string::npos) << r.err;
  EXPECT_EQ(snapshot(dir / "run"), before);

  // With --overwrite: the earlier run's files go, the user's stay; postprocess then has no old
  // monitors to draw.
  r = swmpm_cmd("preprocess " + (dir / "other.json").string() + " -o " + run + " --overwrite", dir);
  EXPECT_EQ(r.status, 0) << r.err;
  for (const char* gone : {"run.json", "monitors.csv", "log.txt", "plots/top.png", "plots/base.png",
                           "output/results.pvd", "output/solid_000000.vtu"})
    EXPECT_FALSE(fs::exists(dir / "run" / gone)) << gone;
  EXPECT_EQ(read_text((dir / "run" / "output" / "my-notes.txt").string()), "mine\n");
  EXPECT_EQ(read_text((dir / "run" / "plots" / "my-sketch.png").string()), "not a png\n");
  r = swmpm_cmd("postprocess " + run + " plot", dir);
  EXPECT_NE(r.status, 0) << "no monitors.csv of this run yet: " << r.out;

  // Solving it replaces nothing of the user's either, and draws only this run's monitor.
  r = swmpm_cmd("solve " + run + " -q", dir);
  EXPECT_EQ(r.status, 0) << r.err;
  r = swmpm_cmd("postprocess " + run + " plot -q", dir);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "run" / "plots" / "top.png"));
  EXPECT_FALSE(fs::exists(dir / "run" / "plots" / "base.png"));
  EXPECT_EQ(read_text((dir / "run" / "output" / "my-notes.txt").string()), "mine\n");
  EXPECT_EQ(read_text((dir / "run" / "plots" / "my-sketch.png").string()), "not a png\n");

  // A file of a name swmpm writes, put there by the user, is never replaced: refused up front.
  write(dir / "run" / "report.md", "my report\n");
  r = swmpm_cmd("postprocess " + run + " report -q", dir);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("report.md exists and swmpm did not write it"), std::string::npos) << r.err;
  EXPECT_EQ(read_text((dir / "run" / "report.md").string()), "my report\n");
}

namespace {

/// Runs `swmpm ARGS` in the background; returns its pid.
pid_t spawn(const std::vector<std::string>& args, const fs::path& out) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen(out.c_str(), "w", stderr);
    std::freopen("/dev/null", "w", stdout);
    std::vector<char*> argv{const_cast<char*>(SWMPM_EXE)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(SWMPM_EXE, argv.data());
    ::_exit(127);
  }
  return pid;
}

}  // namespace

TEST(RunDirectory, RunJsonSaysRunningAndSigtermInterruptsKeepingTheState) {
  const fs::path dir = swmpm::testing::scratch("faults-sigterm");
  json s = column_scene();
  s["time"]["end"] = 1e4;  // far longer than the test waits
  s["output"]["interval"] = 1e3;
  write(dir / "scene.json", s.dump(2));
  const std::string run = (dir / "run").string();
  ASSERT_EQ(swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + run + " -q", dir).status, 0);
  const pid_t pid = spawn({"solve", run, "--threads", "1"}, dir / "stderr.txt");
  json state;
  for (int i = 0; i < 200; ++i) {  // until the first steps are done (10 s at most)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    try {
      state = swmpm::testing::load_json(run + "/run.json");
      if (state.value("status", "") == "running" && fs::exists(dir / "run" / "output" / "results.pvd")) break;
    } catch (const std::exception&) {
    }
  }
  EXPECT_EQ(state.value("status", ""), "running") << "run.json marks a run in progress";
  EXPECT_EQ(state.value("pid", 0L), static_cast<long>(pid));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ::kill(pid, SIGTERM);
  int raw = 0;
  ::waitpid(pid, &raw, 0);
  ASSERT_TRUE(WIFEXITED(raw)) << "SIGTERM is handled, not fatal";
  EXPECT_EQ(WEXITSTATUS(raw), 4);
  const json done = swmpm::testing::load_json(run + "/run.json");
  EXPECT_EQ(done["status"], "interrupted");
  EXPECT_GT(done["steps"].get<long>(), 0);
  EXPECT_NE(read_text((dir / "stderr.txt").string()).find("interrupted by SIGTERM"), std::string::npos);
  // The state at the stop is the last frame, readable.
  const auto frames = swmpm::scene::read_pvd(run + "/output/results.pvd");
  ASSERT_GE(frames.size(), 2u);
  EXPECT_NEAR(frames.back().time, done["end_time"].get<double>(), 1e-12);
  EXPECT_EQ(swmpm::testing::last_frame(run).size(), 160u);
}

// ---------------------------------------------------------------------------------------------
// A full disk

namespace {

/// What a run left when its writes failed: exit 5, run.json `failed` with the reason, every frame
/// results.pvd lists complete, monitors.csv ending with a whole row.
void expect_failed_cleanly(const fs::path& run, int status, const std::string& err, const std::string& reason) {
  EXPECT_EQ(status, 5) << err;
  EXPECT_NE(err.find(reason), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << "one line on stderr: " << err;
  const json rj = swmpm::testing::load_json((run / "run.json").string());
  EXPECT_EQ(rj["status"], "failed");
  EXPECT_NE(rj["diagnosis"].get<std::string>().find(reason), std::string::npos);
  const auto frames = swmpm::scene::read_pvd((run / "output" / "results.pvd").string());
  EXPECT_GE(frames.size(), 1u);
  EXPECT_EQ(rj["frames"].get<std::size_t>(), frames.size());
  for (const auto& f : frames) EXPECT_EQ(swmpm::scene::read_vtu((run / "output" / f.file).string()).size(), 160u) << f.file;
  const std::string monitors = read_text((run / "monitors.csv").string());
  ASSERT_FALSE(monitors.empty());
  EXPECT_EQ(monitors.back(), '\n') << "monitors.csv ends with a whole row";
  // No temporary is left beside the frames.
  for (const auto& e : fs::directory_iterator(run / "output"))
    EXPECT_EQ(e.path().filename().string().find(".swmpm-"), std::string::npos) << e.path();
}

/// The column with a frame and a monitor row every step for 0.5 s (556 steps of 9e-4 s; an
/// interval below the step is refused, so the interval is the step).
json frame_every_step() {
  json s = column_scene();
  s["time"]["end"] = 0.5;
  s["time"]["dt"] = 9e-4;
  s["output"]["interval"] = 9e-4;
  s["output"]["monitor_interval"] = 0.0;
  return s;
}

}  // namespace

TEST(FullDisk, FileSizeLimitStopsTheRunWithStatusFailed) {
  // RLIMIT_FSIZE (no root needed): monitors.csv and results.pvd outgrow 32 KiB mid-run; writes fail
  // with EFBIG.
  const fs::path dir = swmpm::testing::scratch("faults-fsize");
  write(dir / "scene.json", frame_every_step().dump(2));
  const fs::path run = dir / "run";
  ASSERT_EQ(swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + run.string() + " -q", dir).status, 0);
  const std::string cmd = "trap '' XFSZ; ulimit -f 32; exec " + std::string(SWMPM_EXE) + " solve " + run.string() +
                          " -q 2> " + (dir / "err.txt").string();
  const int raw = std::system(("bash -c \"" + cmd + "\"").c_str());
  expect_failed_cleanly(run, WEXITSTATUS(raw), read_text((dir / "err.txt").string()), "File too large");
}

TEST(FullDisk, FullFilesystemStopsTheRunAndPreprocessWritesNothing) {
  // A 5 MiB tmpfs in a private mount namespace (root only; skipped elsewhere): more than twice the
  // run's estimated output (2.3 MB, a lower bound; a disk that cannot hold it is refused up front,
  // ResourceLimits.*), less than the 7 MB it writes.
  const fs::path dir = swmpm::testing::scratch("faults-enospc");
  write(dir / "scene.json", frame_every_step().dump(2));
  const fs::path mnt = dir / "disk", kept = dir / "kept";
  fs::create_directories(mnt);
  const std::string script =
      "set -e; mount -t tmpfs -o size=5m tmpfs " + mnt.string() + "; cd " + dir.string() + "; " +
      std::string(SWMPM_EXE) + " preprocess scene.json -o " + (mnt / "run").string() + " -q; set +e; " +
      SWMPM_EXE + " solve " + (mnt / "run").string() + " -q 2> err.txt; echo $? > status.txt; " +
      // preprocess into the full disk: exit 5, and nothing left behind
      "head -c 10000000 /dev/zero > " + (mnt / "filler").string() + " 2>/dev/null; " + SWMPM_EXE +
      " preprocess scene.json -o " + (mnt / "second").string() + " -q 2> err2.txt; echo $? > status2.txt; " +
      "ls -A " + mnt.string() + " > listing.txt; rm " + (mnt / "filler").string() + "; cp -a " +
      (mnt / "run").string() + " " + kept.string();
  const int raw = std::system(("unshare -m sh -c '" + script + "' 2> " + (dir / "unshare.txt").string()).c_str());
  if (WEXITSTATUS(raw) != 0 && !fs::exists(dir / "status.txt"))
    GTEST_SKIP() << "cannot mount a tmpfs here: " << read_text((dir / "unshare.txt").string());
  expect_failed_cleanly(kept, std::stoi(read_text((dir / "status.txt").string())), read_text((dir / "err.txt").string()),
                        "No space left on device");
  EXPECT_EQ(std::stoi(read_text((dir / "status2.txt").string())), 5) << read_text((dir / "err2.txt").string());
  EXPECT_NE(read_text((dir / "err2.txt").string()).find("No space left on device"), std::string::npos);
  EXPECT_EQ(read_text((dir / "listing.txt").string()), "filler\nrun\n") << "preprocess left nothing on the full disk";
}

// Issue 27, item 4: an output interval below the time step is refused before anything is written
// (output.interval 1e-20 s spun at 100 % CPU after 2-3 frames: adding it to the next frame's time
// no longer changed it). Fixed dt and dt "auto" alike; each key named.
TEST(Hangs, IntervalsBelowTheTimeStepAreRefused) {
  const fs::path dir = swmpm::testing::scratch("hangs-intervals");
  for (const char* key : {"interval", "monitor_interval", "checkpoint_interval"})
    for (bool fixed_dt : {true, false}) {
      json s = column_scene();
      s["time"]["end"] = 0.01;
      if (fixed_dt) s["time"]["dt"] = 1e-4;
      else s["time"].erase("dt");
      s["output"][key] = 1e-20;
      write(dir / "scene.json", s.dump(2));
      const fs::path run = dir / (std::string(key) + (fixed_dt ? "-fixed" : "-auto"));
      ASSERT_EQ(swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + run.string() + " -q", dir).status, 0);
      const Result r = swmpm_cmd("solve " + run.string() + " -q", dir);
      EXPECT_EQ(r.status, 2) << key << ": " << r.err;
      EXPECT_NE(r.err.find(std::string("/output/") + key + ": got 1e-20 s, below the time step"), std::string::npos) << r.err;
      EXPECT_FALSE(fs::exists(run / "run.json")) << key;
      EXPECT_FALSE(fs::exists(run / "output")) << key;
    }
}

// An interval equal to the step (the smallest allowed): a frame and a monitor row every step, each
// next mark computed in one step from the lattice of marks, and the run ends.
TEST(Hangs, TinyIntervalsAboveTheStepStillEnd) {
  const fs::path dir = swmpm::testing::scratch("hangs-tiny");
  json s = column_scene();
  s["time"]["end"] = 2e-3;
  s["time"]["dt"] = 1e-4;
  s["output"]["interval"] = 1e-4;
  s["output"]["monitor_interval"] = 1e-4;
  write(dir / "scene.json", s.dump(2));
  const Result r = swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + (dir / "run").string() + " -q", dir);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(swmpm::testing::load_json((dir / "run" / "run.json").string())["status"], "completed");
}

// ---------------------------------------------------------------------------------------------
// Parser robustness (issue 27, item 6): what a scene file or a postprocess input can hold that
// crashed, hung or exhausted memory. Each is refused with exit 2, one line naming the file (and
// the JSON path), in bounded time, and nothing is written.

namespace {

/// `swmpm ARGS` through the shell, killed after `limit` seconds (a hang must not hang the test);
/// with the wall time it took.
struct Timed {
  Result r;
  double seconds;
};
Timed swmpm_limited(const std::string& args, const fs::path& dir, int limit = 60) {
  const std::string out = (dir / "stdout.txt").string(), err = (dir / "stderr.txt").string();
  const std::string cmd = "timeout -s KILL " + std::to_string(limit) + " " + SWMPM_EXE + " " + args + " > " + out +
                          " 2> " + err;
  const auto start = std::chrono::steady_clock::now();
  const int raw = std::system(cmd.c_str());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return {{WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, read_text(out), read_text(err)}, seconds};
}

std::size_t line_count(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

/// The column scene as text, with `"solver": <value>` in place of its solver object.
std::string column_with_solver(const std::string& value) {
  json s = column_scene();
  s.erase("solver");
  std::string text = s.dump(2);
  text.insert(1, "\n  \"solver\": " + value + ",");
  return text;
}

}  // namespace

// 65,000 levels of arrays or objects crashed with SIGSEGV; preprocess and solve (which reads the
// run directory's scene.json) now stop at 64 levels.
TEST(ParserRobustness, DeepNestingExitsTwoNamingTheFileAndThePath) {
  const fs::path dir = swmpm::testing::scratch("parser-deep");
  std::string objects;
  for (int i = 0; i < 65000; ++i) objects += "{\"a\":";
  objects += "1" + std::string(65000, '}');
  const std::vector<std::pair<std::string, std::string>> cases{
      {std::string(65000, '[') + std::string(65000, ']'), "/solver/0/0/0/0"}, {objects, "/solver/a/a/a/a"}};
  for (const auto& [deep, pointer] : cases) {
    write(dir / "scene.json", column_with_solver(deep));
    const Timed t = swmpm_limited("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
    EXPECT_EQ(t.r.status, 2) << t.r.err.substr(0, 500);
    EXPECT_EQ(line_count(t.r.err), 1u) << t.r.err.substr(0, 500);
    EXPECT_EQ(t.r.err.rfind((dir / "scene.json").string() + ": " + pointer, 0), 0u) << t.r.err.substr(0, 500);
    EXPECT_NE(t.r.err.find(": got arrays and objects nested deeper than 64 levels, expected at most 64 (line 2, column "),
              std::string::npos)
        << t.r.err.substr(0, 500);
    EXPECT_LT(t.seconds, 10.0);
    EXPECT_FALSE(fs::exists(dir / "run")) << "nothing may be written";

    // The same text as a run directory's scene.json: solve reads it before anything else.
    fs::create_directories(dir / "made-up-run");
    write(dir / "made-up-run" / "scene.json", column_with_solver(deep));
    const Timed s = swmpm_limited("solve " + (dir / "made-up-run").string() + " -q", dir);
    EXPECT_EQ(s.r.status, 2) << s.r.err.substr(0, 500);
    EXPECT_EQ(s.r.err.rfind((dir / "made-up-run" / "scene.json").string() + ": " + pointer, 0), 0u)
        << s.r.err.substr(0, 500);
    EXPECT_FALSE(fs::exists(dir / "made-up-run" / "run.json"));
  }
}

// 1e400 gave nlohmann's exception text with exit 1.
TEST(ParserRobustness, NumberOutOfRangeExitsTwoNamingThePath) {
  const fs::path dir = swmpm::testing::scratch("parser-1e400");
  std::string text = column_scene().dump(2);
  const std::size_t at = text.find("\"cell_size\": 0.05");
  ASSERT_NE(at, std::string::npos);
  text.replace(at + 13, 4, "1e400");
  write(dir / "scene.json", text);
  const Timed t = swmpm_limited("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
  EXPECT_EQ(t.r.status, 2) << t.r.err;
  EXPECT_EQ(line_count(t.r.err), 1u) << t.r.err;
  EXPECT_EQ(t.r.err.rfind((dir / "scene.json").string() +
                              ": /grid/cell_size: got 1e400, which is out of the range of a double; expected a finite "
                              "number (line ",
                          0),
            0u)
      << t.r.err;
  EXPECT_FALSE(fs::exists(dir / "run"));
}

// An unknown key and a bad choice of 1 MB each took seconds and gigabytes ("did you mean" on the
// whole value) and echoed the megabyte back.
TEST(ParserRobustness, MegabyteKeysAndValuesAreRefusedQuicklyAndShortly) {
  const fs::path dir = swmpm::testing::scratch("parser-megabyte");
  json s = column_scene();
  s["grid"][std::string(1'000'000, 'k')] = 1;
  s["grid"]["shape_function"] = std::string(1'000'000, 'g');
  write(dir / "scene.json", s.dump());
  const Timed t = swmpm_limited("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
  EXPECT_EQ(t.r.status, 2) << t.r.err.substr(0, 500);
  EXPECT_EQ(line_count(t.r.err), 2u) << t.r.err.substr(0, 500);
  EXPECT_LT(t.r.err.size(), 1000u) << "the values are shortened in the messages";
  EXPECT_NE(t.r.err.find("/grid/shape_function: got \"" + std::string(60, 'g') + "… (1000000 characters)\", expected one of: "),
            std::string::npos)
      << t.r.err.substr(0, 500);
  EXPECT_NE(t.r.err.find(": unknown key \"" + std::string(60, 'k') + "… (1000000 characters)\""), std::string::npos)
      << t.r.err.substr(0, 500);
  EXPECT_LT(t.seconds, 1.0) << "the whole preprocess, reading 2 MB of scene";
  EXPECT_FALSE(fs::exists(dir / "run"));
}

// An initial velocity that is NaN at some particles, but finite at the corners and the centre of
// the body that the scene check samples: preprocess stops at the first particle, naming it.
TEST(ParserRobustness, NonFiniteVelocityAtAParticleStopsPreprocess) {
  const fs::path dir = swmpm::testing::scratch("parser-velocity");
  json s = column_scene();
  const std::string expr = "abs(x - 0.0375) < 0.001 ? sqrt(-1) : 0";
  s["bodies"][0]["initial"] = {{"velocity", {expr, 0}}};
  write(dir / "scene.json", s.dump(2));
  const Timed t = swmpm_limited("preprocess " + (dir / "scene.json").string() + " -o " + (dir / "run").string(), dir);
  EXPECT_EQ(t.r.status, 2) << t.r.err;
  EXPECT_EQ(line_count(t.r.err), 1u) << t.r.err;
  EXPECT_EQ(t.r.err.rfind((dir / "scene.json").string() + ": /bodies/0/initial/velocity/0: got \"" + expr +
                              "\", which is nan at (x, y) = (0.0375, ",
                          0),
            0u)
      << t.r.err;
  EXPECT_NE(t.r.err.find("expected a finite velocity [m/s]"), std::string::npos) << t.r.err;
  EXPECT_FALSE(fs::exists(dir / "run"));
}

// A load function that is infinite between the times the scene check samples: the run stops at
// the step that meets it, naming the load and the expression (it diverged with "J <= 0").
TEST(ParserRobustness, NonFiniteLoadFunctionStopsTheRunNamingIt) {
  const fs::path dir = swmpm::testing::scratch("parser-load");
  json s = column_scene();
  s["time"]["end"] = 0.1;
  const std::string expr = "abs(t - 0.03) < 0.002 ? 1/0 : 1";
  s["loads"] = {{{"type", "traction"}, {"body", "column"}, {"face", "y_max"}, {"value", {0.0, -1000.0}}, {"function", expr}}};
  write(dir / "scene.json", s.dump(2));
  const fs::path run = dir / "run";
  ASSERT_EQ(swmpm_cmd("preprocess " + (dir / "scene.json").string() + " -o " + run.string() + " -q", dir).status, 0)
      << "finite at t = 0, 0.0125, ..., 0.1 s";
  const Timed t = swmpm_limited("solve " + run.string() + " -q --threads 1", dir);
  EXPECT_EQ(t.r.status, 3) << t.r.err;
  const json rj = swmpm::testing::load_json((run / "run.json").string());
  EXPECT_EQ(rj["status"], "diverged");
  const std::string diagnosis = rj.value("diagnosis", "");
  EXPECT_EQ(diagnosis.rfind((run / "scene.json").string() + ": /loads/0/function: got \"" + expr + "\", which is inf at t = ", 0), 0u)
      << diagnosis;
  EXPECT_NE(diagnosis.find(" s; expected a finite value"), std::string::npos) << diagnosis;
  EXPECT_GT(rj["end_time"].get<double>(), 0.026);
  EXPECT_LT(rj["end_time"].get<double>(), 0.032);
}

// compare --reference FIFO blocked forever; a symbolic link to /dev/zero grew memory to 2.2 GB.
// Every file postprocess reads is a regular file (links resolved) of at most 256 MiB.
TEST(ParserRobustness, PostprocessReadsOnlyRegularFilesOfBoundedSize) {
  const fs::path dir = swmpm::testing::scratch("parser-postprocess");
  write(dir / "scene.json", short_column().dump(2));
  const fs::path run = dir / "run";
  ASSERT_EQ(swmpm_cmd("run " + (dir / "scene.json").string() + " -o " + run.string() + " -q", dir).status, 0);
  ASSERT_EQ(::mkfifo((dir / "fifo.csv").c_str(), 0600), 0);
  fs::create_symlink("/dev/zero", dir / "zero.csv");
  { std::ofstream(dir / "huge.csv") << "t,v\n"; }
  fs::resize_file(dir / "huge.csv", 300u << 20);  // sparse: takes no disk space

  const std::string limit = "(a regular file of at most 256 MiB)";
  const std::vector<std::pair<std::string, std::string>> cases{
      {"fifo.csv", "got a FIFO (named pipe), expected a reference file " + limit},
      {"zero.csv", "got a character device, expected a reference file " + limit},
      {"huge.csv", "got 300 MiB (314572800 bytes), expected a reference file " + limit}};
  for (const auto& [name, why] : cases) {
    const std::string file = (dir / name).string();
    for (const std::string& command :
         {"compare --monitor top.displacement_y --reference " + file, "plot --reference top.displacement_y=" + file}) {
      const Timed t = swmpm_limited("postprocess " + run.string() + " " + command, dir, 20);
      EXPECT_EQ(t.r.status, 2) << command << ": " << t.r.err;
      EXPECT_EQ(line_count(t.r.err), 1u) << t.r.err;
      EXPECT_NE(t.r.err.find(file + ": " + why), std::string::npos) << command << ": " << t.r.err;
      EXPECT_LT(t.seconds, 5.0) << command;
    }
  }
  // A file of the run directory itself, e.g. monitors.csv made a link to /dev/zero.
  fs::rename(run / "monitors.csv", dir / "monitors.csv");
  fs::create_symlink("/dev/zero", run / "monitors.csv");
  const Timed t = swmpm_limited("postprocess " + run.string() + " compare --monitor top.displacement_y --reference " +
                                    (dir / "huge.csv").string(),
                                dir, 20);
  fs::remove(run / "monitors.csv");
  fs::rename(dir / "monitors.csv", run / "monitors.csv");
  EXPECT_EQ(t.r.status, 2) << t.r.err;
  EXPECT_NE(t.r.err.find((run / "monitors.csv").string() + ": got a character device, expected a CSV file"), std::string::npos)
      << t.r.err;
}
