// A deterministic mutation fuzzer over the example scenes and the geometry files (issue 27, item
// 10). Each mutant goes through `swmpm preprocess` (and, for the quick scenes, `swmpm solve`
// stopped by SIGINT after a few seconds), and the outcome must be one of what the contract allows:
// - no death by a signal, no hang past the time-out (SIGINT is honoured);
// - a rejection is exit 2 with its first line naming the file that was bad, and nothing written;
// - exit 0 leaves valid output: scene.json that parses, particle files that read; a solve's
//   run.json says what happened (completed, diverged, interrupted) and agrees with the exit status;
// - a geometry script never runs the command planted in it.
// The default suite runs a few hundred mutants with a fixed seed; FuzzSlow.* (label slow) thousands.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "scene/pointcloud.hpp"
#include "support/run_helpers.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// One mutation site: a pointer into the JSON tree.
void collect_paths(const json& j, const json::json_pointer& at, std::vector<json::json_pointer>& out) {
  out.push_back(at);
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it) collect_paths(*it, at / it.key(), out);
  else if (j.is_array())
    for (std::size_t i = 0; i < j.size(); ++i) collect_paths(j[i], at / i, out);
}

/// Values a careless or hostile hand puts in a scene.
json odd_value(std::mt19937& rng) {
  static const std::vector<json> values = {
      nullptr, true, false, "", "x", "auto", 0, -1, 1, 0.5, -0.0, 1e308, -1e308, 1e-308, 1e300, 1e-30, 2147483648.0,
      9.3e18, json::array(), json::object(), json::array({1e308, 1e308, 1e308}), json::array({0, 0}),
      json::array({-1, -1, -1}), std::string(5000, 'k'), "1/0", "exp(1e6)", "sqrt(-1)", "../../etc/passwd",
      "/dev/zero", json::array({json::array({json::array({1})})})};
  return values[rng() % values.size()];
}

/// A scene with one structural change at a random place, or its text damaged.
std::string mutate_scene(const json& scene, std::mt19937& rng) {
  json m = scene;
  std::vector<json::json_pointer> paths;
  collect_paths(m, json::json_pointer(), paths);
  const json::json_pointer at = paths[1 + rng() % (paths.size() - 1)];
  json& v = m[at];
  switch (rng() % 8) {
    case 0: {  // remove the key or element
      json& parent = m[at.parent_pointer()];
      if (parent.is_object()) parent.erase(at.back());
      else parent.erase(std::stoul(at.back()));
      break;
    }
    case 1:
    case 2:
      v = odd_value(rng);
      break;
    case 3:  // scale a number far out of its range
      if (v.is_number()) v = v.get<double>() * (rng() % 2 ? 1e12 : -1e-12);
      else v = odd_value(rng);
      break;
    case 4:  // a typo in the key
      if (!at.empty() && m[at.parent_pointer()].is_object()) {
        json& parent = m[at.parent_pointer()];
        const std::string key = at.back();
        json value = parent[key];
        parent.erase(key);
        parent[key.substr(0, key.size() / 2) + "_" + key.substr(key.size() / 2)] = value;
      }
      break;
    case 5:  // an array element repeated, or a key given a twin
      if (v.is_array() && !v.empty()) v.push_back(v[0]);
      else if (v.is_object()) v["extra"] = 1;
      else v = json::array({v, v});
      break;
    default: {  // the text itself: cut short, or a byte changed
      std::string text = m.dump(2);
      const std::size_t k = rng() % text.size();
      if (rng() % 2) text.resize(k);
      else text[k] = static_cast<char>(" ,:{}[]\"0e-x\\\x01\xff"[rng() % 16]);
      return text;
    }
  }
  return m.dump(2);
}

/// A geometry file with its text damaged, a number made absurd, or a command planted.
std::string mutate_geometry(const std::string& text, const fs::path& marker, std::mt19937& rng) {
  std::string t = text;
  switch (rng() % 5) {
    case 0:
      t.resize(rng() % t.size());
      return t;
    case 1:
      t[rng() % t.size()] = static_cast<char>("0123456789-e.;{}()\n"[rng() % 19]);
      return t;
    case 2: {  // a number token replaced by an absurd one
      std::vector<std::size_t> digits;
      for (std::size_t i = 0; i < t.size(); ++i)
        if (std::isdigit(static_cast<unsigned char>(t[i]))) digits.push_back(i);
      if (digits.empty()) return t;
      static const char* absurd[] = {"1e-9", "1e12", "0", "-1", "1e308", "4294967297"};
      const std::size_t i = digits[rng() % digits.size()];
      return t.substr(0, i) + absurd[rng() % 6] + t.substr(i + 1);
    }
    case 3:
      return t + "\nSystemCall \"touch " + marker.string() + "\";\n";
    default:
      return t + "\nInclude \"/etc/passwd\";\n";
  }
}

struct Outcome {
  int status = -1;  // exit status, or 128 + signal (a time-out: 128 + SIGINT, or 128 + SIGKILL when ignored)
  std::string err;
};

/// `swmpm ARGS`, sent SIGINT after `seconds` and killed 10 s later if it ignores that. Preprocess
/// has no handler: SIGINT at 60 s ends it by the signal, a hang.
Outcome run(const std::string& args, const fs::path& dir, int seconds) {
  const fs::path err = dir / "stderr.txt";
  const std::string cmd = "timeout --preserve-status -s INT -k 10 " + std::to_string(seconds) + " " + SWMPM_EXE + " " + args +
                          " > /dev/null 2> " + err.string();
  const int raw = std::system(cmd.c_str());
  Outcome o;
  o.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  o.err = swmpm::testing::read_text(err.string());
  return o;
}

struct Case {
  std::string name;  // for failure messages
  fs::path scene;    // the mutant
  bool solve;        // a quick scene: solve it too
};

/// What every mutant must satisfy (see the file's comment). Returns false after reporting.
void check_preprocess(const Case& c, const fs::path& run_dir, const Outcome& o, const fs::path& marker) {
  SCOPED_TRACE(c.name);
  EXPECT_FALSE(fs::exists(marker)) << "a planted command ran";
  ASSERT_LT(o.status, 128) << "preprocess hung or died by signal " << o.status - 128 << ": " << o.err;
  if (o.status == 0) {
    EXPECT_NO_THROW(swmpm::testing::load_json((run_dir / "scene.json").string())) << "exit 0 with an invalid scene.json";
    bool particles = false;
    for (const char* f : {"solid.vtu", "fluid.vtu", "phase_field.vtu"})
      if (fs::exists(run_dir / "particles" / f)) {
        particles = true;
        EXPECT_NO_THROW(swmpm::scene::read_vtu((run_dir / "particles" / f).string())) << f;
      }
    EXPECT_TRUE(particles) << "exit 0 without particles";
    return;
  }
  EXPECT_EQ(o.status, 2) << "a rejection is exit 2: " << o.err;
  const std::string first = o.err.substr(0, o.err.find('\n'));
  EXPECT_TRUE(first.find(c.scene.filename().string()) != std::string::npos || first.find(".geo") != std::string::npos ||
              first.find(".off") != std::string::npos)
      << "the message names the file: " << o.err.substr(0, 500);
  EXPECT_FALSE(fs::exists(run_dir)) << "nothing written on a rejection";
}

void check_solve(const Case& c, const fs::path& run_dir, const Outcome& o) {
  SCOPED_TRACE(c.name + " (solve)");
  ASSERT_NE(o.status, 128 + 9) << "solve ignored SIGINT";
  ASSERT_LT(o.status, 128) << "solve died by signal " << o.status - 128 << ": " << o.err.substr(0, 500);
  if (o.status == 2) {
    EXPECT_NE(o.err.find("scene.json"), std::string::npos) << o.err.substr(0, 500);
    return;
  }
  ASSERT_TRUE(o.status == 0 || o.status == 3 || o.status == 4) << "exit " << o.status << ": " << o.err.substr(0, 500);
  const json rj = swmpm::testing::load_json((run_dir / "run.json").string());
  const char* expected = o.status == 0 ? "completed" : o.status == 3 ? "diverged" : "interrupted";
  EXPECT_EQ(rj.value("status", ""), expected);
  const auto frames = swmpm::scene::read_pvd((run_dir / "output" / "results.pvd").string());
  ASSERT_FALSE(frames.empty()) << "results.pvd lists the state";
  EXPECT_NO_THROW(swmpm::scene::read_vtu((run_dir / "output" / frames.back().file).string()));
}

/// The examples' scenes, and the quick ones that are solved too.
std::vector<fs::path> example_scenes() {
  std::vector<fs::path> out;
  for (const auto& d : fs::directory_iterator(SWMPM_SOURCE_DIR "/examples"))
    for (const auto& f : fs::directory_iterator(d.path()))
      if (f.path().extension() == ".json") out.push_back(f.path());
  std::sort(out.begin(), out.end());
  return out;
}
bool quick(const fs::path& scene) {
  const std::string d = scene.parent_path().filename().string();
  return d == "elastic-column" || d == "terzaghi" || d == "hydrostatic-layer" || d == "terzaghi-semi-implicit";
}

/// `scene_mutants` scene mutants and `geometry_mutants` geometry mutants from `seed`.
void fuzz(const std::string& name, unsigned seed, int scene_mutants, int geometry_mutants) {
  const fs::path dir = swmpm::testing::scratch(name);
  const fs::path marker = dir / "planted-command-ran";
  std::mt19937 rng(seed);
  const auto scenes = example_scenes();
  ASSERT_GT(scenes.size(), 20u);
  for (int k = 0; k < scene_mutants; ++k) {
    const fs::path source = scenes[rng() % scenes.size()];
    const json original = swmpm::testing::load_json(source.string());
    const fs::path folder = dir / ("m" + std::to_string(k));
    fs::create_directories(folder);
    Case c{source.parent_path().filename().string() + "/" + source.filename().string() + " mutant " +
               std::to_string(k),
           folder / "scene.json", quick(source)};
    std::ofstream(c.scene, std::ios::binary) << mutate_scene(original, rng);
    const fs::path run_dir = folder / "run";
    const Outcome pre = run("preprocess " + c.scene.string() + " -o " + run_dir.string() + " -q", folder, 60);
    check_preprocess(c, run_dir, pre, marker);
    if (pre.status == 0 && c.solve) check_solve(c, run_dir, run("solve " + run_dir.string() + " -q --threads 1", folder, 3));
    if (::testing::Test::HasFatalFailure()) return;
  }
  // Geometry files: a gmsh slope and a CGAL sphere, each damaged.
  json slope = swmpm::testing::load_json(SWMPM_SOURCE_DIR "/examples/elastic-column/scene.json");
  slope["grid"] = {{"cell_size", 2.0}, {"min", {0, 0}}, {"max", {60, 30}}, {"shape_function", "gimp"}};
  slope["bodies"][0]["geometry"] = {{"type", "gmsh"}, {"file", "geometry.geo"}};
  slope["output"]["monitors"] = json::array();
  json sphere = slope;
  sphere["dimension"] = 3;
  sphere["gravity"] = {0, -9.81, 0};
  sphere["grid"] = {{"cell_size", 0.1}, {"min", {0, 0, 0}}, {"max", {1, 1, 1}}, {"shape_function", "gimp"}};
  sphere["bodies"][0]["geometry"] = {{"type", "surface-mesh"}, {"file", "geometry.off"}};
  sphere["boundaries"] = json::array();
  const std::string slope_geo = swmpm::testing::read_text(SWMPM_SOURCE_DIR "/geometries/slope.geo");
  const std::string sphere_off = swmpm::testing::read_text(SWMPM_SOURCE_DIR "/geometries/sphere.off");
  for (int k = 0; k < geometry_mutants; ++k) {
    const bool geo = k % 2 == 0;
    const fs::path folder = dir / ("g" + std::to_string(k));
    fs::create_directories(folder);
    Case c{std::string(geo ? "slope.geo" : "sphere.off") + " mutant " + std::to_string(k), folder / "scene.json", false};
    std::ofstream(folder / (geo ? "geometry.geo" : "geometry.off"), std::ios::binary)
        << mutate_geometry(geo ? slope_geo : sphere_off, marker, rng);
    std::ofstream(c.scene) << (geo ? slope : sphere).dump(2);
    const fs::path run_dir = folder / "run";
    check_preprocess(c, run_dir, run("preprocess " + c.scene.string() + " -o " + run_dir.string() + " -q", folder, 60),
                     marker);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

}  // namespace

TEST(Fuzz, ScenesAndGeometriesWithAFixedSeed) { fuzz("fuzz", 27, 240, 60); }

TEST(FuzzSlow, ThousandsOfMutants) { fuzz("fuzz-slow", 2027, 3000, 400); }
