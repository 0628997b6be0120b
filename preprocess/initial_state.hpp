// Initial state of the seeded points (bodies[].initial, docs/scene-format.md "Initial state"):
// what each body holds per unit volume, the pore pressure (constant or hydrostatic) and the
// skeleton stress (constant, or geostatic from the weight of the material above each point).
//
// y is the vertical axis in 2D and 3D; gravity must point along -y for geostatic and hydrostatic
// states. Signs: stress tension positive, pore pressure compression positive. The stored stress is
// the EFFECTIVE stress sigma' (for a dry body effective = total); the total stress is
// sigma = sigma' - p I.
#pragma once

#include <array>
#include <vector>

#include "preprocess/preprocess.hpp"
#include "scene/scene.hpp"

namespace swmpm::pre {

/// What a body's points hold, per unit of mixture volume.
struct BodyContent {
  double porosity = 0.0;       // -, pore volume / volume: 1 for free water; the material's (or 0) for a dry body
  double solid_density = 0.0;  // kg/m^3, solid mass per volume: `density`, or (1 - n) grain_density
  double fluid_density = 0.0;  // kg/m^3, fluid mass per volume: n rho_w (saturated), rho_w (free water)
  double rho_w = 0.0;          // kg/m^3, density of the body's fluid material (0: the body has none)

  bool has_solid() const { return solid_density > 0.0; }
  bool has_fluid() const { return rho_w > 0.0; }
  /// Total (bulk) density [kg/m^3]: the weight per volume the column above a point adds.
  double bulk_density() const { return solid_density + fluid_density; }
  /// The same skeleton with empty pores (no suction): (1 - n) rho_s, no fluid.
  BodyContent dry() const { return {porosity, solid_density, 0.0, 0.0}; }
};

/// The content of body `b` (initial.porosity overrides the material's porosity).
BodyContent body_content(const scene::Scene& s, std::size_t b);

/// The content of point `p`: its body's, or the body's dry skeleton where the point lies at or
/// above the body's water table (SeedPoint::above_water_table).
inline BodyContent content_of(const std::vector<BodyContent>& content, const SeedPoint& p) {
  const BodyContent& c = content[static_cast<std::size_t>(p.body)];
  return p.above_water_table ? c.dry() : c;
}

/// Height [m] of each body's hydrostatic water table (p = 0): `water_table` when given, else the
/// top of the body's points (highest centre plus half a spacing). NaN for bodies without a
/// hydrostatic pore pressure.
std::vector<double> water_tables(const scene::Scene& s, const std::vector<SeedPoint>& points);

/// Initial fields per seeded point, in the order of the points.
struct InitialFields {
  std::vector<double> pore_pressure;          // Pa, compression positive (0 where the body has no fluid)
  std::vector<std::array<double, 6>> stress;  // Pa, effective, tension positive, Voigt xx yy zz xy yz xz
  std::vector<double> water_table;            // m, per body: height of hydrostatic p = 0 (NaN: not hydrostatic)
};

/// Computes the initial state of `points` (seed_points) with `content[b]` for body b. Throws
/// scene::SceneError naming the JSON path (geostatic stress without gravity or without a solid,
/// gravity not along -y, ...).
InitialFields initial_state(const scene::Scene& s, const std::vector<SeedPoint>& points,
                            const std::vector<BodyContent>& content);

}  // namespace swmpm::pre
