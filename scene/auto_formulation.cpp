#include "scene/auto_formulation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "scene/budget.hpp"
#include "scene/formulations.hpp"

namespace swmpm::scene {
namespace {

std::string quoted(Formulation f) {
  std::string q = "\"";  // (not "\"" + string: GCC 12's -Wrestrict false positive)
  q += to_string(f);
  q += '"';
  return q;
}

/// Water's bulk modulus where a fluid material does not give one (mpm-fem's incompressible
/// water): the estimate of the explicit step needs a K_f.
constexpr double kWaterBulkModulus = 2.2e9;  // Pa

/// The volume of a body's geometry [m^3, or m^2 in 2D]: exact for box, polygon, footing and slope;
/// a file geometry (gmsh, surface-mesh) is known only once preprocess reads it, so it counts as
/// half the grid's volume (the estimates' particle count, not the choice between them, depends on it).
double body_volume(const Scene& s, const Body& b) {
  const Geometry& g = b.geometry;
  const int dim = s.dimension;
  if (g.type == "box") {
    double v = 1.0;
    for (int a = 0; a < dim; ++a) v *= g.max[static_cast<std::size_t>(a)] - g.min[static_cast<std::size_t>(a)];
    return v;
  }
  if (g.type == "polygon") {  // the shoelace formula
    double twice = 0.0;
    for (std::size_t i = 0; i < g.vertices.size(); ++i) {
      const auto& p = g.vertices[i];
      const auto& q = g.vertices[(i + 1) % g.vertices.size()];
      twice += p[0] * q[1] - q[0] * p[1];
    }
    return 0.5 * std::abs(twice);
  }
  if (g.type == "footing") return g.width * g.height * (dim == 3 ? g.length : 1.0);
  if (g.type == "slope") {
    const double run = g.ratio > 0.0 ? g.ratio * g.height : g.height / std::tan(g.angle * std::numbers::pi / 180.0);
    return g.foundation_depth * (g.toe_length + run + g.crest_length) + g.height * (g.crest_length + 0.5 * run);
  }
  double grid = 1.0;
  for (int a = 0; a < dim; ++a) grid *= s.grid.max[static_cast<std::size_t>(a)] - s.grid.min[static_cast<std::size_t>(a)];
  return 0.5 * grid;
}

double particles_of(const Scene& s, const Body& b) {
  return body_volume(s, b) * std::pow(b.particles_per_cell / s.grid.cell_size, s.dimension);
}

/// The share of a body's volume below its water table (1 without one): exact for box and polygon
/// (the polygon clipped to y < table); 1 for the other geometries, whose shape only preprocess
/// knows (an over-estimate of the water points, never an under-estimate).
double wet_share(const Scene& s, const Body& b) {
  if (!b.initial.hydrostatic || !b.initial.water_table) return 1.0;
  const double table = *b.initial.water_table;
  const Geometry& g = b.geometry;
  if (g.type == "box") {
    const double lo = g.min[1], hi = g.max[1];
    return hi > lo ? std::clamp((table - lo) / (hi - lo), 0.0, 1.0) : 1.0;
  }
  if (g.type == "polygon" && s.dimension == 2) {
    // Sutherland–Hodgman against the half-plane y <= table, then the shoelace formula.
    std::vector<std::array<double, 2>> clipped;
    const std::size_t n = g.vertices.size();
    for (std::size_t i = 0; i < n; ++i) {
      const auto& p = g.vertices[i];
      const auto& q = g.vertices[(i + 1) % n];
      const bool p_in = p[1] <= table, q_in = q[1] <= table;
      if (p_in) clipped.push_back({p[0], p[1]});
      if (p_in != q_in) {
        const double t = (table - p[1]) / (q[1] - p[1]);
        clipped.push_back({p[0] + t * (q[0] - p[0]), table});
      }
    }
    double twice = 0.0;
    for (std::size_t i = 0; i < clipped.size(); ++i) {
      const auto& p = clipped[i];
      const auto& q = clipped[(i + 1) % clipped.size()];
      twice += p[0] * q[1] - q[0] * p[1];
    }
    const double whole = body_volume(s, b);
    return whole > 0.0 ? std::clamp(0.5 * std::abs(twice) / whole, 0.0, 1.0) : 1.0;
  }
  return 1.0;
}

/// Points formulation f carries: a double-point one has a water point beside each soil point of a
/// saturated body (below its water table, when it has one).
double points_of(const Scene& s, Formulation f) {
  double points = 0.0;
  for (const Body& b : s.bodies) {
    const bool water_points = row_of(f).water.fluid_particles && !b.solid.empty() && !b.fluid.empty();
    points += particles_of(s, b) * (1.0 + (water_points ? wet_share(s, b) : 0.0));
  }
  return points;
}

/// Constrained modulus M = K + 4G/3 [Pa] of a solid material at mean effective stress `p` [Pa]:
/// E (1 - nu) / ((1 + nu)(1 - 2 nu)) for the models with Young's modulus; Nor-Sand's tangent
/// K = p / kappa~ and mu_e = mu0 + alpha0 p (NS3, as its max_p_wave_modulus) at p, no less than its
/// reference pressure.
double p_wave_modulus(const Material& m, double p) {
  if (m.model == MaterialModel::nor_sand) {
    const double pp = std::max(p, m.at("reference_pressure"));
    return pp / m.at("swelling_index") + 4.0 / 3.0 * (m.at("shear_modulus") + m.at("shear_modulus_coupling") * pp);
  }
  if (!m.has("youngs_modulus")) return 0.0;
  const double E = m.at("youngs_modulus"), nu = m.has("poisson_ratio") ? m.at("poisson_ratio") : 0.0;
  return E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
}

/// A body's vertical extent [m] (y): its box or polygon, else the grid's.
double body_height(const Scene& s, const Body& b) {
  const Geometry& g = b.geometry;
  if (g.type == "box") return g.max[1] - g.min[1];
  if (g.type == "polygon" && !g.vertices.empty()) {
    double lo = g.vertices[0][1], hi = lo;
    for (const auto& v : g.vertices) lo = std::min(lo, v[1]), hi = std::max(hi, v[1]);
    return hi - lo;
  }
  if (g.type == "slope") return g.foundation_depth + g.height;
  return s.grid.max[1] - s.grid.min[1];
}

/// The P-wave speeds of the saturated bodies at t = 0 (their largest), for the step limits.
struct Waves {
  double c_skeleton = 0.0;  // m/s, sqrt(M / rho_sat): the semi-implicit formulations (core.hpp)
  double c_undrained = 0.0; // m/s, sqrt((M + K_f / n) / rho_sat): explicit-single-point
  double c_double = 0.0;    // m/s, explicit-double-point's solid points:
                            //   c^2 = M / rho_s' + K_f [(1 - n) / (n rho_S) + 1 / rho_f]
  double M = 0.0, Kf_over_n = 0.0;  // Pa, of the body with the fastest undrained wave
  std::string body;                 // that body
};

Waves waves_of(const Scene& s) {
  Waves w;
  const double g = std::hypot(s.gravity[0], s.gravity[1], s.gravity[2]);
  for (const Body& b : s.bodies) {
    if (b.solid.empty() || b.fluid.empty()) continue;
    const Material& soil = s.material(b.solid);
    const Material& water = s.material(b.fluid);
    const double n = b.initial.porosity ? *b.initial.porosity : soil.has("porosity") ? soil.at("porosity") : 0.3;
    const double rho_w = water.has("density") ? water.at("density") : 1000.0;                    // kg/m^3
    const double K_f = water.has("bulk_modulus") ? water.at("bulk_modulus") : kWaterBulkModulus;  // Pa
    const double rho_s = soil.has("density") ? soil.at("density") : (1.0 - n) * soil.at("grain_density");  // (1-n) rho_S
    const double rho_sat = rho_s + n * rho_w;  // kg/m^3, the mixture the wave carries
    // A pressure-dependent skeleton (Nor-Sand) at the geostatic mean effective stress at the body's
    // base, K0 = 0.5: p' = (rho_sat - rho_w) g H (1 + 2 K0) / 3.
    const double p = (rho_sat - rho_w) * g * body_height(s, b) * 2.0 / 3.0;
    const double M = p_wave_modulus(soil, p);
    const double c_u = std::sqrt((M + K_f / n) / rho_sat);
    w.c_skeleton = std::max(w.c_skeleton, std::sqrt(M / rho_sat));
    w.c_double = std::max(w.c_double, std::sqrt(M / rho_s + K_f * ((1.0 - n) / (n * rho_s / (1.0 - n)) + 1.0 / rho_w)));
    if (c_u > w.c_undrained) {
      w.c_undrained = c_u;
      w.M = M;
      w.Kf_over_n = K_f / n;
      w.body = b.name;
    }
  }
  return w;
}

/// Whether the scene passes formulation f's own checks (scene/formulations.hpp, e.g. the
/// semi-implicit ones refuse one point per cell with B-splines): a candidate that fails is not chosen.
bool passes_checks(const Scene& s, Formulation f) {
  const FormulationRow& row = row_of(f);
  if (!row.implemented) return false;
  if (!row.check) return true;
  Scene as_f = s;
  as_f.formulation = f;
  std::vector<Problem> problems;
  row.check(as_f, problems);
  return problems.empty();
}

/// The time a run spans: from the initialisation's start (before t = 0) to time.end.
double span_of(const Scene& s) {
  return s.time.end + (s.initialisation.enabled() ? s.initialisation.duration : 0.0);
}

FormulationEstimate estimate(const Scene& s, Formulation f, double c, const std::string& what) {
  FormulationEstimate e;
  e.formulation = f;
  e.wave_speed = c;
  const double limit = s.grid.cell_size / c;  // s, the CFL limit h / c (the run adds |v|max to c)
  e.dt = s.time.dt ? std::min(*s.time.dt, limit) : s.time.cfl * limit;
  e.dt_reason = what + " c = " + num(c) + " m/s, h/c = " + num(limit) + " s: " +
                (!s.time.dt ? "dt = cfl " + num(s.time.cfl) + " x h/c"
                 : *s.time.dt <= limit ? "dt = time.dt"
                                       : "dt = h/c, below time.dt " + num(*s.time.dt) + " s (which would not be stable)");
  e.steps = std::ceil(span_of(s) / e.dt);
  e.us_per_point_step = row_of(f).cost.us_per_point_step;
  e.points = points_of(s, f);
  e.wall_seconds = e.steps * step_microseconds(s, f, e.points) * 1e-6;
  return e;
}

std::string volume_text(double v, int dim) { return num(v) + (dim == 3 ? " m^3" : " m^2"); }

/// Chooses between an explicit formulation (its step limited by wave speed `c_explicit`) and a
/// semi-implicit one (the skeleton's wave) by their estimated wall times to time.end; a candidate
/// whose own scene checks fail is left out. `why` opens the reason: the branch that led here.
void compare(const Scene& s, FormulationChoice& c, const std::string& why, Formulation explicit_f, double c_explicit,
             const std::string& explicit_what, Formulation semi_f, const Waves& w) {
  c.estimates.push_back(estimate(s, explicit_f, c_explicit, explicit_what));
  c.estimates.push_back(estimate(s, semi_f, w.c_skeleton, "skeleton P-wave"));
  const FormulationEstimate& e = c.estimates[0];
  const FormulationEstimate& i = c.estimates[1];
  const bool semi_ok = passes_checks(s, semi_f);
  const bool explicit_wins = !semi_ok || e.wall_seconds <= i.wall_seconds;
  c.chosen = explicit_wins ? e.formulation : i.formulation;
  const FormulationEstimate& win = explicit_wins ? e : i;
  const FormulationEstimate& lose = explicit_wins ? i : e;
  c.reason = why + ": " + quoted(c.chosen) + " reaches time.end " + num(s.time.end) + " s in about " +
             format_duration(win.wall_seconds) + " (" + num(win.steps) + " steps of " + num(win.dt) + " s) against " +
             format_duration(lose.wall_seconds) + " for " + quoted(lose.formulation) + " (" + num(lose.steps) +
             " steps of " + num(lose.dt) + " s). The pore water's storage (body \"" + w.body +
             "\") makes the explicit step's wave " + num(c_explicit / w.c_skeleton) + " times faster than the skeleton's, and a semi-implicit step costs " +
             num(i.us_per_point_step / e.us_per_point_step) + " times an explicit one";
  if (!semi_ok)
    c.reason += "; " + quoted(semi_f) + " is left out: the scene fails its checks (preprocess --explain with it named says why)";
}

}  // namespace

FormulationChoice choose_formulation(const Scene& s) {
  FormulationChoice c;
  double free_water = 0.0, soil = 0.0;
  std::string free_body, liquefiable_body, liquefiable_material;
  for (const Body& b : s.bodies) {
    c.points += particles_of(s, b);
    const double v = body_volume(s, b);
    if (b.solid.empty() && !b.fluid.empty()) {
      free_water += v;
      if (free_body.empty()) free_body = b.name;
    } else if (!b.solid.empty()) {
      soil += v;
      if (!b.fluid.empty() && s.material(b.solid).model == MaterialModel::nor_sand && liquefiable_body.empty()) {
        liquefiable_body = b.name;
        liquefiable_material = b.solid;
      }
    }
  }

  // 1. No fluid anywhere: the skeleton alone.
  if (!s.has_fluid()) {
    c.chosen = Formulation::dry;
    c.rule = "dry";
    c.reason = "no body has a fluid, so the soil is dry: \"dry\" models the solid phase only";
    return c;
  }

  // 2. Free water: water that moves apart from the soil needs water points of its own, or a fluid
  //    on the grid when it is mostly free water and its waves matter (gravity, a free surface).
  if (!free_body.empty()) {
    c.rule = "free water";
    const bool gravity = std::hypot(s.gravity[0], s.gravity[1], s.gravity[2]) > 0.0;
    const bool bspline = s.grid.shape_function == ShapeFunction::bspline2 || s.grid.shape_function == ShapeFunction::bspline3;
    const std::string volumes = "free water (body \"" + free_body + "\", " + volume_text(free_water, s.dimension) +
                                " in all) against " + volume_text(soil, s.dimension) + " of soil";
    if (free_water > soil && gravity && bspline) {
      c.chosen = Formulation::mpm_fem;
      c.reason = "the scene is mostly " + volumes + ", under gravity: its free surface and waves dominate, so "
                 "\"mpm-fem\" solves the water on the grid (incompressible, no water points to spread or to limit the step)";
    } else {
      c.chosen = Formulation::explicit_double_point;
      c.reason = "the scene has " + volumes + ": water that separates from the soil needs water points of its own, "
                 "so \"explicit-double-point\"";
      if (free_water > soil && gravity)
        c.reason += " (the water dominates, where \"mpm-fem\" would suit, but it needs grid.shape_function "
                    "\"bspline2\" or \"bspline3\", not \"" + to_string(s.grid.shape_function) + "\")";
      else if (free_water <= soil)
        c.reason += "; \"mpm-fem\" is for scenes that are mostly free water";
      else
        c.reason += "; without gravity there are no waves for \"mpm-fem\"'s free surface";
    }
    return c;
  }

  // 3. Soil that can liquefy: a state-dependent model whose loose states contract under shear, so
  //    that the pore pressure can take the whole mean stress and the water separate from the
  //    grains: a double-point formulation, explicit or semi-implicit by cost (as 4).
  const Waves w = waves_of(s);
  if (!liquefiable_body.empty()) {
    c.rule = "liquefiable";
    const std::string why = "body \"" + liquefiable_body + "\" is saturated " +
                            to_string(s.material(liquefiable_material).model) + " (material \"" + liquefiable_material +
                            "\"), which can liquefy and separate from its water, so a double-point formulation (water "
                            "points of their own)";
    compare(s, c, why, Formulation::explicit_double_point, w.c_double,
            "P-wave of the solid points with the water's storage", Formulation::semi_implicit_double_point, w);
    return c;
  }

  // 4. Pore water only: a single-point formulation, the one that reaches time.end sooner. Explicit:
  //    the undrained P-wave (the pore water's K_f / n stiffens the mixture) limits the step;
  //    semi-implicit: the skeleton's P-wave only (the pressure is implicit), at a larger cost per step.
  c.rule = "pore water";
  compare(s, c, "the soil holds pore water only (no free water, no soil that can liquefy), so a single-point formulation",
          Formulation::explicit_single_point, w.c_undrained,
          "undrained P-wave (M " + num(w.M) + " Pa + K_f/n " + num(w.Kf_over_n) + " Pa)",
          Formulation::semi_implicit_single_point, w);
  return c;
}

nlohmann::json to_json(const FormulationChoice& c) {
  nlohmann::json j = {{"chosen", to_string(c.chosen)}, {"automatic", true}, {"rule", c.rule}, {"reason", c.reason}};
  if (!c.estimates.empty()) {
    j["estimates"] = nlohmann::json::array();
    for (const FormulationEstimate& e : c.estimates)
      j["estimates"].push_back({{"formulation", to_string(e.formulation)},
                                {"dt", e.dt},
                                {"dt_reason", e.dt_reason},
                                {"wave_speed", e.wave_speed},
                                {"steps", e.steps},
                                {"points", e.points},
                                {"us_per_point_step", e.us_per_point_step},
                                {"wall_seconds", e.wall_seconds}});
  }
  return j;
}

nlohmann::json choice_of(const Scene& s) {
  if (s.formulation_choice.is_object()) return s.formulation_choice;
  return {{"chosen", to_string(s.formulation)}, {"automatic", false}, {"reason", s.formulation_reason}};
}

std::vector<std::string> explain_lines(const nlohmann::json& choice) {
  if (!choice.is_object()) return {};
  std::vector<std::string> lines;
  try {
    const std::string chosen = choice.value("chosen", std::string("?"));
    if (!choice.value("automatic", false)) return {"formulation " + chosen + ", as named in the scene file"};
    lines.push_back("formulation " + chosen + " (chosen by \"auto\"): " + choice.value("reason", std::string()));
    for (const auto& e : choice.value("estimates", nlohmann::json::array()))
      lines.push_back("  estimate " + e.value("formulation", std::string("?")) + ": dt " + num(e.value("dt", 0.0)) +
                      " s (" + e.value("dt_reason", std::string()) + "), " + num(e.value("steps", 0.0)) +
                      " steps of " + num(e.value("points", 0.0)) + " points at " +
                      num(e.value("us_per_point_step", 0.0)) + " us per point-step (measured) and the grid's nodes: about " +
                      format_duration(e.value("wall_seconds", 0.0)) + " on one thread");
  } catch (const nlohmann::json::exception&) {  // a hand-edited formulation_choice: say so, run on
    lines.push_back("formulation_choice: not as preprocess writes it (" + choice.dump() + ")");
  }
  return lines;
}

}  // namespace swmpm::scene
