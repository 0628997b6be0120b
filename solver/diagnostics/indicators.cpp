// The stability indicators' measures (indicators.hpp).
#include "solver/diagnostics/indicators.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

namespace swmpm::diagnostics {

double typical_spacing(std::span<const double> V0, int dim) {
  if (V0.empty()) return 0.0;
  std::vector<double> s(V0.size());
  for (std::size_t p = 0; p < V0.size(); ++p) s[p] = spacing_of(V0[p], dim);
  const auto mid = s.begin() + static_cast<std::ptrdiff_t>(s.size() / 2);
  std::nth_element(s.begin(), mid, s.end());
  return *mid;
}

Point lowest_corner(std::span<const Point> x) {
  Point lo{0, 0, 0};
  for (int a = 0; a < 3; ++a) {
    bool any = false;
    for (const auto& q : x)
      if (std::isfinite(q[a])) lo[a] = any ? std::min(lo[a], q[a]) : q[a], any = true;
  }
  return lo;
}

Neighbourhood::Neighbourhood(std::span<const Point> x, int dim, double radius)
    : Neighbourhood(x, dim, radius, lowest_corner(x), {}) {}

Neighbourhood::Neighbourhood(std::span<const Point> x, int dim, double radius, const Point& lo,
                             std::span<const std::int64_t> keys)
    : x_(x.begin(), x.end()), dim_(dim), radius_(radius) {
  if (dim != 2 && dim != 3) throw std::invalid_argument("Neighbourhood: dim must be 2 or 3");
  if (!(radius > 0.0)) throw std::invalid_argument("Neighbourhood: the radius must be positive");
  const std::size_t n = x_.size();
  if (!keys.empty() && keys.size() != n) throw std::invalid_argument("Neighbourhood: one key per point expected");
  bin_.resize(n);
  // Bins of side `radius` from the lowest corner; a bin index is clamped far beyond any grid (a
  // non-finite position lands in bin 0, where its distance to every point is NaN: no neighbour).
  constexpr double far = 1e15;
  for (std::size_t p = 0; p < n; ++p)
    for (int a = 0; a < 3; ++a) {
      const double b = std::floor((x_[p][a] - lo[a]) / radius);
      bin_[p][a] = std::isfinite(b) ? static_cast<std::int64_t>(std::clamp(b, -far, far)) : 0;
    }
  sorted_.resize(n);
  for (std::size_t p = 0; p < n; ++p) sorted_[p] = static_cast<std::uint32_t>(p);
  auto key = [&](std::uint32_t p) { return keys.empty() ? std::int64_t{p} : keys[p]; };
  std::sort(sorted_.begin(), sorted_.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (after(bin_[b], bin_[a])) return true;
    if (after(bin_[a], bin_[b])) return false;
    return key(a) < key(b);
  });
}

std::size_t Neighbourhood::first_at(const Bin& b) const {
  // The first entry whose bin is not before b.
  const auto it = std::partition_point(sorted_.begin(), sorted_.end(), [&](std::uint32_t q) { return after(b, bin_[q]); });
  return static_cast<std::size_t>(it - sorted_.begin());
}

namespace {

/// The residual of point p against the least-squares plane through its neighbours' values, or
/// NaN with fewer than `min_neighbours` of them. Dim + 1 unknowns: the value at x_p and the
/// gradient; coordinates relative to x_p.
template <int Dim>
double plane_residual(const Neighbourhood& nb, std::span<const double> value, std::size_t p, int min_neighbours) {
  using Vector = Eigen::Matrix<double, Dim + 1, 1>;
  using Matrix = Eigen::Matrix<double, Dim + 1, Dim + 1>;
  Matrix A = Matrix::Zero();
  Vector b = Vector::Zero();
  int neighbours = 0;
  const Point& xp = nb.x(p);
  nb.for_each_neighbour(p, [&](std::size_t q) {
    Vector row;
    row[0] = 1.0;
    for (int a = 0; a < Dim; ++a) row[a + 1] = nb.x(q)[a] - xp[a];
    A += row * row.transpose();
    b += row * value[q];
    ++neighbours;
  });
  if (neighbours < min_neighbours) return std::numeric_limits<double>::quiet_NaN();
  const double fit = A.ldlt().solve(b)[0];
  return value[p] - fit;
}

}  // namespace

double largest_magnitude(std::span<const double> value) {
  double largest = 0.0;
  for (double v : value) largest = std::max(largest, std::abs(v));
  return largest;
}

double checkerboard_scale(double min, double max, double largest, double absolute_floor) {
  return std::max({max - min, kRangeRelativeFloor * largest, absolute_floor});
}

CheckerboardPart checkerboard_part(const Neighbourhood& nb, std::span<const double> value, std::size_t owned) {
  CheckerboardPart c;
  if (value.size() != nb.size() || owned > nb.size())
    throw std::invalid_argument("checkerboard: one value per point expected");
  std::vector<double> residual(owned);
  const int min_neighbours = nb.dim() == 3 ? kMinNeighbours3D : kMinNeighbours2D;
  const long m = static_cast<long>(owned);
#pragma omp parallel for schedule(static) if (m > 2048)
  for (long p = 0; p < m; ++p)
    residual[p] = nb.dim() == 3 ? plane_residual<3>(nb, value, static_cast<std::size_t>(p), min_neighbours)
                                : plane_residual<2>(nb, value, static_cast<std::size_t>(p), min_neighbours);
  for (std::size_t p = 0; p < owned; ++p) {  // in index order: the same bits for any thread count
    const double e = residual[p];
    if (std::isnan(e)) continue;
    c.sum_squares += e * e;
    ++c.fitted;
    if (c.worst < 0 || std::abs(e) > std::abs(c.worst_residual)) {
      c.worst = static_cast<long>(p);
      c.worst_residual = e;
    }
  }
  return c;
}

Checkerboard checkerboard_of(const CheckerboardPart& whole, double scale) {
  Checkerboard c;
  c.scale = scale;
  c.fitted = whole.fitted;
  c.worst = whole.worst;
  c.worst_residual = whole.worst_residual;
  if (c.fitted == 0) return c;
  c.rms = std::sqrt(whole.sum_squares / static_cast<double>(c.fitted));
  c.index = c.rms / c.scale;
  return c;
}

Checkerboard checkerboard(const Neighbourhood& nb, std::span<const double> value, double absolute_floor) {
  const std::size_t n = nb.size();
  if (value.size() != n) throw std::invalid_argument("checkerboard: one value per point expected");
  Checkerboard c;
  if (n == 0) return c;
  const Range r = range(value);
  c.scale = checkerboard_scale(r.min, r.max, largest_magnitude(value), absolute_floor);
  if (!(c.scale > 0.0) || !std::isfinite(c.scale)) return c;
  return checkerboard_of(checkerboard_part(nb, value, n), c.scale);
}

AtRest at_rest(const Neighbourhood& nb, std::span<const double> displacement, std::span<const double> speed,
               double fraction) {
  AtRest a;
  const std::size_t n = nb.size();
  if (displacement.size() != n || speed.size() != n)
    throw std::invalid_argument("at_rest: one displacement and one speed per point expected");
  largest_motion(displacement, speed, a);
  if (!(a.displacement_max > 0.0)) return a;  // nothing has moved: no region is "at rest" relative to motion
  at_rest_part(nb, displacement, speed, fraction * a.displacement_max, n, a);
  return a;
}

void largest_motion(std::span<const double> displacement, std::span<const double> speed, AtRest& a) {
  for (std::size_t p = 0; p < speed.size(); ++p) {
    a.displacement_max = std::max(a.displacement_max, displacement[p]);
    if (speed[p] > a.speed_max || a.fastest < 0) {
      a.speed_max = std::max(a.speed_max, speed[p]);
      a.fastest = static_cast<long>(p);
    }
  }
}

void at_rest_part(const Neighbourhood& nb, std::span<const double> displacement, std::span<const double> speed,
                  double bound, std::size_t owned, AtRest& a) {
  if (displacement.size() != nb.size() || speed.size() < owned || owned > nb.size())
    throw std::invalid_argument("at_rest: one displacement per point and one speed per own point expected");
  std::vector<char> rest(owned, 0);
  const long m = static_cast<long>(owned);
#pragma omp parallel for schedule(static) if (m > 2048)
  for (long p = 0; p < m; ++p) {
    const auto pp = static_cast<std::size_t>(p);
    if (!(displacement[pp] <= bound)) continue;
    bool all = true;
    nb.for_each_neighbour(pp, [&](std::size_t q) { all = all && displacement[q] <= bound; });
    rest[pp] = all ? 1 : 0;
  }
  for (std::size_t p = 0; p < owned; ++p) {
    if (!rest[p]) continue;
    ++a.count;
    if (a.worst < 0 || speed[p] > a.speed) {
      a.speed = speed[p];
      a.worst = static_cast<long>(p);
    }
  }
}

Range range(std::span<const double> value) {
  Range r;
  for (std::size_t p = 0; p < value.size(); ++p) {
    const double v = value[p];
    if (r.at_min < 0 || v < r.min) r.min = v, r.at_min = static_cast<long>(p);
    if (r.at_max < 0 || v > r.max) r.max = v, r.at_max = static_cast<long>(p);
  }
  return r;
}

Cavitation cavitation(std::span<const double> p, double bound) {
  Cavitation c;
  c.points = p.size();
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (p[k] < bound) ++c.below;
    if (c.lowest < 0 || p[k] < c.p_min) c.p_min = p[k], c.lowest = static_cast<long>(k);
  }
  c.fraction = c.points ? static_cast<double>(c.below) / static_cast<double>(c.points) : 0.0;
  return c;
}

double energy_balance_error(double kinetic, double stored, double initial, double work, double floor) {
  const double e = kinetic + stored;
  const double scale = std::max({std::abs(initial) + std::abs(work), std::abs(e), floor});
  if (!(scale > floor)) return 0.0;
  return (e - initial - work) / scale;
}

}  // namespace swmpm::diagnostics
