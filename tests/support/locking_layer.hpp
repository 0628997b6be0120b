// The volumetric-locking hard case (seed 001 §4.4.2): a nearly incompressible (ν = 0.49) hencky
// layer 5 m wide and 5 m deep on rollers and a fixed base, linear hats without F-bar, 0.25 m cells,
// 2x2 points per cell, under a 30 kPa strip load 1.5 m wide ramped over 0.25 s, no gravity,
// undamped, to 0.5 s. Monitor "centre" reads the settlement under the load. Callers change the
// shape function, the material, the stabilisation and the output interval.
#pragma once

#include <nlohmann/json.hpp>

namespace swmpm::testing {

inline nlohmann::json locking_layer_scene() {
  return nlohmann::json::parse(R"({
    "name": "locking", "dimension": 2, "formulation": "dry", "gravity": [0.0, 0.0],
    "grid": { "cell_size": 0.25, "min": [0.0, 0.0], "max": [5.0, 5.5], "shape_function": "linear" },
    "materials": [ { "name": "soil", "model": "hencky", "density": 2000.0, "youngs_modulus": 1.0e7,
                     "poisson_ratio": 0.49 } ],
    "bodies": [ { "name": "layer", "geometry": { "type": "box", "min": [0.0, 0.0], "max": [5.0, 5.0] },
                  "solid": "soil", "particles_per_cell": 2 } ],
    "boundaries": [ { "on": "x_min", "solid": "roller" }, { "on": "x_max", "solid": "roller" },
                    { "on": "y_min", "solid": "fixed" } ],
    "loads": [ { "type": "pressure", "body": "layer", "face": "y_max", "value": 3.0e4, "ramp": 0.25,
                 "region": { "min": [0.0, 4.5], "max": [1.5, 5.0] } } ],
    "time": { "end": 0.5, "dt": "auto", "cfl": 0.5 },
    "output": { "interval": 0.05, "monitors": [ { "name": "centre", "at": [0.0, 5.0], "quantities": ["displacement_y"] } ] }
  })");
}

}  // namespace swmpm::testing
