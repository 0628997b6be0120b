#include "study/richardson.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace swmpm::study {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<double> minus(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) d[i] = a[i] - b[i];
  return d;
}

double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

/// p from two successive changes (NaN when either vanishes).
double order_of(const std::vector<double>& d1, const std::vector<double>& d2, double r) {
  const double n1 = rms(d1), n2 = rms(d2);
  if (!(n1 > 0.0) || !(n2 > 0.0)) return kNaN;
  return std::log(n1 / n2) / std::log(r);
}

}  // namespace

double rms(const std::vector<double>& v) {
  if (v.empty()) return 0.0;
  return std::sqrt(dot(v, v) / static_cast<double>(v.size()));
}

Extrapolation extrapolate(const std::vector<std::vector<double>>& q, double r, double scale) {
  const std::size_t N = q.size();
  if (N < 3) throw std::invalid_argument("Richardson extrapolation needs three levels or more");
  if (!(r > 1.0)) throw std::invalid_argument("the refinement ratio must be above 1");
  for (const auto& level : q)
    if (level.size() != q.front().size() || level.empty())
      throw std::invalid_argument("every level needs the same number of samples (at least one)");
  Extrapolation e;
  for (std::size_t k = 0; k + 2 < N; ++k) e.orders.push_back(order_of(minus(q[k], q[k + 1]), minus(q[k + 1], q[k + 2]), r));
  const std::vector<double>& qb = q[N - 2];
  const std::vector<double>& qc = q[N - 1];
  const std::vector<double> d1 = minus(q[N - 3], qb), d2 = minus(qb, qc);
  const double n1 = rms(d1), n2 = rms(d2);
  e.order = e.orders.back();

  if (n1 <= kRoundOff * scale && n2 <= kRoundOff * scale) {
    // Nothing changes beyond round-off: the finest level is as good as the arithmetic.
    e.converged = true;
    e.asymptotic = true;
    e.order = kNaN;
  } else if (!(n2 < n1)) {
    e.why = "not converging: the last change is not smaller than the one before";
  } else if (!(dot(d1, d2) > 0.0)) {
    e.why = "oscillating: successive changes point opposite ways";
  } else if (e.order < kMinOrder) {
    e.why = "observed order below 0.5: the changes shrink too slowly to extrapolate";
  } else if (e.order > kMaxOrder) {
    e.why = "observed order above 4: faster than the schemes converge, likely a coincidence of two changes";
  } else {
    e.asymptotic = true;
  }

  e.extrapolated = qc;
  double finest = 0.0;
  if (e.converged) {
    finest = n2;
  } else if (e.asymptotic) {
    const double factor = 1.0 / (std::pow(r, e.order) - 1.0);
    for (std::size_t i = 0; i < qc.size(); ++i) e.extrapolated[i] = qc[i] + (qc[i] - qb[i]) * factor;
  } else {
    finest = n2 / (r - 1.0);  // first order: q_ext = q_c, e_c = |d_2| / (r - 1)
  }
  for (std::size_t k = 0; k < N; ++k) {
    const double spread = rms(minus(q[k], e.extrapolated));
    e.error.push_back(e.asymptotic && !e.converged ? spread : spread + finest);
  }
  return e;
}

double cell_size_for(double h_c, double e_c, double target, double p) {
  if (!(e_c > 0.0) || !(target > 0.0) || !(p > 0.0)) return h_c;
  return h_c * std::pow(target / e_c, 1.0 / p);
}

}  // namespace swmpm::study
