// Richardson extrapolation of a monitored quantity over a ladder of resolutions with a constant
// refinement ratio r (`swmpm study`, issue 26 item 5). Pure arithmetic on numbers the runs wrote;
// the rules and why: docs/study.md, "Error estimate".
//
// A quantity q is a vector of samples: one value (the value at the end time) or a history on
// common times. Levels are ordered coarse to fine, q_0 ... q_{N-1}, cell size h_k = h_0 / r^k.
// With the last three levels (a = N-3, b = N-2, c = N-1) and d_1 = q_a - q_b, d_2 = q_b - q_c:
//
//     observed order    p     = ln(|d_1| / |d_2|) / ln r              (|.|: RMS over the samples)
//     extrapolated      q_ext = q_c + (q_c - q_b) / (r^p - 1)          (per sample)
//     error of level k  e_k   = |q_k - q_ext|                          (RMS over the samples)
//
// so e_c = |d_2| / (r^p - 1), the grid convergence index without its safety factor. The runs are
// in the asymptotic range only when the changes shrink (|d_2| < |d_1|), point the same way
// (<d_1, d_2> > 0) and p lies in [kMinOrder, kMaxOrder]; otherwise the result is flagged, nothing
// is extrapolated (q_ext = q_c) and the finest level's error is taken as |d_2| / (r - 1), the
// first-order estimate (the slowest order MPM converges at), e_k = |q_k - q_c| + e_c.
#pragma once

#include <string>
#include <vector>

namespace swmpm::study {

/// Orders outside this range are not trusted: below it the changes shrink too slowly to
/// extrapolate; above it faster than any scheme here converges (a coincidence of two changes).
inline constexpr double kMinOrder = 0.5;
inline constexpr double kMaxOrder = 4.0;

/// The changes are round-off when both are below this fraction of the quantity's scale.
inline constexpr double kRoundOff = 1e-12;

struct Extrapolation {
  double order = 0.0;               // p of the last three levels (NaN: not defined)
  std::vector<double> orders;       // p of every three consecutive levels, coarse first (NaN: not defined)
  std::vector<double> extrapolated; // q_ext per sample (q of the finest level when flagged)
  std::vector<double> error;        // e_k per level, absolute, RMS over the samples
  bool asymptotic = false;          // the last three levels pass every rule
  bool converged = false;           // the changes are round-off: e = the last change, no order
  std::string why;                  // why flagged (empty when asymptotic)
};

/// RMS of a vector (0 for an empty one).
double rms(const std::vector<double>& v);

/// The estimate for levels q[0..N-1] (coarse to fine, N >= 3, every q[k] of the same length >= 1)
/// refined by the ratio r > 1. `scale` (> 0) is the quantity's magnitude, for the round-off test.
Extrapolation extrapolate(const std::vector<std::vector<double>>& q, double r, double scale);

/// The cell size at which the error e_c of the finest level h_c, converging at order p, would
/// reach `target`: h_c (target / e_c)^(1/p).
double cell_size_for(double h_c, double e_c, double target, double p);

}  // namespace swmpm::study
