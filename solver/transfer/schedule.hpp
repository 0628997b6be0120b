// Race-free, thread-count-independent particle-to-grid scatter.
//
// Particles are binned into stripes of W = S node columns (S = shape support) along the grid axis
// with the most nodes, by their first node index `base`. A particle of stripe s touches node columns
// [sW, sW + W + S - 2], which never overlaps stripe s + 2's columns. So all even stripes run in
// parallel, then all odd ones; inside a stripe particles go in increasing index. Every node therefore
// receives its contributions in one fixed order whatever the number of threads — results are
// bitwise identical for any --threads (tests/verification/test_threads.cpp).
#pragma once

#include <algorithm>
#include <vector>

#include "solver/common.hpp"

namespace swmpm {

class StripeSchedule {
 public:
  /// base_of(p) returns particle p's first node index along the stripe axis.
  template <class BaseOf>
  void build(std::size_t n, int nodes_on_axis, int width, BaseOf&& base_of) {
    width_ = width;
    stripes_ = (nodes_on_axis + width - 1) / width;
    start_.assign(stripes_ + 1, 0);
    key_.resize(n);
    for (std::size_t p = 0; p < n; ++p) {
      key_[p] = base_of(p) / width;
      ++start_[key_[p] + 1];
    }
    for (int s = 0; s < stripes_; ++s) start_[s + 1] += start_[s];
    order_.resize(n);
    fill_ = start_;
    for (std::size_t p = 0; p < n; ++p) order_[fill_[key_[p]]++] = static_cast<int>(p);
  }

  /// Particle indices in schedule order (stripe by stripe, increasing index inside a stripe).
  const std::vector<int>& order() const { return order_; }
  /// Whether the particles are already stored in schedule order.
  bool in_order() const {
    for (std::size_t k = 0; k < order_.size(); ++k)
      if (order_[k] != static_cast<int>(k)) return false;
    return true;
  }

  /// Calls fn(p) for every particle: two colours, stripes of one colour in parallel.
  template <class Fn>
  void run(Fn&& fn) const {
    for (int colour = 0; colour < 2; ++colour) {
#pragma omp parallel for schedule(dynamic, 1) if (static_cast<long>(order_.size()) > parallel_threshold)
      for (int s = colour; s < stripes_; s += 2)
        for (int k = start_[s]; k < start_[s + 1]; ++k) fn(order_[k]);
    }
  }

 private:
  int width_ = 1, stripes_ = 0;
  std::vector<int> start_, fill_, key_, order_;
};

}  // namespace swmpm
