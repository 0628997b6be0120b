// Reading what a user hands swmpm (issue 27, item 6): files that are regular and of bounded size
// (a FIFO would block, /dev/zero would grow memory without end), and JSON text of bounded nesting
// (a value nested 65,000 deep overflowed the stack) with messages that name the JSON path.
// Every file a user names, and every JSON text read from such a file, goes through here.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace swmpm::scene {

/// Deepest nesting of arrays and objects in a JSON input (a scene needs about 8).
constexpr int kMaxJsonDepth = 64;
/// Largest file read as input: scene files, references, the text files of a run directory.
constexpr std::uintmax_t kMaxInputBytes = std::uintmax_t{256} << 20;

/// An input file or JSON text swmpm refuses: one line, "<file>: ...". Bad input, exit status 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// "256 MiB" for a byte count (the limits in messages).
std::string byte_size_text(std::uintmax_t bytes);

/// Checks that `path` (symbolic links resolved) is a regular file of at most `limit` bytes, without
/// blocking on a FIFO; `what` names the file in messages ("reference file"). Throws InputError.
void check_input_file(const std::string& path, const std::string& what, std::uintmax_t limit = kMaxInputBytes);

/// The bytes of `path` after check_input_file (the check is made again on the open file, so a
/// file swapped in between is refused too). Throws InputError.
std::string read_input_file(const std::string& path, const std::string& what, std::uintmax_t limit = kMaxInputBytes);

/// JSON text -> value, refusing nesting deeper than kMaxJsonDepth before any deep value is built.
/// `label` (the file) starts every message. Errors throw InputError with one line:
///   <label>: /solver/0/0/...: got arrays and objects nested deeper than 64 levels, expected at most 64 (line 1, column 70)
///   <label>: /grid/cell_size: got 1e400, which is out of the range of a double; expected a finite number (line 3, column 20)
///   <label>: invalid JSON at line 3, column 18 (byte 35) in /materials: syntax error while parsing ...
/// When `duplicate_keys` is given, a key written twice in one object (the value keeps the last)
/// adds a line "<label>: <pointer>: got key "k" twice in one object, expected each key once".
nlohmann::json parse_json(const std::string& text, const std::string& label,
                          std::vector<std::string>* duplicate_keys = nullptr);
nlohmann::ordered_json parse_ordered_json(const std::string& text, const std::string& label);

/// read_input_file + parse_json.
nlohmann::json read_json_file(const std::string& path, const std::string& what);

/// `s` for a message: at most `max` bytes (cut at a UTF-8 character boundary), the rest replaced
/// by "… (N characters)".
std::string shortened(const std::string& s, std::size_t max = 60);

}  // namespace swmpm::scene
