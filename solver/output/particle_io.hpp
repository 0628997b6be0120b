// ParticleSet <-> PointCloud (VTU) conversion. Array names and units: docs/scene-format.md,
// section "Particle files and frames".
#pragma once

#include <memory>
#include <vector>

#include "scene/pointcloud.hpp"
#include "solver/materials/material.hpp"
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

/// Adds to a frame the state quantities the particles' material models report
/// (MaterialModel::report_names: Nor-Sand's specific_volume, state_parameter, image_pressure), one
/// array per name over all particles, NaN for particles whose material does not report it.
/// `models` is indexed by scene material (nullptr for fluids). Frames only, not the time loop.
template <int Dim>
void add_material_reports(scene::PointCloud& c, const ParticleSet<Dim>& ps,
                          const std::vector<std::unique_ptr<MaterialModel<Dim>>>& models);

/// A frame of double-point water points: id, mass, volume, velocity, displacement, pore_pressure,
/// porosity, material, body.
template <int Dim>
scene::PointCloud water_points_to_cloud(const ParticleSet<Dim>& ws);

}  // namespace swmpm
