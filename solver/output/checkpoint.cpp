#include "solver/output/checkpoint.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
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


Checkpoint Checkpoint::assembled(const std::filesystem::path& dir, std::size_t first, std::size_t last) const {
  const auto& pieces = header.at("pieces");
  const auto all_files = pieces.at("files").get<std::vector<std::string>>();
  const long generation = pieces.at("generation").get<long>();
  last = std::min(last, all_files.size());
  first = std::min(first, last);
  const std::vector<std::string> files(all_files.begin() + static_cast<std::ptrdiff_t>(first),
                                       all_files.begin() + static_cast<std::ptrdiff_t>(last));
  std::vector<Checkpoint> parts;
  for (std::size_t r = 0; r < files.size(); ++r) {
    std::error_code ec;
    if (!std::filesystem::exists(dir / files[r], ec))
      throw CheckpointError((dir / files[r]).string() + ": missing; " + source_.string() + " was written in " +
                            std::to_string(all_files.size()) + " pieces, one per rank, and this is rank " +
                            std::to_string(first + r) + "'s (run the solve again without --resume)");
    parts.push_back(read(dir / files[r]));
    const auto& h = parts.back().header;
    if (h.value("generation", -1L) != generation || h.value("rank", -1L) != static_cast<long>(first + r))
      throw CheckpointError((dir / files[r]).string() + ": a piece of another checkpoint than " + source_.string() +
                            " (generation " + std::to_string(h.value("generation", -1L)) + ", rank " +
                            std::to_string(h.value("rank", -1L)) + "; expected " + std::to_string(generation) + ", " +
                            std::to_string(first + r) + ")");
  }
  Checkpoint whole;
  whole.source_ = source_;
  whole.header = header;
  whole.header.erase("pieces");
  for (const auto& sec : sections_) whole.put_bytes(sec.name, sec.element_bytes, sec.count, data_.data() + sec.offset);
  const std::string key_field = std::to_string(pieces.at("key_field").get<int>());
  // Per set: where each part's particle i went in the whole set.
  std::map<std::string, std::vector<std::vector<int>>> position;
  for (const std::string set : {"solid", "fluid"}) {
    struct Entry {
      std::int64_t key;
      std::size_t part, index;
    };
    std::vector<Entry> entries;
    std::vector<std::size_t> count(parts.size());
    for (std::size_t r = 0; r < parts.size(); ++r) {
      std::vector<std::int64_t> keys;
      parts[r].get(set + "/" + key_field, keys);
      count[r] = keys.size();
      for (std::size_t i = 0; i < keys.size(); ++i) entries.push_back({keys[i], r, i});
    }
    std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.key < b.key; });
    for (std::size_t j = 1; j < entries.size(); ++j)
      if (entries[j].key == entries[j - 1].key)
        throw CheckpointError(source_.string() + ": two pieces hold " + set + " particle " + std::to_string(entries[j].key));
    auto& where = position[set];
    where.resize(parts.size());
    for (std::size_t r = 0; r < parts.size(); ++r) where[r].assign(count[r], -1);
    for (std::size_t j = 0; j < entries.size(); ++j) where[entries[j].part][entries[j].index] = static_cast<int>(j);
    // Each field (the layout checkpoint.bin lists): carried where a piece holds particles (a piece
    // without any carries none; no piece at all: a rank with none to read gets empty sets).
    const auto fields = pieces.at("fields").at(set).get<std::vector<std::size_t>>();
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const std::string name = set + "/" + std::to_string(k);
      const std::size_t bytes = fields[k];
      std::vector<const Section*> sec(parts.size());
      bool active = false;
      for (std::size_t r = 0; r < parts.size(); ++r) {
        sec[r] = &parts[r].find(name, bytes);  // present, of that element size
        active = active || sec[r]->count > 0;
      }
      if (!active) {
        whole.put_bytes(name, bytes, 0, nullptr);
        continue;
      }
      for (std::size_t r = 0; r < parts.size(); ++r)
        if (count[r] > 0 && sec[r]->count != count[r])
          throw CheckpointError((dir / files[r]).string() + ": array \"" + name + "\" holds " + std::to_string(sec[r]->count) +
                                " values for " + std::to_string(count[r]) + " particles");
      std::vector<char> all(entries.size() * bytes);
      for (std::size_t j = 0; j < entries.size(); ++j) {
        const Entry& e = entries[j];
        std::memcpy(all.data() + j * bytes, parts[e.part].data_.data() + sec[e.part]->offset + e.index * bytes, bytes);
      }
      whole.put_bytes(name, bytes, entries.size(), all.data());
    }
  }
  // The particle orders: each piece's entries in piece order, as positions in the whole set.
  for (const auto& [name, set_json] : pieces.at("orders").items()) {
    const std::string set = set_json.get<std::string>();
    std::vector<int> order;
    for (std::size_t r = 0; r < parts.size(); ++r) {
      std::vector<int> mine;
      parts[r].get(name, mine);
      const auto& where = position.at(set)[r];
      for (int i : mine) {
        if (i < 0 || static_cast<std::size_t>(i) >= where.size())
          throw CheckpointError((dir / files[r]).string() + ": order \"" + name + "\" indexes particle " + std::to_string(i) +
                                " of " + std::to_string(where.size()));
        order.push_back(where[static_cast<std::size_t>(i)]);
      }
    }
    whole.put_order(name, set, order);
  }
  return whole;
}

}  // namespace swmpm
