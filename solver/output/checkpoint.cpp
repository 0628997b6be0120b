#include "solver/output/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <fstream>

#include "scene/files.hpp"
#include "scene/input.hpp"

namespace swmpm {
namespace {

constexpr char kMagic[8] = {'S', 'W', 'M', 'P', 'M', 'C', 'K', '1'};

std::size_t padded(std::size_t n) { return (n + 7) / 8 * 8; }

}  // namespace

void Checkpoint::put_bytes(const std::string& name, std::size_t element_bytes, std::size_t count, const void* data) {
  const std::size_t offset = data_.size();
  const std::size_t bytes = element_bytes * count;
  // Appended in place (a resize would zero the bytes before the copy overwrites them), then the
  // zero padding to the next 8-byte boundary.
  const char* first = static_cast<const char*>(data);
  if (bytes) data_.insert(data_.end(), first, first + bytes);
  data_.resize(offset + padded(bytes), 0);
  sections_.push_back({name, element_bytes, count, offset});
}

bool Checkpoint::has(const std::string& name) const {
  for (const auto& s : sections_)
    if (s.name == name) return true;
  return false;
}

const Checkpoint::Section& Checkpoint::find(const std::string& name, std::size_t element_bytes) const {
  for (const auto& s : sections_)
    if (s.name == name) {
      if (s.element_bytes != element_bytes)
        throw CheckpointError(source_.string() + ": array \"" + name + "\" has elements of " +
                              std::to_string(s.element_bytes) + " bytes, expected " + std::to_string(element_bytes));
      return s;
    }
  throw CheckpointError(source_.string() + ": no array \"" + name + "\" (written by another version?)");
}

void Checkpoint::write(const std::filesystem::path& path) const {
  nlohmann::ordered_json h = header;
  nlohmann::ordered_json arrays = nlohmann::ordered_json::array();
  for (const auto& s : sections_)
    arrays.push_back({{"name", s.name}, {"element_bytes", s.element_bytes}, {"count", s.count}, {"offset", s.offset}});
  h["arrays"] = arrays;
  std::string text = h.dump();
  text.resize(padded(text.size()), ' ');  // the sections start 8-byte aligned
  files::write_atomically(
      path,
      [&](const std::string& temporary) {
        const int fd = ::open(temporary.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
        if (fd < 0) throw files::WriteError(path, std::strerror(errno));
        const std::uint64_t length = text.size();
        std::string head(kMagic, sizeof kMagic);
        head.append(reinterpret_cast<const char*>(&length), sizeof length);
        const bool ok = files::write_all(fd, head) && files::write_all(fd, text) &&
                        files::write_all(fd, std::string(data_.data(), data_.size()));
        const int err = errno;
        if (::close(fd) != 0 && ok) throw files::WriteError(path, std::strerror(errno));
        if (!ok) throw files::WriteError(path, std::strerror(err));
      },
      true);
}

Checkpoint Checkpoint::read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CheckpointError(path.string() + ": no checkpoint to resume from (the run wrote none yet)");
  Checkpoint c;
  c.source_ = path;
  char magic[8];
  std::uint64_t length = 0;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(&length), sizeof length);
  if (!in || std::memcmp(magic, kMagic, 8) != 0 || length > (1u << 30))
    throw CheckpointError(path.string() + ": not a swmpm checkpoint (bad magic number or header length)");
  std::string text(length, '\0');
  in.read(text.data(), static_cast<std::streamsize>(length));
  if (!in) throw CheckpointError(path.string() + ": the header is cut short");
  try {
    c.header = scene::parse_ordered_json(text, path.string() + " (header)");  // bounded nesting
  } catch (const scene::InputError& e) {
    throw CheckpointError(std::string(e.what()) + "; the header is not valid JSON");
  }
  c.data_.assign(std::istreambuf_iterator<char>(in), {});
  for (const auto& a : c.header.at("arrays")) {
    Section s{a.at("name"), a.at("element_bytes"), a.at("count"), a.at("offset")};
    if (s.offset + s.element_bytes * s.count > c.data_.size())
      throw CheckpointError(path.string() + ": array \"" + s.name + "\" runs past the end of the file (cut short?)");
    c.sections_.push_back(std::move(s));
  }
  c.header.erase("arrays");
  return c;
}

}  // namespace swmpm
