#include "preprocess/geo_script.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <set>
#include <stdexcept>

#include "preprocess/shape.hpp"
#include "scene/files.hpp"

namespace fs = std::filesystem;

namespace swmpm::pre {
namespace {

/// One token of the .geo language: an identifier (option names such as `Mesh.MeshSizeMax` kept
/// whole), a string literal (its text, unescaped), a number, or one punctuation character ('>>'
/// and '>=' as two-character tokens).
struct Token {
  enum Kind { ident, string, number, punct } kind;
  std::string text;
  int line;
};

bool ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

/// The tokens of a .geo text, comments left out. gmsh's lexer also reads `Mesh.X` as three tokens;
/// one dotted identifier is what the option rules below look at.
std::vector<Token> tokenize(const std::string& s) {
  std::vector<Token> out;
  int line = 1;
  for (std::size_t i = 0; i < s.size();) {
    const char c = s[i];
    if (c == '\n') {
      ++line;
      ++i;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
    } else if (s.compare(i, 2, "//") == 0) {
      while (i < s.size() && s[i] != '\n') ++i;
    } else if (s.compare(i, 2, "/*") == 0) {
      const std::size_t end = s.find("*/", i + 2);
      const std::size_t stop = end == std::string::npos ? s.size() : end + 2;
      line += static_cast<int>(std::count(s.begin() + static_cast<long>(i), s.begin() + static_cast<long>(stop), '\n'));
      i = stop;
    } else if (c == '"') {
      Token t{Token::string, "", line};
      for (++i; i < s.size() && s[i] != '"'; ++i) {
        if (s[i] == '\\' && i + 1 < s.size()) ++i;
        if (s[i] == '\n') ++line;
        t.text += s[i];
      }
      ++i;  // the closing quote
      out.push_back(std::move(t));
    } else if (ident_start(c)) {
      Token t{Token::ident, "", line};
      while (i < s.size()) {
        while (i < s.size() && ident_char(s[i])) t.text += s[i++];
        if (i + 1 < s.size() && s[i] == '.' && ident_start(s[i + 1])) t.text += s[i++];
        else break;
      }
      out.push_back(std::move(t));
    } else if (std::isdigit(static_cast<unsigned char>(c)) ||
               (c == '.' && i + 1 < s.size() && std::isdigit(static_cast<unsigned char>(s[i + 1])))) {
      Token t{Token::number, "", line};
      while (i < s.size() && (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '.' ||
                              ((s[i] == '-' || s[i] == '+') && (s[i - 1] == 'e' || s[i - 1] == 'E'))))
        t.text += s[i++];
      out.push_back(std::move(t));
    } else {
      const bool two = i + 1 < s.size() && c == '>' && (s[i + 1] == '>' || s[i + 1] == '=');
      out.push_back({Token::punct, s.substr(i, two ? 2 : 1), line});
      i += two ? 2 : 1;
    }
  }
  return out;
}

const std::set<std::string>& runs_commands() {
  static const std::set<std::string> s{"SystemCall", "System", "NonBlockingSystemCall", "OnelabRun"};
  return s;
}
const std::set<std::string>& writes_files() {
  static const std::set<std::string> s{"Save", "Print", "CreateDir", "Plugin"};
  return s;
}
const std::set<std::string>& controls_process() {
  static const std::set<std::string> s{"Exit", "Abort", "Sleep", "Draw"};
  return s;
}
/// Messages that take a `> "file"` / `>> "file"` redirection.
const std::set<std::string>& messages() {
  static const std::set<std::string> s{"Printf", "Error", "Warning"};
  return s;
}
/// Option categories whose options name files or programs, or act on post-processing views.
const std::set<std::string>& foreign_options() {
  static const std::set<std::string> s{"General", "Solver", "Print", "PostProcessing", "View"};
  return s;
}
/// What Merge may read besides .geo scripts: meshes and CAD models (no views, no scripts of
/// other languages, which gmsh would hand to an interpreter).
const std::set<std::string>& mergeable() {
  static const std::set<std::string> s{".msh", ".step", ".stp", ".iges", ".igs", ".brep", ".stl", ".unv", ".vtk"};
  return s;
}

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// `inner` lies in `folder` or below it (both already canonical).
bool within(const fs::path& inner, const fs::path& folder) {
  auto f = folder.begin(), i = inner.begin();
  for (; f != folder.end(); ++f, ++i)
    if (i == inner.end() || *f != *i) return false;
  return true;
}

class Checker {
 public:
  explicit Checker(const GeoScriptRoots& roots) {
    for (const auto& r : roots.folders) {
      std::error_code ec;
      const fs::path c = fs::weakly_canonical(fs::absolute(r.empty() ? fs::path(".") : r, ec), ec);
      if (!ec) roots_.push_back(c);
    }
  }

  void check(const fs::path& file, int depth) {
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(fs::absolute(file), ec);
    if (depth > 16) refuse(file, 0, "Include", "nests files more than 16 deep");
    if (!visited_.insert(canonical.string()).second) return;  // an Include cycle: gmsh's own limit applies
    std::ifstream in(file, std::ios::binary);
    if (!in) throw GeometryError("file", file.string() + ": cannot read the geometry script");
    const std::string text(std::istreambuf_iterator<char>(in), {});
    const std::vector<Token> t = tokenize(text);
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (t[k].kind != Token::ident) continue;
      const std::string& w = t[k].text;
      const std::string head = w.substr(0, w.find('.'));
      if (runs_commands().count(w)) refuse(file, t[k].line, w, "runs a shell command");
      if (writes_files().count(w)) refuse(file, t[k].line, w, "writes files");
      if (controls_process().count(w))
        refuse(file, t[k].line, w, w == "Sleep" ? "stalls the process" : w == "Draw" ? "drives a display" : "ends the process");
      if (foreign_options().count(head)) {
        if (w == "View" || w.rfind("View.", 0) == 0 || w.rfind("PostProcessing", 0) == 0)
          refuse(file, t[k].line, w, "acts on post-processing views, which read and write files");
        if (k + 1 < t.size() && t[k + 1].kind == Token::punct && t[k + 1].text == "=")
          refuse(file, t[k].line, w, "sets an option outside Mesh.* and Geometry.* (such options name files and programs)");
      }
      if (messages().count(w)) check_redirect(file, t, k);
      if (w == "Include" || w == "Merge" || w == "MergeWithBoundingBox") {
        const fs::path target = literal_path(file, t, k, k + 1);
        const std::string ext = lower(target.extension().string());
        if (w == "Include" || ext == ".geo") {
          check(target, depth + 1);
        } else if (!mergeable().count(ext)) {
          refuse(file, t[k].line, w + " \"" + target.string() + "\"",
                 "merges a file that is not a mesh or CAD model (expected .geo, .msh, .step, .stp, .iges, .igs, "
                 ".brep, .stl, .unv, .vtk)");
        }
      }
      if (w == "ShapeFromFile") {
        if (k + 1 >= t.size() || t[k + 1].text != "(") refuse(file, t[k].line, w, "is not followed by (\"file\")");
        literal_path(file, t, k, k + 2);
      }
    }
  }

 private:
  [[noreturn]] void refuse(const fs::path& file, int line, const std::string& construct, const std::string& why) const {
    std::string where = file.string();
    if (line > 0) where += ":" + std::to_string(line);
    std::string folders;
    for (const auto& r : roots_) folders += (folders.empty() ? "" : ", ") + r.string();
    throw GeometryError("file", where + ": `" + construct + "` " + why +
                                    "; a geometry script may not run commands, write files, or read files "
                                    "outside the scene's and the geometry's folders (" +
                                    folders + "). Pass --trust-geometry to mesh it as it is");
  }

  /// Printf("...") > "file" and >> "file": the token after the message's closing parenthesis.
  void check_redirect(const fs::path& file, const std::vector<Token>& t, std::size_t k) const {
    std::size_t j = k + 1;
    if (j >= t.size() || t[j].text != "(") return;
    int depth = 0;
    for (; j < t.size(); ++j) {
      if (t[j].kind != Token::punct) continue;
      if (t[j].text == "(") ++depth;
      if (t[j].text == ")" && --depth == 0) break;
    }
    if (j + 1 < t.size() && t[j + 1].kind == Token::punct && (t[j + 1].text == ">" || t[j + 1].text == ">>"))
      refuse(file, t[k].line, t[k].text + "(...) " + t[j + 1].text, "writes to a file");
  }

  /// The file a reading command names: a string literal at t[at], resolved as gmsh does (relative
  /// to the folder of the file being read), and inside one of the roots.
  fs::path literal_path(const fs::path& file, const std::vector<Token>& t, std::size_t k, std::size_t at) const {
    if (at >= t.size() || t[at].kind != Token::string ||
        (at + 1 < t.size() && t[at + 1].kind == Token::punct && t[at + 1].text != ";" && t[at + 1].text != ")"))
      refuse(file, t[k].line, t[k].text, "names its file by an expression, which cannot be checked before it runs; "
                                          "write the path as a string literal");
    fs::path target(t[at].text);
    if (target.is_relative()) target = fs::absolute(file).parent_path() / target;
    std::error_code ec;
    const fs::path canonical = fs::weakly_canonical(target, ec);
    const bool inside = !ec && std::any_of(roots_.begin(), roots_.end(),
                                           [&](const fs::path& r) { return within(canonical, r); });
    if (!inside) refuse(file, t[k].line, t[k].text + " \"" + t[at].text + "\"", "reads a file outside the allowed folders");
    return canonical;
  }

  std::vector<fs::path> roots_;
  std::set<std::string> visited_;
};

}  // namespace

void check_geo_script(const fs::path& file, const GeoScriptRoots& roots) { Checker(roots).check(file, 0); }

PrivateTempFile::PrivateTempFile(const std::string& name, const std::string& content) {
  std::string pattern = (fs::temp_directory_path() / "swmpm-XXXXXX").string();
  if (!::mkdtemp(pattern.data()))  // mode 0700, a name no other process can predict
    throw std::runtime_error(pattern + ": cannot create a private temporary folder: " + std::strerror(errno));
  dir_ = pattern;
  path_ = dir_ / name;
  const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  bool ok = fd >= 0 && files::write_all(fd, content);
  const int saved = errno;
  if (fd >= 0 && ::close(fd) != 0) ok = false;
  if (!ok) {
    std::error_code ec;
    fs::remove_all(dir_, ec);
    throw std::runtime_error(path_.string() + ": cannot write the temporary file: " + std::strerror(saved));
  }
}

PrivateTempFile::~PrivateTempFile() {
  std::error_code ec;
  fs::remove_all(dir_, ec);
}

}  // namespace swmpm::pre
