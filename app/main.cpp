// swmpm — the command (interface.md §1): preprocess | solve | postprocess | run | study | element.
#include <CLI/CLI.hpp>
#include <malloc.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "postprocess/postprocess.hpp"
#include "preprocess/preprocess.hpp"
#include "scene/budget.hpp"
#include "scene/files.hpp"
#include "scene/input.hpp"
#include "scene/scene.hpp"
#include "solver/element.hpp"
#include "solver/output/checkpoint.hpp"
#include "solver/run.hpp"
#include "solver/parallel/comm.hpp"
#include "study/study.hpp"
#include "swmpm/version.hpp"

namespace {

/// glibc's allocator returns memory to the system as soon as the top of the heap holds more than
/// 128 kB free, and serves blocks above 128 kB to 32 MB by mmap: a frame's arrays and the VTU
/// compressor's per-block buffers were then mapped, zeroed by page faults and unmapped (with a
/// TLB flush on every core) each frame. Keeping freed memory for reuse cut the frame time of B4
/// 12^2 double-point (172k points) from 0.136 to 0.047 s with lz4 and from 0.43 to 0.34 s with
/// zlib, and the elastic column's (160 points) from 15 to 2.4 ms; peak memory at B4 12^2 is
/// unchanged (240 MB). docs/verification.md, "Cost of writing frames".
void keep_freed_memory() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // glibc's largest: blocks up to 32 MB come from the heap
  mallopt(M_TRIM_THRESHOLD, 256 << 20);  // give back only when 256 MB are free at the heap's top
}

/// What `swmpm postprocess RUN_DIR COMMAND ...` was given; one struct for every command.
struct PostArgs {
  std::string command;  // history | profile | frame | compare | plot | report; empty: plot
  std::string point, from, to, phase = "solid", quantity, method = "nearest", out;
  double radius = 0.0, time = 0.0;  // m, s
  int points = 50;
  std::string monitor, reference, reference_column;
  double tolerance = std::numeric_limits<double>::quiet_NaN();  // NaN: no check
  std::vector<std::string> references;                          // NAME.QUANTITY=FILE.csv
  std::string field, times;
};

void add_postprocess_commands(CLI::App* post, PostArgs& a, bool& quiet) {
  auto command = [&](const char* name, const char* help) {
    auto* sub = post->add_subcommand(name, help);
    sub->callback([&a, name] { a.command = name; });
    sub->add_flag("-q,--quiet", quiet, "No terminal output except results and errors");
    return sub;
  };
  auto phase = [&](CLI::App* sub) {
    sub->add_option("--phase", a.phase, "solid (default), fluid, or grid (mpm-fem's nodes: the fluid's fields)")
        ->check(CLI::IsMember({"solid", "fluid", "grid"}));
  };
  auto sampling = [&](CLI::App* sub) {
    sub->add_option("--method", a.method,
                    "nearest (default): the nearest particle; interpolate: kernel average within --radius")
        ->check(CLI::IsMember({"nearest", "interpolate"}));
    sub->add_option("--radius", a.radius, "Sampling radius [m] (default 1.5 x the particle spacing)")
        ->check(CLI::PositiveNumber);
    sub->add_option("--quantity", a.quantity, "e.g. displacement_y, stress_yy, mean_effective_stress")->required();
    sub->add_option("--out", a.out, "CSV file (default: standard output)");
  };
  post->require_subcommand(0, 1);
  post->footer("Without a command: plot (every monitor into RUN_DIR/plots). COMMAND --help for its options.");

  auto* history = command("history", "A quantity at a point through every frame (CSV: time,<quantity>)");
  history->add_option("--point", a.point, "X,Y[,Z] in m")->required();
  phase(history);
  sampling(history);

  auto* profile = command("profile", "A quantity along a segment in the frame nearest a time (CSV: s,x,y[,z],<quantity>)");
  profile->add_option("--from", a.from, "X,Y[,Z] in m")->required();
  profile->add_option("--to", a.to, "X,Y[,Z] in m")->required();
  profile->add_option("--time", a.time, "Time [s]; the nearest frame is used")->required();
  profile->add_option("--points", a.points, "Points along the segment (default 50)")->check(CLI::Range(2, 1000000));
  phase(profile);
  sampling(profile);
  auto* frame = command("frame", "Every particle of the frame nearest a time (CSV: x,y[,z], then every array)");
  frame->add_option("--time", a.time, "Time [s]; the nearest frame is used")->required();
  frame->add_option("--out", a.out, "CSV file (default: standard output)");
  phase(frame);

  auto* compare = command("compare", "Error norms of a monitor against a reference curve");
  compare->add_option("--monitor", a.monitor, "Column of monitors.csv, MONITOR.QUANTITY")->required();
  compare->add_option("--reference", a.reference, "CSV: time, value (header and # comments optional)")->required();
  compare->add_option("--reference-column", a.reference_column, "Value column by header name (default: the second)");
  compare->add_option("--tolerance", a.tolerance, "Exit 1 when the relative L2 error is larger")
      ->check(CLI::NonNegativeNumber);

  auto* plot = command("plot", "PNGs in RUN_DIR/plots: every monitor (default), or field snapshots");
  plot->add_option("--reference", a.references, "MONITOR.QUANTITY=FILE.csv: overlay a reference curve (repeatable)");
  plot->add_option("--field", a.field, "Draw the particles coloured by this quantity");
  plot->add_option("--times", a.times, "t1,t2,... [s] for --field (default: the last frame)");
  phase(plot);

  auto* report = command("report", "RUN_DIR/report.md: setup, cost, comparisons, plots");
  report->add_option("--reference", a.references, "MONITOR.QUANTITY=FILE.csv: add a comparison (repeatable)");
}

/// Writes a history or profile CSV to --out or standard output.
void emit_csv(const swmpm::post::CsvResult& r, const PostArgs& a, bool quiet) {
  if (a.out.empty()) {
    swmpm::post::write_csv(r, std::cout);
    return;
  }
  std::ofstream out(a.out);
  if (!out) throw std::runtime_error(a.out + ": cannot write file");
  swmpm::post::write_csv(r, out);
  if (!out) throw std::runtime_error(a.out + ": write failed");
  if (!quiet) std::cout << a.command << ": " << a.out << " (" << r.rows.size() << " rows)\n";
}

int postprocess_command(const std::string& run_dir, const PostArgs& a, bool quiet) {
  namespace post = swmpm::post;
  const std::string cmd = a.command.empty() ? "plot" : a.command;
  std::vector<post::ReferenceSpec> refs;
  try {
    for (const auto& r : a.references) refs.push_back(post::parse_reference_spec(r));
    if (cmd == "history") {
      post::HistoryOptions o;
      o.point = post::parse_point(a.point, "--point", &o.point_coordinates);
      o.phase = a.phase;
      o.quantity = a.quantity;
      o.method = post::parse_method(a.method);
      o.radius = a.radius;
      emit_csv(post::history(run_dir, o), a, quiet);
    } else if (cmd == "profile") {
      post::ProfileOptions o;
      int from_n = 0, to_n = 0;
      o.from = post::parse_point(a.from, "--from", &from_n);
      o.to = post::parse_point(a.to, "--to", &to_n);
      o.point_coordinates = std::min(from_n, to_n);
      o.time = a.time;
      o.phase = a.phase;
      o.quantity = a.quantity;
      o.points = a.points;
      o.method = post::parse_method(a.method);
      o.radius = a.radius;
      std::string note;
      const auto r = post::profile(run_dir, o, &note);
      // Standard output may be the CSV itself: the frame note then goes to stderr.
      if (!quiet) (a.out.empty() ? std::cerr : std::cout) << "profile: " << note << "\n";
      emit_csv(r, a, quiet);
    } else if (cmd == "frame") {
      std::string note;
      const auto r = post::frame_table(run_dir, a.time, a.phase, &note);
      if (!quiet) (a.out.empty() ? std::cerr : std::cout) << "frame: " << note << "\n";
      emit_csv(r, a, quiet);
    } else if (cmd == "compare") {
      const auto c = post::compare(run_dir, a.monitor, a.reference, a.reference_column);
      if (!quiet) std::cout << post::describe(c);
      if (!std::isnan(a.tolerance)) {
        if (!(c.rel_l2 <= a.tolerance)) {
          std::cerr << "swmpm postprocess compare: relative L2 error " << c.rel_l2 << " of " << c.monitor
                    << " against " << c.reference << " is over the tolerance " << a.tolerance << "\n";
          return 1;
        }
        if (!quiet) std::cout << "  within tolerance " << a.tolerance << "\n";
      }
    } else if (cmd == "plot") {
      if (!a.times.empty() && a.field.empty()) throw std::runtime_error("--times needs --field QUANTITY");
      std::vector<std::string> files;
      if (a.field.empty() || !refs.empty()) files = post::plot_monitors(run_dir, refs);
      if (!a.field.empty()) {
        const auto times = a.times.empty()
                               ? std::vector<double>{post::RunSeries(run_dir, a.phase).frames().back().time}
                               : post::parse_times(a.times, "--times");
        for (const auto& f : post::plot_fields(run_dir, a.field, times, a.phase)) files.push_back(f);
      }
      if (!quiet)
        for (const auto& f : files) std::cout << "plot: " << f << "\n";
    } else if (cmd == "report") {
      const std::string path = post::write_report(run_dir, refs);
      if (!quiet)  // report.html beside it: the same page, pictures embedded
        std::cout << "report: " << path << " and " << (std::filesystem::path(path).parent_path() / "report.html").string()
                  << "\n";
    }
  } catch (const swmpm::scene::InputError& e) {  // a file refused: not regular, too large, bad JSON
    std::cerr << "swmpm postprocess " << cmd << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "swmpm postprocess " << cmd << ": " << e.what() << "\n";
    return 1;
  }
  return 0;
}

/// What `swmpm element SCENE.json ...` was given.
struct ElementArgs {
  std::string material, test, out, plot;
  std::vector<double> p0;  // one run per value
  double axial_strain = 0.0;
  int steps = 100;
};

/// The element CSV: axial_strain, p, q, volumetric_strain (interface.md), then the model's state
/// columns (Nor-Sand: specific_volume, state_parameter), excess_pore_pressure for the undrained
/// test, and p0 when several --p0 were given (the runs one after another).
swmpm::post::CsvResult element_table(const std::vector<swmpm::ElementResult>& runs) {
  swmpm::post::CsvResult csv;
  const swmpm::ElementResult& first = runs.front();
  const bool undrained = first.test == swmpm::ElementTest::undrained_triaxial;
  csv.names = {"axial_strain", "p", "q", "volumetric_strain"};
  for (const auto& n : first.state_names) csv.names.push_back(n);
  // Conventional undrained triaxial: constant cell pressure, u = p0 + q/3 − p′ [Pa].
  if (undrained) csv.names.push_back("excess_pore_pressure");
  if (runs.size() > 1) csv.names.push_back("p0");
  for (const auto& r : runs) {
    for (std::size_t i = 0; i < r.size(); ++i) {
      std::vector<double> row{r.axial_strain[i], r.p[i], r.q[i], r.volumetric_strain[i]};
      for (const auto& c : r.state_columns) row.push_back(c[i]);
      if (undrained) row.push_back(r.p0 + r.q[i] / 3.0 - r.p[i]);
      if (runs.size() > 1) row.push_back(r.p0);
      csv.rows.push_back(std::move(row));
    }
  }
  return csv;
}

int element_command(const swmpm::scene::Scene& scene, const ElementArgs& a, bool quiet) {
  std::vector<swmpm::ElementResult> runs;
  try {
    for (double p0 : a.p0)
      runs.push_back(swmpm::run_element(scene, a.material, swmpm::parse_element_test(a.test), p0, a.axial_strain, a.steps));
  } catch (const std::invalid_argument& e) {
    std::cerr << "swmpm element: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "swmpm element: " << e.what() << "\n";
    return 1;
  }
  swmpm::post::CsvResult csv = element_table(runs);
  std::ostringstream note;
  note << "swmpm element: " << a.test << ", material " << runs.front().material << " (" << runs.front().model
       << "), p0 =";
  for (std::size_t k = 0; k < a.p0.size(); ++k) note << (k ? ", " : " ") << a.p0[k];
  note << " Pa, " << a.steps << " steps; compression positive, axial = z";
  csv.comments.push_back(note.str());
  try {
    if (a.out.empty()) {
      swmpm::post::write_csv(csv, std::cout);
    } else {
      std::ofstream out(a.out);
      if (!out) throw std::runtime_error(a.out + ": cannot write file");
      swmpm::post::write_csv(csv, out);
      if (!out) throw std::runtime_error(a.out + ": write failed");
      if (!quiet) std::cout << "element: " << a.out << " (" << csv.rows.size() << " rows)\n";
    }
    if (!a.plot.empty()) {
      swmpm::post::plot_element_curves(csv, note.str(), a.plot);
      if (!quiet) (a.out.empty() ? std::cerr : std::cout) << "plot: " << a.plot << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "swmpm element: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int command(int argc, char** argv) {
  keep_freed_memory();
  CLI::App app{"swmpm — soil–water coupled large-deformation Material Point Method"};
  app.set_version_flag("--version", std::string("swmpm ") + swmpm::version + " (" + swmpm::git_hash + ")");
  app.require_subcommand(1);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "No terminal output (log.txt is still written)");

  std::string scene_path, out_dir, run_dir;
  int threads = 0;
  PostArgs post_args;

  auto* pre = app.add_subcommand("preprocess", "Seed particles from the scene's geometry into RUN_DIR");
  pre->add_option("scene", scene_path, "Scene file (JSON)")->required();
  pre->add_option("-o,--output", out_dir, "Run directory (default runs/<scene name>)");
  swmpm::pre::PreprocessOptions pre_opt;
  std::string max_memory;
  auto memory_flag = [&max_memory](CLI::App* sub) {
    sub->add_option("--max-memory", max_memory,
                    "Refuse a scene whose run would need more memory than this (8G, 512M, 2e9 bytes; default: the "
                    "machine's memory)");
  };
  auto run_dir_flags = [&pre_opt, &memory_flag](CLI::App* sub) {
    memory_flag(sub);
    sub->add_flag("--overwrite", pre_opt.overwrite,
                  "Replace an earlier run in the run directory (only the files swmpm wrote there are removed)");
    sub->add_flag("--trust-geometry", pre_opt.trust_geometry,
                  "Mesh .geo scripts as they are; by default one that could run commands, write files or read "
                  "files outside the scene's and its own folder is refused");
  };
  run_dir_flags(pre);
  bool explain = false;
  pre->add_flag("--explain", explain,
                "Print the formulation, why (\"auto\": the rule and, for pore water only, both single-point "
                "estimates) and exit; writes nothing");

  auto* solve = app.add_subcommand("solve", "Run the scene's formulation in RUN_DIR");
  solve->add_option("run_dir", run_dir, "Run directory written by preprocess")->required();
  solve->add_option("--threads", threads, "OpenMP threads (default: all cores); results do not depend on it")
      ->check(CLI::NonNegativeNumber);
  bool resume = false;
  memory_flag(solve);
  solve->add_flag("--resume", resume,
                  "Continue from the last checkpoint (RUN_DIR/checkpoint.bin), bit for bit as if the run had not "
                  "stopped");

  auto* post = app.add_subcommand("postprocess", "Histories, profiles, comparisons, plots, reports");
  post->add_option("run_dir", run_dir, "Run directory")->required();
  add_postprocess_commands(post, post_args, quiet);

  auto* run = app.add_subcommand("run", "preprocess + solve + postprocess plot and report in one go");
  run->add_option("scene", scene_path, "Scene file (JSON)")->required();
  run->add_option("-o,--output", out_dir, "Run directory (default runs/<scene name>)");
  run->add_option("--threads", threads, "OpenMP threads (default: all cores)")->check(CLI::NonNegativeNumber);
  run_dir_flags(run);

  auto* study = app.add_subcommand("study", "The scene at several resolutions: wall time against the estimated error "
                                             "of every monitor, and the cheapest resolution within a tolerance");
  swmpm::study::StudyOptions st;
  study->add_option("scene", st.scene_path, "Scene file (JSON)")->required();
  study->add_option("-o,--output", st.out_dir, "Study folder (default study/<scene name>): report.md, report.html, "
                                               "cost-error.png, study.json, runs/<level>/, scenes/<level>.json");
  study->add_option("--budget", st.budget_minutes, "Wall time the whole study may take [min] (default 30): sets the finest level");
  study->add_option("--tolerance", st.tolerance, "Relative error the recommended level must meet (default 0.02)");
  study->add_option("--levels", st.levels, "Fewest levels (default 3, at most 8)");
  study->add_option("--ratio", st.ratio, "Refinement ratio of the cell size between levels (default 2)");
  study->add_option("--cell-sizes", st.cell_sizes, "H1,H2,H3,... [m]: these levels, coarse to fine, a constant ratio")
      ->delimiter(',');
  study->add_option("--monitor", st.monitors, "MONITOR or MONITOR.QUANTITY to estimate (repeatable; default: every one)");
  study->add_option("--metric", st.metric, "end (the value at the end time), history (RMS over the rows) or both (default)");
  study->add_option("--from", st.from, "The history metric starts at this time [s] (default 0)");
  study->add_option("--threads", threads, "OpenMP threads of each run (default: all cores)")->check(CLI::NonNegativeNumber);
  run_dir_flags(study);

  auto* element = app.add_subcommand("element", "Drive one material point of a scene's material (calibration, checks)");
  ElementArgs el;
  element->add_option("scene", scene_path, "Scene file (JSON) that defines the material")->required();
  element->add_option("--material", el.material, "Name of the scene material to test")->required();
  element->add_option("--test", el.test, "drained-triaxial, undrained-triaxial or oedometer (axial = z)")
      ->required()
      ->check(CLI::IsMember({"drained-triaxial", "undrained-triaxial", "oedometer"}));
  element->add_option("--p0", el.p0,
                      "Initial isotropic effective stress [Pa], compression positive; several (1e5,2e5): one run each")
      ->required()
      ->delimiter(',')
      ->check(CLI::PositiveNumber);
  element->add_option("--axial-strain", el.axial_strain, "Final axial strain [-], compression positive")->required();
  element->add_option("--steps", el.steps, "Equal strain increments (default 100)")->check(CLI::Range(1, 100000000));
  element->add_option("--out", el.out, "CSV file (default: standard output)");
  element->add_option("--plot", el.plot,
                      "PNG: q-p', q-axial strain, volumetric strain (undrained: excess pore pressure) and, "
                      "where the model has it, the state parameter against axial strain; one curve per p0");
  for (auto* sub : {pre, solve, post, run, study, element}) sub->add_flag("-q,--quiet", quiet, "No terminal output");

  CLI11_PARSE(app, argc, argv);
  try {
    pre_opt.quiet = quiet;
    if (!max_memory.empty()) {
      try {
        pre_opt.max_memory = swmpm::scene::parse_memory_size(max_memory);
      } catch (const std::invalid_argument& e) {
        std::cerr << "swmpm: --max-memory: " << e.what() << "\n";
        return 2;
      }
    }
    if (*pre && explain) {
      for (const std::string& line : swmpm::pre::explain(scene_path)) std::cout << line << "\n";
      return 0;
    }
    if (*pre) {
      swmpm::pre::preprocess(scene_path, out_dir, pre_opt);
      return 0;
    }
    if (*solve) {
      return swmpm::solve(run_dir, {threads, quiet, resume, pre_opt.max_memory});
    }
    if (*post) return postprocess_command(run_dir, post_args, quiet);
    if (*run) {
      const std::string dir = swmpm::pre::preprocess(scene_path, out_dir, pre_opt);
      const int rc = swmpm::solve(dir, {threads, quiet, false, pre_opt.max_memory});
      if (rc != 0) return rc;
      // The plots of every monitor, then RUN_DIR/report.md (setup, cost, the plots).
      if (const int plotted = postprocess_command(dir, {}, quiet); plotted != 0) return plotted;
      PostArgs report;
      report.command = "report";
      return postprocess_command(dir, report, quiet);
    }
    if (*study) {
      st.threads = threads;
      st.quiet = quiet;
      st.overwrite = pre_opt.overwrite;
      st.trust_geometry = pre_opt.trust_geometry;
      st.max_memory = pre_opt.max_memory;
      try {
        return swmpm::study::run_study(st);
      } catch (const std::invalid_argument& e) {  // an option: named in the message, nothing written
        std::cerr << "swmpm study: " << e.what() << "\n";
        return 2;
      }
    }
    if (*element) return element_command(swmpm::scene::load_scene(scene_path), el, quiet);
  } catch (const swmpm::parallel::ElsewhereError&) {  // mpirun: the failing rank said why
    return 2;
  } catch (const swmpm::scene::SceneError& e) {
    for (const auto& line : e.lines()) std::cerr << line << "\n";
    return 2;
  } catch (const swmpm::CheckpointError& e) {
    std::cerr << "swmpm solve: " << e.what() << "\n";
    return 2;
  } catch (const swmpm::files::RunDirectoryError& e) {
    std::cerr << "swmpm: " << e.what() << "\n";
    return 2;
  } catch (const swmpm::files::WriteError& e) {
    std::cerr << "swmpm: " << e.what() << "\n";
    return 5;
  } catch (const std::exception& e) {
    std::cerr << "swmpm: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

int main(int argc, char** argv) {
  // Under mpirun (`mpirun -n N swmpm solve RUN_DIR`) MPI and PETSc start here; without it nothing does.
  try {
    swmpm::parallel::start(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "swmpm: " << e.what() << "\n";
    return 1;
  }
  const int code = command(argc, argv);
  swmpm::parallel::stop();
  return code;
}
