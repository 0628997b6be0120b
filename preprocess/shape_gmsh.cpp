// `gmsh` geometries: a .geo file meshed by gmsh (with its DefineConstant parameters set from the
// scene), or a finished .msh, read through the gmsh C++ API. The body is the union of the mesh's
// elements of the scene's dimension (or of one physical group); the inside test locates points in
// those elements split into simplices; physical groups of dimension dim - 1 become named surfaces.
#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <regex>
#include <sstream>

#include "preprocess/geo_script.hpp"
#include "preprocess/shape_types.hpp"

namespace fs = std::filesystem;

namespace swmpm::pre {
namespace {

/// gmsh keeps one global model and is not thread-safe, so every use holds one lock for its whole
/// duration. The library is initialised on first use and finalised when the process exits.
class GmshSession {
 public:
  GmshSession() : lock_(mutex()) {
    static const Library library;
    gmsh::clear();
    gmsh::onelab::clear();
    gmsh::logger::start();
  }
  ~GmshSession() {
    gmsh::logger::stop();
    gmsh::clear();
    gmsh::onelab::clear();
  }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  /// The first error gmsh logged since the session began or the last call, on one line; "" if none.
  std::string first_error() {
    std::vector<std::string> log;
    gmsh::logger::get(log);
    std::string first;
    for (std::size_t i = seen_; i < log.size() && first.empty(); ++i)
      if (log[i].rfind("Error: ", 0) == 0) first = log[i].substr(7);
    seen_ = log.size();
    std::replace(first.begin(), first.end(), '\n', ' ');
    return first;
  }

 private:
  struct Library {
    Library() {
      gmsh::initialize(0, nullptr, false);  // no user configuration files: the same mesh everywhere
      gmsh::option::setNumber("General.Terminal", 0);
      // Errors are logged and read back: an exception thrown inside gmsh's OpenMP mesher aborts.
      gmsh::option::setNumber("General.AbortOnError", 0);
    }
    ~Library() { gmsh::finalize(); }
  };
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  std::size_t seen_ = 0;
};

/// What a .msh file declares before its data: gmsh reserves memory for the counts of its $Nodes
/// and $Elements headers, so a 79-byte file that declares 1e8 nodes once cost 2.4 GB. A count the
/// file's bytes cannot hold (every node and element takes at least 4 bytes, ASCII or binary), or
/// node tags far sparser than the nodes (tags index arrays), is refused before gmsh reads it.
/// Returns "" or why. MSH 2 and 4, ASCII and binary.
std::string msh_header_problem(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  const double bytes = static_cast<double>(fs::file_size(file));
  std::string line;
  bool binary = false, v4 = true;
  double nodes = 0.0, elements = 0.0, max_node_tag = 0.0, max_element_tag = 0.0;
  // Reads the counts that follow a section header: MSH 4 "blocks count min_tag max_tag" (binary:
  // four size_t), MSH 2 "count".
  auto counts = [&](double& count, double& max_tag) {
    if (v4 && binary) {
      std::uint64_t c[4] = {0, 0, 0, 0};
      in.read(reinterpret_cast<char*>(c), sizeof c);
      count = static_cast<double>(c[1]);
      max_tag = static_cast<double>(c[3]);
    } else if (std::getline(in, line)) {
      std::istringstream is(line);
      double blocks = 0.0, min_tag = 0.0;
      if (v4) is >> blocks >> count >> min_tag >> max_tag;
      else {
        is >> count;
        max_tag = count;
      }
    }
  };
  int sections = 0;
  while (sections < 2 && std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "$MeshFormat" && std::getline(in, line)) {
      std::istringstream is(line);
      double version = 0.0;
      int type = 0;
      is >> version >> type;
      v4 = version >= 4.0;
      binary = type == 1;
      if (binary) std::getline(in, line);  // the endianness check, one int and a newline
    } else if (line == "$Nodes") {
      counts(nodes, max_node_tag);
      ++sections;
    } else if (line == "$Elements") {
      counts(elements, max_element_tag);
      ++sections;
    }
  }
  if (4.0 * (nodes + elements) > bytes)
    return "declares " + std::to_string(static_cast<long long>(std::min(nodes, 9e18))) + " nodes and " +
           std::to_string(static_cast<long long>(std::min(elements, 9e18))) + " elements in " +
           std::to_string(static_cast<long long>(bytes)) +
           " bytes (each takes at least 4): a truncated or corrupt mesh file";
  if (max_node_tag > 64.0 * nodes + 1e6 || max_element_tag > 64.0 * elements + 1e6)
    return "declares node or element tags up to " + std::to_string(static_cast<long long>(std::min(
               std::max(max_node_tag, max_element_tag), 9e18))) +
           " for " + std::to_string(static_cast<long long>(nodes)) + " nodes and " +
           std::to_string(static_cast<long long>(elements)) +
           " elements: tags that sparse would be indexed densely; renumber the mesh (gmsh -renumber)";
  return "";
}

/// The smallest element size a .geo is meshed with: an eighth of the body's particle spacing (the
/// inside test needs no finer: a chord of a boundary of radius R then strays by (dx/8)^2 / 8R), and
/// no finer than what keeps the mesh under kMaxGeoElements in the model's bounding box. A script's
/// size of 1e-5 m on a 1 m body once meshed without end.
constexpr double kMaxGeoElements = 4e6;
double mesh_size_floor(int dim, double lattice_spacing) {
  double x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0;
  gmsh::model::getBoundingBox(-1, -1, x0, y0, z0, x1, y1, z1);
  const double extent[3] = {x1 - x0, y1 - y0, z1 - z0};
  double measure = 1.0;
  for (int a = 0; a < dim; ++a) measure *= std::max(extent[a], 0.0);
  return std::max(lattice_spacing / 8.0, std::pow(measure / kMaxGeoElements, 1.0 / dim));
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "none" : out;
}

/// `text` without // and /* */ comments (string literals kept as they are).
std::string strip_comments(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '"') {
      const std::size_t end = text.find('"', i + 1);
      const std::size_t stop = end == std::string::npos ? text.size() : end + 1;
      out.append(text, i, stop - i);
      i = stop - 1;
    } else if (text.compare(i, 2, "//") == 0) {
      i = std::min(text.find('\n', i), text.size()) - 1;
    } else if (text.compare(i, 2, "/*") == 0) {
      const std::size_t end = text.find("*/", i + 2);
      i = end == std::string::npos ? text.size() : end + 1;
    } else {
      out += text[i];
    }
  }
  return out;
}

/// The variables of `DefineConstant[ a = 1, b = {2, Name "..."}, ... ]` blocks: the name before
/// the `=` of each top-level entry.
void define_constant_names(const std::string& text, std::vector<std::string>& names) {
  static const std::regex block(R"(DefineConstant\s*\[)");
  static const std::regex entry(R"(^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(\[\s*\]|\(\s*\))?\s*=)");
  for (std::sregex_iterator it(text.begin(), text.end(), block), end; it != end; ++it) {
    std::size_t i = static_cast<std::size_t>(it->position() + it->length());
    int depth = 0;
    std::string item;
    for (; i < text.size(); ++i) {
      const char ch = text[i];
      if (ch == '"') {
        const std::size_t close = text.find('"', i + 1);
        if (close == std::string::npos) break;
        item.append(text, i, close + 1 - i);
        i = close;
        continue;
      }
      if (depth == 0 && (ch == ',' || ch == ']')) {
        std::smatch m;
        if (std::regex_search(item, m, entry)) names.push_back(m[1]);
        item.clear();
        if (ch == ']') break;
        continue;
      }
      if (ch == '[' || ch == '{' || ch == '(') ++depth;
      if (ch == ']' || ch == '}' || ch == ')') --depth;
      item += ch;
    }
  }
}

/// The names `parameters` may set: the DefineConstant variables (and `x = DefineNumber[...]`) of
/// the .geo file and of the files it Includes. gmsh 4.8 has no API to list parser variables, and
/// ONELAB knows only the constants that carry a `Name`, so the text is read.
std::vector<std::string> geo_constants(const fs::path& file, int depth = 0) {
  std::ifstream in(file);
  const std::string text = strip_comments(std::string(std::istreambuf_iterator<char>(in), {}));
  std::vector<std::string> names;
  define_constant_names(text, names);
  static const std::regex number(R"(([A-Za-z_][A-Za-z0-9_]*)\s*=\s*DefineNumber\s*\[)");
  for (std::sregex_iterator it(text.begin(), text.end(), number), end; it != end; ++it) names.push_back((*it)[1]);
  static const std::regex include(R"re(Include\s+"([^"]+)")re");
  for (std::sregex_iterator it(text.begin(), text.end(), include), end; depth < 8 && it != end; ++it) {
    const fs::path inner((*it)[1].str());
    for (const auto& n : geo_constants(inner.is_absolute() ? inner : file.parent_path() / inner, depth + 1))
      names.push_back(n);
  }
  return names;
}

std::string surface_or_volume(int dim) { return dim == 2 ? "surface" : "volume"; }

/// How an element with `corners` corner nodes splits into simplices of its dimension (corner
/// indices; unused entries repeat), or nullptr for a kind that is not a cell of that dimension.
const std::vector<std::array<int, 4>>* simplex_split(int dim, int corners) {
  static const std::vector<std::array<int, 4>> segment{{0, 1, 1, 1}}, tri{{0, 1, 2, 0}},
      quad{{0, 1, 2, 0}, {0, 2, 3, 0}}, tet{{0, 1, 2, 3}},
      hex{{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}},
      prism{{0, 1, 2, 3}, {1, 2, 3, 4}, {2, 3, 4, 5}}, pyramid{{0, 1, 2, 4}, {0, 2, 3, 4}};
  if (dim == 1 && corners == 2) return &segment;
  if (dim == 2 && corners == 3) return &tri;
  if (dim == 2 && corners == 4) return &quad;
  if (dim == 3 && corners == 4) return &tet;
  if (dim == 3 && corners == 8) return &hex;
  if (dim == 3 && corners == 6) return &prism;
  if (dim == 3 && corners == 5) return &pyramid;
  return nullptr;
}

/// Elements of dimension `dim` of the given entities, split into simplices (corner nodes only:
/// straight-sided). Triangles/tetrahedra as they are, quadrangles into 2 triangles, hexahedra
/// into 6 tetrahedra around the 0-6 diagonal, prisms into 3, pyramids into 2. Node tags.
std::vector<std::array<std::size_t, 4>> simplices(int dim, const std::vector<int>& entities) {
  std::vector<std::array<std::size_t, 4>> out;
  for (int entity : entities) {
    std::vector<int> types;
    std::vector<std::vector<std::size_t>> element_tags, node_tags;
    gmsh::model::mesh::getElements(types, element_tags, node_tags, dim, entity);
    for (std::size_t t = 0; t < types.size(); ++t) {
      std::string name;
      int element_dim = 0, order = 0, nodes = 0, corners = 0;
      std::vector<double> local;
      gmsh::model::mesh::getElementProperties(types[t], name, element_dim, order, nodes, local, corners);
      if (element_dim != dim) continue;
      const auto* split = simplex_split(dim, corners);
      if (!split) continue;
      const auto& n = node_tags[t];
      for (std::size_t e = 0; e * nodes < n.size(); ++e) {
        const std::size_t* corner = &n[e * nodes];
        for (const auto& s : *split) out.push_back({corner[s[0]], corner[s[1]], corner[s[2]], corner[s[3]]});
      }
    }
  }
  return out;
}

/// Physical groups of one dimension, by name (unnamed groups are skipped: nothing can refer to them).
std::vector<std::pair<std::string, int>> physical_groups(int dim) {
  gmsh::vectorpair groups;
  gmsh::model::getPhysicalGroups(groups, dim);
  std::vector<std::pair<std::string, int>> out;
  for (const auto& [d, tag] : groups) {
    std::string name;
    gmsh::model::getPhysicalName(d, tag, name);
    if (!name.empty()) out.emplace_back(name, tag);
  }
  return out;
}

std::vector<int> entities_of(int dim, int physical_tag) {
  std::vector<int> tags;
  if (physical_tag >= 0) {
    gmsh::model::getEntitiesForPhysicalGroup(dim, physical_tag, tags);
    return tags;
  }
  gmsh::vectorpair all;
  gmsh::model::getEntities(all, dim);
  for (const auto& [d, tag] : all) tags.push_back(tag);
  return tags;
}

class GmshShape final : public SurfacedShape {
 public:
  GmshShape(const scene::Geometry& g, int dim, const GeoAccess& access) : file_(g.file) {
    std::error_code ec;
    if (!fs::is_regular_file(file_, ec)) fail("no such file");
    const bool geo = fs::path(file_).extension() == ".geo" || fs::path(file_).extension() == ".GEO";
    if (!geo)
      if (const std::string why = msh_header_problem(file_); !why.empty()) fail(why);
    // A .geo is a program: read it before gmsh runs it (preprocess/geo_script.hpp).
    if (geo && !access.trust_scripts)
      check_geo_script(file_, {{fs::path(access.scene_dir), fs::path(file_).parent_path()}});
    GmshSession session;
    open(g, geo, session);
    check_dimension(dim);
    if (geo) {
      const double floor = mesh_size_floor(dim, access.lattice_spacing);
      double set_min = 0.0;
      gmsh::option::getNumber("Mesh.MeshSizeMin", set_min);
      gmsh::option::setNumber("Mesh.MeshSizeMin", std::max(set_min, floor));
      gmsh::model::mesh::generate(dim);
      if (const std::string e = session.first_error(); !e.empty()) fail("gmsh could not mesh it: " + e);
    }
    read_body(g.physical, dim);
    read_surfaces(dim);
  }
  bool inside(const Point& x) const override { return mesh_.contains(x); }
  std::array<Point, 2> bounds() const override { return mesh_.bounds(); }

 private:
  [[noreturn]] void fail(const std::string& why, const std::string& key = "file") const {
    throw GeometryError(key, file_ + ": " + why);
  }

  /// Opens the file; a .geo with parameters is merged after a prelude that sets them, once its
  /// DefineConstant names are known to include every parameter.
  void open(const scene::Geometry& g, bool geo, GmshSession& session) {
    if (geo && !g.parameters.empty()) {
      std::vector<std::string> defined;
      for (const auto& n : geo_constants(file_))
        if (std::find(defined.begin(), defined.end(), n) == defined.end()) defined.push_back(n);
      for (const auto& [name, value] : g.parameters)
        if (std::find(defined.begin(), defined.end(), name) == defined.end())
          fail("got parameter \"" + name + "\", but the file has no DefineConstant of that name (defined: " +
                   join(defined) + ")",
               "parameters/" + name);
      // The values go first, in a private file: gmsh keeps a variable that is already defined, so
      // they win over the file's DefineConstant defaults.
      std::string prelude;
      for (const auto& [name, value] : g.parameters) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.17g", value);
        prelude += name + " = " + buf + ";\n";
      }
      const PrivateTempFile file(fs::path(file_).stem().string() + "-parameters.geo", prelude);
      gmsh::open(file.path().string());
      gmsh::merge(file_);
    } else {
      gmsh::open(file_);
    }
    if (const std::string e = session.first_error(); !e.empty()) fail("gmsh could not read it: " + e);
  }

  void check_dimension(int dim) const {
    const int model = gmsh::model::getDimension();
    if (dim == 2 && model == 3)
      fail("got a 3D model (it has volumes), expected a 2D model for a 2D scene: plane surfaces in z = 0");
    if (dim == 3 && model >= 0 && model < 3)
      fail("got a " + std::to_string(model) + "D model (no volumes), expected volumes for a 3D scene");
  }

  void read_body(const std::string& physical, int dim) {
    int tag = -1;
    if (!physical.empty()) {
      std::vector<std::string> names;
      for (const auto& [name, t] : physical_groups(dim)) {
        names.push_back(name);
        if (name == physical) tag = t;
      }
      if (tag < 0)
        fail("got physical group \"" + physical + "\", expected a physical " + surface_or_volume(dim) +
                 " of the file (defined: " + join(names) + ")",
             "physical");
    }
    std::vector<std::size_t> node_tags;
    std::vector<double> coords, parametric;
    gmsh::model::mesh::getNodes(node_tags, coords, parametric, -1, -1, false, false);
    std::size_t max_tag = 0;
    for (std::size_t t : node_tags) max_tag = std::max(max_tag, t);
    index_.assign(max_tag + 1, kNone);
    for (std::size_t i = 0; i < node_tags.size(); ++i) {
      index_[node_tags[i]] = static_cast<std::uint32_t>(i);
      nodes_.push_back({coords[3 * i], coords[3 * i + 1], coords[3 * i + 2]});
    }

    std::vector<std::array<std::uint32_t, 4>> cells;
    for (const auto& s : simplices(dim, entities_of(dim, tag))) cells.push_back(to_index<4>(s, dim + 1));
    if (cells.empty())
      fail("gmsh produced no " + std::string(dim == 2 ? "triangles or quadrangles" : "volume elements") +
           (physical.empty() ? "" : " in physical group \"" + physical + "\"") + ", expected a meshed " +
           surface_or_volume(dim));
    if (dim == 2) check_planar(cells);
    mesh_ = SimplexMesh(dim, nodes_, cells);
    if (mesh_.size() == 0) fail("every element is degenerate (zero " + std::string(dim == 2 ? "area" : "volume") + ")");
  }

  /// A 2D body lies in z = 0: the scene's plane.
  void check_planar(const std::vector<std::array<std::uint32_t, 4>>& cells) const {
    double size = 0.0, z = 0.0;
    for (const auto& c : cells)
      for (int k = 0; k < 3; ++k) {
        const Point& p = nodes_[c[k]];
        size = std::max({size, std::abs(p[0]), std::abs(p[1])});
        z = std::max(z, std::abs(p[2]));
      }
    if (z > 1e-9 * std::max(size, 1.0))
      fail("got surfaces outside the plane z = 0 (|z| up to " + std::to_string(z) +
           " m), expected a 2D model in the x-y plane");
  }

  void read_surfaces(int dim) {
    for (const auto& [name, tag] : physical_groups(dim - 1)) {
      std::vector<std::array<std::uint32_t, 3>> facets;
      for (const auto& s : simplices(dim - 1, entities_of(dim - 1, tag))) facets.push_back(to_index<3>(s, dim));
      add_surface(name, SurfaceElements(dim, nodes_, facets));
    }
  }

  /// Node tags -> indices into nodes_, for the first `used` corners.
  template <std::size_t N>
  std::array<std::uint32_t, N> to_index(const std::array<std::size_t, 4>& tags, int used) const {
    std::array<std::uint32_t, N> out{};
    for (int k = 0; k < used; ++k) {
      const std::size_t t = tags[k];
      if (t >= index_.size() || index_[t] == kNone)
        fail("an element refers to node " + std::to_string(t) + ", which the file does not define");
      out[k] = index_[t];
    }
    return out;
  }

  static constexpr std::uint32_t kNone = 0xffffffffu;
  std::string file_;
  std::vector<Point> nodes_;
  std::vector<std::uint32_t> index_;  // node tag -> index into nodes_
  SimplexMesh mesh_;
};

}  // namespace

std::unique_ptr<Shape> make_gmsh(const scene::Geometry& g, int dim, const GeoAccess& access) {
  return std::make_unique<GmshShape>(g, dim, access);
}

}  // namespace swmpm::pre
