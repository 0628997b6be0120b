// Geometry types (preprocess/shape_*.cpp) through seeding, as a user meets them: the number of
// particles a geometry gets at n x n (x n) per cell against its exact area or volume, the particles
// tagged on a named surface against its length / spacing, and one test per error a geometry can
// raise (each asserting the JSON path and a key phrase). Gmsh meshes small geometries only.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "preprocess/preprocess.hpp"
#include "preprocess/shape.hpp"
#include "scene/scene.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace swmpm;

const std::string kGeometries = SWMPM_SOURCE_DIR "/geometries";

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / "swmpm-geometry" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

/// A dry scene with one body of `geometry` on the grid [lo, hi] with cells `h`.
json scene(int dim, const json& geometry, std::vector<double> lo, std::vector<double> hi, double h, int n = 2) {
  return {{"name", "geometry"},
          {"dimension", dim},
          {"grid", {{"cell_size", h}, {"min", lo}, {"max", hi}}},
          {"materials", json::array({{{"name", "soil"}, {"model", "linear-elastic"}, {"density", 2000.0},
                                      {"youngs_modulus", 1e7}, {"poisson_ratio", 0.3}}})},
          {"bodies", json::array({{{"name", "body"}, {"solid", "soil"}, {"particles_per_cell", n},
                                   {"geometry", geometry}}})},
          {"time", {{"end", 1.0}}}};
}

/// Parses `j` as if it were a scene file in `dir` (relative geometry files resolve there).
scene::Scene parse(const json& j, const std::string& dir = kGeometries) {
  return scene::parse_scene(j, dir + "/scene.json");
}

/// The problem lines of parsing and then seeding `j` (empty when both succeed).
std::vector<std::string> problems(const json& j, const std::string& dir = kGeometries) {
  try {
    pre::seed_solid(parse(j, dir));
  } catch (const scene::SceneError& e) {
    return e.lines();
  }
  return {};
}

/// Exactly one problem line, at `path`, containing every phrase.
::testing::AssertionResult one_problem(const json& j, const std::string& path, const std::vector<std::string>& phrases,
                                       const std::string& dir = kGeometries) {
  const auto lines = problems(j, dir);
  std::string all;
  for (const auto& l : lines) all += "\n  " + l;
  if (lines.size() != 1) return ::testing::AssertionFailure() << "expected one line, got:" << all;
  if (lines[0].find(": " + path + ": ") == std::string::npos)
    return ::testing::AssertionFailure() << "expected path " << path << ", got:" << all;
  for (const auto& p : phrases)
    if (lines[0].find(p) == std::string::npos) return ::testing::AssertionFailure() << "no \"" << p << "\" in:" << all;
  return ::testing::AssertionSuccess();
}

/// Particles seeded, and how many carry face bit `bit`.
struct Seeded {
  std::size_t count = 0, tagged = 0;
};
Seeded seed(const scene::Scene& s, int bit = -1) {
  const auto c = pre::seed_solid(s);
  Seeded out{c.size(), 0};
  const auto& faces = c.get("faces", "test").values;
  for (double f : faces)
    if (bit >= 0 && (static_cast<std::uint32_t>(f) >> bit & 1u)) ++out.tagged;
  return out;
}

double relative_error(double got, double exact) { return std::abs(got - exact) / exact; }

/// Area of the parametric / slope.geo outline [m^2]: foundation + crest block + face wedge.
double slope_area(double D, double H, double angle_deg, double toe, double crest) {
  const double run = H / std::tan(angle_deg * std::numbers::pi / 180.0);
  return (toe + run + crest) * D + crest * H + 0.5 * run * H;
}

/// Volume enclosed by a triangle mesh in OFF format (divergence theorem) [m^3].
double off_volume(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> tokens;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    for (std::string t; ls >> t;) tokens.push_back(t);
  }
  std::size_t k = 1;  // after "OFF"
  const auto nv = std::stoul(tokens[k++]), nf = std::stoul(tokens[k++]);
  ++k;
  std::vector<std::array<double, 3>> v(nv);
  for (auto& p : v)
    for (double& c : p) c = std::stod(tokens[k++]);
  double vol = 0.0;
  for (std::size_t f = 0; f < nf; ++f) {
    ++k;  // 3
    const auto& a = v[std::stoul(tokens[k++])];
    const auto& b = v[std::stoul(tokens[k++])];
    const auto& c = v[std::stoul(tokens[k++])];
    // a . (b x c) / 6: the signed volume of the tetrahedron (origin, a, b, c)
    vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
            a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
  }
  return vol;
}

constexpr int kBit0 = scene::kFirstSurfaceBit;  // the first named surface the scene refers to

// ---- slope (parametric) -------------------------------------------------------------------------

json slope_geometry() {
  return {{"type", "slope"}, {"foundation_depth", 4.0}, {"height", 6.0}, {"angle", 30.0},
          {"toe_length", 5.0}, {"crest_length", 4.0}, {"origin", {1.0, 1.0}}};
}

TEST(GeometrySlope, ParticleCountMatchesAreaAndSurfaceLength) {
  json j = scene(2, slope_geometry(), {0, 0}, {22, 12}, 0.5);
  j["loads"] = json::array({{{"type", "pressure"}, {"body", "body"}, {"face", "surface"}, {"value", 1e3}}});
  const scene::Scene s = parse(j);
  const double dx = 0.25;
  const Seeded got = seed(s, kBit0);
  const double area = slope_area(4, 6, 30, 5, 4);
  const double run = 6.0 / std::tan(std::numbers::pi / 6);
  const double surface = 5.0 + std::hypot(run, 6.0) + 4.0;  // toe + face + crest
  const double e_area = relative_error(static_cast<double>(got.count) * dx * dx, area);
  const double e_surface = relative_error(static_cast<double>(got.tagged), surface / dx);
  std::printf("slope 2x2 per cell: %zu particles, area error %.3f %%; %zu tagged on \"surface\" (%.1f expected), "
              "error %.2f %%\n", got.count, 100 * e_area, got.tagged, surface / dx, 100 * e_surface);
  EXPECT_LT(e_area, 0.02);
  EXPECT_LT(e_surface, 0.05);
}

TEST(GeometrySlope, RatioEqualsTheAngleAndOriginDefaultsToTheGridMin) {
  json a = slope_geometry();
  a.erase("origin");
  json r = a;
  r.erase("angle");
  r["ratio"] = 1.0 / std::tan(std::numbers::pi / 6);
  const Seeded by_angle = seed(parse(scene(2, a, {-1, -1}, {22, 12}, 0.5)));
  const Seeded by_ratio = seed(parse(scene(2, r, {-1, -1}, {22, 12}, 0.5)));
  EXPECT_EQ(by_angle.count, by_ratio.count);
  const scene::Scene s = parse(scene(2, r, {-1, -1}, {22, 12}, 0.5));
  EXPECT_EQ(s.bodies[0].geometry.origin, (std::array<double, 2>{-1, -1}));
  // The resolved scene writes the origin out and parses back to itself.
  const json resolved = scene::to_json(s);
  EXPECT_EQ(resolved["bodies"][0]["geometry"]["origin"], json({-1.0, -1.0}));
  EXPECT_EQ(scene::to_json(scene::parse_scene(resolved, "t.json")), resolved);
}

TEST(GeometrySlope, NamedSurfacesAreListedInTheDocumentedOrder) {
  const scene::Scene s = parse(scene(2, slope_geometry(), {0, 0}, {22, 12}, 0.5));
  const auto shape = pre::make_shape(s.bodies[0].geometry, 2, "");
  EXPECT_EQ(shape->surface_names(), scene::named_surfaces(s.bodies[0].geometry, 2));
  EXPECT_EQ(shape->surface_names(),
            (std::vector<std::string>{"surface", "base", "left", "right", "toe", "slope_face", "crest"}));
  // The crest is at y = 1 + 4 + 6 = 11 from x = 1 + 5 + run to x = 1 + 5 + run + 4.
  const double run = 6.0 / std::tan(std::numbers::pi / 6);
  EXPECT_TRUE(shape->on_surface("crest", {6 + run + 2, 11.1, 0}, 0.11));
  EXPECT_FALSE(shape->on_surface("crest", {6 + run + 2, 11.2, 0}, 0.11));
  EXPECT_FALSE(shape->on_surface("toe", {6 + run + 2, 11.0, 0}, 0.11));
  EXPECT_TRUE(shape->inside({2, 2, 0}));
  EXPECT_FALSE(shape->inside({2, 6, 0}));  // above the toe ground
  // Outward normals: up-left on the 30 deg face, up on the crest, down on the base; none far off.
  const auto n = shape->outward_normal("slope_face", {6 + run / 2 + 0.1, 5 + 3 - 0.02, 0}, 0.25);
  EXPECT_NEAR(n[0], -0.5, 1e-12);
  EXPECT_NEAR(n[1], std::sqrt(3.0) / 2, 1e-12);
  EXPECT_EQ(shape->outward_normal("crest", {6 + run + 2, 10.9, 0}, 0.25), (pre::Point{0, 1, 0}));
  EXPECT_EQ(shape->outward_normal("base", {3, 1, 0}, 0.25), (pre::Point{0, -1, 0}));  // on the surface itself
  EXPECT_EQ(shape->outward_normal("base", {3, 2, 0}, 0.25), (pre::Point{0, 0, 0}));
}

TEST(GeometrySlope, ParserErrors) {
  json both = slope_geometry();
  both["ratio"] = 2.0;
  EXPECT_TRUE(one_problem(scene(2, both, {0, 0}, {40, 12}, 0.5), "/bodies/0/geometry/ratio",
                          {"got both \"angle\" and \"ratio\""}));
  json neither = slope_geometry();
  neither.erase("angle");
  EXPECT_TRUE(one_problem(scene(2, neither, {0, 0}, {22, 12}, 0.5), "/bodies/0/geometry/angle",
                          {"missing, expected \"angle\""}));
  json steep = slope_geometry();
  steep["angle"] = 90.0;
  EXPECT_TRUE(one_problem(scene(2, steep, {0, 0}, {22, 12}, 0.5), "/bodies/0/geometry/angle", {"(0, 90) [deg]"}));
  json negative = slope_geometry();
  negative["height"] = -1.0;
  EXPECT_TRUE(one_problem(scene(2, negative, {0, 0}, {22, 12}, 0.5), "/bodies/0/geometry/height",
                          {"positive number [m]"}));
  json typo = slope_geometry();
  typo.erase("crest_length");
  typo["crest_lenght"] = 4.0;
  EXPECT_TRUE(one_problem(scene(2, typo, {0, 0}, {22, 12}, 0.5), "/bodies/0/geometry/crest_lenght",
                          {"did you mean \"crest_length\"?"}));
  EXPECT_TRUE(one_problem(scene(2, slope_geometry(), {0, 0}, {15, 12}, 0.5), "/bodies/0/geometry",
                          {"expected a geometry inside the grid"}));
  EXPECT_TRUE(one_problem(scene(3, slope_geometry(), {0, 0, 0}, {22, 12, 1}, 0.5), "/bodies/0/geometry/type",
                          {"slope is 2D only"}));
}

// ---- footing ------------------------------------------------------------------------------------

TEST(GeometryFooting, RestsOnTheSlopeCrestWithNamedFaces) {
  json j = scene(2, slope_geometry(), {0, 0}, {22, 14}, 0.5);
  const double run = 6.0 / std::tan(std::numbers::pi / 6);
  j["bodies"].push_back({{"name", "footing"}, {"solid", "soil"},
                         {"geometry", {{"type", "footing"}, {"width", 2.0}, {"height", 1.0},
                                       {"center_x", 6 + run + 2}, {"on", "body"}}}});
  j["loads"] = json::array({{{"type", "pressure"}, {"body", "footing"}, {"face", "top"}, {"value", 1e5}}});
  const scene::Scene s = parse(j);
  EXPECT_DOUBLE_EQ(s.bodies[1].geometry.base_y, 11.0);
  const auto c = pre::seed_solid(s);
  std::size_t footing = 0, top = 0;
  const auto& body = c.get("body", "test").values;
  const auto& faces = c.get("faces", "test").values;
  for (std::size_t p = 0; p < c.size(); ++p) {
    if (body[p] != 1) continue;
    ++footing;
    if (static_cast<std::uint32_t>(faces[p]) >> kBit0 & 1u) ++top;
  }
  EXPECT_EQ(footing, 2u * 1u * 16u);  // 2 m x 1 m at 0.25 m spacing
  EXPECT_EQ(top, 8u);                 // one row along the 2 m top
  // The resolved scene has base_y in place of on.
  const json g = scene::to_json(s)["bodies"][1]["geometry"];
  EXPECT_EQ(g["base_y"], 11.0);
  EXPECT_FALSE(g.contains("on"));
}

TEST(GeometryFooting, Block3DVolumeAndFaces) {
  const json g = {{"type", "footing"}, {"width", 0.6}, {"height", 0.2}, {"length", 0.4}, {"center_x", 0.5},
                  {"center_z", 0.5}, {"base_y", 0.1}};
  const scene::Scene s = parse(scene(3, g, {0, 0, 0}, {1, 1, 1}, 0.1));
  EXPECT_EQ(seed(s).count, 12u * 4u * 8u);  // 0.05 m spacing
  const auto shape = pre::make_shape(s.bodies[0].geometry, 3, "");
  EXPECT_EQ(shape->surface_names(), (std::vector<std::string>{"bottom", "top", "left", "right", "back", "front"}));
  EXPECT_TRUE(shape->on_surface("front", {0.5, 0.2, 0.72}, 0.05));
  EXPECT_FALSE(shape->on_surface("back", {0.5, 0.2, 0.72}, 0.05));
  EXPECT_EQ(shape->outward_normal("front", {0.5, 0.2, 0.68}, 0.05), (pre::Point{0, 0, 1}));
  EXPECT_EQ(shape->outward_normal("back", {0.5, 0.2, 0.32}, 0.05), (pre::Point{0, 0, -1}));
}

TEST(GeometryFooting, ParserErrors) {
  const json g = {{"type", "footing"}, {"width", 1.0}, {"height", 0.5}, {"center_x", 2.0}, {"base_y", 0.0}};
  json both = g;
  both["on"] = "body";
  EXPECT_TRUE(one_problem(scene(2, both, {0, 0}, {4, 4}, 0.5), "/bodies/0/geometry/base_y",
                          {"got both \"on\" and \"base_y\""}));
  json self = g;
  self.erase("base_y");
  self["on"] = "body";
  EXPECT_TRUE(one_problem(scene(2, self, {0, 0}, {4, 4}, 0.5), "/bodies/0/geometry/on",
                          {"expected the name of another body"}));
  json z2d = g;
  z2d["center_z"] = 1.0;
  EXPECT_TRUE(one_problem(scene(2, z2d, {0, 0}, {4, 4}, 0.5), "/bodies/0/geometry/center_z", {"in a 2D scene"}));
  json no_length = g;
  no_length["center_z"] = 1.0;
  EXPECT_TRUE(one_problem(scene(3, no_length, {0, 0, 0}, {4, 4, 4}, 0.5), "/bodies/0/geometry/length",
                          {"missing"}));
  json on_gmsh = scene(2, {{"type", "gmsh"}, {"file", "strip-footing.geo"}}, {0, 0}, {10, 12}, 0.5);
  json f = g;
  f.erase("base_y");
  f["on"] = "body";
  on_gmsh["bodies"].push_back({{"name", "footing"}, {"solid", "soil"}, {"geometry", f}});
  EXPECT_TRUE(one_problem(on_gmsh, "/bodies/1/geometry/on", {"known only when preprocess reads its file"}));
}

// ---- named surfaces in loads and boundaries --------------------------------------------------------

TEST(GeometryNamedSurfaces, UnknownNamesListTheAvailableOnes) {
  json j = scene(2, slope_geometry(), {0, 0}, {22, 12}, 0.5);
  j["loads"] = json::array({{{"type", "pressure"}, {"body", "body"}, {"face", "crst"}, {"value", 1e3}}});
  EXPECT_TRUE(one_problem(j, "/loads/0/face",
                          {"or a named surface: surface, base, left, right, toe, slope_face, crest",
                           "did you mean \"crest\"?"}));
  json k = scene(2, {{"type", "box"}, {"min", {0, 0}}, {"max", {1, 1}}}, {0, 0}, {2, 2}, 0.5);
  k["boundaries"] = json::array({{{"on", "crest"}, {"solid", "fixed"}}});
  EXPECT_TRUE(one_problem(k, "/boundaries/0/on", {"no body's geometry has named surfaces"}));
  // A boundary on a named surface is accepted (and stored; the solver does not apply it yet).
  json l = scene(2, slope_geometry(), {0, 0}, {22, 12}, 0.5);
  l["boundaries"] = json::array({{{"on", "base"}, {"solid", "fixed"}}, {{"on", "y_min"}, {"solid", "fixed"}}});
  l["loads"] = json::array({{{"type", "pressure"}, {"body", "body"}, {"face", "crest"}, {"value", 1e3}}});
  const scene::Scene s = parse(l);
  EXPECT_EQ(scene::surface_bit_names(s), (std::vector<std::string>{"base", "crest"}));
}

TEST(GeometryNamedSurfaces, AtMost26NamesPerScene) {
  // A 3D gmsh body could have any names; the parser counts them before reading the file.
  json j = scene(3, {{"type", "gmsh"}, {"file", "slope.geo"}}, {0, 0, 0}, {1, 1, 1}, 0.5);
  j["boundaries"] = json::array();
  for (int k = 0; k < 27; ++k) {
    std::string name = std::to_string(k);
    name.insert(name.begin(), 's');  // not "s" + ...: GCC 12 reports a false -Wrestrict (bug 105329)
    j["boundaries"].push_back({{"on", name}});
  }
  const auto lines = [&] {
    try {
      parse(j);
    } catch (const scene::SceneError& e) {
      return e.lines();
    }
    return std::vector<std::string>{};
  }();
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("/boundaries/26/on: got \"s26\", a named surface beyond the 26"), std::string::npos)
      << lines[0];
}

// ---- gmsh ---------------------------------------------------------------------------------------

TEST(GeometryGmsh, SlopeGeoMatchesItsAreaAndTagsItsSurface) {
  const double dx = 0.5;
  const Seeded defaults = seed(parse(scene(2, {{"type", "gmsh"}, {"file", "slope.geo"}}, {0, 0}, {45, 20}, 1.0)));
  const double e_area = relative_error(static_cast<double>(defaults.count) * dx * dx, 600.0);
  // Tagging at 30 deg: a 45 deg face through lattice points has lattice diagonals at 0 and
  // 0.71 spacings from it, so a one-spacing band holds two of them (+41 % on the face); at an
  // angle with an irrational slope the count per metre is 1 / spacing.
  json j = scene(2, {{"type", "gmsh"}, {"file", "slope.geo"}, {"parameters", {{"angle", 30}}}}, {0, 0}, {53, 20}, 1.0);
  j["loads"] = json::array({{{"type", "pressure"}, {"body", "body"}, {"face", "surface"}, {"value", 1e3}}});
  const Seeded got = seed(parse(j), kBit0);
  const double surface = 25 + 20 + 10;  // toe + height / sin(30 deg) + crest
  const double e_surface = relative_error(static_cast<double>(got.tagged), surface / dx);
  std::printf("slope.geo 2x2 per cell: %zu particles, area error %.3f %%; at 30 deg %zu tagged on \"surface\" "
              "(%.1f expected), error %.2f %%\n", defaults.count, 100 * e_area, got.tagged, surface / dx,
              100 * e_surface);
  EXPECT_LT(e_area, 0.02);
  EXPECT_LT(e_surface, 0.05);
}

TEST(GeometryGmsh, ParametersOverrideDefineConstants) {
  const json g = {{"type", "gmsh"}, {"file", "slope.geo"},
                  {"parameters", {{"angle", 30}, {"height", 6}, {"foundation_depth", 4}, {"toe_length", 5},
                                  {"crest_length", 4}, {"x0", 1}, {"y0", 1}}}};
  const Seeded got = seed(parse(scene(2, g, {0, 0}, {22, 12}, 0.5)));
  const double e = relative_error(static_cast<double>(got.count) * 0.0625, slope_area(4, 6, 30, 5, 4));
  std::printf("slope.geo with parameters: %zu particles, area error %.3f %%\n", got.count, 100 * e);
  EXPECT_LT(e, 0.02);
  // The parametric slope of the same dimensions seeds the same lattice points.
  EXPECT_EQ(got.count, seed(parse(scene(2, slope_geometry(), {0, 0}, {22, 12}, 0.5))).count);
}

TEST(GeometryGmsh, StripFootingRectangleAndLoadCurve) {
  json j = scene(2, {{"type", "gmsh"}, {"file", "strip-footing.geo"}}, {0, 0}, {10, 10}, 0.5);
  j["loads"] = json::array({{{"type", "traction"}, {"body", "body"}, {"face", "load"}, {"value", {0, -2e4}}}});
  const Seeded got = seed(parse(j), kBit0);
  std::printf("strip-footing.geo: %zu particles (%d exact), %zu tagged on \"load\" (12 expected)\n", got.count,
              1600, got.tagged);
  EXPECT_EQ(got.count, 1600u);  // 10 m x 10 m at 0.25 m
  EXPECT_EQ(got.tagged, 12u);   // 3 m / 0.25 m
  const auto shape = pre::make_shape(parse(j).bodies[0].geometry, 2, "");
  EXPECT_EQ(shape->surface_names(),
            (std::vector<std::string>{"load", "top_free", "top", "base", "right", "symmetry"}));
  const auto up = shape->outward_normal("load", {1.0, 9.9, 0}, 0.25);
  EXPECT_NEAR(up[1], 1.0, 1e-12);
  const auto left = shape->outward_normal("symmetry", {0.1, 5.0, 0}, 0.25);
  EXPECT_NEAR(left[0], -1.0, 1e-12);
}

TEST(GeometryGmsh, PhysicalGroupsSelectTheBody) {
  const double dx = 0.005 / 2;
  auto count = [&](const std::string& physical, const json& parameters) {
    const json g = {{"type", "gmsh"}, {"file", "column-in-tank.geo"}, {"physical", physical},
                    {"parameters", parameters}};
    return static_cast<double>(seed(parse(scene(2, g, {0, 0}, {0.5, 0.08}, 0.005))).count) * dx * dx;
  };
  EXPECT_LT(relative_error(count("column", json::object()), 0.0048), 0.02);
  EXPECT_LT(relative_error(count("water", json::object()), 0.5 * 0.07 - 0.0048), 0.02);
  // The column out of the water (benchmark D3 has 0.024 m; 0.025 m is whole particle rows): the
  // other branch of the file.
  EXPECT_LT(relative_error(count("water", {{"water_depth", 0.025}}), 0.4 * 0.025), 0.02);
  EXPECT_LT(relative_error(count("column", {{"water_depth", 0.025}}), 0.0048), 0.02);
}

TEST(GeometryGmsh, RampTankMass) {
  const json g = {{"type", "gmsh"}, {"file", "ramp-tank.geo"}, {"physical", "mass"}};
  const double dx = 0.004 / 4;
  const Seeded got = seed(parse(scene(2, g, {0, 0}, {2.2, 0.3}, 0.004, 4)));
  const double e = relative_error(static_cast<double>(got.count) * dx * dx, 0.010368);
  std::printf("ramp-tank.geo mass at 4x4 per 0.004 m cell: %zu particles (paper: 10,368), area error %.3f %%\n",
              got.count, 100 * e);
  EXPECT_LT(e, 0.02);
}

const char* kBox3D = R"(
DefineConstant[ a = 0.6, b = 0.4, c = 0.5 ];
Point(1) = {0.2, 0.1, 0.2, 0.2}; Point(2) = {0.2 + a, 0.1, 0.2, 0.2};
Point(3) = {0.2 + a, 0.1 + b, 0.2, 0.2}; Point(4) = {0.2, 0.1 + b, 0.2, 0.2};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
out[] = Extrude {0, 0, c} { Surface{1}; };
Physical Volume("block") = {out[1]};
Physical Surface("side") = {out[2]};
)";

TEST(GeometryGmsh, BoxVolume3D) {
  const fs::path dir = scratch("gmsh-box");
  write(dir / "box.geo", kBox3D);
  json j = scene(3, {{"type", "gmsh"}, {"file", "box.geo"}, {"parameters", {{"c", 0.4}}}}, {0, 0, 0}, {1, 1, 1}, 0.1);
  j["loads"] = json::array({{{"type", "pressure"}, {"body", "body"}, {"face", "side"}, {"value", 1e3}}});
  const Seeded got = seed(parse(j, dir.string()), kBit0);
  std::printf("gmsh 3D box: %zu particles (%d exact), %zu tagged on \"side\" (%d expected)\n", got.count, 12 * 8 * 8,
              got.tagged, 12 * 8);
  EXPECT_EQ(got.count, 12u * 8u * 8u);  // 0.6 x 0.4 x 0.4 at 0.05 m
  EXPECT_EQ(got.tagged, 12u * 8u);      // the extruded side y = 0.1 (first curve), 0.6 x 0.4
}

TEST(GeometryGmsh, MshFilesWithQuadranglesAndHexahedra) {
  const fs::path dir = scratch("gmsh-msh");
  write(dir / "plate.msh", R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
1 1 "top"
2 2 "plate"
$EndPhysicalNames
$Nodes
6
1 0 0 0
2 0.5 0 0
3 1 0 0
4 1 0.5 0
5 0.5 0.5 0
6 0 0.5 0
$EndNodes
$Elements
4
1 1 2 1 5 4 5
2 1 2 1 5 5 6
3 3 2 2 1 1 2 5 6
4 3 2 2 1 2 3 4 5
$EndElements
)");
  json j = scene(2, {{"type", "gmsh"}, {"file", "plate.msh"}}, {0, 0}, {1, 1}, 0.1);
  j["loads"] = json::array({{{"type", "pressure"}, {"body", "body"}, {"face", "top"}, {"value", 1e3}}});
  const Seeded got = seed(parse(j, dir.string()), kBit0);
  EXPECT_EQ(got.count, 20u * 10u);
  EXPECT_EQ(got.tagged, 20u);
  json p = j;
  p["bodies"][0]["geometry"]["parameters"] = {{"a", 1}};
  EXPECT_TRUE(one_problem(p, "/bodies/0/geometry/parameters", {"a .msh is a finished mesh"}, dir.string()));
  // One hexahedron, a skewed brick (split into 6 tetrahedra): x in [0.1, 0.9], y in [0.2, 0.6] + x / 4 ...
  write(dir / "brick.msh", R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
8
1 0.1 0.2 0.1
2 0.9 0.4 0.1
3 0.9 0.8 0.1
4 0.1 0.6 0.1
5 0.1 0.2 0.7
6 0.9 0.4 0.7
7 0.9 0.8 0.7
8 0.1 0.6 0.7
$EndNodes
$Elements
1
1 5 2 1 1 1 2 3 4 5 6 7 8
$EndElements
)");
  // ... a parallelepiped of volume 0.8 x 0.4 x 0.6 = 0.192 m^3.
  const Seeded brick = seed(parse(scene(3, {{"type", "gmsh"}, {"file", "brick.msh"}}, {0, 0, 0}, {1, 1, 1}, 0.05),
                                  dir.string()));
  const double e = relative_error(static_cast<double>(brick.count) * std::pow(0.025, 3), 0.192);
  std::printf("hexahedron .msh: %zu particles, volume error %.3f %%\n", brick.count, 100 * e);
  EXPECT_LT(e, 0.02);
}

TEST(GeometryGmsh, ResolvedSceneParsesBackToItself) {
  json j = scene(2, {{"type", "gmsh"}, {"file", "column-in-tank.geo"}, {"physical", "column"},
                     {"parameters", {{"water_depth", 0.03}}}}, {0, 0}, {0.5, 0.1}, 0.01);
  j["bodies"].push_back({{"name", "footing"}, {"solid", "soil"},
                         {"geometry", {{"type", "footing"}, {"width", 0.1}, {"height", 0.02}, {"center_x", 0.3},
                                       {"on", "pad"}}}});
  j["bodies"].push_back({{"name", "pad"}, {"solid", "soil"},
                         {"geometry", {{"type", "box"}, {"min", {0.2, 0.0}}, {"max", {0.4, 0.05}}}}});
  const json resolved = scene::to_json(parse(j));
  const json g = resolved["bodies"][0]["geometry"];
  EXPECT_EQ(g["file"], kGeometries + "/column-in-tank.geo");  // absolute: RUN_DIR/scene.json is elsewhere
  EXPECT_EQ(g["parameters"]["water_depth"], 0.03);
  EXPECT_EQ(g["physical"], "column");
  EXPECT_EQ(resolved["bodies"][1]["geometry"]["base_y"], 0.05);  // on the later body "pad"
  const scene::Scene again = scene::parse_scene(resolved, "/elsewhere/scene.json");
  EXPECT_EQ(scene::to_json(again), resolved);
}

// ---- gmsh errors: one line naming the geometry's JSON path and the file --------------------------

TEST(GeometryGmshErrors, MissingFile) {
  EXPECT_TRUE(one_problem(scene(2, {{"type", "gmsh"}, {"file", "slop.geo"}}, {0, 0}, {45, 20}, 1.0),
                          "/bodies/0/geometry/file", {"no such file", "slop.geo", "did you mean \"slope.geo\"?"}));
  EXPECT_TRUE(one_problem(scene(2, {{"type", "gmsh"}, {"file", "slope.step"}}, {0, 0}, {45, 20}, 1.0),
                          "/bodies/0/geometry/file", {".geo or .msh"}));
}

TEST(GeometryGmshErrors, GeoThatDoesNotMesh) {
  const fs::path dir = scratch("gmsh-open-loop");
  write(dir / "open.geo", R"(
Point(1) = {0, 0, 0}; Point(2) = {1, 0, 0}; Point(3) = {1, 1, 0}; Point(4) = {0, 1, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4};
Curve Loop(1) = {1, 2, 3}; Plane Surface(1) = {1};
)");
  const json j = scene(2, {{"type", "gmsh"}, {"file", "open.geo"}}, {0, 0}, {1, 1}, 0.1);
  EXPECT_TRUE(one_problem(j, "/bodies/0/geometry/file", {(dir / "open.geo").string(), "gmsh could not mesh it"},
                          dir.string()));
  write(dir / "syntax.geo", "Point(1) = {0, 0, 0\n");
  const json k = scene(2, {{"type", "gmsh"}, {"file", "syntax.geo"}}, {0, 0}, {1, 1}, 0.1);
  EXPECT_TRUE(one_problem(k, "/bodies/0/geometry/file", {"syntax.geo", "gmsh could not read it"}, dir.string()));
  write(dir / "empty.geo", "Point(1) = {0, 0, 0};\n");
  const json l = scene(2, {{"type", "gmsh"}, {"file", "empty.geo"}}, {0, 0}, {1, 1}, 0.1);
  EXPECT_TRUE(one_problem(l, "/bodies/0/geometry/file", {"empty.geo", "no triangles or quadrangles"}, dir.string()));
}

TEST(GeometryGmshErrors, WrongDimension) {
  const fs::path dir = scratch("gmsh-dimension");
  write(dir / "box.geo", kBox3D);
  EXPECT_TRUE(one_problem(scene(2, {{"type", "gmsh"}, {"file", "box.geo"}}, {0, 0}, {1, 1}, 0.1),
                          "/bodies/0/geometry/file", {"box.geo", "3D model", "2D scene"}, dir.string()));
  EXPECT_TRUE(one_problem(scene(3, {{"type", "gmsh"}, {"file", "strip-footing.geo"}}, {0, 0, 0}, {10, 10, 1}, 0.5),
                          "/bodies/0/geometry/file", {"strip-footing.geo", "no volumes"}));
}

TEST(GeometryGmshErrors, UnknownParameterPhysicalGroupOrSurface) {
  const json bad_parameter = {{"type", "gmsh"}, {"file", "slope.geo"}, {"parameters", {{"angel", 30}}}};
  EXPECT_TRUE(one_problem(scene(2, bad_parameter, {0, 0}, {45, 20}, 1.0), "/bodies/0/geometry/parameters/angel",
                          {"slope.geo", "no DefineConstant of that name", "angle"}));
  const json bad_physical = {{"type", "gmsh"}, {"file", "column-in-tank.geo"}, {"physical", "colum"}};
  EXPECT_TRUE(one_problem(scene(2, bad_physical, {0, 0}, {0.5, 0.08}, 0.01), "/bodies/0/geometry/physical",
                          {"column-in-tank.geo", "defined: column, water"}));
  json bad_load = scene(2, {{"type", "gmsh"}, {"file", "slope.geo"}}, {0, 0}, {45, 20}, 1.0);
  bad_load["loads"] = json::array({{{"type", "pressure"}, {"body", "body"}, {"face", "crown"}, {"value", 1e3}}});
  EXPECT_TRUE(one_problem(bad_load, "/loads/0/face", {"slope.geo", "surface, toe, slope_face, crest, base"}));
  json bad_boundary = scene(2, {{"type", "gmsh"}, {"file", "slope.geo"}}, {0, 0}, {45, 20}, 1.0);
  bad_boundary["boundaries"] = json::array({{{"on", "bottom"}, {"solid", "fixed"}}});
  EXPECT_TRUE(one_problem(bad_boundary, "/boundaries/0/on", {"\"bottom\"", "named surfaces: surface"}));
  EXPECT_TRUE(one_problem(scene(2, {{"type", "gmsh"}, {"file", "slope.geo"}}, {0, 0}, {40, 20}, 1.0),
                          "/bodies/0/geometry", {"slope.geo", "expected a geometry inside the grid"}));
}

TEST(GeometryGmshErrors, PreprocessReportsOneLineAndWritesNothing) {
  const fs::path dir = scratch("gmsh-preprocess");
  write(dir / "open.geo", "Point(1) = {0,0,0}; Point(2) = {1,0,0}; Point(3) = {1,1,0};\n"
                          "Line(1) = {1,2}; Line(2) = {2,3}; Curve Loop(1) = {1,2}; Plane Surface(1) = {1};\n");
  write(dir / "scene.json", scene(2, {{"type", "gmsh"}, {"file", "open.geo"}}, {0, 0}, {1, 1}, 0.1).dump());
  try {
    pre::preprocess((dir / "scene.json").string(), (dir / "run").string(), true);
    ADD_FAILURE() << "preprocess accepted a .geo that does not mesh";
  } catch (const scene::SceneError& e) {
    ASSERT_EQ(e.lines().size(), 1u);
    EXPECT_EQ(e.lines()[0].rfind((dir / "scene.json").string() + ": /bodies/0/geometry/file: ", 0), 0u) << e.lines()[0];
  }
  EXPECT_FALSE(fs::exists(dir / "run"));
}

// ---- surface meshes -----------------------------------------------------------------------------

TEST(GeometrySurfaceMesh, SphereVolume) {
  const std::string sphere = kGeometries + "/sphere.off";
  const json g = {{"type", "surface-mesh"}, {"file", "sphere.off"}};
  const scene::Scene s = parse(scene(3, g, {0, 0, 0}, {1, 1, 1}, 0.05));
  const double dx = 0.025, volume = off_volume(sphere);
  const Seeded got = seed(s);
  const double e = relative_error(static_cast<double>(got.count) * dx * dx * dx, volume);
  std::printf("sphere.off 2x2x2 per cell: %zu particles, volume error %.3f %% (mesh volume %.5f m^3)\n", got.count,
              100 * e, volume);
  EXPECT_LT(e, 0.03);
  const auto [lo, hi] = pre::make_shape(s.bodies[0].geometry, 3, "")->bounds();
  EXPECT_NEAR(lo[0], 0.1, 0.01);
  EXPECT_NEAR(hi[1], 0.9, 0.01);
}

TEST(GeometrySurfaceMeshErrors, OpenAndSelfIntersectingMeshes) {
  const fs::path dir = scratch("surface-mesh");
  // A tetrahedron without its bottom face.
  write(dir / "open.off", "OFF\n4 3 0\n0.2 0.2 0.2\n0.8 0.2 0.2\n0.5 0.8 0.2\n0.5 0.5 0.8\n"
                          "3 0 1 3\n3 1 2 3\n3 2 0 3\n");
  EXPECT_TRUE(one_problem(scene(3, {{"type", "surface-mesh"}, {"file", "open.off"}}, {0, 0, 0}, {1, 1, 1}, 0.1),
                          "/bodies/0/geometry/file", {"open.off", "open surface", "border edges"}, dir.string()));
  // Two closed tetrahedra that pass through each other.
  write(dir / "crossing.off", "OFF\n8 8 0\n"
                              "0.1 0.1 0.1\n0.7 0.1 0.1\n0.4 0.7 0.1\n0.4 0.4 0.7\n"
                              "0.3 0.3 0.3\n0.9 0.3 0.3\n0.6 0.9 0.3\n0.6 0.6 0.9\n"
                              "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n"
                              "3 4 6 5\n3 4 5 7\n3 5 6 7\n3 6 4 7\n");
  EXPECT_TRUE(one_problem(scene(3, {{"type", "surface-mesh"}, {"file", "crossing.off"}}, {0, 0, 0}, {1, 1, 1}, 0.1),
                          "/bodies/0/geometry/file", {"crossing.off", "self-intersecting"}, dir.string()));
  EXPECT_TRUE(one_problem(scene(2, {{"type", "surface-mesh"}, {"file", "sphere.off"}}, {0, 0}, {1, 1}, 0.1),
                          "/bodies/0/geometry/type", {"surface-mesh is 3D only"}));
}

}  // namespace
