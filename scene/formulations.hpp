// One row per formulation: its name, its paper, the particle sets preprocess writes for it, the
// formulation-specific switches it reads (with the values it has and its default), and its scene
// checks. The parser (defaults, refusals), preprocess (particle sets, refusals of switches set
// in vain), the time loop (which sets it carries) and the solver's registry (factories) all read
// this table; adding a formulation is adding its row (docs/architecture.md, "Adding a formulation").
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace swmpm::scene {

/// Where a formulation keeps the water (docs/architecture.md, "Preprocess in detail").
struct WaterLayout {
  bool pore_fluid_on_solid = false;  // single-point: porosity, pore_pressure, fluid_mass, fluid_material on solid.vtu
  bool fluid_particles = false;      // double-point: fluid.vtu holds the pore fluid and the free water
  bool free_water_on_grid = false;   // mpm-fem: free water is a grid field, not particles
};

/// A formulation-specific switch: its JSON path below the scene's root, the values this
/// formulation has, and its default here. A switch that is in some rows and not in a scene's
/// formulation's row is refused when the scene sets it.
struct Switch {
  std::string path;  // e.g. "/solver/stabilisation/pressure"
  std::vector<std::string> values;
  std::string def;
};

/// A scene problem: the JSON path and what is wrong there.
struct Problem {
  std::string path, message;
};

/// What a run of a formulation costs, for the estimates made before it starts (scene/budget.hpp):
/// lower bounds of its memory (peak RSS less the program's, bench/ and docs/verification.md,
/// "Resource estimates") and its speed on the 2-core bench machine, one thread. The coupled rows'
/// µs per particle-step are measured (each cites its bench/results file); `auto` compares them
/// (scene/auto_formulation.hpp). The per-node costs are rough: no bench separates them yet.
struct Cost {
  double bytes_per_point = 600.0;    // B per particle or water point
  double bytes_per_node = 60.0;      // B per node of the whole grid in 2D (the grid's fields)
  double node_bytes_3d = 1.0;        // x bytes_per_node in 3D (a node has more neighbours)
  double us_per_point_step = 0.15;   // µs per particle (or water point) and step
  double us_per_node_step = 0.002;   // µs per node of the whole grid and step
};

struct FormulationRow {
  Formulation id;
  std::string name;
  std::string paper;       // the seed it implements (shared/README.md), "" for dry
  bool implemented = false;
  bool coupled = false;    // needs a body with a fluid (dry: none may have one)
  WaterLayout water;
  std::vector<Switch> switches;
  /// Scene checks of this formulation beyond its switches.
  void (*check)(const Scene& s, std::vector<Problem>& problems) = nullptr;
  /// Material keys only some formulations read (e.g. `grain_diameter`): a scene whose formulation
  /// does not list a key it gives is refused, naming who reads it.
  std::vector<std::string> material_keys = {};
  /// Other keys only some formulations read, as JSON paths (e.g. `/solver/air`): a scene that gives
  /// one its formulation does not list is refused, naming who reads it; to_json writes them for
  /// the formulations that list them only.
  std::vector<std::string> keys = {};
  Cost cost = {};
  bool reads(const std::string& path) const;

  /// This formulation's entry for a switch path, or nullptr when it does not read it.
  const Switch* find(const std::string& path) const;
};

/// Every formulation swmpm knows, implemented or not, in the order of the scene docs.
const std::vector<FormulationRow>& formulation_rows();
/// The row of a formulation (not "auto", which the parser resolves first).
const FormulationRow& row_of(Formulation f);
/// The paths of every formulation-specific switch (the union of the rows' switches).
std::vector<std::string> formulation_switch_paths();
/// The implemented formulations' names, comma-separated (for messages).
std::string implemented_formulations();

/// The scene file's formulation-specific switches (raw: the file as written) against the row of
/// the scene's resolved formulation — a switch it does not read, a value it does not have — and
/// then the row's own checks.
std::vector<Problem> check_formulation(const nlohmann::json& raw, const Scene& s);
/// The switches the file left unset take the row's defaults; those the formulation does not read
/// take neutral values (pressure "none", continuity "non-conservative").
void apply_formulation_defaults(Scene& s);

}  // namespace swmpm::scene
