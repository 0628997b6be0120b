// The distributed solve of a symmetric system on the grid's nodes (the semi-implicit pressure
// Poisson equation, seed 001 eq. 60) over the ranks: PETSc's KSP, conjugate gradients
// preconditioned with hypre's BoomerAMG. One rank solves it with CHOLMOD
// (formulations/semi_implicit/pressure_poisson.hpp); N ranks agree with it to the solver's
// tolerance, not bit for bit.
//
// The rows come as PressurePoisson keeps them: per node a dense stencil of K = (2R + 1)^Dim
// slots (linear::Stencil), slot k >= K / 2 holding L_{i, i + d_k} (the offsets with a flat step
// >= 0; the other half is the neighbour's), and a role per node (inactive, unknown, prescribed with
// its known increment). The system numbers every grid node (an inactive or prescribed node is an
// identity row, a prescribed one's increment moved to its neighbours' right-hand sides), rank r
// owning the node columns [c_r, c_{r+1}) along the cut axis and every node across it (the
// domain's stripes), numbered x fastest inside each rank's slab.
//
// Which rank adds an entry: the one owning the lower column of its two nodes. Its node box reaches
// R columns past its own (the shared columns, whose rows, roles and increments it holds finished),
// so it has both nodes' rows, roles and increments; every entry is added exactly once.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/linear/stencil.hpp"
#include "solver/parallel/comm.hpp"

namespace swmpm::parallel {

/// A sparse symmetric positive definite system over the ranks, solved by CG with BoomerAMG
/// (poisson.cpp, PETSc). n of the N rows live on this rank, the ranks' rows in rank order; entries and right-hand
/// side contributions may name any row (PETSc moves them to their rank and adds duplicates).
class KspSolve {
 public:
  KspSolve();
  ~KspSolve();
  KspSolve(const KspSolve&) = delete;
  KspSolve& operator=(const KspSolve&) = delete;

  struct Stats {
    int iterations = 0;
    double relative_residual = 0.0;  // |b - A x| / |b| at the end
    bool converged = false;
  };
  /// Solves A x = b to |b - A x| <= rtol |b| (unpreconditioned norm, as one rank's CG) and
  /// returns x at the global rows `wanted` (any rank's) in `x_wanted`. Collective.
  Stats solve(long n, long N, const std::vector<long>& rows, const std::vector<long>& cols,
              const std::vector<double>& values, const std::vector<long>& b_rows, const std::vector<double>& b_values,
              const std::vector<long>& wanted, std::vector<double>& x_wanted, double rtol);
  /// The preconditioner of CG: hypre's BoomerAMG (scalable), or the whole system factorised by
  /// CHOLMOD on every rank (PCREDUNDANT: for small 2D systems, whose factor is cheap). Set before
  /// the first solve.
  enum class Preconditioner { amg, redundant_cholesky };
  void set_preconditioner(Preconditioner p) { preconditioner_ = p; }
  /// Preconditioner setups so far (a setup is reused by later solves; see poisson.cpp).
  long setups() const;
  static constexpr int kMaxAge = 50;  // solves between setups at most

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Preconditioner preconditioner_ = Preconditioner::amg;
};

/// The pressure Poisson system of a grid over the ranks (see the header comment).
template <int Dim, int R>
class GridPoisson {
 public:
  using St = linear::Stencil<Dim, R>;
  static constexpr int K = St::K;
  enum Role : std::uint8_t { inactive = 0, unknown = 1, prescribed = 2 };

  /// `column_cuts`: the first node column of every rank along `axis`, then the node count.
  GridPoisson(const Grid<Dim>& g, int axis, std::vector<int> column_cuts)
      : grid_(g), nodes_(g.nodes_per_axis()), axis_(axis), cuts_(std::move(column_cuts)) {
    long across = 1;
    for (int a = 0; a < Dim; ++a)
      if (a != axis_) across *= nodes_[a];
    offset_.assign(cuts_.size(), 0);
    for (std::size_t r = 1; r < cuts_.size(); ++r) offset_[r] = offset_[r - 1] + (cuts_[r] - cuts_[r - 1]) * across;
    owner_.resize(static_cast<std::size_t>(nodes_[axis_]));
    for (std::size_t r = 0; r + 1 < cuts_.size(); ++r)
      for (int c = cuts_[r]; c < cuts_[r + 1]; ++c) owner_[static_cast<std::size_t>(c)] = static_cast<int>(r);
    // 2D systems up to kDirectRows: CHOLMOD's factor on every rank beats BoomerAMG (B3 slope, 4,000
    // rows, 2 ranks, 800 steps: the solve 4.1 s against 6.8 s; one rank's CHOLMOD 2.7 s). 3D keeps
    // BoomerAMG (3D box, 33,000 rows: 9.1 s against 15.0 s redundant). Measured 2026-12-06.
    if (Dim == 2 && offset_.back() <= kDirectRows) ksp_.set_preconditioner(KspSolve::Preconditioner::redundant_cholesky);
  }
  static constexpr long kDirectRows = 250000;
  /// Another preconditioner than the dimension's choice above (before the first solve).
  void set_preconditioner(KspSolve::Preconditioner p) { ksp_.set_preconditioner(p); }

  /// The system's row of node ijk.
  long row(const std::array<int, Dim>& ijk) const {
    const int r = owner_[static_cast<std::size_t>(ijk[axis_])];
    long idx = 0, stride = 1;
    for (int a = 0; a < Dim; ++a) {
      const int lo = a == axis_ ? cuts_[static_cast<std::size_t>(r)] : 0;
      const int n = a == axis_ ? cuts_[static_cast<std::size_t>(r) + 1] - lo : nodes_[a];
      idx += (ijk[a] - lo) * stride;
      stride *= n;
    }
    return offset_[static_cast<std::size_t>(r)] + idx;
  }

  /// Solves L dp = rhs for the unknown nodes. `stencil` (K per node), `rhs`, `role` and `dp` (a
  /// prescribed node's increment) are grid arrays, finished for this rank's node columns and the
  /// R above them; `box` (across the axis) holds every node with a role, the same on every rank.
  /// On return dp holds the solution at the unknown nodes of those columns and at every node of
  /// the `ghost` columns below them (prescribed ones there to the solver's tolerance). Collective.
  KspSolve::Stats solve(const NodeBox<Dim>& box, const double* stencil, const double* rhs, const std::uint8_t* role,
                        double* dp, int ghost, double rtol) {
    const int me = rank();
    const int c_lo = cuts_[static_cast<std::size_t>(me)], c_hi = cuts_[static_cast<std::size_t>(me) + 1];
    const int top = std::min(nodes_[axis_], c_hi + R);  // the columns whose rows this rank holds: [c_lo, top)
    const auto steps = St::steps(nodes_);
    rows_.clear(), cols_.clear(), values_.clear(), b_rows_.clear(), b_values_.clear();
    // The pattern: every pair of nodes in `box` (an explicit zero unless both are unknown now). It
    // changes only when the box does (the points' supports reach a new node plane), not as nodes
    // pass between unknown, prescribed and dry at a moving surface or a coupling vanishes: the
    // matrix and hypre's setup are reused (KspSolve). A pattern of the nodes with water changed
    // every step or two as a compression wave pushed the free faces of a 3D box outwards by less
    // than a node spacing (rebuilt 25 times in 60 steps). (Keeping the coordinates and each entry's
    // stencil slot between solves, to set only the values, gained nothing measurable: 9.69 against
    // 10.07 s of the solve stage in 60 steps at 16,000 rows per rank, for 32 MB per rank.)
    auto in_pattern = [&](const std::array<int, Dim>& ijk) {
      for (int a = 0; a < Dim; ++a)
        if (a != axis_ && (ijk[a] < box.lo[a] || ijk[a] > box.hi[a])) return false;
      return true;
    };
    for_each_node(c_lo, top, [&](std::size_t i, const std::array<int, Dim>& ijk) {
      const bool own = ijk[axis_] < c_hi;
      const Role ri = static_cast<Role>(role[i]);
      const long row_i = row(ijk);
      if (own) {  // the diagonal, the right-hand side
        rows_.push_back(row_i), cols_.push_back(row_i);
        values_.push_back(ri == unknown ? stencil[i * K + K / 2] : 1.0);
        if (ri == unknown) b_rows_.push_back(row_i), b_values_.push_back(rhs[i]);
      }
      if (!in_pattern(ijk)) return;  // an identity row and no couplings
      for (int k = K / 2 + 1; k < K; ++k) {
        const auto d = St::offset(k);
        std::array<int, Dim> jk = ijk;
        bool inside = true;
        for (int a = 0; a < Dim; ++a) {
          jk[a] += d[a];
          inside = inside && jk[a] >= 0 && jk[a] < nodes_[a];
        }
        if (!inside || !in_pattern(jk)) continue;
        // The entry belongs to the owner of the pair's lower column.
        if (owner_[static_cast<std::size_t>(std::min(ijk[axis_], jk[axis_]))] != me) continue;
        const std::size_t j = static_cast<std::size_t>(static_cast<long>(i) + steps[static_cast<std::size_t>(k)]);
        const Role rj = static_cast<Role>(role[j]);
        const double L = stencil[i * K + static_cast<std::size_t>(k)];
        const long row_j = row(jk);
        const double value = ri == unknown && rj == unknown ? L : 0.0;
        rows_.push_back(row_i), cols_.push_back(row_j), values_.push_back(value);
        rows_.push_back(row_j), cols_.push_back(row_i), values_.push_back(value);
        if (L == 0.0) continue;
        if (ri == unknown && rj == prescribed) {
          b_rows_.push_back(row_i), b_values_.push_back(-L * dp[j]);
        } else if (ri == prescribed && rj == unknown) {
          b_rows_.push_back(row_j), b_values_.push_back(-L * dp[i]);
        }
      }
    });
    // The solution wanted here: this rank's columns with the R above and `ghost` below.
    const int want_lo = std::max(0, c_lo - ghost);
    wanted_.clear();
    for_each_node(want_lo, top, [&](std::size_t, const std::array<int, Dim>& ijk) { wanted_.push_back(row(ijk)); });
    const long N = offset_.back();
    const KspSolve::Stats stats =
        ksp_.solve(offset_[static_cast<std::size_t>(me) + 1] - offset_[static_cast<std::size_t>(me)], N, rows_, cols_, values_, b_rows_, b_values_, wanted_, x_, rtol);
    std::size_t w = 0;
    for_each_node(want_lo, top, [&](std::size_t i, const std::array<int, Dim>& ijk) {
      const double x = x_[w++];
      const bool held = ijk[axis_] >= c_lo;  // this rank holds the roles of its columns and the R above
      if (!held || role[i] == unknown) dp[i] = x;
      else if (role[i] == inactive) dp[i] = 0.0;
    });
    return stats;
  }
  /// Preconditioner setups so far (KspSolve::setups).
  long setups() const { return ksp_.setups(); }

 private:
  /// fn(flat index, ijk) over the nodes of columns [lo, hi) along the axis, all across.
  template <class Fn>
  void for_each_node(int lo, int hi, Fn&& fn) const {
    NodeBox<Dim> columns;
    for (int a = 0; a < Dim; ++a) columns.lo[a] = 0, columns.hi[a] = nodes_[a] - 1;
    columns.lo[axis_] = lo, columns.hi[axis_] = hi - 1;
    if (lo < hi) grid_.for_each_node(columns, fn);
  }

  const Grid<Dim>& grid_;
  std::array<int, Dim> nodes_;
  int axis_;
  std::vector<int> cuts_;
  std::vector<long> offset_;  // per rank (and the total): its first row
  std::vector<int> owner_;    // per node column along the axis: its rank
  KspSolve ksp_;
  std::vector<long> rows_, cols_, b_rows_, wanted_;
  std::vector<double> values_, b_values_, x_;
};

}  // namespace swmpm::parallel
