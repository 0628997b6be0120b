// Stability indicators of one frame (issue 26, item 4): the measures themselves, on plain arrays
// of points and values. The time loop takes them at every frame through diagnostics/stability.hpp;
// the tests take them through tests/support/indicators.hpp, which calls these functions, so that
// the suite and the user see the same numbers. Definitions and thresholds: docs/verification.md,
// "Stability indicators of every run".
//
// Cost: a frame sorts each point set once by bin (N log N) and fits one small least-squares plane
// per point and field; nothing here runs per step. Per-point work runs on OpenMP threads into
// per-point arrays; every reduction is then a serial pass over those arrays in index order, so the
// results do not depend on the thread count.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace swmpm::diagnostics {

using Point = std::array<double, 3>;  // m; z = 0 in 2D

/// The radius of the neighbourhoods, in typical point spacings: 1.6 spacings hold a lattice
/// point's 8 (2D) or 18 (3D) nearest and diagonal neighbours and none beyond.
inline constexpr double kRadiusInSpacings = 1.6;
/// A point enters the checkerboard index only with at least this many neighbours within the
/// radius (2D: 6 of the 8 of an interior lattice point; 3D: 14 of 18), so that the plane's fit is
/// over-determined and points on free surfaces, edges and corners (5 and 13 or fewer) stay out.
inline constexpr int kMinNeighbours2D = 6;
inline constexpr int kMinNeighbours3D = 14;
/// The checkerboard index divides by max(range, relative floor x max |value|, absolute floor):
/// a nearly uniform field (round-off only) is not judged as rough. The runs' fields are pressures
/// and stresses, with the absolute floor 1 Pa; a field of another unit (the tests' porosity)
/// passes its own (0 by default).
inline constexpr double kRangeRelativeFloor = 0.01;
inline constexpr double kStressFloor = 1.0;  // Pa
/// "At rest": a point whose displacement since t = 0 and whose every neighbour's displacement are
/// at most this fraction of the largest displacement of its set. 5 %: under self-weight a
/// column's displacement grows as 2y/H near its fixed base, so with 4 points per 0.05 m cell in a
/// 1 m column the two bottom rows (1.25 % and 3.75 %) are at rest; at 1 % nothing would be.
inline constexpr double kAtRestFraction = 0.05;
/// Cavitation bound: water at about -100 kPa gauge pressure (one atmosphere below atmospheric)
/// cavitates; p is gauge, compression positive.
inline constexpr double kCavitationBound = -1.0e5;  // Pa

/// The typical spacing of a set's points: the median over the points of V0^(1/dim) (V0 the
/// initial volume, m^3, or the area per metre, m^2, in 2D). 0 for an empty set.
double typical_spacing(std::span<const double> V0, int dim);
/// A point's spacing from its initial volume: V0^(1/dim) (0 for V0 <= 0).
inline double spacing_of(double V0, int dim) { return std::pow(std::max(V0, 0.0), 1.0 / dim); }

/// The lowest corner of the points' finite coordinates (0 on an axis where none is finite): where
/// a Neighbourhood's bins start.
Point lowest_corner(std::span<const Point> x);

/// Points of one set (positions copied) with a fixed-radius neighbour search: the points sorted by
/// their bin (cubes or squares of side `radius` from `origin`, sorted z, y, x, then by key), so
/// that one binary search finds the three consecutive bins of a row. Any spread of positions costs
/// memory in proportion to the points only.
///
/// By default the origin is the points' lowest corner and a point's key its index. Ranks that
/// each measure their share of a set (with copies of the other ranks' points near it) pass the
/// whole set's lowest corner and the particles' keys (their one-rank storage order): every point
/// then meets its neighbours in the order the one-rank run does, and its sums have the same bits.
class Neighbourhood {
 public:
  Neighbourhood(std::span<const Point> x, int dim, double radius);
  Neighbourhood(std::span<const Point> x, int dim, double radius, const Point& origin,
                std::span<const std::int64_t> keys);
  std::size_t size() const { return x_.size(); }
  int dim() const { return dim_; }
  double radius() const { return radius_; }
  const Point& x(std::size_t p) const { return x_[p]; }
  /// Calls f(q) for every point q != p within the radius of point p, in a fixed order (the bins'
  /// order, then the index).
  template <class F>
  void for_each_neighbour(std::size_t p, F&& f) const {
    const Bin& b = bin_[p];
    const std::int64_t dz = dim_ == 3 ? 1 : 0;
    const double r2 = radius_ * radius_;
    for (std::int64_t k = b[2] - dz; k <= b[2] + dz; ++k)
      for (std::int64_t j = b[1] - 1; j <= b[1] + 1; ++j) {
        const Bin last{b[0] + 1, j, k};
        for (std::size_t e = first_at({b[0] - 1, j, k}); e < sorted_.size() && !after(bin_[sorted_[e]], last); ++e) {
          const std::size_t q = sorted_[e];
          if (q == p) continue;
          double d2 = 0.0;
          for (int a = 0; a < 3; ++a) d2 += (x_[q][a] - x_[p][a]) * (x_[q][a] - x_[p][a]);
          if (d2 <= r2) f(q);
        }
      }
  }

 private:
  using Bin = std::array<std::int64_t, 3>;  // x, y, z; compared z first
  static bool after(const Bin& a, const Bin& b) {  // a > b in the order z, y, x
    if (a[2] != b[2]) return a[2] > b[2];
    if (a[1] != b[1]) return a[1] > b[1];
    return a[0] > b[0];
  }
  std::size_t first_at(const Bin& b) const;  // the first sorted entry whose bin is not before b
  std::vector<Point> x_;
  int dim_;
  double radius_;
  std::vector<Bin> bin_;               // per point
  std::vector<std::uint32_t> sorted_;  // point indices by (bin, index)
};

/// Checkerboard index of a scalar field on points: each point with enough neighbours (above) is
/// compared with the least-squares plane a + b.(x_q - x_p) through its neighbours' values; the
/// index is the RMS of those residuals divided by the field's scale, max(max - min,
/// kRangeRelativeFloor max|v|, absolute_floor). A smooth field gives ~0 (only curvature remains),
/// a checkerboard of amplitude A on a field of range R A/R (2D; 2A/(3R) on a 3D lattice).
struct Checkerboard {
  double index = 0.0;     // -, rms / scale
  double rms = 0.0;       // the field's unit
  double scale = 0.0;     // the field's unit
  std::size_t fitted = 0;  // points with a fit
  long worst = -1;        // the point with the largest |residual| (-1: none fitted)
  double worst_residual = 0.0;
};
Checkerboard checkerboard(const Neighbourhood& nb, std::span<const double> value, double absolute_floor = 0.0);
/// The largest |value| (0 for none): with the range, what the index's scale reads.
double largest_magnitude(std::span<const double> value);

/// The index in parts, for ranks that each hold a share of the points: the scale from the whole
/// field's smallest and largest value and largest |value|; each rank's residuals of its own points
/// [0, owned) (their neighbours may lie beyond: the other ranks' points near it); the index from
/// the parts summed (`worst` then indexes the rank's points that had it).
double checkerboard_scale(double min, double max, double largest, double absolute_floor);
struct CheckerboardPart {
  double sum_squares = 0.0;
  std::size_t fitted = 0;
  long worst = -1;
  double worst_residual = 0.0;
};
CheckerboardPart checkerboard_part(const Neighbourhood& nb, std::span<const double> value, std::size_t owned);
Checkerboard checkerboard_of(const CheckerboardPart& whole, double scale);

/// The largest speed among the points at rest (kAtRestFraction above). No point is at rest
/// before anything has moved (largest displacement 0).
struct AtRest {
  std::size_t count = 0;          // points at rest
  double speed = 0.0;             // m/s, the largest speed among them
  long worst = -1;                // that point (-1: none at rest)
  double displacement_max = 0.0;  // m, the set's largest displacement
  double speed_max = 0.0;         // m/s, the set's largest speed
  long fastest = -1;
};
AtRest at_rest(const Neighbourhood& nb, std::span<const double> displacement, std::span<const double> speed,
               double fraction = kAtRestFraction);
/// The set's largest displacement, its largest speed and the first point that has it (fills
/// displacement_max, speed_max and fastest; `speed` may be shorter than `displacement`: its points).
void largest_motion(std::span<const double> displacement, std::span<const double> speed, AtRest& a);
/// A rank's part: its own points [0, owned) at rest, judged against `bound` (the fraction of the
/// whole set's largest displacement, m) over all their neighbours; fills count, speed and worst.
void at_rest_part(const Neighbourhood& nb, std::span<const double> displacement, std::span<const double> speed,
                  double bound, std::size_t owned, AtRest& a);

/// The smallest and largest value and where (the first index of each). Empty: NaN, -1.
struct Range {
  double min = std::numeric_limits<double>::quiet_NaN(), max = std::numeric_limits<double>::quiet_NaN();
  long at_min = -1, at_max = -1;
};
Range range(std::span<const double> value);

/// Points whose pressure p (gauge, compression positive) is below `bound`, of `p.size()`.
struct Cavitation {
  std::size_t points = 0, below = 0;
  double fraction = 0.0;  // below / points (0 without points)
  double p_min = std::numeric_limits<double>::quiet_NaN();  // Pa
  long lowest = -1;
};
Cavitation cavitation(std::span<const double> p, double bound = kCavitationBound);

/// Energy balance error: (K + U - E0 - W) / max(|E0| + |W|, |K + U|, floor), with K + U the
/// kinetic and stored energy now, E0 their sum at the start and W the work of gravity and loads
/// since. Positive: energy the scheme created; negative: what damping, drag, plasticity and PIC
/// dissipated (physical). floor: J (J/m in 2D) below which nothing is judged (0 then).
double energy_balance_error(double kinetic, double stored, double initial, double work, double floor = 1e-9);

}  // namespace swmpm::diagnostics
