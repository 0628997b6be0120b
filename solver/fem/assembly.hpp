// A finite-element system on the grid's nodes with B unknowns per node, assembled cell by cell
// straight into the values of a fixed CSC pattern (linear/stencil.hpp's StencilPattern over all
// nodes, every entry stored): no triplets, no sorting, and the factorisation's symbolic analysis
// is kept for the life of the grid.
//
// Where an entry lives: the pattern stores column (J, b) as the rows (I, a) of the stencil slots
// around J that lie inside the grid, slot by slot (x fastest), unknowns a within a slot. The
// slots inside the grid form a sub-box [dlo, dhi] of [-R, R]^Dim around J, so entry (I, a) of
// column (J, b) sits at col_start(J B + b) + rank_J(I - J) B + a, rank_J the offset's index in
// J's sub-box (x fastest). Cells add their dense local matrices there, colour by colour
// (cell_basis.hpp), so sums do not depend on the thread count.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/linear/stencil.hpp"
#include "solver/parallel/comm.hpp"
#include "solver/parallel/sparse_solve.hpp"

namespace swmpm::fem {

template <int Dim, int R, int B>
class NodeSystem {
 public:
  /// Pattern of the whole grid (every node carries B equations).
  void build(const Grid<Dim>& g) {
    nodes_ = g.nodes_per_axis();
    std::vector<int> eqs(g.num_nodes()), eq_of(g.num_nodes());
    for (std::size_t i = 0; i < eqs.size(); ++i) eqs[i] = eq_of[i] = static_cast<int>(i);
    pattern_.build(nodes_, g.all_nodes(), eqs, eq_of, linear::Storage::full, A);
    rhs.setZero(A.rows());
    fixed_.assign(A.rows(), 0);
    fixed_value_.assign(A.rows(), 0.0);
  }

  std::array<int, Dim> ijk(std::size_t i) const {
    std::array<int, Dim> c;
    for (int a = 0; a < Dim; ++a) {
      c[a] = static_cast<int>(i % static_cast<std::size_t>(nodes_[a]));
      i /= static_cast<std::size_t>(nodes_[a]);
    }
    return c;
  }

  /// Column (J, b)'s geometry, for position(): J's sub-box of inside offsets.
  struct Column {
    std::array<int, Dim> dlo, stride;
    int start[B];
  };
  Column column(std::size_t J) const {
    Column c;
    const auto q = ijk(J);
    int stride = 1;
    for (int a = 0; a < Dim; ++a) {
      c.dlo[a] = q[a] - R < 0 ? -q[a] : -R;
      const int dhi = q[a] + R > nodes_[a] - 1 ? nodes_[a] - 1 - q[a] : R;
      c.stride[a] = stride;
      stride *= dhi - c.dlo[a] + 1;
    }
    for (int b = 0; b < B; ++b) c.start[b] = A.outerIndexPtr()[J * B + b];
    return c;
  }
  /// The value index of A(I a, J b), d = ijk(I) - ijk(J) (inside the grid, |d| <= R).
  static int position(const Column& c, const std::array<int, Dim>& d, int a, int b) {
    int rank = 0;
    for (int ax = 0; ax < Dim; ++ax) rank += (d[ax] - c.dlo[ax]) * c.stride[ax];
    return c.start[b] + rank * B + a;
  }

  /// Adds a cell's dense matrix Ae (row-major, (K B) x (K B), local unknown k B + a) and vector fe
  /// to A and rhs; `node` the cell's K = S^Dim nodes, local k = s_0 + S s_1 (+ S^2 s_2). Cells of
  /// one colour share no node, so calls for them may run in parallel.
  template <int S, std::size_t K>
  void add_cell(const std::array<std::size_t, K>& node, const double* Ae, const double* fe) {
    std::array<int, Dim> s_of[K];
    for (std::size_t k = 0; k < K; ++k) {
      int r = static_cast<int>(k);
      for (int a = 0; a < Dim; ++a) {
        s_of[k][a] = r % S;
        r /= S;
      }
    }
    constexpr int KB = static_cast<int>(K) * B;
    double* val = A.valuePtr();
    for (std::size_t kb = 0; kb < K; ++kb) {
      const Column col = column(node[kb]);
      for (std::size_t ka = 0; ka < K; ++ka) {
        std::array<int, Dim> d;
        for (int a = 0; a < Dim; ++a) d[a] = s_of[ka][a] - s_of[kb][a];
        for (int bb = 0; bb < B; ++bb) {
          const int pos0 = position(col, d, 0, bb);
          for (int aa = 0; aa < B; ++aa) val[pos0 + aa] += Ae[(static_cast<int>(ka) * B + aa) * KB + static_cast<int>(kb) * B + bb];
        }
      }
    }
    for (std::size_t ka = 0; ka < K; ++ka)
      for (int aa = 0; aa < B; ++aa) rhs[static_cast<long>(node[ka]) * B + aa] += fe[ka * B + aa];
  }

  /// A(r, r) += v for unknown r = I B + a.
  void add_diagonal(std::size_t I, int a, double v) {
    const Column col = column(I);
    A.valuePtr()[position(col, std::array<int, Dim>{}, a, a)] += v;
  }

  void clear() {
    std::fill_n(A.valuePtr(), A.nonZeros(), 0.0);
    rhs.setZero();
  }
  /// Only the unknowns (columns and right-hand-side rows) [lo, hi): over ranks, those a rank's
  /// cells reach (RankShare::unknowns); the others it never writes.
  void clear(long lo, long hi) {
    const int* outer = A.outerIndexPtr();
    std::fill(A.valuePtr() + outer[lo], A.valuePtr() + outer[hi], 0.0);
    rhs.segment(lo, hi - lo).setZero();
  }

  /// Unknown r = I B + a is prescribed (value v): its row and column are replaced by the identity
  /// times `scale`, the column's products with v moved to the right-hand side.
  void fix(long r, double v) {
    fixed_[r] = 1;
    fixed_value_[r] = v;
  }
  void unfix_all() { std::fill(fixed_.begin(), fixed_.end(), 0); }
  bool is_fixed(long r) const { return fixed_[r] != 0; }

  /// Applies the prescribed unknowns to the assembled A and rhs (after assembly, before the solve).
  /// Over ranks, each rank's A and rhs are its cells' part of the sums: the products moved to the
  /// right-hand side add up, and only the owner of a prescribed row, an unknown in [own_lo, own_hi),
  /// puts its identity and value. Only the columns and rows [lo, hi) are visited (the unknowns a
  /// rank's cells reach).
  void apply_fixed(double scale, long own_lo = 0, long own_hi = -1, long lo = 0, long hi = -1) {
    if (own_hi < 0) own_hi = A.cols();
    if (hi < 0) hi = A.cols();
    auto own = [&](long r) { return r >= own_lo && r < own_hi; };
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    double* val = A.valuePtr();
    // Columns: move the known values to the right-hand side, then zero them.
    for (long col = lo; col < hi; ++col) {
      if (!fixed_[col]) continue;
      const double v = fixed_value_[col];
      for (int e = outer[col]; e < outer[col + 1]; ++e) {
        if (v != 0.0 && !fixed_[inner[e]]) rhs[inner[e]] -= val[e] * v;
        val[e] = inner[e] == col && own(col) ? scale : 0.0;
      }
    }
    // Rows of fixed unknowns in free columns.
    for (long col = lo; col < hi; ++col) {
      if (fixed_[col]) continue;
      for (int e = outer[col]; e < outer[col + 1]; ++e)
        if (fixed_[inner[e]]) val[e] = 0.0;
    }
    for (long r = lo; r < hi; ++r)
      if (fixed_[r]) rhs[r] = own(r) ? scale * fixed_value_[r] : 0.0;
  }

  linear::CscMatrix A;
  Eigen::VectorXd rhs;

 private:
  std::array<int, Dim> nodes_{};
  linear::StencilPattern<Dim, R, B> pattern_;
  std::vector<std::uint8_t> fixed_;
  std::vector<double> fixed_value_;
};

/// This rank's share of a NodeSystem over mpirun's ranks (fem/fluid.hpp and fem/phase_field.hpp
/// assemble and solve their systems so). Along the grid's last axis (C cells, C + S - 1 node
/// planes) rank r of R assembles the cells [C r / R, C (r + 1) / R) (an equal share of the work)
/// and owns the rows of the nodes of the same planes, the last rank also those of the S - 1 planes
/// above the last cell (the node order has that axis slowest, so a rank's rows are one range,
/// numbered as one rank numbers them); its cells reach S - 1 planes into the next rank's rows. It hands
/// PETSc every entry of A among the rows its cells touch (in the pattern's order; an entry none
/// of its cells adds is an explicit zero) and the right-hand side of those rows; PETSc adds the
/// ranks' parts. One rank: every cell and node, nothing handed.
template <int Dim, int S, int B>
class RankShare {
 public:
  std::array<int, Dim> cell_lo{}, cell_hi{};  // the cells assembled here (inclusive)
  std::size_t own_lo = 0, own_hi = 0;         // the nodes whose rows are owned here
  bool over_ranks = false;
  bool owns(std::size_t node) const { return node >= own_lo && node < own_hi; }
  /// The unknowns [first, second) this rank's cells reach (one rank: all).
  std::pair<long, long> unknowns() const { return {rhs_lo_, rhs_hi_}; }

  /// The share of grid g's system A (its pattern built); over ranks, A's pattern in `solver` too.
  void build(const Grid<Dim>& g, const linear::CscMatrix& A, parallel::SparseSolve& solver) {
    const std::size_t nn = g.num_nodes();
    for (int a = 0; a < Dim; ++a) cell_lo[a] = 0, cell_hi[a] = g.axis(a).cells - 1;
    own_lo = 0, own_hi = nn;
    rhs_lo_ = 0, rhs_hi_ = static_cast<long>(nn) * B;
    over_ranks = parallel::distributed();
    if (!over_ranks) return;
    constexpr int last = Dim - 1;
    const long P = g.nodes_per_axis()[last], C = g.axis(last).cells, across = static_cast<long>(nn) / P;
    const long ranks = parallel::ranks(), r = parallel::rank();
    const long p_lo = C * r / ranks, p_hi = r + 1 == ranks ? P : C * (r + 1) / ranks;
    cell_lo[last] = static_cast<int>(p_lo);
    cell_hi[last] = static_cast<int>(C * (r + 1) / ranks) - 1;
    own_lo = static_cast<std::size_t>(p_lo * across), own_hi = static_cast<std::size_t>(p_hi * across);
    rhs_lo_ = p_lo * across * B, rhs_hi_ = std::min(P, p_hi + S - 1) * across * B;
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    std::vector<long> rows, cols, b_rows;
    pos_.clear();
    for (long col = rhs_lo_; col < rhs_hi_; ++col)
      for (int e = outer[col]; e < outer[col + 1]; ++e)
        if (inner[e] >= rhs_lo_ && inner[e] < rhs_hi_) pos_.push_back(e), rows.push_back(inner[e]), cols.push_back(col);
    for (long row = rhs_lo_; row < rhs_hi_; ++row) b_rows.push_back(row);
    solver.set_pattern(static_cast<long>(own_lo) * B, static_cast<long>(own_hi - own_lo) * B, static_cast<long>(nn) * B, rows,
                       cols, b_rows);
  }

  /// This rank's values of A and rhs as set_pattern named them.
  void values(const linear::CscMatrix& A, const Eigen::VectorXd& rhs, std::vector<double>& a, std::vector<double>& b) const {
    a.resize(pos_.size());
    const double* val = A.valuePtr();
    for (std::size_t k = 0; k < pos_.size(); ++k) a[k] = val[pos_[k]];
    b.assign(rhs.data() + rhs_lo_, rhs.data() + rhs_hi_);
  }

 private:
  std::vector<int> pos_;  // the value index in A of each entry handed to PETSc
  long rhs_lo_ = 0, rhs_hi_ = 0;  // the rows handed to PETSc
};

}  // namespace swmpm::fem
