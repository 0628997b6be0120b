// Restart checkpoints on disk (RUN_DIR/checkpoint.bin): everything a run carries from one step to
// the next, so that `swmpm solve RUN_DIR --resume` continues bit for bit as if it had not stopped.
//
// Layout (docs/architecture.md, "Checkpoints"), little-endian:
//   bytes 0-7   magic "SWMPMCK1"
//   bytes 8-15  uint64 H, the length of the header
//   H bytes     the header, JSON: software_version, git_hash, scene (the resolved scene.json as
//               text), formulation, dimension, step, time, "loop" (the time loop's own state),
//               "formulation_state" (small values of the formulation), and "arrays": a list of
//               {name, element_bytes, count, offset} for the sections that follow
//   sections    raw arrays, each starting at an offset that is a multiple of 8 from the end of the
//               header: per-particle fields "<set>/<field>" (solid/x, fluid/V, ...) as stored in
//               ParticleSet, and the formulation's own arrays
// The file is replaced atomically (files::write_atomically), so a kill while it is written
// leaves the previous checkpoint whole. Under mpirun each rank writes its particles in a piece
// of the same layout (RUN_DIR/checkpoint/piece-<generation>-<rank>.bin) and checkpoint.bin names
// them (header "pieces"); assembled() puts them together (solver/run.cpp, write_checkpoint).
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

namespace swmpm {

class Checkpoint {
 public:
  nlohmann::ordered_json header = nlohmann::ordered_json::object();

  /// Adds an array of trivially copyable elements under `name` (copied into the checkpoint).
  /// Elements are copied as bytes: plain numbers, std::array and Eigen's fixed-size matrices
  /// (which the type trait does not call trivially copyable, but which hold only their numbers).
  template <class T, class Alloc>
  void put(const std::string& name, const std::vector<T, Alloc>& v) {
    static_assert(std::is_trivially_destructible_v<T> && std::is_standard_layout_v<T>);
    put_bytes(name, sizeof(T), v.size(), v.data());
  }
  /// The array stored under `name`; throws CheckpointError when it is missing or of another type.
  template <class T, class Alloc>
  void get(const std::string& name, std::vector<T, Alloc>& v) const {
    static_assert(std::is_trivially_destructible_v<T> && std::is_standard_layout_v<T>);
    const Section& s = find(name, sizeof(T));
    v.resize(s.count);
    if (s.count) std::memcpy(static_cast<void*>(v.data()), data_.data() + s.offset, s.count * sizeof(T));
  }
  bool has(const std::string& name) const;
  /// A particle order (indices into the particle set `set`, as a scatter schedule's): stored as
  /// put() does and marked in the header ("particle_orders"), so that a run on several ranks can
  /// write it with its set in pieces and a resume put it together (assembled).
  void put_order(const std::string& name, const std::string& set, const std::vector<int>& order) {
    put(name, order);
    header["particle_orders"][name] = set;
  }
  /// A small array with the same values on every rank (a run's scalars): stored as put() does and
  /// marked in the header ("global_arrays"), so that a run on several ranks writes rank 0's.
  template <class T>
  void put_global(const std::string& name, const std::vector<T>& v) {
    put(name, v);
    header["global_arrays"][name] = true;
  }
  /// Copies array `name` of `other` (its element size and values) into this checkpoint.
  void copy_array(const Checkpoint& other, const std::string& name) {
    for (const auto& s : other.sections_)
      if (s.name == name) return put_bytes(name, s.element_bytes, s.count, other.data_.data() + s.offset);
    throw std::logic_error("Checkpoint::copy_array: no array " + name);
  }
  /// The names of the arrays, in the order they were put.
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& s : sections_) n.push_back(s.name);
    return n;
  }
  /// Empties the checkpoint, keeping its memory (the loop's in-memory snapshot is refilled in place).
  void clear() {
    header = nlohmann::ordered_json::object();
    sections_.clear();
    data_.clear();
  }

  void write(const std::filesystem::path& path) const;  // atomically; throws files::WriteError
  static Checkpoint read(const std::filesystem::path& path);  // throws CheckpointError

  /// A checkpoint written in pieces (mpirun: checkpoint.bin with the loop's state, the global
  /// arrays and header "pieces"; each rank's particles in its own file, named there, relative to
  /// `dir`): pieces [first, last) put together, each set's fields in key order ("pieces"/
  /// "key_field" names the key's field), each particle order as positions in that set (each
  /// piece's entries in piece order). All pieces: the
  /// snapshot one rank writes (key order is the one-rank storage order); none: empty sets and
  /// orders ("pieces"/"fields" and "orders" give their layout). Throws CheckpointError
  /// when a piece is missing, damaged or of another checkpoint.
  Checkpoint assembled(const std::filesystem::path& dir, std::size_t first, std::size_t last) const;
  /// The number of pieces (0: written whole, by one rank).
  std::size_t pieces() const { return header.contains("pieces") ? header["pieces"]["files"].size() : 0; }

 private:
  struct Section {
    std::string name;
    std::size_t element_bytes = 0, count = 0, offset = 0;
  };
  void put_bytes(const std::string& name, std::size_t element_bytes, std::size_t count, const void* data);
  const Section& find(const std::string& name, std::size_t element_bytes) const;

  std::vector<Section> sections_;
  std::vector<char> data_;
  std::filesystem::path source_;  // the file read, for messages
};

/// Every per-particle field of a set (ParticleSet::for_each_field's list, in its order) as arrays
/// "<name>/<k>"; restore_set reads them into a set of the same layout (the run's initial set).
template <class Set>
void save_set(Checkpoint& c, const std::string& name, const Set& ps) {
  int k = 0;
  const_cast<Set&>(ps).for_each_field([&](const auto& v) { c.put(name + "/" + std::to_string(k++), v); });
}
template <class Set>
void restore_set(const Checkpoint& c, const std::string& name, Set& ps) {
  int k = 0;
  ps.for_each_field([&](auto& v) { c.get(name + "/" + std::to_string(k++), v); });
}

/// A checkpoint that cannot be used: missing, damaged, or of another scene or version.
class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace swmpm
