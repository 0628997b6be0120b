// `"formulation": "auto"`: the formulation an expert would pick for a scene, the reason in one or
// two sentences with numbers, and, where the choice is a matter of cost, each candidate's estimated
// step and wall time to `time.end` (issue 26, item 1; the rules and why: docs/formulations.md,
// "Choosing a formulation: auto").
//
// One function, choose_formulation, used by the parser (which then checks the scene's keys against
// the chosen formulation's row), by `preprocess` and `preprocess --explain` (which print it), and by
// solve (the log line before the first step and run.json's `formulation_choice`, read back from the
// resolved scene.json that preprocess writes).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace swmpm::scene {

/// One candidate's cost to time.end, from its own step limit at t = 0 and its Cost row
/// (scene/formulations.hpp): a one-thread estimate at the bench machine's speed.
struct FormulationEstimate {
  Formulation formulation = Formulation::dry;
  double wave_speed = 0.0;         // m/s: the P-wave speed that limits its step
  double dt = 0.0;                 // s: the step it would run at (cfl x h / c, or time.dt when smaller)
  std::string dt_reason;           // what limits the step, in words with the modulus
  double steps = 0.0;              // to time.end
  double points = 0.0;             // particles and water points it carries (from the bodies' volumes)
  double us_per_point_step = 0.0;  // µs, the Cost row's measured cost per particle and step
  double wall_seconds = 0.0;       // one thread
};

struct FormulationChoice {
  Formulation chosen = Formulation::dry;
  std::string rule;    // the branch that decided: "dry", "pore water", "free water", "liquefiable"
  std::string reason;  // one or two sentences with numbers
  double points = 0.0; // particles the bodies would seed (from their volumes)
  std::vector<FormulationEstimate> estimates;  // the compared candidates; empty when no cost decided
};

/// The choice for a parsed scene (its bodies, materials, grid and time; its own `formulation` is
/// ignored). Never throws for a scene the parser accepted up to the formulation.
FormulationChoice choose_formulation(const Scene& s);

/// run.json's and the resolved scene.json's `formulation_choice`:
/// {"chosen", "automatic": true, "rule", "reason", "estimates": [{"formulation", "dt", "dt_reason",
/// "wave_speed", "steps", "points", "us_per_point_step", "wall_seconds"}, ...]}.
nlohmann::json to_json(const FormulationChoice& c);

/// A parsed scene's `formulation_choice`, or for a formulation the file named {"chosen", "automatic":
/// false, "reason"}: what preprocess and solve print and run.json holds.
nlohmann::json choice_of(const Scene& s);

/// The lines `preprocess --explain`, preprocess and solve print: the choice and its reason, then
/// one line per estimate ("  explicit-single-point: dt 1.2e-05 s (...), 8.3e+04 steps x ... = 12 s").
std::vector<std::string> explain_lines(const nlohmann::json& choice);

}  // namespace swmpm::scene
