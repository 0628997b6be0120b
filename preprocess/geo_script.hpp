// What a gmsh .geo script may do when preprocess meshes it (docs/scene-format.md, "Geometry
// scripts"). A .geo file is a program: gmsh's language can run shell commands, write files and
// read any file. Scenes and geometries travel between people, so by default a script is read
// first and refused when it could act outside the mesh it describes; `--trust-geometry` lifts the
// check for a file the user vouches for.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace swmpm::pre {

/// The folders a geometry script may read from: the scene file's folder and the named geometry
/// file's own folder, with everything below them.
struct GeoScriptRoots {
  std::vector<std::filesystem::path> folders;
};

/// Reads `file` and every file it Includes (or Merges as .geo) and throws GeometryError("file",
/// "<file>:<line>: <construct> ...") for the first construct that
///   - runs a command (SystemCall, System, NonBlockingSystemCall, OnelabRun),
///   - writes a file (Save, Print, CreateDir, Plugin, Printf/Error/Warning with > or >>),
///   - ends or stalls the process (Exit, Abort, Sleep) or drives a display (Draw),
///   - sets an option outside Mesh.* and Geometry.* (General.*, Solver.*, Print.*, PostProcessing.*,
///     View.*: their file names and programs) or touches post-processing views,
///   - reads a file outside `roots` (Include, Merge, MergeWithBoundingBox, ShapeFromFile), names it
///     by anything but a string literal, or merges a kind of file that is not a mesh or CAD model.
void check_geo_script(const std::filesystem::path& file, const GeoScriptRoots& roots);

/// A private file for the parameter prelude: created with O_EXCL in a fresh 0700 directory
/// (mkdtemp), so no other user can predict, plant or read it. Both are removed with the object.
class PrivateTempFile {
 public:
  /// Writes `content` to `<tmp>/swmpm-XXXXXX/<name>`; throws std::runtime_error naming the path.
  PrivateTempFile(const std::string& name, const std::string& content);
  ~PrivateTempFile();
  PrivateTempFile(const PrivateTempFile&) = delete;
  PrivateTempFile& operator=(const PrivateTempFile&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path dir_, path_;
};

}  // namespace swmpm::pre
