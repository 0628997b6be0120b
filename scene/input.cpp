// Reading user input safely: regular files of bounded size, JSON of bounded nesting (input.hpp).
#include "scene/input.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <set>

namespace swmpm::scene {

namespace {

/// JSON pointer escaping of one reference token (RFC 6901), shortened for messages.
std::string token(const std::string& key) {
  std::string out;
  for (char ch : shortened(key)) {
    if (ch == '~') out += "~0";
    else if (ch == '/') out += "~1";
    else out += ch;
  }
  return out;
}

/// What a non-regular file is, for "got a FIFO".
std::string kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string expected_file(const std::string& what, std::uintmax_t limit) {
  return "expected a " + what + " (a regular file of at most " + byte_size_text(limit) + ")";
}

/// An open, checked input file: closed on destruction.
class CheckedFile {
 public:
  CheckedFile(const std::string& path, const std::string& what, std::uintmax_t limit) {
    // O_NONBLOCK: opening a FIFO without a writer would otherwise wait for one forever.
    fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) {
      const int err = errno;
      struct stat st {};
      if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
        throw InputError(path + ": got " + kind_of(st.st_mode) + ", " + expected_file(what, limit));
      throw InputError(path + ": cannot read the " + what + " (" + std::strerror(err) + ")");
    }
    struct stat st {};
    if (::fstat(fd_, &st) != 0) {
      const int err = errno;
      ::close(fd_);
      throw InputError(path + ": cannot read the " + what + " (" + std::strerror(err) + ")");
    }
    if (!S_ISREG(st.st_mode)) {
      ::close(fd_);
      throw InputError(path + ": got " + kind_of(st.st_mode) + ", " + expected_file(what, limit));
    }
    if (static_cast<std::uintmax_t>(st.st_size) > limit) {
      ::close(fd_);
      throw InputError(path + ": got " + byte_size_text(static_cast<std::uintmax_t>(st.st_size)) + " (" +
                       std::to_string(st.st_size) + " bytes), " + expected_file(what, limit));
    }
  }
  ~CheckedFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  CheckedFile(const CheckedFile&) = delete;
  CheckedFile& operator=(const CheckedFile&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

std::pair<std::size_t, std::size_t> line_and_column(const std::string& text, std::size_t byte) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < byte && i < text.size(); ++i) {
    if (text[i] == '\n') ++line, column = 1;
    else ++column;
  }
  return {line, column};
}

/// Builds the value from nlohmann's SAX events (no recursion on the input), refusing a container
/// deeper than kMaxJsonDepth before it is created, and tracking the JSON pointer of the current
/// position for messages.
template <class J>
class GuardedBuilder {
 public:
  GuardedBuilder(const std::string& text, const std::string& label, std::vector<std::string>* duplicates)
      : text_(text), label_(label), duplicates_(duplicates) {}

  J result;
  std::string error;  // set when parsing stopped

  bool null() { return add(J(nullptr)); }
  bool boolean(bool b) { return add(J(b)); }
  bool number_integer(typename J::number_integer_t n) { return add(J(n)); }
  bool number_unsigned(typename J::number_unsigned_t n) { return add(J(n)); }
  bool number_float(typename J::number_float_t x, const typename J::string_t&) { return add(J(x)); }
  bool string(typename J::string_t& s) { return add(J(std::move(s))); }
  bool binary(typename J::binary_t& b) { return add(J::binary(b)); }  // not in JSON text
  bool start_object(std::size_t) { return open(J::object(), false); }
  bool start_array(std::size_t) { return open(J::array(), true); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }
  bool key(typename J::string_t& k) {
    Frame& f = frames_.back();
    f.key = k;
    if (duplicates_ != nullptr && !f.keys.insert(k).second)
      duplicates_->push_back(label_ + ": " + pointer() + ": got key \"" + shortened(k) +
                             "\" twice in one object, expected each key once");
    return true;
  }

  bool parse_error(std::size_t byte, const std::string& last_token, const nlohmann::json::exception& e) {
    // `byte` counts the bytes read, the failing one included: it is the 1-based position.
    const auto [line, column] = line_and_column(text_, byte == 0 ? 0 : byte - 1);
    if (e.id == 406) {  // a number beyond the range of a double (1e400); byte is just past it
      const auto [l, c] = line_and_column(text_, byte > last_token.size() ? byte - last_token.size() : 0);
      error = label_ + ": " + here() + ": got " + shortened(last_token) +
              ", which is out of the range of a double; expected a finite number (line " + std::to_string(l) +
              ", column " + std::to_string(c) + ")";
      return false;
    }
    std::string why = e.what();
    const auto at = why.find(": ", why.find("parse error"));
    if (at != std::string::npos) why = why.substr(at + 2);
    const std::string inside = frames_.size() < 2 ? std::string() : " in " + container();
    error = label_ + ": invalid JSON at line " + std::to_string(line) + ", column " + std::to_string(column) +
            " (byte " + std::to_string(byte) + ")" + inside + ": " + why;
    return false;
  }

 private:
  struct Frame {
    J* value;
    bool array;
    std::string key;        // object: the current key
    std::size_t index = 0;  // array: the index of the current element
    std::set<std::string> keys;
  };

  /// Where the next value goes, as a JSON pointer ("" for the document itself).
  std::string pointer() const { return pointer_of(frames_.size()); }
  /// The pointer through the first `n` frames.
  std::string pointer_of(std::size_t n) const {
    std::string p;
    for (std::size_t k = 0; k < n; ++k) {
      p += '/';
      p += frames_[k].array ? std::to_string(frames_[k].index) : token(frames_[k].key);
    }
    return p;
  }
  std::string here() const { return frames_.empty() ? std::string("(top level)") : pointer(); }
  /// The innermost open container, as a JSON pointer (empty: the document).
  std::string container() const { return frames_.empty() ? std::string() : pointer_of(frames_.size() - 1); }

  /// Puts `v` where the next value goes; returns where it is.
  J* place(J&& v) {
    if (frames_.empty()) {
      result = std::move(v);
      return &result;
    }
    Frame& f = frames_.back();
    if (f.array) {
      f.value->push_back(std::move(v));
      return &f.value->back();
    }
    J& slot = (*f.value)[f.key];
    slot = std::move(v);
    return &slot;
  }
  /// After a whole value: an array's next element.
  void element_done() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
  }
  bool add(J&& v) {
    place(std::move(v));
    element_done();
    return true;
  }
  bool open(J&& empty, bool array) {
    if (frames_.size() >= static_cast<std::size_t>(kMaxJsonDepth)) {
      const auto [line, column] = line_and_column(text_, offset_of_open());
      error = label_ + ": " + pointer() + ": got arrays and objects nested deeper than " +
              std::to_string(kMaxJsonDepth) + " levels, expected at most " + std::to_string(kMaxJsonDepth) +
              " (line " + std::to_string(line) + ", column " + std::to_string(column) + ")";
      return false;
    }
    J* at = place(std::move(empty));
    frames_.push_back({at, array, {}, 0, {}});
    return true;
  }
  bool close() {
    frames_.pop_back();
    element_done();
    return true;
  }
  /// The byte of the bracket that went over the limit: the (kMaxJsonDepth + 1)-th unclosed one.
  /// Only called once, when parsing stops; a plain scan that skips strings.
  std::size_t offset_of_open() const {
    std::size_t depth = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < text_.size(); ++i) {
      const char ch = text_[i];
      if (in_string) {
        if (ch == '\\') ++i;
        else if (ch == '"') in_string = false;
      } else if (ch == '"') {
        in_string = true;
      } else if (ch == '[' || ch == '{') {
        if (++depth > static_cast<std::size_t>(kMaxJsonDepth)) return i;
      } else if ((ch == ']' || ch == '}') && depth > 0) {
        --depth;
      }
    }
    return text_.size();
  }

  const std::string& text_;
  const std::string& label_;
  std::vector<std::string>* duplicates_;
  std::vector<Frame> frames_;
};

template <class J>
J parse_guarded(const std::string& text, const std::string& label, std::vector<std::string>* duplicates) {
  GuardedBuilder<J> b(text, label, duplicates);
  if (!J::sax_parse(text, &b)) {
    // What was built up to the stop is at most kMaxJsonDepth deep, so dropping it is safe.
    throw InputError(b.error.empty() ? label + ": invalid JSON" : b.error);
  }
  return std::move(b.result);
}

}  // namespace

std::string byte_size_text(std::uintmax_t bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB"};
  std::size_t u = 0;
  std::uintmax_t v = bytes;
  while (v >= 1024 && v % 1024 == 0 && u + 1 < std::size(units)) v /= 1024, ++u;
  if (u == 0 && bytes >= 1024) {  // not a whole number of KiB: one decimal of the largest unit
    double x = static_cast<double>(bytes);
    while (x >= 1024.0 && u + 1 < std::size(units)) x /= 1024.0, ++u;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f %s", x, units[u]);
    return buf;
  }
  return std::to_string(v) + " " + units[u];
}

void check_input_file(const std::string& path, const std::string& what, std::uintmax_t limit) {
  CheckedFile f(path, what, limit);
}

std::string read_input_file(const std::string& path, const std::string& what, std::uintmax_t limit) {
  CheckedFile f(path, what, limit);
  std::string text;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(f.fd(), buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw InputError(path + ": cannot read the " + what + " (" + std::strerror(errno) + ")");
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > limit)  // it grew while being read
      throw InputError(path + ": got more than " + byte_size_text(limit) + ", " + expected_file(what, limit));
  }
  return text;
}

nlohmann::json parse_json(const std::string& text, const std::string& label, std::vector<std::string>* duplicate_keys) {
  return parse_guarded<nlohmann::json>(text, label, duplicate_keys);
}

nlohmann::ordered_json parse_ordered_json(const std::string& text, const std::string& label) {
  return parse_guarded<nlohmann::ordered_json>(text, label, nullptr);
}

nlohmann::json read_json_file(const std::string& path, const std::string& what) {
  return parse_json(read_input_file(path, what), path);
}

std::string shortened(const std::string& s, std::size_t max) {
  if (s.size() <= max) return s;
  std::size_t cut = max;
  while (cut > 0 && (static_cast<unsigned char>(s[cut]) & 0xC0) == 0x80) --cut;  // not inside a UTF-8 character
  std::size_t characters = 0;
  for (unsigned char ch : s) characters += (ch & 0xC0) != 0x80;
  return s.substr(0, cut) + "… (" + std::to_string(characters) + " characters)";
}

}  // namespace swmpm::scene
