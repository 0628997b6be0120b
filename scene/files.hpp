// Files swmpm writes: every write checked, whole files replaced atomically, and a run directory's
// ledger of what swmpm wrote there, so that nothing else is ever replaced or removed
// (docs/scene-format.md, "Run directories").
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace swmpm::files {

namespace fs = std::filesystem;

/// A write that failed: the file and the system's reason ("No space left on device"). The time
/// loop stops on it with status `failed` (exit 5); preprocess removes what it wrote.
class WriteError : public std::runtime_error {
 public:
  WriteError(const fs::path& path, const std::string& reason)
      : std::runtime_error(path.string() + ": cannot write the file: " + reason), path_(path) {}
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// Writes `path` through a fresh temporary beside it (`.NAME.swmpm-XXXXXX`, mkstemp), renamed over
/// `path` once `fill(temporary)` has returned: a reader or a kill sees the old file or the new one,
/// never a part. `fill` writes the temporary by name (a library writer may open it itself) and
/// throws on failure; with `sync` the data are also forced to the disk (fdatasync) first. The
/// temporary is removed on any failure, and the file gets the mode 0666 & ~umask.
void write_atomically(const fs::path& path, const std::function<void(const std::string& temporary)>& fill,
                      bool sync = false);

/// write_atomically for text held in memory, every write(2) and the close checked.
void write_text_atomically(const fs::path& path, const std::string& text, bool sync = false);

/// Overwrites the start of an existing file in place and cuts it to `text`'s length: needs no new
/// disk block when the file was at least that long. The last resort for run.json on a full disk.
bool overwrite_in_place(const fs::path& path, const std::string& text);

/// Writes all of `text` to the open file `fd` (retrying short writes); false with errno set.
bool write_all(int fd, const std::string& text);

/// Whether `name` is one of write_atomically's temporaries (left behind by a kill).
bool is_temporary(const std::string& name);

/// A text file written line by line (monitors.csv, log.txt), each write checked: a failed write
/// is cut off again (the file ends with the last whole write) and throws WriteError naming the
/// file, and so does every later one.
class CheckedFile {
 public:
  CheckedFile() = default;
  explicit CheckedFile(const fs::path& path);  // creates or truncates
  /// Opens an existing file cut to its first `keep` bytes, to append to (a resumed run).
  CheckedFile(const fs::path& path, std::size_t keep);
  ~CheckedFile();
  CheckedFile(const CheckedFile&) = delete;
  CheckedFile& operator=(const CheckedFile&) = delete;
  CheckedFile(CheckedFile&& o) noexcept;
  CheckedFile& operator=(CheckedFile&& o) noexcept;

  void write(const std::string& text);  // appended and flushed to the system
  const fs::path& path() const { return path_; }
  bool is_open() const { return file_ != nullptr; }
  std::size_t size() const { return size_; }  // bytes in the file

 private:
  fs::path path_;
  std::FILE* file_ = nullptr;
  std::size_t size_ = 0;  // bytes of whole writes in the file
  std::string error_;  // the first failure, repeated by every later write
};

/// What swmpm wrote in a run directory: RUN_DIR/.swmpm-files, one path (relative to RUN_DIR) a
/// line, appended before the file is renamed into place. swmpm replaces or removes a file only
/// when it is on this list; a file of another name in the folder is never touched.
class RunDirectory {
 public:
  /// Opens `dir` (created if missing) and reads its ledger (none yet: an empty list).
  explicit RunDirectory(const fs::path& dir);

  const fs::path& dir() const { return dir_; }
  fs::path operator/(const std::string& relative) const { return dir_ / relative; }

  /// Whether swmpm wrote `relative` here (it is on the ledger).
  bool owns(const std::string& relative) const { return owned_.count(relative) > 0; }
  /// Whether the ledger lists any file that still exists: the folder holds a run.
  bool holds_a_run() const;

  /// Checks that swmpm may write `relative`: throws RunDirectoryError when a file of that name
  /// exists that swmpm did not write. Then puts it on the ledger (checked, flushed).
  void claim(const std::string& relative);
  /// claim + write_atomically.
  void write(const std::string& relative, const std::function<void(const std::string& temporary)>& fill);
  void write_text(const std::string& relative, const std::string& text, bool sync = false);

  /// Removes the files on the ledger for which `which(relative)` holds (and the temporaries left in
  /// their folders by a kill); folders swmpm made are removed when they end up empty, and so are
  /// the ledger and the run directory itself when nothing of swmpm's is left in them.
  void remove_owned(const std::function<bool(const std::string& relative)>& which);

  /// Existing files among `relatives` that swmpm did not write (the first `limit`).
  std::vector<std::string> foreign(const std::vector<std::string>& relatives) const;

 private:
  void record(const std::string& relative);

  fs::path dir_;
  std::set<std::string> owned_;
};

/// The files in `dir` whose names swmpm writes (relative paths): scene.json, run.json, log.txt,
/// monitors.csv, report.md, particles/{solid,fluid,surfaces}.vtu, output/results.pvd, frames
/// output/<phase>_NNNNNN.vtu and grid fields output/grid_NNNNNN.vtu. Whether swmpm wrote them is
/// RunDirectory's question. (Plots take the monitors' names: each is checked when it is drawn,
/// RunDirectory::claim.)
std::vector<std::string> swmpm_files_in(const fs::path& dir);

/// A run directory that swmpm may not use as asked: exit 2, nothing written.
class RunDirectoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace swmpm::files
