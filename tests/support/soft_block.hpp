// A saturated soft block 2 m wide and 1 m high standing free on a roller, impermeable base (its
// top and both sides free and drained), under a 0.1 s gravity ramp, GIMP, 0.1 m cells, 2x2 points
// per cell, dt auto (cfl 0.5): the free-surface hard case of the explicit and semi-implicit
// formulations. Callers set the end time, stabilisation and output.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace swmpm::testing {

inline nlohmann::json soft_block_scene(const std::string& formulation, double youngs_modulus) {
  nlohmann::json s = nlohmann::json::parse(R"json({
    "name": "soft-block", "dimension": 2, "formulation": "explicit-single-point",
    "gravity": [0.0, -9.81], "gravity_ramp": 0.1,
    "grid": { "cell_size": 0.1, "min": [0.0, 0.0], "max": [3.0, 1.5], "shape_function": "gimp" },
    "materials": [
      { "name": "soft", "model": "linear-elastic", "grain_density": 2650.0, "porosity": 0.4,
        "youngs_modulus": 1.0e5, "poisson_ratio": 0.3, "hydraulic_conductivity": 1.0e-4 },
      { "name": "water", "model": "fluid", "density": 1000.0, "bulk_modulus": 2.2e9 } ],
    "bodies": [ { "name": "block", "geometry": { "type": "box", "min": [0.5, 0.0], "max": [2.5, 1.0] },
                  "solid": "soft", "fluid": "water", "particles_per_cell": 2 } ],
    "boundaries": [ { "on": "y_min", "solid": "roller", "fluid": "impermeable" } ],
    "time": { "end": 0.3, "dt": "auto", "cfl": 0.5 }
  })json");
  s["formulation"] = formulation;
  s["materials"][0]["youngs_modulus"] = youngs_modulus;
  return s;
}

}  // namespace swmpm::testing
