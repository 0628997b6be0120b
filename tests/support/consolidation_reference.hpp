// Reference solution of 1D large-strain consolidation (A2) for tests: the same finite-volume model
// as examples/large-strain-consolidation/reference.py (derivation in that example's README.md).
//
// Lagrangian coordinate a in [0, H] (a = 0 impermeable base, a = H drained top), J = V / V0:
//   sigma'_yy = E ln J (Cauchy, tension positive),  sigma'_yy - p = -q  =>  J = exp((p - q) / E)
//   J (1/E + n / K_f) dp/dt = d/da [ k / (gamma_w J) dp/da ],   n = 1 - (1 - n0) / J,
//   k = k0 (constant) or k0 J^2 (Xie & Leo).
// Backward Euler with Picard iterations, time steps growing geometrically; with k = k0 J^2 and
// K_f = inf it reproduces Xie & Leo's closed form to 3e-5 m (reference.py --self-test).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace swmpm::testing {

struct LargeStrainColumn {
  double H = 1.0, E = 1.0e6, q = 2.0e5, n0 = 0.3, k0 = 1.0e-4, K_f = 2.2e9, gamma_w = 1000.0 * 9.81;
  bool xie_leo_k = false;  // k = k0 J^2 instead of k0
  int cells = 200;

  /// Pore-pressure profiles p(a) (cell centres) at the requested times (ascending).
  std::vector<std::vector<double>> solve(const std::vector<double>& times) const {
    const int N = cells;
    const double da = H / N;
    std::vector<double> p(N, q), p_old, cap(N), cond(N), lo(N), di(N), up(N), rhs(N), cp(N), dp(N);
    std::vector<std::vector<double>> out;
    double t = 0.0, dt = 1.0e-5;
    std::size_t next = 0;
    while (next < times.size()) {
      const double step = std::min(dt, times[next] - t);
      p_old = p;
      for (int it = 0; it < 50; ++it) {
        for (int i = 0; i < N; ++i) {
          const double J = std::exp((p[i] - q) / E), n = 1.0 - (1.0 - n0) / J;
          cap[i] = J * (1.0 / E + (std::isfinite(K_f) ? n / K_f : 0.0));
          cond[i] = k0 * (xie_leo_k ? J * J : 1.0) / (gamma_w * J);
        }
        for (int i = 0; i < N; ++i) {
          lo[i] = up[i] = 0.0;
          di[i] = cap[i] * da / step;
          rhs[i] = di[i] * p_old[i];
          if (i > 0) {
            const double kf = 2.0 / (1.0 / cond[i] + 1.0 / cond[i - 1]) / da;
            lo[i] -= kf;
            di[i] += kf;
          }
          if (i < N - 1) {
            const double kf = 2.0 / (1.0 / cond[i] + 1.0 / cond[i + 1]) / da;
            up[i] -= kf;
            di[i] += kf;
          } else {
            di[i] += cond[i] / (0.5 * da);  // drained top, p = 0 half a cell away
          }
        }
        cp[0] = up[0] / di[0];
        dp[0] = rhs[0] / di[0];
        for (int i = 1; i < N; ++i) {
          const double m = di[i] - lo[i] * cp[i - 1];
          cp[i] = up[i] / m;
          dp[i] = (rhs[i] - lo[i] * dp[i - 1]) / m;
        }
        double change = 0.0;
        for (int i = N - 1; i >= 0; --i) {
          const double v = i == N - 1 ? dp[i] : dp[i] - cp[i] * p[i + 1];
          change = std::max(change, std::abs(v - p[i]));
          p[i] = v;
        }
        if (change < 1e-7 * q) break;
      }
      t += step;
      if (std::abs(t - times[next]) < 1e-12) {
        out.push_back(p);
        ++next;
      } else {
        dt = std::min(dt * 1.005, 0.05);
      }
    }
    return out;
  }

  /// Settlement of the point at initial height a above the base, from a profile of solve().
  double settlement(const std::vector<double>& p, double a) const {
    const int N = static_cast<int>(p.size());
    const double da = H / N;
    double s = 0.0;
    for (int i = 0; i < N; ++i) {
      const double lo = i * da, hi = std::min(a, lo + da);
      if (hi <= lo) break;
      s += (1.0 - std::exp((p[i] - q) / E)) * (hi - lo);
    }
    return s;
  }

  /// Pore pressure at initial height a (piecewise constant per cell).
  double pressure(const std::vector<double>& p, double a) const {
    const int N = static_cast<int>(p.size());
    return p[std::clamp(static_cast<int>(a / H * N), 0, N - 1)];
  }
};

}  // namespace swmpm::testing
