// ParticleSet <-> PointCloud (VTU) conversion. Array names and units: docs/scene-format.md,
// section "Particle files and frames".
#pragma once

#include "scene/pointcloud.hpp"
#include "solver/particles/particles.hpp"

namespace swmpm {

/// Reads a seeded particle file (preprocess output); `where` names it in errors.
template <int Dim>
ParticleSet<Dim> particles_from_cloud(const scene::PointCloud& c, const std::string& where);

/// Reads particles/surfaces.vtu (preprocess's named-surface samples).
template <int Dim>
SurfaceSamples<Dim> surface_samples_from_cloud(const scene::PointCloud& c, const std::string& where);

/// A frame: the seeded arrays plus displacement, stress invariants and J.
template <int Dim>
scene::PointCloud particles_to_cloud(const ParticleSet<Dim>& ps);

/// A frame of double-point water points: id, mass, volume, velocity, displacement, pore_pressure,
/// porosity, material, body.
template <int Dim>
scene::PointCloud water_points_to_cloud(const ParticleSet<Dim>& ws);

}  // namespace swmpm
