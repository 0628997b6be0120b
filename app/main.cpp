// swmpm — the command (interface.md §1): preprocess | solve | postprocess | run | element.
#include <CLI/CLI.hpp>

#include <iostream>
#include <string>

#include "postprocess/postprocess.hpp"
#include "preprocess/preprocess.hpp"
#include "scene/scene.hpp"
#include "solver/run.hpp"
#include "swmpm/version.hpp"

namespace {

int postprocess_command(const std::string& run_dir, const std::vector<std::string>& args, bool quiet) {
  const std::string cmd = args.empty() ? "plot" : args[0];
  if (cmd == "plot" && args.size() <= 1) {
    for (const auto& f : swmpm::post::plot_monitors(run_dir))
      if (!quiet) std::cout << "plot: " << f << "\n";
    return 0;
  }
  std::cerr << "swmpm postprocess: \"" << cmd
            << "\" is not implemented yet in this version (available: plot with no options)\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"swmpm — soil–water coupled large-deformation Material Point Method"};
  app.set_version_flag("--version", std::string("swmpm ") + swmpm::version + " (" + swmpm::git_hash + ")");
  app.require_subcommand(1);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "No terminal output (log.txt is still written)");

  std::string scene_path, out_dir, run_dir;
  int threads = 0;
  std::vector<std::string> post_args;

  auto* pre = app.add_subcommand("preprocess", "Seed particles from the scene's geometry into RUN_DIR");
  pre->add_option("scene", scene_path, "Scene file (JSON)")->required();
  pre->add_option("-o,--output", out_dir, "Run directory (default runs/<scene name>)");

  auto* solve = app.add_subcommand("solve", "Run the scene's formulation in RUN_DIR");
  solve->add_option("run_dir", run_dir, "Run directory written by preprocess")->required();
  solve->add_option("--threads", threads, "OpenMP threads (default: all cores); results do not depend on it")
      ->check(CLI::NonNegativeNumber);
  bool resume = false;
  solve->add_flag("--resume", resume, "Continue from the last frame (not implemented yet)");

  auto* post = app.add_subcommand("postprocess", "Histories, profiles, comparisons, plots, reports");
  post->add_option("run_dir", run_dir, "Run directory")->required();
  post->add_option("command", post_args, "plot (default)");

  auto* run = app.add_subcommand("run", "preprocess + solve + postprocess plot in one go");
  run->add_option("scene", scene_path, "Scene file (JSON)")->required();
  run->add_option("-o,--output", out_dir, "Run directory (default runs/<scene name>)");
  run->add_option("--threads", threads, "OpenMP threads (default: all cores)")->check(CLI::NonNegativeNumber);

  auto* element = app.add_subcommand("element", "Drive one material point (calibration; not implemented yet)");
  element->allow_extras();
  for (auto* sub : {pre, solve, post, run, element}) sub->add_flag("-q,--quiet", quiet, "No terminal output");

  CLI11_PARSE(app, argc, argv);
  try {
    if (*pre) {
      swmpm::pre::preprocess(scene_path, out_dir, quiet);
      return 0;
    }
    if (*solve) {
      if (resume) {
        std::cerr << "swmpm solve: --resume is not implemented yet in this version\n";
        return 2;
      }
      return swmpm::solve(run_dir, {threads, quiet});
    }
    if (*post) return postprocess_command(run_dir, post_args, quiet);
    if (*run) {
      const std::string dir = swmpm::pre::preprocess(scene_path, out_dir, quiet);
      const int rc = swmpm::solve(dir, {threads, quiet});
      if (rc != 0) return rc;
      return postprocess_command(dir, {}, quiet);
    }
    if (*element) {
      std::cerr << "swmpm element: not implemented yet in this version\n";
      return 2;
    }
  } catch (const swmpm::scene::SceneError& e) {
    for (const auto& line : e.lines()) std::cerr << line << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "swmpm: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
