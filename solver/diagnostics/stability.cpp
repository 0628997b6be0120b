// A frame's stability indicators from the state, and the run's record of them (stability.hpp).
#include "solver/diagnostics/stability.hpp"

#include <algorithm>
#include <cmath>
#include <bit>
#include <cstring>
#include <iomanip>
#include <numeric>
#include <optional>
#include <sstream>

#include "solver/common.hpp"
#include "solver/diagnostics/indicators.hpp"
#include "solver/parallel/comm.hpp"

namespace swmpm::diagnostics {

namespace {

std::string fmt(double v, int prec = 4) {
  std::ostringstream os;
  os << std::setprecision(prec) << v;
  return os.str();
}

constexpr double kInf = std::numeric_limits<double>::infinity();

/// A point that holds a frame's extreme value on one rank (key -1: none there), and the one the
/// whole run's loop over the set in key order finds first: the largest value (`larger`) or the
/// smallest, the smaller key among equal values, a point of set `set`. Collective; at one rank it
/// is `mine`.
struct Candidate {
  double value = std::numeric_limits<double>::quiet_NaN();
  std::int64_t key = -1;
  Place place;
};

Candidate best_over_ranks(const Candidate& mine, bool larger, const char* set, int dim) {
  if (!parallel::distributed()) return mine;
  std::vector<char> bytes(sizeof(double) * 6);
  const double id = static_cast<double>(mine.place.id);  // ids below 2^53
  const double fields[6] = {mine.value, static_cast<double>(mine.key), id, mine.place.x[0], mine.place.x[1], mine.place.x[2]};
  std::memcpy(bytes.data(), fields, sizeof fields);
  Candidate best;
  best.place.set = set;
  best.place.dim = dim;
  for (const auto& part : parallel::all_gather(bytes)) {
    double got[6];
    std::memcpy(got, part.data(), sizeof got);
    const auto key = static_cast<std::int64_t>(got[1]);
    if (key < 0) continue;
    const double v = got[0];
    const bool better = best.key < 0 || (larger ? v > best.value : v < best.value) || (v == best.value && key < best.key);
    if (!better) continue;
    best.value = v;
    best.key = key;
    best.place.id = static_cast<long>(got[2]);
    best.place.x = {got[3], got[4], got[5]};
  }
  if (best.key < 0) best.place = {};
  return best;
}

/// A set as this rank measures it: its own points first ([0, owned), in key order), then copies of
/// the other ranks' points within the neighbourhood radius (1.6 typical spacings) of its own
/// points' bounding box (ghosts), with what the neighbour measures read of them: the displacement,
/// and the mean effective stress and pore pressure when the set has them. The bins start at the
/// whole set's lowest corner and the points meet their neighbours in key order, so every own
/// point's neighbour sums are those of the one-rank run. One rank: no ghosts, keys the indices.
template <int Dim>
struct SetView {
  const ParticleSet<Dim>& ps;
  const char* name;
  long whole = 0;          // points of the set over all ranks
  std::size_t owned = 0;   // this rank's
  std::vector<Point> x;    // m
  std::vector<std::int64_t> key;
  std::vector<double> u;            // m, |x - x0|
  std::vector<double> mean_stress;  // Pa, effective, compression positive (with_stress)
  std::vector<double> p;            // Pa, pore or water pressure (with_pressure)
  std::array<double, 6> box;        // m, lowest and highest finite coordinates of the own points
  std::array<double, 6> whole_box;  // m, the same over the ranks (the whole set's)
  std::optional<Neighbourhood> nb;

  SetView(const ParticleSet<Dim>& set, const char* set_name, long whole_size, bool with_stress, bool with_pressure)
      : ps(set), name(set_name), whole(whole_size), owned(set.size()) {
    x.assign(owned, Point{0, 0, 0});
    key.resize(owned);
    u.resize(owned);
    for (std::size_t q = 0; q < owned; ++q) {
      for (int a = 0; a < Dim; ++a) x[q][a] = ps.x[q][a];
      key[q] = ps.key.empty() ? static_cast<std::int64_t>(q) : ps.key[q];
      u[q] = (ps.x[q] - ps.x0[q]).norm();
    }
    if (with_stress) {
      mean_stress.resize(owned);
      for (std::size_t q = 0; q < owned; ++q) mean_stress[q] = swmpm::mean_stress(ps.sigma[q]);
    }
    if (with_pressure) p.assign(ps.p.begin(), ps.p.begin() + static_cast<std::ptrdiff_t>(owned));
    const double s = typical_spacing_over_ranks(ps.V0, Dim, whole);
    const double radius = s > 0.0 ? kRadiusInSpacings * s : 1.0;
    // This rank's box, and the whole set's (highest corner negated for one min over the ranks).
    box = {kInf, kInf, kInf, -kInf, -kInf, -kInf};
    for (const auto& q : x)
      for (int a = 0; a < 3; ++a)
        if (std::isfinite(q[a])) box[a] = std::min(box[a], q[a]), box[3 + a] = std::max(box[3 + a], q[a]);
    whole_box = box;
    for (int a = 3; a < 6; ++a) whole_box[a] = -whole_box[a];
    parallel::min(std::span<double>(whole_box));
    for (int a = 3; a < 6; ++a) whole_box[a] = -whole_box[a];
    // The bins' origin: the whole set's lowest corner (lowest_corner over the ranks).
    Point lo{0, 0, 0};
    for (int a = 0; a < 3; ++a) lo[a] = whole_box[a] == kInf ? 0.0 : whole_box[a];
    if (parallel::distributed()) add_ghosts(radius, with_stress, with_pressure);
    nb.emplace(x, Dim, radius, lo, key);
  }

  /// Every rank's bounding box of its own finite points; each rank sends those of its points within
  /// `radius` of another's box to it (one all-to-all). Collective.
  void add_ghosts(double radius, bool with_stress, bool with_pressure) {
    std::vector<char> mine(sizeof box);
    std::memcpy(mine.data(), box.data(), sizeof box);
    const auto boxes = parallel::all_gather(mine);
    constexpr std::size_t kRecord = 7;  // key, x, y, z, u, mean stress, p
    std::vector<std::vector<char>> to(boxes.size());
    for (std::size_t r = 0; r < boxes.size(); ++r) {
      if (static_cast<int>(r) == parallel::rank()) continue;
      std::array<double, 6> b;
      std::memcpy(b.data(), boxes[r].data(), sizeof b);
      auto near = [&](const Point& q) {
        for (int a = 0; a < Dim; ++a)
          if (!(q[a] >= b[a] - radius && q[a] <= b[3 + a] + radius)) return false;
        return true;
      };
      if (!(b[0] <= b[3])) continue;  // a rank without points
      std::vector<double> records;
      for (std::size_t q = 0; q < owned; ++q) {
        if (!near(x[q])) continue;
        records.insert(records.end(), {std::bit_cast<double>(key[q]), x[q][0], x[q][1], x[q][2], u[q],
                                       with_stress ? mean_stress[q] : 0.0, with_pressure ? p[q] : 0.0});
      }
      to[r].resize(records.size() * sizeof(double));
      std::memcpy(to[r].data(), records.data(), to[r].size());
    }
    for (const auto& part : parallel::all_to_all(to)) {
      const std::size_t n = part.size() / (kRecord * sizeof(double));
      for (std::size_t g = 0; g < n; ++g) {
        double r[kRecord];
        std::memcpy(r, part.data() + g * sizeof r, sizeof r);
        key.push_back(std::bit_cast<std::int64_t>(r[0]));
        x.push_back({r[1], r[2], r[3]});
        u.push_back(r[4]);
        if (with_stress) mean_stress.push_back(r[5]);
        if (with_pressure) p.push_back(r[6]);
      }
    }
  }

  Place place(long k) const {
    if (k < 0) return {};
    return {name, static_cast<long>(ps.id[static_cast<std::size_t>(k)]), x[static_cast<std::size_t>(k)], Dim};
  }
  /// The candidate of own point k (-1: none) with `value`, and the best over the ranks.
  Candidate best(double value, long k, bool larger) const {
    Candidate c;
    if (k >= 0) c = {value, key[static_cast<std::size_t>(k)], place(k)};
    return best_over_ranks(c, larger, name, Dim);
  }
  /// The smallest and largest of own points' `value` and where, over the ranks.
  std::pair<Candidate, Candidate> range_over_ranks(std::span<const double> value) const {
    const Range r = range(value.first(owned));
    return {best(r.min, r.at_min, false), best(r.max, r.at_max, true)};
  }
  /// The largest extent of the whole set's bounding box [m].
  double extent() const {
    double e = 0.0;
    for (int a = 0; a < Dim; ++a) e = std::max(e, whole_box[3 + a] - whole_box[a]);
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

/// at_rest over the ranks: the set's largest displacement is reduced first, then each rank judges
/// its own points against their neighbours (ghosts included).
template <int Dim>
void add_motion(const SetView<Dim>& v, double elapsed, Motion& m) {
  const std::size_t n = v.owned;
  std::vector<double> speed(n);
  for (std::size_t p = 0; p < n; ++p) speed[p] = v.ps.v[p].norm();
  AtRest a;
  largest_motion(v.u, speed, a);  // over this rank's points (speed has those only)
  a.displacement_max = parallel::max(a.displacement_max);
  const Candidate fastest = v.best(a.speed_max, a.fastest, true);
  // Nothing has moved: no region is "at rest" relative to motion.
  if (a.displacement_max > 0.0) at_rest_part(*v.nb, v.u, speed, kAtRestFraction * a.displacement_max, n, a);
  const long count = parallel::sum(static_cast<long>(a.count));
  const Candidate rest = v.best(a.speed, a.count > 0 ? a.worst : -1, true);
  if (count > 0 && rest.value > m.speed) {
    m.speed = rest.value;
    m.at = rest.place;
  }
  if (elapsed > 0.0) m.displacement_rate = std::max(m.displacement_rate, a.displacement_max / elapsed);
  if (fastest.key >= 0 && (m.fastest.set.empty() || fastest.value > m.speed_max)) {
    m.speed_max = fastest.value;
    m.fastest = fastest.place;
  }
  m.extent = std::max(m.extent, v.extent());
}

/// The checkerboard index over the ranks: the scale from the reduced range, the residual sums of
/// each rank's own points added (their order differs from one rank's: round-off), the worst
/// residual's point the one-rank run's.
template <int Dim>
void set_checkerboard(FrameIndicators& f, Indicator k, const SetView<Dim>& v, const std::vector<double>& value) {
  const std::span<const double> own(value.data(), v.owned);
  const Range r = range(own);
  const double scale = checkerboard_scale(parallel::min(v.owned ? r.min : kInf), parallel::max(v.owned ? r.max : -kInf),
                                          parallel::max(largest_magnitude(own)), kStressFloor);
  f.value[k] = 0.0;
  f.where[k] = {};
  if (!(scale > 0.0) || !std::isfinite(scale)) return;
  CheckerboardPart part = checkerboard_part(*v.nb, value, v.owned);
  const Candidate worst = v.best(std::abs(part.worst_residual), part.worst, true);
  part.sum_squares = parallel::sum(part.sum_squares);
  part.fitted = static_cast<std::size_t>(parallel::sum(static_cast<long>(part.fitted)));
  f.value[k] = checkerboard_of(part, scale).index;
  f.where[k] = worst.place;
}

/// The cavitating fraction over the ranks, of this rank's pressures `p` at points `index` of v.
template <int Dim>
void set_cavitation(FrameIndicators& f, const SetView<Dim>& v, std::span<const double> p, const std::vector<long>& index) {
  const Cavitation c = cavitation(p);
  const Candidate lowest = v.best(c.p_min, c.lowest >= 0 ? index[static_cast<std::size_t>(c.lowest)] : -1, false);
  f.water_points = static_cast<std::size_t>(parallel::sum(static_cast<long>(c.points)));
  f.cavitating = static_cast<std::size_t>(parallel::sum(static_cast<long>(c.below)));
  f.value[cavitation_fraction] = f.water_points ? static_cast<double>(f.cavitating) / static_cast<double>(f.water_points) : 0.0;
  f.where[cavitation_fraction] = lowest.place;
}

/// The grid's cavitation (mpm-fem; the grid is whole on the rank that measures it).
void set_cavitation(FrameIndicators& f, std::span<const double> p, const Place& lowest) {
  const Cavitation c = cavitation(p);
  f.value[cavitation_fraction] = c.fraction;
  f.where[cavitation_fraction] = lowest;
  f.water_points = c.points;
  f.cavitating = c.below;
}
}  // namespace

// Bisection on the spacings' bits (non-negative doubles order as their bits), one count over the
// ranks per bit: 63 sums at most.
double typical_spacing_over_ranks(std::span<const double> V0, int dim, long whole) {
  if (!parallel::distributed()) return typical_spacing(V0, dim);
  if (whole == 0) return 0.0;
  std::vector<std::uint64_t> bits(V0.size());
  for (std::size_t p = 0; p < V0.size(); ++p) {
    const double s = spacing_of(V0[p], dim);
    bits[p] = std::bit_cast<std::uint64_t>(s >= 0.0 ? s : kInf);
  }
  std::sort(bits.begin(), bits.end());
  // The k-th smallest (k = whole / 2, from 0, as typical_spacing's nth_element): the smallest u
  // with at least k + 1 spacings of bits <= u.
  const long k = whole / 2;
  std::uint64_t lo = 0, hi = std::bit_cast<std::uint64_t>(kInf);
  while (lo < hi) {
    const std::uint64_t mid = lo + (hi - lo) / 2;
    const long below = parallel::sum(static_cast<long>(std::upper_bound(bits.begin(), bits.end(), mid) - bits.begin()));
    if (below >= k + 1) hi = mid;
    else lo = mid + 1;
  }
  return std::bit_cast<double>(lo);
}

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
  // mpirun: each rank holds its share of the sets (and rank 0 the grid fields); every decision
  // below is taken on the whole run's counts, so that the ranks meet in the same collectives.
  const long solid_points = parallel::sum(static_cast<long>(s.solid.size()));
  const long water_points_n = parallel::sum(static_cast<long>(s.fluid.size()));

  // Where the pore or free water's pressure lives: on the grid (mpm-fem), on the water points
  // (double-point), or on the soil points (single-point); a dry run has none.
  const scene::PointArray* grid_p = grid ? grid->cloud.find("pressure") : nullptr;
  const scene::PointArray* grid_phi = grid ? grid->cloud.find("phase_field") : nullptr;
  const bool on_grid = parallel::any(grid_p && grid_phi);
  const bool water_points =
      !on_grid && parallel::any(s.fluid.size() > 0 && s.fluid.p.size() == s.fluid.size());
  const bool soil_pressure = !on_grid && !water_points && s.solid.two_phase() && solid_points > 0;

  if (solid_points > 0) {
    const bool stress = parallel::any(s.solid.size() > 0 && !s.solid.sigma.empty());
    const SetView<Dim> v(s.solid, "solid", solid_points, stress, soil_pressure);
    const std::size_t n = s.solid.size();
    if (stress) set_checkerboard(f, mean_stress_checkerboard, v, v.mean_stress);
    std::vector<double> a(n);
    for (std::size_t p = 0; p < n; ++p) a[p] = s.solid.V[p] / s.solid.V0[p];
    const auto [J_lo, J_hi] = v.range_over_ranks(a);
    f.value[J_min] = J_lo.value, f.where[J_min] = J_lo.place;
    f.value[J_max] = J_hi.value, f.where[J_max] = J_hi.place;
    if (s.solid.two_phase()) {
      const auto [n_lo, n_hi] = v.range_over_ranks(s.solid.n);
      f.value[porosity_min] = n_lo.value, f.where[porosity_min] = n_lo.place;
      f.value[porosity_max] = n_hi.value, f.where[porosity_max] = n_hi.place;
    } else {
      f.omitted[porosity_min] = f.omitted[porosity_max] = "a dry skeleton has no porosity";
    }
    if (soil_pressure) {
      set_checkerboard(f, pressure_checkerboard, v, v.p);
      // Saturated points: those that carry pore fluid (m_f > 0 where the set has fluid masses).
      std::vector<double> pw;
      std::vector<long> index;
      for (std::size_t p = 0; p < n; ++p)
        if (s.solid.m_f.empty() || s.solid.m_f[p] > 0.0) pw.push_back(s.solid.p[p]), index.push_back(static_cast<long>(p));
      set_cavitation(f, v, pw, index);
    }
    add_motion(v, elapsed, motion);
  } else {
    f.omitted[mean_stress_checkerboard] = "no solid points";
    f.omitted[J_min] = f.omitted[J_max] = "no solid points";
    f.omitted[porosity_min] = f.omitted[porosity_max] = "no solid points";
  }

  if (water_points_n > 0) {
    const SetView<Dim> w(s.fluid, "water", water_points_n, false, water_points);
    if (water_points) {
      set_checkerboard(f, pressure_checkerboard, w, w.p);
      std::vector<long> index(s.fluid.size());
      std::iota(index.begin(), index.end(), 0L);
      set_cavitation(f, w, std::span<const double>(w.p.data(), w.owned), index);
    }
    add_motion(w, elapsed, motion);
  }

  if (on_grid && grid_p && grid_phi) {  // the rank that holds the grid fields (rank 0)
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
  if (solid_points + water_points_n == 0) {
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
