// A frame's stability indicators from the state, and the run's record of them (stability.hpp).
#include "solver/diagnostics/stability.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "solver/common.hpp"
#include "solver/diagnostics/indicators.hpp"

namespace swmpm::diagnostics {

namespace {

std::string fmt(double v, int prec = 4) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

/// A set's neighbourhood (its positions as 3-vectors, radius 1.6 typical spacings), and the place
/// of its point k.
template <int Dim>
struct SetView {
  const ParticleSet<Dim>& ps;
  const char* name;
  Neighbourhood nb;
  static std::vector<Point> points(const ParticleSet<Dim>& ps) {
    std::vector<Point> x(ps.size(), Point{0, 0, 0});
    for (std::size_t p = 0; p < ps.size(); ++p)
      for (int a = 0; a < Dim; ++a) x[p][a] = ps.x[p][a];
    return x;
  }
  static double radius(const ParticleSet<Dim>& ps) {
    const double s = typical_spacing(ps.V0, Dim);
    return s > 0.0 ? kRadiusInSpacings * s : 1.0;
  }
  SetView(const ParticleSet<Dim>& set, const char* set_name)
      : ps(set), name(set_name), nb(points(set), Dim, radius(set)) {}
  Place place(long k) const {
    if (k < 0) return {};
    return {name, static_cast<long>(ps.id[k]), nb.x(static_cast<std::size_t>(k)), Dim};
  }
  /// The largest extent of the set's bounding box [m].
  double extent() const {
    double e = 0.0;
    for (int a = 0; a < Dim; ++a) {
      double lo = 0.0, hi = 0.0;
      for (std::size_t p = 0; p < nb.size(); ++p) {
        lo = p ? std::min(lo, nb.x(p)[a]) : nb.x(p)[a];
        hi = p ? std::max(hi, nb.x(p)[a]) : nb.x(p)[a];
      }
      e = std::max(e, hi - lo);
    }
    return e;
  }
};

/// The at-rest speeds of a set, folded into the frame's (the set with the faster point at rest wins).
struct Motion {
  double speed = -1.0;  // m/s, the largest at-rest speed of the sets (-1: none at rest)
  Place at;
  double displacement_rate = 0.0;  // m/s, the largest displacement over the elapsed time
  double speed_max = 0.0;          // m/s, of any point
  Place fastest;
  double extent = 0.0;             // m
};

template <int Dim>
void add_motion(const SetView<Dim>& v, double elapsed, Motion& m) {
  const std::size_t n = v.nb.size();
  std::vector<double> u(n), speed(n);
  for (std::size_t p = 0; p < n; ++p) {
    u[p] = (v.ps.x[p] - v.ps.x0[p]).norm();
    speed[p] = v.ps.v[p].norm();
  }
  const AtRest a = at_rest(v.nb, u, speed);
  if (a.count > 0 && a.speed > m.speed) {
    m.speed = a.speed;
    m.at = v.place(a.worst);
  }
  if (elapsed > 0.0) m.displacement_rate = std::max(m.displacement_rate, a.displacement_max / elapsed);
  if (a.fastest >= 0 && (m.fastest.set.empty() || a.speed_max > m.speed_max)) {
    m.speed_max = a.speed_max;
    m.fastest = v.place(a.fastest);
  }
  m.extent = std::max(m.extent, v.extent());
}

template <int Dim>
void set_checkerboard(FrameIndicators& f, Indicator k, const SetView<Dim>& v, std::span<const double> value) {
  const Checkerboard c = checkerboard(v.nb, value, kStressFloor);
  f.value[k] = c.index;
  f.where[k] = v.place(c.worst);
}

void set_cavitation(FrameIndicators& f, std::span<const double> p, const Place& lowest) {
  const Cavitation c = cavitation(p);
  f.value[cavitation_fraction] = c.fraction;
  f.where[cavitation_fraction] = lowest;
  f.water_points = c.points;
  f.cavitating = c.below;
}

}  // namespace

std::string Place::text() const {
  if (set.empty()) return "the whole model";
  std::ostringstream os;
  os << (set == "grid" ? "grid node " : set == "water" ? "water point " : "solid particle ") << id << " at (";
  for (int a = 0; a < dim; ++a) os << (a ? ", " : "") << std::setprecision(6) << x[a];
  os << ")";
  return os.str();
}

nlohmann::ordered_json Place::json() const {
  nlohmann::ordered_json j;
  if (set.empty()) return j;
  j["set"] = set;
  j[set == "grid" ? "node" : "particle"] = id;
  j["position"] = std::vector<double>(x.begin(), x.begin() + dim);
  return j;
}

template <int Dim>
FrameIndicators measure(const State<Dim>& s, const GridFields* grid, const Energies& e,
                        const std::array<double, 3>& gravity, double elapsed) {
  FrameIndicators f;
  f.time = s.time;
  Motion motion;

  // Where the pore or free water's pressure lives: on the grid (mpm-fem), on the water points
  // (double-point), or on the soil points (single-point); a dry run has none.
  const scene::PointArray* grid_p = grid ? grid->cloud.find("pressure") : nullptr;
  const scene::PointArray* grid_phi = grid ? grid->cloud.find("phase_field") : nullptr;
  const bool on_grid = grid_p && grid_phi;
  const bool water_points = !on_grid && s.fluid.size() > 0 && s.fluid.p.size() == s.fluid.size();
  const bool soil_pressure = !on_grid && !water_points && s.solid.two_phase() && s.solid.size() > 0;

  if (s.solid.size() > 0) {
    const SetView<Dim> v(s.solid, "solid");
    const std::size_t n = s.solid.size();
    std::vector<double> a(n);
    if (!s.solid.sigma.empty()) {
      for (std::size_t p = 0; p < n; ++p) a[p] = mean_stress(s.solid.sigma[p]);  // Pa, effective, compression positive
      set_checkerboard(f, mean_stress_checkerboard, v, a);
    }
    for (std::size_t p = 0; p < n; ++p) a[p] = s.solid.V[p] / s.solid.V0[p];
    const Range J = range(a);
    f.value[J_min] = J.min, f.where[J_min] = v.place(J.at_min);
    f.value[J_max] = J.max, f.where[J_max] = v.place(J.at_max);
    if (s.solid.two_phase()) {
      const Range n_range = range(s.solid.n);
      f.value[porosity_min] = n_range.min, f.where[porosity_min] = v.place(n_range.at_min);
      f.value[porosity_max] = n_range.max, f.where[porosity_max] = v.place(n_range.at_max);
    } else {
      f.omitted[porosity_min] = f.omitted[porosity_max] = "a dry skeleton has no porosity";
    }
    if (soil_pressure) {
      set_checkerboard(f, pressure_checkerboard, v, s.solid.p);
      // Saturated points: those that carry pore fluid (m_f > 0 where the set has fluid masses).
      std::vector<double> pw;
      std::vector<long> index;
      for (std::size_t p = 0; p < n; ++p)
        if (s.solid.m_f.empty() || s.solid.m_f[p] > 0.0) pw.push_back(s.solid.p[p]), index.push_back(static_cast<long>(p));
      const Cavitation c = cavitation(pw);
      set_cavitation(f, pw, c.lowest >= 0 ? v.place(index[c.lowest]) : Place{});
    }
    add_motion(v, elapsed, motion);
  } else {
    f.omitted[mean_stress_checkerboard] = "no solid points";
    f.omitted[J_min] = f.omitted[J_max] = "no solid points";
    f.omitted[porosity_min] = f.omitted[porosity_max] = "no solid points";
  }

  if (s.fluid.size() > 0) {
    const SetView<Dim> w(s.fluid, "water");
    if (water_points) {
      set_checkerboard(f, pressure_checkerboard, w, s.fluid.p);
      const Cavitation c = cavitation(s.fluid.p);
      set_cavitation(f, s.fluid.p, w.place(c.lowest));
    }
    add_motion(w, elapsed, motion);
  }

  if (on_grid) {
    // The water's nodes (phi >= 1/2) of the lattice; radius 1.6 node spacings.
    std::vector<Point> x;
    std::vector<double> p;
    std::vector<long> node;
    for (std::size_t i = 0; i < grid->cloud.size(); ++i)
      if (grid_phi->values[i] >= 0.5) {
        x.push_back(grid->cloud.points[i]);
        p.push_back(grid_p->values[i]);
        node.push_back(static_cast<long>(i));
      }
    // The node spacing: the median gap along the first row (B-spline lattices put a node at h/2
    // from the boundary's, so the first gap is not the spacing).
    std::vector<double> gaps;
    for (int i = 0; i + 1 < grid->nodes[0] && static_cast<std::size_t>(i + 1) < grid->cloud.size(); ++i)
      gaps.push_back(std::abs(grid->cloud.points[i + 1][0] - grid->cloud.points[i][0]));
    double h = 1.0;
    if (!gaps.empty()) {
      std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2), gaps.end());
      h = gaps[gaps.size() / 2];
    }
    auto place = [&](long k) { return k < 0 ? Place{} : Place{"grid", node[k], x[k], Dim}; };
    if (!x.empty()) {
      const Neighbourhood nb(x, Dim, kRadiusInSpacings * h);
      const Checkerboard c = checkerboard(nb, p, kStressFloor);
      f.value[pressure_checkerboard] = c.index, f.where[pressure_checkerboard] = place(c.worst);
    }
    const Cavitation c = cavitation(p);
    set_cavitation(f, p, place(c.lowest));
  }
  if (!on_grid && !water_points && !soil_pressure)
    f.omitted[pressure_checkerboard] = f.omitted[cavitation_fraction] = "no pore or free water in this run";

  // The energy balance of the whole model; its place: the fastest point.
  f.value[energy_error] = energy_balance_error(e.kinetic, e.stored, e.initial, e.work);
  f.where[energy_error] = motion.fastest;

  // The at-rest speed over the run's velocity scale: the fastest point's speed, the largest mean
  // displacement rate since the start, and the gravity wave speed sqrt(|g| L) over the sets'
  // largest extent L, whichever is largest.
  if (s.solid.size() + s.fluid.size() == 0) {
    f.omitted[spurious_velocity] = "no points";
  } else if (motion.speed >= 0.0) {
    const double g = std::sqrt(gravity[0] * gravity[0] + gravity[1] * gravity[1] + gravity[2] * gravity[2]);
    f.velocity_scale = std::max({motion.speed_max, motion.displacement_rate, std::sqrt(g * motion.extent)});
    f.spurious_speed = motion.speed;
    f.value[spurious_velocity] = f.velocity_scale > 0.0 ? motion.speed / f.velocity_scale : 0.0;
    f.where[spurious_velocity] = motion.at;
  }
  return f;
}

template FrameIndicators measure<2>(const State<2>&, const GridFields*, const Energies&, const std::array<double, 3>&, double);
template FrameIndicators measure<3>(const State<3>&, const GridFields*, const Energies&, const std::array<double, 3>&, double);

// ---- the run's record ----------------------------------------------------------------------

std::vector<std::string> StabilityReport::add(const FrameIndicators& f) {
  std::vector<std::string> warnings;
  time_.push_back(f.time);
  spurious_speed_.push_back(f.spurious_speed);
  for (int k = 0; k < kIndicators; ++k) {
    const auto ind = static_cast<Indicator>(k);
    if (!f.omitted[k].empty() && omitted_[k].empty()) omitted_[k] = f.omitted[k];
    const double v = f.value[k];
    history_[k].push_back(v);
    if (std::isnan(v)) continue;
    Worst& w = worst_[k];
    const bool worse = std::isnan(w.value) || (kSpecs[k].above ? v > w.value : v < w.value);
    if (worse) {
      w.value = v;
      w.time = f.time;
      w.where = f.where[k];
    }
    if (!crosses(ind, v)) continue;
    if (w.crossings++ == 0) {
      std::ostringstream os;
      os << "warning: stability: " << kSpecs[k].label << " " << fmt(v) << (kSpecs[k].above ? " above" : " below")
         << " its threshold " << fmt(kSpecs[k].threshold) << " at t = " << fmt(f.time, 6) << " s, at "
         << f.where[k].text();
      if (k == spurious_velocity) os << " (" << fmt(f.spurious_speed) << " m/s of " << fmt(f.velocity_scale) << " m/s)";
      if (k == cavitation_fraction) os << " (" << f.cavitating << " of " << f.water_points << " below -100 kPa)";
      os << "; later frames that cross it are counted in the summary";
      warnings.push_back(os.str());
      warnings_.push_back(os.str());
    }
  }
  return warnings;
}

std::string StabilityReport::frame_line(const FrameIndicators& f) {
  std::ostringstream os;
  os << "stability at t = " << fmt(f.time, 6) << " s:";
  auto value = [&](Indicator k) { return std::isnan(f.value[k]) ? std::string("-") : fmt(f.value[k]); };
  if (f.omitted[pressure_checkerboard].empty()) os << " p checkerboard " << value(pressure_checkerboard) << ",";
  if (f.omitted[mean_stress_checkerboard].empty()) os << " p' checkerboard " << value(mean_stress_checkerboard) << ",";
  os << " energy error " << (std::isnan(f.value[energy_error]) ? std::string("-") : fmt(100.0 * f.value[energy_error], 3) + " %");
  if (!std::isnan(f.value[spurious_velocity]))
    os << ", at-rest speed " << fmt(f.spurious_speed) << " m/s (" << value(spurious_velocity) << " of " << fmt(f.velocity_scale)
       << " m/s)";
  if (f.omitted[porosity_min].empty()) os << ", porosity " << value(porosity_min) << " to " << value(porosity_max);
  if (f.omitted[J_min].empty()) os << ", J " << value(J_min) << " to " << value(J_max);
  if (f.omitted[cavitation_fraction].empty())
    os << ", cavitation " << f.cavitating << " of " << f.water_points << " with water";
  return os.str();
}

std::vector<std::string> StabilityReport::summary() const {
  std::vector<std::string> lines;
  std::ostringstream os;
  os << "stability over " << time_.size() << " frames (worst values):";
  const char* sep = " ";
  for (int k = 0; k < kIndicators; ++k) {
    if (!omitted_[k].empty() || std::isnan(worst_[k].value)) continue;
    os << sep << kSpecs[k].key << " " << fmt(worst_[k].value) << " (t = " << fmt(worst_[k].time) << " s)";
    sep = ", ";
  }
  lines.push_back(os.str());
  for (int k = 0; k < kIndicators; ++k) {
    const Worst& w = worst_[k];
    if (w.crossings == 0) continue;
    std::ostringstream c;
    c << "warning: stability: " << kSpecs[k].label << " crossed its threshold " << fmt(kSpecs[k].threshold) << " in "
      << w.crossings << " of " << time_.size() << " frames; worst " << fmt(w.value) << " at t = " << fmt(w.time, 6)
      << " s, at " << w.where.text();
    lines.push_back(c.str());
  }
  return lines;
}

nlohmann::ordered_json StabilityReport::json() const {
  using J = nlohmann::ordered_json;
  J j;
  J thresholds = J::object();
  for (int k = 0; k < kIndicators; ++k) thresholds[kSpecs[k].key] = {{kSpecs[k].above ? "above" : "below", kSpecs[k].threshold}};
  j["thresholds"] = thresholds;
  J omitted = J::object();
  for (int k = 0; k < kIndicators; ++k)
    if (!omitted_[k].empty()) omitted[kSpecs[k].key] = omitted_[k];
  j["omitted"] = omitted;
  J frames = J::object();
  frames["time"] = time_;
  // NaN (not measured at that frame) is written as null.
  for (int k = 0; k < kIndicators; ++k)
    if (omitted_[k].empty()) frames[kSpecs[k].key] = history_[k];
  frames["spurious_speed"] = spurious_speed_;
  j["frames"] = frames;
  J worst = J::object();
  for (int k = 0; k < kIndicators; ++k) {
    const Worst& w = worst_[k];
    if (!omitted_[k].empty() || std::isnan(w.value)) {
      worst[kSpecs[k].key] = nullptr;
      continue;
    }
    J e;
    e["value"] = w.value;
    e["time"] = w.time;
    e["where"] = w.where.json();
    e["crossed_frames"] = w.crossings;
    worst[kSpecs[k].key] = e;
  }
  j["worst"] = worst;
  j["warnings"] = warnings_;
  j["seconds"] = seconds_;
  return j;
}

void StabilityReport::restore(const nlohmann::ordered_json& j) {
  *this = StabilityReport();
  auto numbers = [](const nlohmann::ordered_json& a) {
    std::vector<double> v;
    for (const auto& x : a) v.push_back(x.is_null() ? std::numeric_limits<double>::quiet_NaN() : x.get<double>());
    return v;
  };
  const auto& frames = j.at("frames");
  time_ = numbers(frames.at("time"));
  spurious_speed_ = numbers(frames.at("spurious_speed"));
  for (int k = 0; k < kIndicators; ++k) {
    const char* key = kSpecs[k].key;
    if (j.at("omitted").contains(key)) omitted_[k] = j.at("omitted").at(key).get<std::string>();
    history_[k] = frames.contains(key) ? numbers(frames.at(key))
                                       : std::vector<double>(time_.size(), std::numeric_limits<double>::quiet_NaN());
    const auto& w = j.at("worst").at(key);
    if (w.is_null()) continue;
    worst_[k].value = w.at("value").get<double>();
    worst_[k].time = w.at("time").get<double>();
    worst_[k].crossings = w.at("crossed_frames").get<int>();
    const auto& at = w.at("where");
    if (!at.is_null() && at.contains("set")) {
      Place& p = worst_[k].where;
      p.set = at.at("set").get<std::string>();
      p.id = at.at(p.set == "grid" ? "node" : "particle").get<long>();
      const auto x = at.at("position").get<std::vector<double>>();
      p.dim = static_cast<int>(x.size());
      for (std::size_t a = 0; a < x.size() && a < 3; ++a) p.x[a] = x[a];
    }
  }
  warnings_ = j.at("warnings").get<std::vector<std::string>>();
  seconds_ = j.at("seconds").get<double>();
}

}  // namespace swmpm::diagnostics
