// Stage 1: geometry -> particles. Seeds n^dim lattice points per cell inside each body, resolves
// overlaps by body order (later bodies win), tags face particles for loads, sets the initial state
// (preprocess/initial_state.hpp), and writes RUN_DIR/scene.json and one particles/<phase>.vtu per
// phase the formulation needs (docs/architecture.md, "Preprocess in detail").
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "preprocess/shape.hpp"
#include "scene/files.hpp"
#include "scene/pointcloud.hpp"
#include "scene/scene.hpp"

namespace swmpm::pre {

/// One lattice point of a body, kept after overlap resolution.
struct SeedPoint {
  Point x;              // m
  int body;             // index into scene.bodies
  double spacing;       // m, lattice spacing h / particles_per_cell: the particle's width per axis
  std::uint32_t faces;  // bit f: the lattice neighbour across face f is outside the body or the grid
  // The point's body has a fluid and a hydrostatic pore pressure, and the point's centre lies at or
  // above the body's water table (x[1] >= y_wt): it is dry skeleton, without pore water (no
  // suction), while the body's points below the table are saturated (docs/scene-format.md, "Pore
  // pressure"). Set by seed_points.
  bool above_water_table;
};

/// The lattice points of every body (solid, saturated and free water), in body order, with
/// overlaps resolved (a point inside a later body's geometry belongs to that body), and the points
/// of a hydrostatic body at or above its water table marked (SeedPoint::above_water_table).
std::vector<SeedPoint> seed_points(const scene::Scene& s);
/// The same with the bodies' shapes already built (make_shapes).
std::vector<SeedPoint> seed_points(const scene::Scene& s, const std::vector<std::unique_ptr<Shape>>& shapes);

/// particles/surfaces.vtu: samples of every named surface the scene refers to, on each body whose
/// geometry has it (Shape::surface_samples at a quarter of the body's lattice spacing). Arrays:
/// `surface` (k of face bit 6 + k), `body`, `normal` (outward unit), `area` (m in 2D, m^2 in 3D).
/// Empty when the scene names no surface.
scene::PointCloud surface_samples(const scene::Scene& s, const std::vector<std::unique_ptr<Shape>>& shapes);

/// mpm-fem's initial phase field (particles/phase_field.vtu): the solver's grid nodes for the
/// scene's shape function (scene_grid, solver/grid/grid.hpp: positions and flat order, x fastest)
/// with the array `phi`, the water's volume fraction at each node (1 water, 0 air):
///
///     phi_I = min(1, sum_p integral_{Omega_p} N_I dOmega / integral N_I dOmega)
///
/// over the water-bearing points p: N the scene's basis functions, Omega_p the point's domain (the
/// box of side `spacing` around x_p, its whole volume V_p = spacing^dim: saturated soil is water
/// between the grains; integrated exactly, phase_field.cpp), the denominator over the grid
/// (porous::basis_integral). So phi_I = 1 wherever node I's support is full of water, walls
/// included, and sum_I phi_I integral N_I is the water's volume where no node is over-full. Water-bearing
/// are the points of bodies with a fluid (free water, saturated soil) and those of dry bodies that
/// lie below the water on their vertical line: below the top y_q + l_q of the highest
/// water-bearing point q within half a cell in x (and z in 3D), h/2 widened by 1e-9 of itself as
/// the water_level gauge does: pores below the water are full of it.
/// The array `velocity` (3 components, m/s) is the water's initial velocity at each node, the
/// average of its bodies' `initial.velocity` weighted as phi is, sum_p int N_I v_p / sum_p int N_I
/// (zero where no water is; the submerged pores of a dry body hold water at rest).
struct InitialPhaseField {
  scene::PointCloud nodes;          // the grid's nodes, arrays `phi` and `velocity`
  std::array<int, 3> lattice{1, 1, 1};  // nodes per axis (1 for the axis a 2D grid lacks)
};
InitialPhaseField initial_phase_field(const scene::Scene& s, const std::vector<SeedPoint>& points);

/// The particle sets of a scene, as written to particles/<phase>.vtu. An empty set is not written.
struct Phases {
  scene::PointCloud solid;  // skeleton particles (single-point sets also carry the pore fluid)
  scene::PointCloud fluid;  // double-point pore fluid and free water
  scene::PointCloud surfaces;  // named-surface samples (surface_samples)
  InitialPhaseField phase_field;   // mpm-fem: the water on the grid (empty otherwise)
  std::vector<std::string> notes;  // what was left out on purpose and why, for the log
};

/// Seeds every phase the scene's formulation needs and sets the initial state. Throws
/// scene::SceneError (one line naming the file and JSON path) for a scene the formulation cannot
/// represent or an initial state that cannot be built.
Phases seed_phases(const scene::Scene& s);

/// The solid particles of a scene (all bodies with a solid material), as written to solid.vtu.
scene::PointCloud seed_solid(const scene::Scene& s);

struct PreprocessOptions {
  bool quiet = false;
  bool overwrite = false;       // --overwrite: replace an earlier run in the folder (swmpm's files only)
  bool trust_geometry = false;  // --trust-geometry: mesh .geo scripts without reading them first
  double max_memory = 0.0;      // B, --max-memory: refuse a scene that needs more (0: the machine's memory)
};

/// `preprocess --explain`: the scene's formulation, why, and the estimates behind an "auto" choice
/// (scene/auto_formulation.hpp), as printed lines. Checks the scene as preprocess does before it
/// seeds (throws scene::SceneError) and writes nothing.
std::vector<std::string> explain(const std::string& scene_path);

/// Throws files::RunDirectoryError when preprocess could not use `run` as its run directory: it
/// holds an earlier run and `overwrite` is false, or a file of a name swmpm writes is there that
/// swmpm did not write. Writes nothing (`swmpm study` checks every run directory before it starts).
void check_run_directory(const files::RunDirectory& run, bool overwrite);

/// Runs the whole stage. Nothing is written unless everything succeeds. Returns the run directory
/// (`out_dir`, or runs/<scene name> when empty). Throws scene::SceneError (the scene),
/// files::RunDirectoryError (a folder holding an earlier run, or a file swmpm did not write where
/// it would write one), files::WriteError, std::runtime_error.
std::string preprocess(const std::string& scene_path, const std::string& out_dir, const PreprocessOptions& options);
std::string preprocess(const std::string& scene_path, const std::string& out_dir, bool quiet);

}  // namespace swmpm::pre
