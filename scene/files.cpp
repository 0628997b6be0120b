#include "scene/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>

namespace swmpm::files {
namespace {

constexpr const char* kLedger = ".swmpm-files";
constexpr const char* kTemporaryTag = ".swmpm-";

mode_t file_mode() {
  static const mode_t mode = [] {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    return static_cast<mode_t>(0666 & ~mask);
  }();
  return mode;
}

std::string reason(int err) { return std::strerror(err); }

}  // namespace

bool write_all(int fd, const std::string& text) {
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  return true;
}

namespace {

/// A ledger line that could only be a path inside the run directory (no root, no "..").
bool safe_relative(const std::string& rel) {
  if (rel.empty()) return false;
  const fs::path p(rel);
  if (p.is_absolute() || p.has_root_name()) return false;
  for (const auto& part : p)
    if (part == ".." || part == ".") return false;
  return true;
}

}  // namespace

void write_atomically(const fs::path& path, const std::function<void(const std::string& temporary)>& fill,
                      bool sync) {
  const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::string name = ".";  // appended piece by piece: GCC 12 warns falsely on "." + string (bug 105329)
  name.append(path.filename().string()).append(kTemporaryTag).append("XXXXXX");
  std::string temporary = (folder / name).string();
  const int fd = ::mkstemp(temporary.data());
  if (fd < 0) throw WriteError(path, reason(errno));
  const bool chmod_ok = ::fchmod(fd, file_mode()) == 0;
  const int chmod_err = errno;
  ::close(fd);
  try {
    if (!chmod_ok) throw WriteError(path, reason(chmod_err));
    fill(temporary);
    if (sync) {
      const int check = ::open(temporary.c_str(), O_RDONLY | O_CLOEXEC);
      if (check < 0) throw WriteError(path, reason(errno));
      const bool synced = ::fdatasync(check) == 0;
      const int sync_err = errno;
      ::close(check);
      if (!synced) throw WriteError(path, reason(sync_err));
    }
    if (::rename(temporary.c_str(), path.c_str()) != 0) throw WriteError(path, reason(errno));
  } catch (...) {
    ::unlink(temporary.c_str());
    throw;
  }
}

void write_text_atomically(const fs::path& path, const std::string& text, bool sync) {
  write_atomically(
      path,
      [&](const std::string& temporary) {
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
    if (fd < 0) throw WriteError(path, reason(errno));
    const bool ok = write_all(fd, text);
    const int err = errno;
    if (::close(fd) != 0 && ok) throw WriteError(path, reason(errno));
    if (!ok) throw WriteError(path, reason(err));
      },
      sync);
}

bool overwrite_in_place(const fs::path& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return false;
  bool ok = write_all(fd, text) && ::ftruncate(fd, static_cast<off_t>(text.size())) == 0 && ::fdatasync(fd) == 0;
  ok = ::close(fd) == 0 && ok;
  return ok;
}

bool is_temporary(const std::string& name) {
  const std::size_t tag = name.rfind(kTemporaryTag);
  return name.size() > 1 && name[0] == '.' && tag != std::string::npos &&
         name.size() == tag + std::strlen(kTemporaryTag) + 6;
}

// ---------------------------------------------------------------------------------------------

CheckedFile::CheckedFile(const fs::path& path) : path_(path), file_(std::fopen(path.c_str(), "w")) {
  if (!file_) throw WriteError(path, reason(errno));
}

CheckedFile::CheckedFile(const fs::path& path, std::size_t keep) : path_(path), size_(keep) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) throw WriteError(path, reason(errno));
  if (::ftruncate(fd, static_cast<off_t>(keep)) != 0 || ::lseek(fd, 0, SEEK_END) < 0 || !(file_ = ::fdopen(fd, "a"))) {
    const int err = errno;
    ::close(fd);
    throw WriteError(path, reason(err));
  }
}

CheckedFile::~CheckedFile() {
  if (file_) std::fclose(file_);
}

CheckedFile::CheckedFile(CheckedFile&& o) noexcept
    : path_(std::move(o.path_)), file_(o.file_), size_(o.size_), error_(std::move(o.error_)) {
  o.file_ = nullptr;
}

CheckedFile& CheckedFile::operator=(CheckedFile&& o) noexcept {
  if (this != &o) {
    if (file_) std::fclose(file_);
    path_ = std::move(o.path_);
    file_ = o.file_;
    size_ = o.size_;
    error_ = std::move(o.error_);
    o.file_ = nullptr;
  }
  return *this;
}

void CheckedFile::write(const std::string& text) {
  if (!error_.empty()) throw WriteError(path_, error_);
  if (!file_) throw WriteError(path_, "the file is not open");
  errno = 0;
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size() || std::fflush(file_) != 0) {
    error_ = reason(errno ? errno : EIO);
    // What reached the file of this write is cut off again: the file ends with a whole line.
    if (::ftruncate(::fileno(file_), static_cast<off_t>(size_)) != 0) error_ += " (and it could not be cut back)";
    throw WriteError(path_, error_);
  }
  size_ += text.size();
}

// ---------------------------------------------------------------------------------------------

RunDirectory::RunDirectory(const fs::path& dir) : dir_(dir) {
  std::ifstream in(dir_ / kLedger);
  for (std::string line; std::getline(in, line);)
    if (safe_relative(line)) owned_.insert(line);  // a torn last line names no file of ours
}

bool RunDirectory::holds_a_run() const {
  std::error_code ec;
  for (const auto& rel : owned_)
    if (fs::exists(fs::symlink_status(dir_ / rel, ec))) return true;
  return false;
}

std::vector<std::string> RunDirectory::foreign(const std::vector<std::string>& relatives) const {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& rel : relatives)
    if (!owns(rel) && fs::exists(fs::symlink_status(dir_ / rel, ec))) out.push_back(rel);
  return out;
}

void RunDirectory::record(const std::string& relative) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  const fs::path ledger = dir_ / kLedger;
  const int fd = ::open(ledger.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NOFOLLOW, file_mode());
  if (fd < 0) throw WriteError(ledger, reason(errno));
  const bool ok = write_all(fd, relative + "\n");
  const int err = errno;
  ::close(fd);
  if (!ok) throw WriteError(ledger, reason(err));
  owned_.insert(relative);
}

void RunDirectory::claim(const std::string& relative) {
  if (!safe_relative(relative)) throw std::logic_error("RunDirectory::claim: not a relative path: " + relative);
  if (owns(relative)) return;
  if (!foreign({relative}).empty())
    throw RunDirectoryError((dir_ / relative).string() +
                            " exists and swmpm did not write it; swmpm never replaces a file it did not write: "
                            "move it away or choose another run directory (-o)");
  const fs::path parent = (dir_ / relative).parent_path();
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw WriteError(parent, ec.message());
  record(relative);
}

void RunDirectory::write(const std::string& relative, const std::function<void(const std::string& temporary)>& fill) {
  claim(relative);
  write_atomically(dir_ / relative, fill);
}

void RunDirectory::write_text(const std::string& relative, const std::string& text, bool sync) {
  claim(relative);
  write_text_atomically(dir_ / relative, text, sync);
}

void RunDirectory::remove_owned(const std::function<bool(const std::string& relative)>& which) {
  std::set<fs::path> folders;
  std::set<std::string> kept;
  std::error_code ec;
  for (const auto& rel : owned_) {
    if (!which(rel)) {
      kept.insert(rel);
      continue;
    }
    const fs::path p = dir_ / rel;
    if (!fs::is_directory(fs::symlink_status(p, ec))) fs::remove(p, ec);
    folders.insert(p.parent_path());
  }
  for (const auto& folder : folders) {
    if (fs::is_directory(folder, ec))
      for (const auto& e : fs::directory_iterator(folder, ec))
        if (is_temporary(e.path().filename().string())) fs::remove(e.path(), ec);
    if (folder != dir_) fs::remove(folder, ec);  // only when empty
  }
  owned_ = std::move(kept);
  if (owned_.empty()) {  // nothing of swmpm's is left: neither is the ledger, nor a folder it leaves empty
    fs::remove(dir_ / kLedger, ec);
    fs::remove(dir_, ec);
    return;
  }
  std::string text;
  for (const auto& rel : owned_) text += rel + "\n";
  write_text_atomically(dir_ / kLedger, text);
}

std::vector<std::string> swmpm_files_in(const fs::path& dir) {
  static const std::regex frame(R"((solid|fluid|grid)_[0-9]{6}\.vtu)");
  std::vector<std::string> out;
  std::error_code ec;
  auto add = [&](const std::string& rel) {
    if (fs::exists(fs::symlink_status(dir / rel, ec))) out.push_back(rel);
  };
  for (const char* top : {"scene.json", "run.json", "log.txt", "monitors.csv", "report.md", "report.html", "particles/solid.vtu",
                          "particles/fluid.vtu", "particles/surfaces.vtu", "particles/phase_field.vtu",
                          "output/results.pvd"})
    add(top);
  if (fs::is_directory(dir / "output", ec))
    for (const auto& e : fs::directory_iterator(dir / "output", ec))
      if (const std::string name = e.path().filename().string(); std::regex_match(name, frame))
        out.push_back("output/" + name);
  return out;
}

}  // namespace swmpm::files
