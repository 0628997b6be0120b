// Nor-Sand test materials: seed 001 Table 6 (Hostun sand, Andrade & Ellison's calibration) as a
// scene material, and a one-body scene around materials for `swmpm element` and model tests.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "scene/scene.hpp"

namespace swmpm::testing {

inline nlohmann::json hostun_material(const std::string& name, double v0, double cutoff_start = 1.0,
                                      double cutoff_end = 1.5) {
  return {{"name", name},
          {"model", "nor-sand"},
          {"density", 1600.0},
          {"shear_modulus", 40e6},
          {"swelling_index", 0.002},
          {"reference_specific_volume", 1.892},
          {"compression_index", 0.02},
          {"critical_state_ratio", 1.0},
          {"yield_coefficient", 0.1},
          {"potential_coefficient", 0.1},
          {"hardening_modulus", 100.0},
          {"dilatancy_multiplier", -2.0},
          {"initial_specific_volume", v0},
          {"dilatancy_cutoff_start", cutoff_start},
          {"dilatancy_cutoff_end", cutoff_end}};
}

/// A 3D dry scene whose one body uses the first of `materials` (only the materials matter to
/// `swmpm element` and to model tests).
inline nlohmann::json material_scene(const nlohmann::json& materials) {
  return {{"name", "material-test"},
          {"dimension", 3},
          {"formulation", "dry"},
          {"gravity", {0.0, 0.0, 0.0}},
          {"grid", {{"cell_size", 0.1}, {"min", {0.0, 0.0, 0.0}}, {"max", {0.4, 0.4, 0.4}}}},
          {"materials", materials},
          {"bodies",
           {{{"name", "sample"},
             {"geometry", {{"type", "box"}, {"min", {0.1, 0.1, 0.1}}, {"max", {0.3, 0.3, 0.3}}}},
             {"solid", materials[0]["name"]}}}},
          {"time", {{"end", 0.01}, {"dt", 1e-4}}},
          {"output", {{"interval", 0.0}}}};
}

/// The scene material (defaults filled in by the parser) of one JSON material.
inline scene::Material parsed_material(const nlohmann::json& material) {
  return scene::parse_scene(material_scene(nlohmann::json::array({material})), "material-test").materials.at(0);
}

}  // namespace swmpm::testing
