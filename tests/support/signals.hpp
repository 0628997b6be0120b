// Time-series helpers for monitor histories (monitors.csv columns): zero crossings, the period
// they imply, and a least-squares harmonic fit at a known frequency.
#pragma once

#include <cmath>
#include <complex>
#include <vector>

#include <Eigen/Dense>

namespace swmpm::testing {

/// Times where v(t) - level changes sign (linear interpolation between samples), for t in
/// [from, to]. `rising` > 0: only upward crossings; < 0: only downward; 0: both.
inline std::vector<double> zero_crossings(const std::vector<double>& t, const std::vector<double>& v, double level,
                                          double from, double to, int rising = 0) {
  std::vector<double> out;
  for (std::size_t k = 1; k < t.size() && k < v.size(); ++k) {
    if (t[k - 1] < from || t[k] > to) continue;
    const double a = v[k - 1] - level, b = v[k] - level;
    const bool up = a < 0.0 && b >= 0.0, down = a > 0.0 && b <= 0.0;
    if ((up && rising >= 0) || (down && rising <= 0)) out.push_back(t[k - 1] + (t[k] - t[k - 1]) * a / (a - b));
  }
  return out;
}

/// Period from the crossings of both directions: twice the mean spacing of consecutive crossings
/// (first to last over their count - 1). Needs at least 2 crossings; returns 0 otherwise.
inline double period_from_crossings(const std::vector<double>& crossings) {
  if (crossings.size() < 2) return 0.0;
  return 2.0 * (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
}

/// Least-squares fit v(t) ~ mean + Re[A e^{i omega t}] over samples with t in [from, to]: returns
/// the mean and the complex amplitude A (|A| the amplitude, arg A the phase of a cosine).
struct Harmonic {
  double mean = 0.0;
  std::complex<double> amplitude;
  double rms_residual = 0.0;  // of the fit, same unit as v
};

inline Harmonic harmonic_fit(const std::vector<double>& t, const std::vector<double>& v, double omega, double from,
                             double to) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < t.size() && k < v.size(); ++k) {
    if (t[k] < from || t[k] > to) continue;
    const Eigen::Vector3d row(1.0, std::cos(omega * t[k]), std::sin(omega * t[k]));
    A += row * row.transpose();
    b += row * v[k];
  }
  const Eigen::Vector3d c = A.ldlt().solve(b);
  Harmonic h;
  h.mean = c[0];
  h.amplitude = {c[1], -c[2]};  // c1 cos + c2 sin = Re[(c1 - i c2) e^{i omega t}]
  double r2 = 0.0;
  int count = 0;
  for (std::size_t k = 0; k < t.size() && k < v.size(); ++k) {
    if (t[k] < from || t[k] > to) continue;
    const double fit = c[0] + c[1] * std::cos(omega * t[k]) + c[2] * std::sin(omega * t[k]);
    r2 += (v[k] - fit) * (v[k] - fit);
    ++count;
  }
  h.rms_residual = count ? std::sqrt(r2 / count) : 0.0;
  return h;
}

}  // namespace swmpm::testing
