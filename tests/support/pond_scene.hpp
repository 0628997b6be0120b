// A pond of free water (explicit-double-point, liquid points only) with one water_level gauge on
// its middle line, 2D or 3D: the scene the gauge's parse tests (unit) and its runs (verification)
// start from. 0.2 m wide (and 0.1 m deep in z), 0.3 m of water in a 0.5 m high grid of 0.05 m
// GIMP cells, hydrostatic, impermeable walls, 0.2 s.
#pragma once

#include <nlohmann/json.hpp>

namespace swmpm::testing {

inline nlohmann::json pond_scene(int dim) {
  nlohmann::json j = nlohmann::json::parse(R"json({
    "name": "pond", "dimension": 2, "formulation": "explicit-double-point", "gravity": [0, -9.81],
    "grid": { "cell_size": 0.05, "min": [0, 0], "max": [0.2, 0.5], "shape_function": "gimp" },
    "materials": [ { "name": "water", "model": "fluid", "density": 1000, "bulk_modulus": 2e6 } ],
    "bodies": [ { "name": "pond", "geometry": { "type": "box", "min": [0, 0], "max": [0.2, 0.3] },
                  "fluid": "water", "initial": { "pore_pressure": "hydrostatic" } } ],
    "boundaries": [ { "on": "x_min", "fluid": "impermeable" }, { "on": "x_max", "fluid": "impermeable" },
                    { "on": "y_min", "fluid": "impermeable" } ],
    "time": { "end": 0.2 },
    "output": { "monitors": [ { "name": "gauge", "at": [0.1], "quantities": ["water_level"] } ] }
  })json");
  if (dim == 3) {  // walls in z too
    j["dimension"] = 3;
    j["gravity"] = {0, -9.81, 0};
    j["grid"]["min"] = {0, 0, 0};
    j["grid"]["max"] = {0.2, 0.5, 0.1};
    j["bodies"][0]["geometry"]["min"] = {0, 0, 0};
    j["bodies"][0]["geometry"]["max"] = {0.2, 0.3, 0.1};
    j["boundaries"].push_back({{"on", "z_min"}, {"fluid", "impermeable"}});
    j["boundaries"].push_back({{"on", "z_max"}, {"fluid", "impermeable"}});
    j["output"]["monitors"][0]["at"] = {0.1, 0.05};
  }
  return j;
}

}  // namespace swmpm::testing
