#include "preprocess/preprocess.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "preprocess/initial_state.hpp"
#include "preprocess/shape.hpp"
#include "scene/auto_formulation.hpp"
#include "scene/budget.hpp"
#include "scene/expression.hpp"
#include "scene/input.hpp"
#include "scene/files.hpp"
#include "scene/formulations.hpp"

namespace fs = std::filesystem;

namespace swmpm::pre {

std::vector<SeedPoint> seed_points(const scene::Scene& s) { return seed_points(s, make_shapes(s)); }

namespace {

/// The lattice of a body's seeding: its bounding box's cells [c_lo, c_hi] (clamped to the grid),
/// n points per cell and axis, spacing dx.
struct Lattice {
  std::array<int, 3> c_lo{0, 0, 0}, c_hi{0, 0, 0};
  std::array<int, 3> count{1, 1, 1};  // lattice points per axis
  double dx = 0.0;
  double points() const { return double(count[0]) * double(count[1]) * double(count[2]); }
};

/// `cells` per axis fit an int: the parser refuses more than scene::kMaxCellsPerAxis.
Lattice lattice_of(const scene::Scene& s, const Shape& shape, int n, const std::array<int, 3>& cells) {
  const double h = s.grid.cell_size;
  Lattice l;
  l.dx = h / n;
  const auto box = shape.bounds();
  for (int a = 0; a < s.dimension; ++a) {
    l.c_lo[a] = static_cast<int>(std::clamp(std::floor((box[0][a] - s.grid.min[a]) / h), 0.0, cells[a] - 1.0));
    l.c_hi[a] = static_cast<int>(std::clamp(std::ceil((box[1][a] - s.grid.min[a]) / h) - 1.0, 0.0, cells[a] - 1.0));
    // Whole cells of n points; the scan refuses more than scene's kMaxScanned points in all, so
    // a count that would overflow an int never reaches the loops.
    l.count[a] = static_cast<int>(std::min<double>((l.c_hi[a] - l.c_lo[a] + 1.0) * n, 1 << 30));
  }
  return l;
}

std::array<int, 3> grid_cells(const scene::Scene& s) {
  std::array<int, 3> cells{1, 1, 1};
  for (int a = 0; a < s.dimension; ++a)
    cells[a] = std::max(1, static_cast<int>(std::ceil((s.grid.max[a] - s.grid.min[a]) / s.grid.cell_size - 1e-9)));
  return cells;
}

/// Particles each body would seed, estimated before seeding: its lattice's points times the share
/// of 4,096 stratified samples of its bounding box that fall inside the geometry.
std::vector<scene::BodyCount> body_counts(const scene::Scene& s, const std::vector<std::unique_ptr<Shape>>& shapes) {
  const auto cells = grid_cells(s);
  std::vector<scene::BodyCount> out;
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const Lattice l = lattice_of(s, *shapes[b], s.bodies[b].particles_per_cell, cells);
    const int m = s.dimension == 3 ? 16 : 64;  // samples per axis
    std::array<int, 3> per{1, 1, 1};
    for (int a = 0; a < s.dimension; ++a) per[a] = std::min(m, l.count[a]);
    double inside = 0.0, wet = 0.0;
    // a body with a water table carries water below it only (the solver's points above are dry)
    const auto& ini = s.bodies[b].initial;
    const double table = ini.hydrostatic && ini.water_table ? *ini.water_table : std::numeric_limits<double>::infinity();
    for (int k = 0; k < per[2]; ++k)
      for (int j = 0; j < per[1]; ++j)
        for (int i = 0; i < per[0]; ++i) {
          const std::array<int, 3> ijk{i, j, k};
          Point x{0.0, 0.0, 0.0};
          for (int a = 0; a < s.dimension; ++a)
            x[a] = s.grid.min[a] + l.c_lo[a] * s.grid.cell_size + (ijk[a] + 0.5) / per[a] * l.count[a] * l.dx;
          if (shapes[b]->inside(x)) {
            inside += 1.0;
            if (x[1] < table) wet += 1.0;
          }
        }
    const double samples = double(per[0]) * per[1] * per[2];
    out.push_back({inside / samples * l.points(), l.points(), wet / samples * l.points()});
  }
  return out;
}

}  // namespace

std::vector<SeedPoint> seed_points(const scene::Scene& s, const std::vector<std::unique_ptr<Shape>>& shapes) {
  const int dim = s.dimension;
  const double h = s.grid.cell_size;

  using Seeded = SeedPoint;
  // Named surfaces get face bits 6..
  const std::vector<std::string> surface_bits = scene::surface_bit_names(s);
  const std::array<int, 3> cells = grid_cells(s);

  std::vector<Seeded> seeded;
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const auto& body = s.bodies[b];  // every body: solid, saturated or free water
    const int n = body.particles_per_cell;
    const Lattice l = lattice_of(s, *shapes[b], n, cells);
    const double dx = l.dx;  // lattice spacing
    const auto& c_lo = l.c_lo;
    const int nx = l.count[0], ny = l.count[1], nz = l.count[2];
    auto lattice = [&](int a, int k) { return s.grid.min[a] + c_lo[a] * h + (k + 0.5) * dx; };
    auto inside_grid = [&](const Point& x) {
      for (int a = 0; a < dim; ++a)
        if (x[a] < s.grid.min[a] || x[a] > s.grid.min[a] + cells[a] * h) return false;
      return true;
    };
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          Point x{lattice(0, i), lattice(1, j), dim == 3 ? lattice(2, k) : 0.0};
          if (!shapes[b]->inside(x)) continue;
          // Face f = 2 axis + side: the neighbouring lattice point across that face is outside.
          std::uint32_t faces = 0;
          for (int a = 0; a < dim; ++a)
            for (int side = 0; side < 2; ++side) {
              Point y = x;
              y[a] += side == 0 ? -dx : dx;
              if (!inside_grid(y) || !shapes[b]->inside(y)) faces |= 1u << (2 * a + side);
            }
          // Named surfaces: bit 6 + k when within one lattice spacing of the k-th named surface.
          faces |= named_surface_bits(surface_bits, *shapes[b], x, dx);
          seeded.push_back({x, static_cast<int>(b), dx, faces, false});
        }
  }

  // Overlaps: a particle inside a later body belongs to that body (later bodies win).
  std::vector<Seeded> kept;
  kept.reserve(seeded.size());
  for (const auto& p : seeded) {
    bool overwritten = false;
    for (std::size_t later = p.body + 1; later < s.bodies.size() && !overwritten; ++later)
      overwritten = shapes[later]->inside(p.x);
    if (!overwritten) kept.push_back(p);
  }

  // Water only where there is water: the soil of a hydrostatic body is dry above its water table
  // (free water is water wherever it is seeded).
  const std::vector<double> table = water_tables(s, kept);
  for (auto& p : kept) {
    const auto& body = s.bodies[static_cast<std::size_t>(p.body)];
    const double wt = table[static_cast<std::size_t>(p.body)];
    p.above_water_table = !body.solid.empty() && !body.fluid.empty() && !std::isnan(wt) && p.x[1] >= wt;
  }
  return kept;
}

namespace {

using scene::WaterLayout;

/// A single-point particle is a skeleton with water in its pores: it cannot be water alone.
void reject_free_water(const scene::Scene& s, const std::vector<BodyContent>& content, const WaterLayout& w) {
  if (w.fluid_particles || w.free_water_on_grid) return;
  for (std::size_t b = 0; b < s.bodies.size(); ++b)
    if (!content[b].has_solid())
      throw scene::SceneError({s.source_file + ": /bodies/" + std::to_string(b) + ": body \"" + s.bodies[b].name +
                               "\" is free water (a fluid without a solid), which \"" + scene::to_string(s.formulation) +
                               "\" cannot represent (a single-point particle is a skeleton with water in its pores); "
                               "expected \"explicit-double-point\" or \"mpm-fem\" (semi-implicit-double-point "
                               "does not model free water either)"});
}

/// A soil body whose water table lies at or below every one of its points would be dry throughout:
/// its `fluid` would model nothing, and a coupled formulation would find no water. Refused, naming
/// the table; a body above the water is written without a fluid.
void reject_tables_below_bodies(const scene::Scene& s, const std::vector<SeedPoint>& points) {
  std::vector<double> lowest(s.bodies.size(), std::numeric_limits<double>::infinity());  // m, lowest centre
  std::vector<char> any_wet(s.bodies.size(), 0);
  for (const auto& p : points) {
    const auto b = static_cast<std::size_t>(p.body);
    lowest[b] = std::min(lowest[b], p.x[1]);
    any_wet[b] = any_wet[b] || !p.above_water_table;
  }
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const auto& body = s.bodies[b];
    if (any_wet[b] || !std::isfinite(lowest[b]) || body.solid.empty() || !body.initial.water_table) continue;
    std::ostringstream os;
    os << s.source_file << ": /bodies/" << b << "/initial/water_table: got " << *body.initial.water_table
       << ", at or below every point of body \"" << body.name << "\" (the lowest lies at y = " << lowest[b]
       << " m), so the body would hold no water; expected a table above its lowest point, or the body without "
          "\"fluid\" and \"pore_pressure\" (a dry body)";
    throw scene::SceneError({os.str()});
  }
}

/// Indices of the points whose content (content_of) satisfies `keep`.
template <class Keep>
std::vector<std::size_t> select(const std::vector<SeedPoint>& points, const std::vector<BodyContent>& content,
                                Keep&& keep) {
  std::vector<std::size_t> out;
  for (std::size_t p = 0; p < points.size(); ++p)
    if (keep(content_of(content, points[p]))) out.push_back(p);
  return out;
}

/// Index of the array after `velocity` in particle_cloud's output (where phase arrays go).
constexpr long kAfterVelocity = 5;

/// The arrays every particle file has, for the points `sel`: id, mass (density_of(content) V),
/// volume, half_size, velocity (the body's initial expressions), material (material_of(body)),
/// body, faces.
template <class Density, class MaterialOf>
scene::PointCloud particle_cloud(const scene::Scene& s, const std::vector<SeedPoint>& points,
                                 const std::vector<std::size_t>& sel, const std::vector<BodyContent>& content,
                                 Density&& density_of, MaterialOf&& material_of) {
  const int dim = s.dimension;
  scene::PointCloud c;
  c.points.resize(sel.size());
  auto& id = c.add("id", 1);
  auto& mass = c.add("mass", 1);
  auto& volume = c.add("volume", 1);
  auto& half = c.add("half_size", 3);
  auto& vel = c.add("velocity", 3);
  auto& material = c.add("material", 1);
  auto& body_arr = c.add("body", 1);
  auto& faces = c.add("faces", 1);
  for (std::size_t k = 0; k < sel.size(); ++k) {
    const auto& sp = points[sel[k]];
    const auto& body = s.bodies[static_cast<std::size_t>(sp.body)];
    c.points[k] = sp.x;
    id.values[k] = static_cast<double>(k);
    const double V = std::pow(sp.spacing, dim);  // m^3, or m^2 per metre of thickness in 2D
    volume.values[k] = V;
    mass.values[k] = density_of(content_of(content, sp)) * V;
    for (int a = 0; a < dim; ++a) {
      half.values[3 * k + a] = 0.5 * sp.spacing;
      vel.values[3 * k + a] = scene::initial_velocity(s, static_cast<std::size_t>(sp.body), static_cast<std::size_t>(a), sp.x);
    }
    material.values[k] = material_of(body);
    body_arr.values[k] = sp.body;
    faces.values[k] = sp.faces;
  }
  return c;
}

/// particles/solid.vtu: the points of bodies with a solid; mass = (1 - n) rho_s V (or density V);
/// `stress` is the effective stress. A single-point set adds its pore fluid on the same points, a
/// double-point set the porosity.
scene::PointCloud solid_cloud(const scene::Scene& s, const std::vector<SeedPoint>& points,
                              const std::vector<BodyContent>& content, const InitialFields& init,
                              const WaterLayout& w) {
  const auto sel = select(points, content, [](const BodyContent& c) { return c.has_solid(); });
  scene::PointCloud c = particle_cloud(
      s, points, sel, content, [](const BodyContent& bc) { return bc.solid_density; },
      [&](const scene::Body& b) { return static_cast<double>(s.material_index(b.solid)); });
  scene::PointArray stress{"stress", 6, std::vector<double>(6 * sel.size())};
  for (std::size_t k = 0; k < sel.size(); ++k)
    for (std::size_t j = 0; j < 6; ++j) stress.values[6 * k + j] = init.stress[sel[k]][j];
  c.arrays.insert(c.arrays.begin() + kAfterVelocity, std::move(stress));  // the documented order
  if (w.pore_fluid_on_solid || w.fluid_particles) {
    auto& porosity = c.add("porosity", 1);
    for (std::size_t k = 0; k < sel.size(); ++k) porosity.values[k] = content_of(content, points[sel[k]]).porosity;
  }
  if (w.fluid_particles) {
    // Double-point: the pore pressure at the soil points too (the solver keeps it as the water
    // field interpolated there, for output and monitors).
    auto& pore_pressure = c.add("pore_pressure", 1);
    for (std::size_t k = 0; k < sel.size(); ++k) pore_pressure.values[k] = init.pore_pressure[sel[k]];
  }
  if (w.pore_fluid_on_solid) {
    // Pore fluid of the same points; a dry body in a coupled scene, and the soil above a
    // hydrostatic body's water table, have none (fluid_mass 0, fluid_material -1).
    const auto& volume = c.get("volume", "solid");
    auto& pore_pressure = c.add("pore_pressure", 1);
    auto& fluid_mass = c.add("fluid_mass", 1);
    auto& fluid_material = c.add("fluid_material", 1);
    for (std::size_t k = 0; k < sel.size(); ++k) {
      const auto& sp = points[sel[k]];
      const auto& body = s.bodies[static_cast<std::size_t>(sp.body)];
      const BodyContent bc = content_of(content, sp);
      pore_pressure.values[k] = init.pore_pressure[sel[k]];
      fluid_mass.values[k] = bc.fluid_density * volume.values[k];
      fluid_material.values[k] = bc.has_fluid() ? static_cast<double>(s.material_index(body.fluid)) : -1.0;
    }
  }
  return c;
}

/// particles/fluid.vtu (double-point): the points of bodies with a fluid, coincident with the
/// solid points of saturated bodies. mass = n rho_w V (saturated) or rho_w V (free water, n = 1).
scene::PointCloud fluid_cloud(const scene::Scene& s, const std::vector<SeedPoint>& points,
                              const std::vector<BodyContent>& content, const InitialFields& init) {
  const auto sel = select(points, content, [](const BodyContent& c) { return c.has_fluid(); });
  scene::PointCloud c = particle_cloud(
      s, points, sel, content, [](const BodyContent& bc) { return bc.fluid_density; },
      [&](const scene::Body& b) { return static_cast<double>(s.material_index(b.fluid)); });
  scene::PointArray pore_pressure{"pore_pressure", 1, std::vector<double>(sel.size())};
  scene::PointArray porosity{"porosity", 1, std::vector<double>(sel.size())};
  for (std::size_t k = 0; k < sel.size(); ++k) {
    pore_pressure.values[k] = init.pore_pressure[sel[k]];
    porosity.values[k] = content_of(content, points[sel[k]]).porosity;
  }
  // The documented order: ... velocity, pore_pressure, porosity, material, body, faces.
  c.arrays.insert(c.arrays.begin() + kAfterVelocity, std::move(porosity));
  c.arrays.insert(c.arrays.begin() + kAfterVelocity, std::move(pore_pressure));
  return c;
}

}  // namespace

scene::PointCloud surface_samples(const scene::Scene& s, const std::vector<std::unique_ptr<Shape>>& shapes) {
  const auto names = scene::surface_bit_names(s);
  scene::PointCloud c;
  std::vector<double> surface, body, normal, area;
  for (std::size_t k = 0; k < names.size(); ++k)
    for (std::size_t b = 0; b < s.bodies.size(); ++b) {
      // A quarter of the body's lattice spacing: every particle of the surface gets samples, and
      // every grid node along it is within half a cell of one.
      const double spacing = s.grid.cell_size / s.bodies[b].particles_per_cell;
      const Shape::Samples smp = shapes[b]->surface_samples(names[k], 0.25 * spacing);
      for (std::size_t j = 0; j < smp.x.size(); ++j) {
        c.points.push_back(smp.x[j]);
        surface.push_back(static_cast<double>(k));
        body.push_back(static_cast<double>(b));
        for (int a = 0; a < 3; ++a) normal.push_back(smp.normal[j][a]);
        area.push_back(smp.measure[j]);
      }
    }
  if (c.points.empty()) return c;
  c.add("surface", 1).values = std::move(surface);
  c.add("body", 1).values = std::move(body);
  c.add("normal", 3).values = std::move(normal);
  c.add("area", 1).values = std::move(area);
  return c;
}

Phases seed_phases(const scene::Scene& s) {
  const WaterLayout w = scene::row_of(s.formulation).water;
  std::vector<BodyContent> content;
  for (std::size_t b = 0; b < s.bodies.size(); ++b) content.push_back(body_content(s, b));
  reject_free_water(s, content, w);
  // Free water stays in the points even where it is not written as particles (mpm-fem): it still
  // loads the soil below it, takes its place where bodies overlap, and makes the phase field.
  // Built and checked once (files read, named surfaces present).
  // Resources first: the grid before any geometry is meshed, the particles before they are seeded.
  const scene::MemoryLimit limit = scene::memory_limit(s.max_memory);
  scene::check_memory(s, s.source_file, {}, limit);
  const std::vector<std::unique_ptr<Shape>> shapes = make_shapes(s);
  scene::check_memory(s, s.source_file, body_counts(s, shapes), limit);
  const std::vector<SeedPoint> points = seed_points(s, shapes);
  reject_tables_below_bodies(s, points);
  const InitialFields init = initial_state(s, points, content);

  Phases out;
  out.solid = solid_cloud(s, points, content, init, w);
  if (w.fluid_particles) out.fluid = fluid_cloud(s, points, content, init);
  out.surfaces = surface_samples(s, shapes);
  if (w.free_water_on_grid) {
    out.phase_field = initial_phase_field(s, points);
    for (std::size_t b = 0; b < s.bodies.size(); ++b)
      if (!content[b].has_solid())
        out.notes.push_back("body \"" + s.bodies[b].name + "\" is free water: " + scene::to_string(s.formulation) +
                            " models it on the grid, so no particles are written for it; its water is in the "
                            "initial phase field, particles/phase_field.vtu");
  }
  return out;
}

scene::PointCloud seed_solid(const scene::Scene& s) { return seed_phases(s).solid; }

namespace {

/// Switches a scene may set that the chosen formulation does not use yet: rejected rather than
/// silently ignored. Checked on the file as written (the resolved scene leaves them out).
void reject_unused_switches(const std::string& scene_path, const scene::Scene& s) {
  // A scene error (exit 2, one line naming the file and the JSON pointer), like the parser's.
  const auto reject = [&](const std::string& line) { throw scene::SceneError({scene_path + ": " + line}); };
  // A formulation that has a row but no solver yet: refused before anything is written.
  if (!scene::row_of(s.formulation).implemented)
    reject("/formulation: got \"" + scene::to_string(s.formulation) + "\", which is not implemented in this version; "
           "expected one of " + scene::implemented_formulations() + " (or \"auto\")");
  // Nor-Sand (Borja & Andrade 2006) and Drucker-Prager (Hencky elasticity, seed 004) are
  // finite-strain models.
  for (std::size_t k = 0; k < s.materials.size(); ++k) {
    const auto model = s.materials[k].model;
    if ((model == scene::MaterialModel::nor_sand || model == scene::MaterialModel::drucker_prager) &&
        s.solver.kinematics != "finite-strain")
      reject("/solver/kinematics: got \"" + s.solver.kinematics + "\", but material \"" + s.materials[k].name +
             "\" is " + scene::to_string(model) + ", a finite-strain model; expected \"finite-strain\"");
  }
  nlohmann::json raw;
  try {
    raw = scene::read_json_file(scene_path, "scene file");
  } catch (const scene::InputError&) {
    return;
  }
  if (!raw.is_object() || !raw.contains("solver")) return;
  const auto& solver = raw["solver"];
  const auto stab = solver.contains("stabilisation") && solver["stabilisation"].is_object() ? solver["stabilisation"]
                                                                                               : nlohmann::json::object();
  // Formulation-specific switches are checked by the parser against the formulation's row
  // (scene/formulations.hpp); these depend on the other switches and the materials.
  if (stab.contains("fbar_patch") && !scene::reads_switch(s, "fbar_patch"))
    reject("/solver/stabilisation/fbar_patch: the patch size is read only by the modified F-bar (fbar is \"" +
           s.solver.stabilisation.fbar + "\"); remove the key or set fbar to \"modified\"");
  if (solver.contains("kinematics") && !scene::reads_switch(s, "kinematics"))
    reject("/solver/kinematics: no material of the scene reads it (linear-elastic follows the Jaumann rate, hencky "
           "is finite strain; only mohr-coulomb, drucker-prager and nor-sand read the switch); remove the key");
}

/// The run directory preprocess writes: a folder that holds an earlier run is cleared (only the
/// files swmpm wrote there) when `overwrite` is given and refused otherwise; a file of a name swmpm
/// writes that swmpm did not write is always refused.
void prepare_run_directory(files::RunDirectory& run, bool overwrite) {
  check_run_directory(run, overwrite);
  if (run.holds_a_run()) run.remove_owned([](const std::string&) { return true; });
}

}  // namespace

void check_run_directory(const files::RunDirectory& run, bool overwrite) {
  if (run.holds_a_run() && !overwrite) {
    std::string status;
    try {
      status = scene::read_json_file((run / "run.json").string(), "run.json").value("status", "");
    } catch (const std::exception&) {
    }
    throw files::RunDirectoryError(
        run.dir().string() + ": holds an earlier swmpm run" + (status.empty() ? "" : " (status " + status + ")") +
        "; pass --overwrite to replace it (only the files swmpm wrote there are removed), or choose another run "
        "directory (-o)");
  }
  // After an overwrite only foreign files remain: check those the run would write.
  const auto foreign = run.foreign(files::swmpm_files_in(run.dir()));
  if (!foreign.empty())
    throw files::RunDirectoryError((run / foreign.front()).string() +
                                   " exists and swmpm did not write it; swmpm never replaces or removes a file it did "
                                   "not write: choose an empty or new run directory (-o)" +
                                   (foreign.size() > 1 ? " (" + std::to_string(foreign.size() - 1) + " more such files)"
                                                       : std::string()));
}

std::vector<std::string> explain(const std::string& scene_path) {
  const scene::Scene s = scene::load_scene(scene_path);
  reject_unused_switches(scene_path, s);
  return scene::explain_lines(scene::choice_of(s));
}

std::string preprocess(const std::string& scene_path, const std::string& out_dir, bool quiet) {
  return preprocess(scene_path, out_dir, PreprocessOptions{quiet, false, false});
}

std::string preprocess(const std::string& scene_path, const std::string& out_dir, const PreprocessOptions& options) {
  scene::Scene s = scene::load_scene(scene_path);
  s.trust_geometry = options.trust_geometry;
  s.max_memory = options.max_memory;
  const bool quiet = options.quiet;
  reject_unused_switches(scene_path, s);
  // Everything is built in memory first, so a failure writes nothing.
  const Phases phases = seed_phases(s);
  if (phases.solid.size() == 0 && phases.fluid.size() == 0 && phases.notes.empty())
    throw scene::SceneError({scene_path + ": /bodies: no particle was seeded (are the bodies inside the grid?)"});

  const fs::path dir = out_dir.empty() ? fs::path("runs") / s.name : fs::path(out_dir);
  files::RunDirectory run(dir);
  prepare_run_directory(run, options.overwrite);
  if (!quiet)
    for (const std::string& line : scene::explain_lines(scene::choice_of(s))) std::cout << "preprocess: " << line << "\n";
  const bool pore_fluid_on_solid = phases.solid.find("fluid_mass") != nullptr;  // single-point (double-point: water points in fluid.vtu)
  try {
    run.write_text("scene.json", scene::to_json(s).dump(2) + "\n");
    for (const auto& [phase, cloud] : {std::pair{"solid", &phases.solid}, std::pair{"fluid", &phases.fluid},
                                       std::pair{"surfaces", &phases.surfaces}}) {
      if (cloud->size() == 0) continue;
      const std::string file = "particles/" + std::string(phase) + ".vtu";
      run.claim(file);
      scene::write_vtu((run / file).string(), *cloud);
      if (!quiet)
        std::cout << "preprocess: " << cloud->size() << " " << (phase == std::string("surfaces") ? "named-surface samples" : std::string(phase) + " particles")
                  << (phase == std::string("solid") && pore_fluid_on_solid ? " (with their pore fluid)" : "") << " -> "
                  << (run / file).string() << "\n";
    }
    if (phases.phase_field.nodes.size() > 0) {  // mpm-fem: the water on the grid's nodes
      const std::string file = "particles/phase_field.vtu";
      run.claim(file);
      scene::write_lattice_vtu((run / file).string(), phases.phase_field.nodes, phases.phase_field.lattice);
      if (!quiet)
        std::cout << "preprocess: phase field phi on " << phases.phase_field.nodes.size() << " grid nodes -> "
                  << (run / file).string() << "\n";
    }
  } catch (const files::WriteError&) {
    run.remove_owned([](const std::string&) { return true; });  // no half-written run is left
    throw;
  }
  if (!quiet)
    for (const auto& note : phases.notes) std::cout << "preprocess: " << note << "\n";
  if (!quiet) std::cout << std::flush;
  return dir.string();
}

}  // namespace swmpm::pre
