// PointCloud: named particle arrays, and their VTU (VTK XML, binary, compressed) read/write.
//
// This is what crosses stage boundaries: preprocess writes particles/<phase>.vtu, the solver
// reads them and writes output/<phase>_NNNNNN.vtu frames, postprocess reads frames back.
// Well-known array names are in docs/scene-format.md ("Particle files and frames").
#pragma once

#include <array>
#include <deque>
#include <string>
#include <vector>

namespace swmpm::scene {

struct PointArray {
  std::string name;
  int components = 1;          // 1 scalar, 3 vector, 6 symmetric tensor (xx yy zz xy yz xz)
  std::vector<double> values;  // size = points * components
};

struct PointCloud {
  std::vector<std::array<double, 3>> points;  // m
  std::deque<PointArray> arrays;  // deque: references returned by add() stay valid

  std::size_t size() const { return points.size(); }
  /// The array of that name, or nullptr.
  const PointArray* find(const std::string& name) const;
  /// The array of that name; throws std::runtime_error naming the array and `where`.
  const PointArray& get(const std::string& name, const std::string& where) const;
  /// Adds a zero-initialised array (size points * components; set points first) and returns it.
  PointArray& add(const std::string& name, int components);
};

/// Compression of a VTU file's appended binary data (scene key output.compression).
enum class VtuCompression { zlib, lz4, none };
/// "zlib", "lz4" or "none" (the scene parser has checked the name).
VtuCompression vtu_compression(const std::string& name);

/// Writes a VTK XML unstructured grid of vertex cells, binary appended data. zlib runs at level 1:
/// on the solver's float fields it gives files within 1 % of the default level 6 (B4 12^2 frames:
/// 337 against 334 MB) in 70 % of the time. The file is replaced atomically (files::write_atomically)
/// and the write checked: a failure throws files::WriteError, leaving the old file as it was.
void write_vtu(const std::string& path, const PointCloud& cloud, VtuCompression compression = VtuCompression::zlib);
/// Writes grid nodes as a VTK XML unstructured grid of cells over the node lattice (pixels in 2D,
/// voxels in 3D; `nodes` per axis, 1 for an axis a 2D grid lacks), the points in the lattice's flat
/// order (x fastest): the grid fields a formulation adds to a frame. Written as write_vtu is.
void write_lattice_vtu(const std::string& path, const PointCloud& cloud, const std::array<int, 3>& nodes,
                       VtuCompression compression = VtuCompression::zlib);
/// One rank's piece of a frame written by several ranks (mpirun): VTK's parallel writer writes
/// the piece (pvtu_piece_name) and rank 0 the .pvtu summary that lists all `pieces` (collective
/// over VTK's global controller, which solver/parallel/comm.cpp sets). Throws files::WriteError.
void write_pvtu_piece(const std::string& path, const PointCloud& cloud, int piece, int pieces,
                      VtuCompression compression = VtuCompression::zlib);
std::string pvtu_piece_name(const std::string& pvtu_name, int piece);
/// Reads a .vtu written by write_vtu (or a .pvtu over pieces) (or by another tool): every point-data array is returned.
PointCloud read_vtu(const std::string& path);

/// One entry of a ParaView time series.
struct PvdEntry {
  double time;
  std::string group;  // phase name (solid, fluid), or grid (a formulation's node fields)
  int part = 0;       // block index per group, as ParaView's PVD reader expects
  std::string file;   // relative to the .pvd
};
/// Replaced atomically, as write_vtu; throws files::WriteError.
void write_pvd(const std::string& path, const std::vector<PvdEntry>& entries);
/// Entries of a .pvd file (as written by write_pvd).
std::vector<PvdEntry> read_pvd(const std::string& path);

}  // namespace swmpm::scene
