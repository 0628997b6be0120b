// Sparse systems on the structured grid: each equation sits at a grid node (B unknowns per node)
// and couples the nodes within R per axis (R = S - 1 for shape functions of support S: the nodes
// that can share a particle). Assemblers keep each node's row as a dense stencil of
// (2R + 1)^Dim slots (Stencil), filled by the particles through the scatter schedule, with no
// triplets and no sorting; StencilPattern builds, once per set of equation nodes, the CSC
// pattern of the system with every entry's node pair, stencil slot and unknowns, so that the
// matrix values are gathered from the stencils in one pass each step and the factorisation's
// symbolic analysis is kept while the pattern does (linear/factorisation.hpp).
#pragma once

#include <Eigen/Sparse>
#include <array>
#include <cstddef>
#include <vector>

#include "solver/grid/grid.hpp"

namespace swmpm::linear {

/// A box stencil of reach R nodes per axis around a node: slot k <-> offset d in [-R, R]^Dim
/// (x fastest), and each slot's step in flat node index on a grid with `nodes` per axis. Slot
/// K - 1 - k is the opposite offset of slot k; slots >= K / 2 are the offsets with step >= 0.
template <int Dim, int R>
struct Stencil {
  static constexpr int W = 2 * R + 1;
  static constexpr int K = Dim == 2 ? W * W : W * W * W;
  static std::array<int, Dim> offset(int k) {
    std::array<int, Dim> d;
    for (int a = 0; a < Dim; ++a) {
      d[a] = k % W - R;
      k /= W;
    }
    return d;
  }
  static int slot(const std::array<int, Dim>& d) {
    int k = 0, mul = 1;
    for (int a = 0; a < Dim; ++a) {
      k += (d[a] + R) * mul;
      mul *= W;
    }
    return k;
  }
  static std::array<long, K> steps(const std::array<int, Dim>& nodes) {
    std::array<long, K> st{};
    for (int k = 0; k < K; ++k) {
      const auto d = offset(k);
      long step = 0, stride = 1;
      for (int a = 0; a < Dim; ++a) {
        step += d[a] * stride;
        stride *= nodes[a];
      }
      st[k] = step;
    }
    return st;
  }
};

/// Compressed sparse column, 0-based int indices: what CHOLMOD and UMFPACK factorise.
using CscMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// Which entries a pattern holds: the lower triangle of a symmetric system (CHOLMOD reads that
/// half), or every entry of a general one.
enum class Storage { lower, full };

/// One stored entry A(row, col): row node I, unknown a; column node J, unknown b; the stencil
/// slot k of the offset from J to I (I = J + step[k]).
struct Entry {
  std::size_t I, J;
  int k, a, b;
};

/// The CSC pattern of a system on the grid's equation nodes, B unknowns per node, numbered node
/// by node (equation e, unknown a -> index e B + a) in the order of `equations`, which must be
/// increasing flat node indices: then the rows of every column come out sorted.
template <int Dim, int R, int B = 1>
class StencilPattern {
 public:
  using St = Stencil<Dim, R>;
  static constexpr int K = St::K;

  /// equations: the nodes that carry equations (increasing); eq_of_node: per node its position
  /// in `equations`, or < 0; box: the nodes eq_of_node is current for (a node outside it is
  /// ignored as a neighbour). Sets A's pattern (values zero) and entries().
  void build(const std::array<int, Dim>& nodes, const NodeBox<Dim>& box, const std::vector<int>& equations,
             const std::vector<int>& eq_of_node, Storage storage, CscMatrix& A) {
    const auto step = St::steps(nodes);
    const int n = static_cast<int>(equations.size()) * B;
    std::vector<int> col_start(n + 1, 0), rows;
    entries_.clear();
    rows.reserve(static_cast<std::size_t>(n) * (storage == Storage::lower ? K / 2 + 1 : K) * B);
    int col = 0;
    for (const int node : equations) {
      const std::size_t J = static_cast<std::size_t>(node);
      const auto ijk = ijk_of(nodes, J);
      for (int b = 0; b < B; ++b, ++col) {
        for (int k = 0; k < K; ++k) {
          if (storage == Storage::lower && step[k] < 0) continue;  // lower triangle: rows I >= J
          const auto d = St::offset(k);
          bool inside = true;
          for (int a = 0; a < Dim; ++a) inside = inside && ijk[a] + d[a] >= box.lo[a] && ijk[a] + d[a] <= box.hi[a];
          if (!inside) continue;
          const std::size_t I = J + step[k];
          if (eq_of_node[I] < 0) continue;
          for (int a = storage == Storage::lower && step[k] == 0 ? b : 0; a < B; ++a) {
            rows.push_back(eq_of_node[I] * B + a);
            entries_.push_back({I, J, k, a, b});
          }
        }
        col_start[col + 1] = static_cast<int>(rows.size());
      }
    }
    A.resize(n, n);
    A.resizeNonZeros(static_cast<Eigen::Index>(rows.size()));
    std::copy(col_start.begin(), col_start.end(), A.outerIndexPtr());
    std::copy(rows.begin(), rows.end(), A.innerIndexPtr());
    std::fill_n(A.valuePtr(), rows.size(), 0.0);
  }

  /// Per stored entry of A (in A's value order): its nodes, stencil slot and unknowns.
  const std::vector<Entry>& entries() const { return entries_; }

  static std::array<int, Dim> ijk_of(const std::array<int, Dim>& nodes, std::size_t i) {
    std::array<int, Dim> ijk;
    for (int a = 0; a < Dim; ++a) {
      ijk[a] = static_cast<int>(i % nodes[a]);
      i /= nodes[a];
    }
    return ijk;
  }

 private:
  std::vector<Entry> entries_;
};

}  // namespace swmpm::linear
