// Helpers for tests that run the whole pipeline in-process: write a scene, preprocess, solve, read
// back monitors.csv and frames exactly as a user's script would.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "postprocess/postprocess.hpp"
#include "preprocess/preprocess.hpp"
#include "scene/pointcloud.hpp"
#include "solver/run.hpp"

namespace swmpm::testing {

namespace fs = std::filesystem;

inline fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / "swmpm-tests" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// Writes `scene` under a scratch folder, runs preprocess + solve; returns the run directory.
inline std::string run_scene(const nlohmann::json& scene, const std::string& name, int threads = 0,
                             int* status = nullptr) {
  const fs::path dir = scratch(name);
  const fs::path scene_file = dir / "scene.json";
  std::ofstream(scene_file) << scene.dump(2);
  const std::string run_dir = swmpm::pre::preprocess(scene_file.string(), (dir / "run").string(), true);
  const int rc = swmpm::solve(run_dir, {threads, true});
  if (status) *status = rc;
  else EXPECT_EQ(rc, 0) << "solve failed for " << name;
  return run_dir;
}

/// RUN/monitors.csv (postprocess's reader: the header's names, a column each).
inline post::Table read_monitors(const std::string& run) { return post::read_csv(run + "/monitors.csv"); }

/// Terzaghi's series: p / p0 at depth z below the drained top of a layer of height H = 1 m.
inline double terzaghi(double z, double Tv) {
  double sum = 0.0;
  for (int m = 0; m < 200; ++m) {
    const double M = (2 * m + 1) * M_PI / 2;
    sum += 2.0 / M * std::sin(M * z) * std::exp(-M * M * Tv);
  }
  return sum;
}

inline nlohmann::json load_json(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

/// The last frame of the run's results.pvd for one phase (solid: the soil points; fluid: the
/// water points of a double-point run).
inline scene::PointCloud last_frame(const std::string& run_dir, const std::string& group = "solid") {
  const auto entries = scene::read_pvd(run_dir + "/output/results.pvd");
  for (auto e = entries.rbegin(); e != entries.rend(); ++e)
    if (e->group == group) return scene::read_vtu(run_dir + "/output/" + e->file);
  ADD_FAILURE() << run_dir << ": no " << group << " frame";
  return {};
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// What the `swmpm` executable (SWMPM_EXE, a compile definition of the test targets) did.
struct Result {
  int status;
  std::string out, err;
};

/// Runs `swmpm ARGS` through the shell, capturing stdout and stderr into files under `dir`.
inline Result swmpm_cmd(const std::string& args, const fs::path& dir) {
  const std::string out = (dir / "stdout.txt").string(), err = (dir / "stderr.txt").string();
  const std::string cmd = std::string(SWMPM_EXE) + " " + args + " > " + out + " 2> " + err;
  const int raw = std::system(cmd.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, read_text(out), read_text(err)};
}

}  // namespace swmpm::testing
