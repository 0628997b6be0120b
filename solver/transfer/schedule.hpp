// Race-free, thread-count-independent particle-to-grid scatter.
//
// Particles are binned into stripes of W = S node columns (S = shape support) along the grid axis
// with the most nodes, by their first node index `base`. A particle of stripe s touches node columns
// [sW, sW + W + S - 2], which never overlaps stripe s + 2's columns. So all even stripes run in
// parallel, then all odd ones; inside a stripe particles go in increasing index. Every node therefore
// receives its contributions in one fixed order whatever the number of threads — results are
// bitwise identical for any --threads (tests/verification/test_threads.cpp).
#pragma once

#include <omp.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "solver/common.hpp"

namespace swmpm {

/// Under mpirun (solver/parallel/domain.hpp): the ranks own whole stripes, so a node column near a
/// cut between ranks gets the contributions of two stripes on two ranks, one of each colour. After
/// colour 0 the rank that ran the colour-0 stripe hands its partial sums of those columns to the
/// other one (which has none yet), and after colour 1 the finished sums go back: every node then
/// holds the one-rank sum, bit for bit, on both ranks. `nodes` is a node array (any element of
/// `bytes` bytes, a whole number of doubles) indexed by the grid's flat node index.
///
/// What a particle of stripe s reaches along the axis: the nodes of its shape functions at the
/// start of the step (`support`, columns [base, base + S - 1]), or the grid cell that holds it
/// after the step moved it by less than a cell (`moved_cell`, cells indexed by their lowest node,
/// columns [base - 1, base + S - 1]). At a cut s W the shared columns are [s W, s W + S - 2] for
/// the support and [s W - 1, s W + S - 2] for moved cells; either way only stripes s - 1 and s
/// reach them.
enum class Reach { support, moved_cell };
class NodeExchange {
 public:
  virtual ~NodeExchange() = default;
  virtual void after_colour(int colour, void* nodes, std::size_t bytes, Reach reach) const = 0;
};

/// A node array stored as `per_node` consecutive values per node (a stencil row of an operator),
/// as a scatter names it to the exchange and a ghost fill copies it.
template <class T>
struct NodeRows {
  T* first;
  std::size_t per_node;
  T* data() const { return first; }
};
/// The bytes of one node's entry in a node array (NodeArray, std::vector) or in NodeRows.
template <class Array>
std::size_t node_bytes(const Array& a) {
  return sizeof(a[0]);
}
template <class T>
std::size_t node_bytes(const NodeRows<T>& a) {
  return a.per_node * sizeof(T);
}

class StripeSchedule {
 public:
  /// base_of(p) returns particle p's first node index along the stripe axis. A stable counting
  /// sort by stripe, done in parallel over contiguous chunks of particles (per-chunk histograms,
  /// then each chunk scatters its particles after those of earlier chunks): the result is the one
  /// stable order, whatever the number of threads.
  template <class BaseOf>
  void build(std::size_t n, int nodes_on_axis, int width, BaseOf&& base_of) {
    width_ = width;
    built_ = true;
    stripes_ = (nodes_on_axis + width - 1) / width;
    key_.resize(n);
    order_.resize(n);
    start_.assign(stripes_ + 1, 0);
    const long N = static_cast<long>(n);
#pragma omp parallel if (N > parallel_threshold)
    {
      const int T = omp_get_num_threads(), t = omp_get_thread_num();
#pragma omp single
      counts_.assign(static_cast<std::size_t>(T) * stripes_, 0);
      const long lo = N * t / T, hi = N * (t + 1) / T;
      int* count = counts_.data() + static_cast<std::size_t>(t) * stripes_;
      for (long p = lo; p < hi; ++p) {
        key_[p] = base_of(static_cast<std::size_t>(p)) / width;
        ++count[key_[p]];
      }
#pragma omp barrier
#pragma omp single
      {
        // Stripe starts, then each chunk's first slot in each stripe.
        for (int s = 0; s < stripes_; ++s) {
          int sum = start_[s];
          for (int c = 0; c < T; ++c) {
            const int k = counts_[static_cast<std::size_t>(c) * stripes_ + s];
            counts_[static_cast<std::size_t>(c) * stripes_ + s] = sum;
            sum += k;
          }
          start_[s + 1] = sum;
        }
      }
      for (long p = lo; p < hi; ++p) order_[count[key_[p]]++] = static_cast<int>(p);
    }
  }

  /// Particle indices in schedule order (stripe by stripe, increasing index inside a stripe).
  const std::vector<int>& order() const { return order_; }
  /// Restart: the order of the step before a checkpoint, which the next step's reordering reads
  /// (the stripes themselves are rebuilt by every step before they are used).
  void restore_order(std::vector<int> order) {
    order_ = std::move(order);
    built_ = true;
  }
  /// Whether build() has run (the first step has).
  bool built() const { return built_; }
  /// Whether the particles are already stored in schedule order.
  bool in_order() const {
    for (std::size_t k = 0; k < order_.size(); ++k)
      if (order_[k] != static_cast<int>(k)) return false;
    return true;
  }

  /// Calls fn(p) for every particle: two colours, stripes of one colour in parallel. `scattered`:
  /// the node arrays fn adds to, which a rank shares with its neighbours after each colour
  /// (NodeExchange; nothing at one rank).
  template <class Fn, class... NodeArrays>
  void run(Fn&& fn, NodeArrays&&... scattered) const {
    run_reaching(Reach::support, fn, scattered...);
  }
  /// run() for a scatter into the cells that hold the particles after the step's move (arrays
  /// indexed as cells by their lowest node): a particle moves less than a cell per step, so a
  /// cell still gets the points of at most two neighbouring stripes, of two colours.
  template <class Fn, class... CellArrays>
  void run_after_move(Fn&& fn, CellArrays&&... scattered) const {
    run_reaching(Reach::moved_cell, fn, scattered...);
  }
  /// The ranks' exchange of scattered node columns (nullptr: one rank).
  void set_exchange(const NodeExchange* exchange) { exchange_ = exchange; }
  const NodeExchange* exchange() const { return exchange_; }

 private:
  template <class Fn, class... NodeArrays>
  void run_reaching([[maybe_unused]] Reach reach, Fn& fn, NodeArrays&&... scattered) const {
    if constexpr (sizeof...(NodeArrays) == 0)
      if (exchange_) throw std::logic_error("a scatter that does not name its node arrays ran on several ranks");
    for (int colour = 0; colour < 2; ++colour) {
#pragma omp parallel for schedule(dynamic, 1) if (static_cast<long>(order_.size()) > parallel_threshold)
      for (int s = colour; s < stripes_; s += 2)
        for (int k = start_[s]; k < start_[s + 1]; ++k) fn(order_[k]);
      if (exchange_) (exchange_->after_colour(colour, scattered.data(), node_bytes(scattered), reach), ...);
    }
  }

  const NodeExchange* exchange_ = nullptr;
  bool built_ = false;
  int width_ = 1, stripes_ = 0;
  std::vector<int> start_, key_, order_;
  std::vector<int> counts_;  // per chunk and stripe: counts, then first slots
};

}  // namespace swmpm
