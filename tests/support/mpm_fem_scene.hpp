// A small mpm-fem scene (seed 004's layout): a saturated bed of beads (Mohr–Coulomb, Kozeny–Carman
// D50) under a pond of free water (incompressible: no bulk_modulus), in a 2D grid of 0.05 m
// quadratic B-spline cells with air above.
// The bed is 0.1 m deep, the pond 0.2 m, both 0.4 m wide; the grid 0.4 m x 0.5 m. Shared by the
// parse tests of mpm-fem's keys (unit), preprocess's phase field (unit) and the grid-fluid monitors
// (cli).
#pragma once

#include <nlohmann/json.hpp>

namespace swmpm::testing {

inline nlohmann::json mpm_fem_scene() {
  return nlohmann::json::parse(R"json({
    "name": "mpm-fem-pond", "dimension": 2, "formulation": "mpm-fem", "gravity": [0, -9.81],
    "grid": { "cell_size": 0.05, "min": [0, 0], "max": [0.4, 0.5], "shape_function": "bspline2" },
    "materials": [
      { "name": "beads", "model": "mohr-coulomb", "grain_density": 2650, "porosity": 0.4, "youngs_modulus": 1e6,
        "poisson_ratio": 0.3, "friction_angle": 30, "grain_diameter": 0.003 },
      { "name": "water", "model": "fluid", "density": 1000 } ],
    "bodies": [
      { "name": "bed", "geometry": { "type": "box", "min": [0, 0], "max": [0.4, 0.1] }, "solid": "beads", "fluid": "water" },
      { "name": "pond", "geometry": { "type": "box", "min": [0, 0.1], "max": [0.4, 0.3] }, "fluid": "water" } ],
    "boundaries": [ { "on": "x_min", "solid": "roller" }, { "on": "x_max", "solid": "roller" },
                    { "on": "y_min", "solid": "fixed" } ],
    "time": { "end": 0.1 }
  })json");
}

}  // namespace swmpm::testing
