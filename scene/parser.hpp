// The scene parser (internal to swmpm_scene): typed values out of checked objects, and the rules
// across keys. Members are defined in parse.cpp (top level, grid, materials, boundaries and loads,
// time, output, solver, initialisation, formulation) and parse_bodies.cpp (bodies: geometries,
// footings, initial state).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "scene/validate.hpp"

namespace swmpm::scene::detail {

// ------------------------------------------------------------------------------------------------
// The section parsers: typed values out of checked objects, and the rules across keys.
// ------------------------------------------------------------------------------------------------

/// Axis-aligned bounds of a geometry [m].
struct Bounds {
  Vec3 min{0, 0, 0}, max{0, 0, 0};
};

class SceneParser {
 public:
  SceneParser(const json& root, const std::string& label) : root_(root) { c_.label = label; }

  Scene parse();

 private:
  struct MaterialInfo {
    std::string path;
    bool known = false;  // model known (parameters checked)
    bool gives_density = false, gives_grain_density = false, gives_porosity = false;
    bool gives_permeability = false;
    bool saturated_reported = false;
  };

  Ctx c_;
  const json& root_;
  Scene s_;
  bool grid_ok_ = false;
  Vec3 grid_min_{0, 0, 0}, grid_max_{0, 0, 0};  // as written (before rounding up) [m]
  std::vector<MaterialInfo> material_info_;
  std::vector<std::string> body_paths_;
  std::vector<std::string> water_monitors_;  // JSON paths of monitors with points "water"
  std::vector<std::string> gauges_;          // JSON paths of water_level quantities (gauges)
  std::vector<std::optional<Bounds>> body_bounds_;  // per body, when known before preprocess
  struct PendingFooting {
    std::size_t body;
    std::string on, path;  // the body it rests on; the footing's geometry path
  };
  std::vector<PendingFooting> pending_footings_;  // footings with `on`, resolved after all bodies
  std::vector<std::string> surface_names_;        // named surfaces referred to (face bits 6..)

  int dim() const { return s_.dimension; }

  std::vector<std::string> faces() const;
  bool check_face(const std::string& face, const std::string& path, const std::vector<std::string>& named,
                  bool deferred, const std::string& none);
  bool check_min_max(const Vec3& mn, const Vec3& mx, const std::string& max_path);

  // -- grid, materials (parse.cpp) ----------------------------------------------------------------

  void parse_grid(const json& j, const std::string& path);
  void parse_materials(const json& arr, const std::string& path);
  void check_solid_material(const Obj& o, const Material& m);
  std::vector<std::string> material_names(bool fluid) const;
  int check_material_ref(const Obj& o, const std::string& key, bool fluid);

  // -- bodies (parse_bodies.cpp) ------------------------------------------------------------------

  void parse_bodies(const json& arr, const std::string& path);
  void check_saturated_solid(std::size_t idx, const Body& b, const std::string& body_path);
  std::string dimension_problem(const std::string& type) const;
  static const Table* type_table(const std::string& type);
  std::optional<Bounds> parse_geometry(const json& j, const std::string& path, Geometry& g);
  std::optional<Bounds> parse_box(const Obj& o, Geometry& g);
  std::optional<Bounds> parse_polygon(const Obj& o, Geometry& g);
  bool one_of(const Obj& o, const std::string& a, const std::string& b, const std::string& what);
  std::optional<Bounds> parse_slope(const Obj& o, Geometry& g);
  std::optional<Bounds> parse_footing(const Obj& o, Geometry& g);
  Bounds footing_bounds(const Geometry& g) const;
  void resolve_footings();
  void check_inside_grid(const Bounds& b, const std::string& path);
  void parse_initial(const json& j, const std::string& path, Body& b);

  // -- boundaries, loads, time, output, solver, formulation (parse.cpp) ---------------------------

  bool check_boundary_on(const std::string& on, const std::string& path);
  void check_load_face(const Load& l, const std::string& path);
  void parse_boundaries(const json& arr, const std::string& path);
  void parse_loads(const json& arr, const std::string& path);
  void parse_time(const json& j, const std::string& path);
  void parse_output(const json& j, const std::string& path);
  void parse_point_or_global(const Obj& m, Monitor& mon);
  void parse_gauge(const Obj& m, Monitor& mon);
  void check_quantity(const std::string& q, bool global, const std::string& path);
  void parse_solver(const json& j, const std::string& path);
  void parse_initialisation(const json& j, const std::string& path, const Obj& top);
  void parse_phase_materials(const json& j, const std::string& path);
  void resolve_formulation(const std::string& name, const std::string& path);
  // -- expressions: finite values at representative points (parse.cpp) ---------------------------
  void check_expression_values();
};

}  // namespace swmpm::scene::detail
