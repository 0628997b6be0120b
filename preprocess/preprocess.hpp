// Stage 1: geometry -> particles. Seeds n^dim particles per cell on a lattice inside each body,
// resolves overlaps by body order (later bodies win), tags face particles for loads, sets the
// initial state, and writes RUN_DIR/{scene.json, particles/solid.vtu}.
#pragma once

#include <string>

#include "scene/pointcloud.hpp"
#include "scene/scene.hpp"

namespace swmpm::pre {

/// The solid particles of a scene (all bodies with a solid material), as written to solid.vtu.
scene::PointCloud seed_solid(const scene::Scene& s);

/// Runs the whole stage. Nothing is written unless everything succeeds. Returns the run directory
/// (`out_dir`, or runs/<scene name> when empty). Throws scene::SceneError / std::runtime_error.
std::string preprocess(const std::string& scene_path, const std::string& out_dir, bool quiet);

}  // namespace swmpm::pre
