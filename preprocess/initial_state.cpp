#include "preprocess/initial_state.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>

namespace swmpm::pre {

namespace {

constexpr double not_hydrostatic = std::numeric_limits<double>::quiet_NaN();

std::string initial_path(std::size_t b) { return "/bodies/" + std::to_string(b) + "/initial"; }

[[noreturn]] void fail(const scene::Scene& s, const std::string& path, const std::string& what) {
  throw scene::SceneError({s.source_file + ": " + path + ": " + what});
}

std::string shown(const scene::Vec3& v, int dim) {
  std::ostringstream out;
  out << "[";
  for (int a = 0; a < dim; ++a) out << (a ? ", " : "") << v[static_cast<std::size_t>(a)];
  out << "]";
  return out.str();
}

/// |gravity| [m/s^2]. A state built from the weight of the material needs gravity along -y (y is
/// the vertical axis in 2D and 3D) or zero; `user` says what needs it, for the message.
double vertical_gravity(const scene::Scene& s, const std::string& user) {
  const auto& g = s.gravity;
  double norm2 = 0.0;
  for (int a = 0; a < s.dimension; ++a) norm2 += g[static_cast<std::size_t>(a)] * g[static_cast<std::size_t>(a)];
  const double norm = std::sqrt(norm2);
  bool vertical = g[1] <= 0.0;
  for (int a = 0; a < s.dimension; ++a)
    if (a != 1) vertical = vertical && std::abs(g[static_cast<std::size_t>(a)]) <= 1e-12 * norm;
  if (!vertical)
    fail(s, "/gravity",
         "got " + shown(g, s.dimension) + ", expected gravity along -y (y is the vertical axis) for " + user);
  return norm;
}

/// Initial states the bodies cannot have. Reported at the first problem found.
void check_bodies(const scene::Scene& s, const std::vector<BodyContent>& content) {
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const auto& body = s.bodies[b];
    const auto& init = body.initial;
    const std::string path = initial_path(b);
    const std::string name = "\"" + body.name + "\"";
    if ((init.stress || init.geostatic) && !content[b].has_solid())
      fail(s, path + "/stress", "body " + name + " is free water (no solid), expected no stress (water has no skeleton; "
                                "give pore_pressure instead)");
    if (init.porosity && !content[b].has_solid())
      fail(s, path + "/porosity", "body " + name + " is free water (porosity 1), expected no porosity");
    if ((init.stress || init.geostatic) && s.material(body.solid).model == scene::MaterialModel::hencky)
      fail(s, path + "/stress", "hencky computes stress from the deformation gradient; an initial stress needs an "
                                "initial F, which is not implemented yet (use linear-elastic)");
    if (init.geostatic &&
        vertical_gravity(s, "the geostatic stress of body " + name + " (" + path + "/stress)") == 0.0)
      fail(s, path + "/stress", "got \"geostatic\" with zero gravity, expected a non-zero /gravity along -y "
                                "(geostatic stress is the weight of the material above)");
  }
}

/// A point's lattice segment [y - s/2, y + s/2] in one vertical column.
struct ColumnEntry {
  std::int64_t column;
  double y;             // m, centre height
  std::uint32_t point;  // index into the points
  bool home;            // the column through (nearest) the point's centre: where its own integrals are taken
};

/// What the column above each point holds.
struct ColumnIntegrals {
  std::vector<double> weight;      // Pa, g sum(rho_bulk dy) above the centre (every body)
  std::vector<double> wet_length;  // m, length between the centre and the body's water table held by
                                   // points with a fluid (0 when the body is not hydrostatic)
};

/// Vertical columns of width w = h / (largest particles_per_cell). A point's segment enters every
/// column whose centre lies in its horizontal extent [x - s/2, x + s/2) per horizontal axis, so
/// each column gets one segment per lattice layer also where bodies have different
/// particles_per_cell; its own integrals are taken in the column nearest its centre. The columns
/// are built from the seeded points themselves, so any shape and any stack of bodies works.
ColumnIntegrals integrate_columns(const scene::Scene& s, const std::vector<SeedPoint>& points,
                                  const std::vector<BodyContent>& content, const std::vector<double>& water_table,
                                  double g) {
  int n_max = 1;
  for (const auto& b : s.bodies) n_max = std::max(n_max, b.particles_per_cell);
  const double w = s.grid.cell_size / n_max;  // m, column width
  const std::int64_t columns_x =
      static_cast<std::int64_t>(std::ceil((s.grid.max[0] - s.grid.min[0]) / w)) + 2;

  // Column index range [first, last] along horizontal axis a covered by point p, and its home.
  struct Range {
    std::int64_t first, last, home;
  };
  auto range = [&](const SeedPoint& p, std::size_t a) {
    const double centre = (p.x[a] - s.grid.min[a]) / w - 0.5;  // in column-centre units
    const double half = 0.5 * p.spacing / w;
    Range r{};
    r.first = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(centre - half - 1e-9)));
    r.last = std::max(r.first, static_cast<std::int64_t>(std::ceil(centre + half - 1e-9)) - 1);
    r.home = std::clamp(static_cast<std::int64_t>(std::lround(centre)), r.first, r.last);
    return r;
  };

  std::vector<ColumnEntry> entries;
  entries.reserve(points.size());
  for (std::size_t p = 0; p < points.size(); ++p) {
    const Range rx = range(points[p], 0);
    const Range rz = s.dimension == 3 ? range(points[p], 2) : Range{0, 0, 0};
    for (std::int64_t k = rz.first; k <= rz.last; ++k)
      for (std::int64_t i = rx.first; i <= rx.last; ++i)
        entries.push_back({i + columns_x * k, points[p].x[1], static_cast<std::uint32_t>(p),
                           i == rx.home && k == rz.home});
  }
  // Each column from the top down; ties by point index so the result does not depend on the sort.
  std::sort(entries.begin(), entries.end(), [](const ColumnEntry& a, const ColumnEntry& b) {
    if (a.column != b.column) return a.column < b.column;
    if (a.y != b.y) return a.y > b.y;
    return a.point < b.point;
  });

  ColumnIntegrals out{std::vector<double>(points.size(), 0.0), std::vector<double>(points.size(), 0.0)};
  std::vector<double> mass_above, wet_above;  // per entry of a column: kg/m^2 and m above its segment
  auto spacing = [&](const ColumnEntry& e) { return points[e.point].spacing; };
  auto wet = [&](const ColumnEntry& e) { return content_of(content, points[e.point]).has_fluid(); };
  for (auto begin = entries.begin(); begin != entries.end();) {
    const auto end = std::find_if(begin, entries.end(), [&](const ColumnEntry& e) { return e.column != begin->column; });
    const auto n = static_cast<std::size_t>(end - begin);
    mass_above.assign(n + 1, 0.0);
    wet_above.assign(n + 1, 0.0);
    for (std::size_t k = 0; k < n; ++k) {
      const ColumnEntry& e = begin[static_cast<std::ptrdiff_t>(k)];
      mass_above[k + 1] = mass_above[k] + content_of(content, points[e.point]).bulk_density() * spacing(e);
      wet_above[k + 1] = wet_above[k] + (wet(e) ? spacing(e) : 0.0);
    }
    // Length [m] held by points with a fluid above height y in this column.
    auto wet_length_above = [&](double y) {
      const auto it = std::partition_point(begin, end, [&](const ColumnEntry& e) { return e.y - 0.5 * spacing(e) >= y; });
      const auto k = static_cast<std::size_t>(it - begin);
      if (k == n) return wet_above[n];
      return wet_above[k] + (wet(*it) ? std::clamp(it->y + 0.5 * spacing(*it) - y, 0.0, spacing(*it)) : 0.0);
    };
    for (std::size_t k = 0; k < n; ++k) {
      const ColumnEntry& e = begin[static_cast<std::ptrdiff_t>(k)];
      if (!e.home) continue;
      const SeedPoint& p = points[e.point];
      const BodyContent c = content_of(content, p);
      out.weight[e.point] = g * (mass_above[k] + c.bulk_density() * 0.5 * p.spacing);
      const double wt = water_table[static_cast<std::size_t>(p.body)];
      if (!std::isnan(wt) && wt > p.x[1])
        out.wet_length[e.point] = std::max(0.0, wet_length_above(p.x[1]) - wet_length_above(wt));
    }
    begin = end;
  }
  return out;
}

}  // namespace

std::vector<double> water_tables(const scene::Scene& s, const std::vector<SeedPoint>& points) {
  std::vector<double> wt(s.bodies.size(), not_hydrostatic);
  std::vector<double> top(s.bodies.size(), -std::numeric_limits<double>::infinity());
  for (const auto& p : points) {
    auto& t = top[static_cast<std::size_t>(p.body)];
    t = std::max(t, p.x[1] + 0.5 * p.spacing);
  }
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const auto& init = s.bodies[b].initial;
    if (init.hydrostatic) wt[b] = init.water_table ? *init.water_table : top[b];
  }
  return wt;
}

BodyContent body_content(const scene::Scene& s, std::size_t b) {
  const auto& body = s.bodies[b];
  BodyContent c;
  if (!body.solid.empty()) {
    const auto& m = s.material(body.solid);
    c.porosity = body.initial.porosity ? *body.initial.porosity : m.has("porosity") ? m.at("porosity") : 0.0;
    // A dry body given by `density` keeps it whatever the porosity; a porous skeleton is (1 - n) rho_s.
    c.solid_density = m.has("grain_density") ? (1.0 - c.porosity) * m.at("grain_density") : m.solid_bulk_density();
  }
  if (!body.fluid.empty()) {
    c.rho_w = s.material(body.fluid).at("density");
    if (body.solid.empty()) c.porosity = 1.0;  // free water
    c.fluid_density = c.porosity * c.rho_w;
  }
  return c;
}

InitialFields initial_state(const scene::Scene& s, const std::vector<SeedPoint>& points,
                            const std::vector<BodyContent>& content) {
  check_bodies(s, content);
  InitialFields f;
  f.water_table = water_tables(s, points);
  f.pore_pressure.assign(points.size(), 0.0);
  f.stress.assign(points.size(), {0, 0, 0, 0, 0, 0});

  double g = 0.0;  // m/s^2
  bool any_geostatic = false;
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const auto& init = s.bodies[b].initial;
    if (!init.geostatic && !init.hydrostatic) continue;
    g = vertical_gravity(s, std::string(init.geostatic ? "the geostatic stress" : "the hydrostatic pore pressure") +
                                " of body \"" + s.bodies[b].name + "\" (" + initial_path(b) + ")");
    any_geostatic = any_geostatic || init.geostatic;
  }
  const ColumnIntegrals column =
      any_geostatic ? integrate_columns(s, points, content, f.water_table, g) : ColumnIntegrals{};

  for (std::size_t p = 0; p < points.size(); ++p) {
    const auto b = static_cast<std::size_t>(points[p].body);
    const auto& init = s.bodies[b].initial;
    const BodyContent c = content_of(content, points[p]);  // dry above a hydrostatic body's water table
    const double y = points[p].x[1];
    if (c.has_fluid()) {
      // Hydrostatic: p = rho_w g (y_wt - y) below the table; 0 above it (no suction).
      f.pore_pressure[p] = init.hydrostatic ? c.rho_w * g * std::max(0.0, f.water_table[b] - y)
                                            : init.pore_pressure.value_or(0.0);
    }
    if (init.geostatic) {
      // sigma'_v = -(weight above) + rho_w g (length below the water table held by points with a
      // fluid): per metre below the table a saturated layer adds its buoyant weight
      // (1 - n)(rho_s - rho_w) g and free water nothing; above the table the total unit weight.
      // Where the column is full of such points the buoyancy term is p, so sigma = sigma' - p I is
      // -(weight above); where water above the body is not seeded (mpm-fem, or a table set above
      // the top) the effective stress is still the buoyant one. A constant pore pressure is an
      // excess pressure on top of a drained geostatic state, so it does not enter sigma'.
      const double buoyancy = init.hydrostatic ? c.rho_w * g * column.wet_length[p] : 0.0;  // Pa
      const double sv = -column.weight[p] + buoyancy;                                     // Pa, tension positive
      f.stress[p] = {init.k0 * sv, sv, init.k0 * sv, 0.0, 0.0, 0.0};
    } else if (init.stress) {
      f.stress[p] = *init.stress;
    }
  }
  return f;
}

}  // namespace swmpm::pre
