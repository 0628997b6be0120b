// The small dry c-φ slope two verification tests share: 7 m high in all (2 m foundation, 5 m
// face at 45°, 3 m toe, 5 m crest), c = 20 kPa, φ = 30°, ψ = 0, ρ = 2000 kg/m³, E = 20 MPa,
// ν = 0.3, GIMP with 0.5 m cells and 2x2 points per cell, roller sides and a fixed base, FLIP 0.99
// with damping 0.1, dt auto (cfl 0.5). No initial stress, no output frames: each test adds those.
#pragma once

#include <nlohmann/json.hpp>

namespace swmpm::testing {

/// Pa, the total overburden at the base of B3's saturated slope (examples/slope-stability-mohr-coulomb:
/// n = 0.4, ρ_s = 2500 kg/m³, 20 m high): ρ_sat g H, the bound of its pore pressure.
inline constexpr double kB3SlopeBaseOverburden = ((1 - 0.4) * 2500.0 + 0.4 * 1000.0) * 9.81 * 20.0;

inline nlohmann::json dry_mc_slope(const char* name, double srf, double end) {
  return {
      {"name", name},
      {"dimension", 2},
      {"formulation", "dry"},
      {"gravity", {0.0, -9.81}},
      {"grid", {{"cell_size", 0.5}, {"min", {0.0, 0.0}}, {"max", {13.0, 8.5}}, {"shape_function", "gimp"}}},
      {"materials",
       {{{"name", "soil"}, {"model", "mohr-coulomb"}, {"density", 2000.0}, {"youngs_modulus", 2e7},
         {"poisson_ratio", 0.3}, {"cohesion", 20e3}, {"friction_angle", 30.0}, {"dilation_angle", 0.0},
         {"strength_reduction_factor", srf}}}},
      {"bodies",
       {{{"name", "slope"},
         {"geometry",
          {{"type", "slope"}, {"foundation_depth", 2.0}, {"height", 5.0}, {"angle", 45.0}, {"toe_length", 3.0},
           {"crest_length", 5.0}}},
         {"solid", "soil"},
         {"particles_per_cell", 2}}}},
      {"boundaries",
       {{{"on", "x_min"}, {"solid", "roller"}}, {{"on", "x_max"}, {"solid", "roller"}},
        {{"on", "y_min"}, {"solid", "fixed"}}}},
      {"time", {{"end", end}, {"dt", "auto"}, {"cfl", 0.5}}},
      {"solver", {{"flip", 0.99}, {"damping", 0.1}}},
      {"output", {{"interval", 0.0}, {"monitor_interval", 0.01}}}};
}

}  // namespace swmpm::testing
