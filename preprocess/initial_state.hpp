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
};

/// The content of body `b` (initial.porosity overrides the material's porosity).
BodyContent body_content(const scene::Scene& s, std::size_t b);

/// The content of the body point `p` belongs to.
inline const BodyContent& content_of(const std::vector<BodyContent>& content, const SeedPoint& p) {
  return content[static_cast<std::size_t>(p.body)];
}

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
