// The pressure-increment Poisson system of the semi-implicit formulations (seed 001, eq. 60), on
// the structured grid, assembled into a fixed sparsity pattern (linear/stencil.hpp) and solved
// with CHOLMOD (linear/factorisation.hpp).
//
// Each node I keeps the row of L in a dense stencil of (2R + 1)^Dim coefficients (the nodes that
// can share a particle with it: R = S - 1 for shape functions of support S). Particles scatter into these rows
// through the stripe schedule (race-free, fixed order), so assembly builds no triplets and sorts
// nothing. The CSC matrix (lower triangle) has an equation for every unknown node (its row of L)
// and for every prescribed node that was unknown within the last kStickySteps solves (the
// identity; its known increment goes to its neighbours' right-hand sides); it is filled from the
// stencils by a gather map. Its pattern and CHOLMOD's symbolic analysis are rebuilt only when an
// unknown node has no equation or a node with one has lost its water, not when a node passes
// back and forth between unknown and prescribed as a free surface moves (B5 reduced, 1 + 1 s:
// 2222 rebuilds when keyed on the unknown set, 6 now), and reused otherwise. The numeric
// factorisation is reused too, as the preconditioner of conjugate gradients on later steps' L
// (which changes only as the points move): refactorised when CG needs more than kMaxIterations or
// the factor is kMaxAge steps old.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/linear/factorisation.hpp"
#include "solver/linear/stencil.hpp"
#include "solver/output/checkpoint.hpp"
#include "solver/shape/shape.hpp"

namespace swmpm {

/// Symmetric system on grid nodes whose rows reach R nodes per axis (R = S - 1 for shape
/// functions with support S).
template <int Dim, int R>
class PressurePoisson {
 public:
  using St = linear::Stencil<Dim, R>;
  static constexpr int W = St::W;
  static constexpr int K = St::K;

  /// Role of a node in the system: no equation (no water touches it), unknown, or prescribed.
  enum Role : std::uint8_t { inactive = 0, unknown = 1, prescribed = 2 };

  explicit PressurePoisson(const Grid<Dim>& g) : nodes_(g.nodes_per_axis()), step_(St::steps(g.nodes_per_axis())) {
    const std::size_t n = g.num_nodes();
    // Zero (inactive, no equation) until a step's box reaches them: NodeArray, memory only there.
    stencil_.resize(n * K);
    rhs_.resize(n);
    dp_.resize(n);
    role_.resize(n);
    member_.resize(n);
    eq_.assign(n, -1);
    last_unknown_.assign(n, std::numeric_limits<long>::min() / 2);
  }

  /// Zeroes the rows, right-hand sides and roles of the nodes in `box`, and of those in the box
  /// cleared last (nodes the points have left), so that no node outside `box` holds a former
  /// step's row, role or increment (solve() reads its neighbours' rows and roles).
  void clear(const Grid<Dim>& g, const NodeBox<Dim>& box) {
    NodeBox<Dim> both = box;
    for (int a = 0; a < Dim; ++a) {
      both.lo[a] = std::min(both.lo[a], cleared_.lo[a]);
      both.hi[a] = std::max(both.hi[a], cleared_.hi[a]);
    }
    cleared_ = box;
    g.parallel_for_each_node(both, [&](std::size_t i, const auto&) {
      std::fill_n(stencil_.data() + i * K, K, 0.0);
      rhs_[i] = 0.0;
      dp_[i] = 0.0;
      role_[i] = inactive;
    });
  }

  /// Row i of L over the stencil: slot St::slot(d) holds L_{i, i + d} for the offsets whose flat
  /// step is >= 0 only (slots >= K / 2, column i of the lower triangle); L being symmetric, the
  /// other half is read from the neighbour's row (L_{i, i + d} = L_{i + d, i}). Callers add into
  /// those slots only.
  double* row(std::size_t i) { return stencil_.data() + i * K; }
  double& rhs(std::size_t i) { return rhs_[i]; }
  /// Sets a node's role; a prescribed node takes the increment `value`.
  void set_unknown(std::size_t i) { role_[i] = unknown; }
  void prescribe(std::size_t i, double value) {
    role_[i] = prescribed;
    dp_[i] = value;
  }
  Role role(std::size_t i) const { return static_cast<Role>(role_[i]); }

  /// Solves L dp = rhs on the unknown nodes of `box` (prescribed nodes keep their value, inactive
  /// nodes get 0). Returns false when L is not positive definite (a part of the water touches no
  /// prescribed node: its pressure is undetermined).
  bool solve(const Grid<Dim>& g, const NodeBox<Dim>& box) {
    // The equations: every unknown node, and the prescribed nodes that were unknown within the
    // last kStickySteps solves, in increasing flat node index (the stencil walks rows in that
    // order too, so every CSC column comes out sorted). A prescribed node's equation is the
    // identity with a zero right-hand side, decoupled from the others (its known increment moves
    // to its neighbours' right-hand sides, like any prescribed node's); its dp_ is not
    // overwritten. So a node passing back and forth between unknown and prescribed (a free
    // surface moving through the supports) keeps its equation and the pattern, and CHOLMOD's
    // symbolic analysis, stay; while nodes that stay prescribed (drained faces, a settled
    // surface) leave the system at the next rebuild and do not enlarge the factor.
    // The pattern is rebuilt only when an unknown node has no equation, or a node with an
    // equation has lost its water (a node outside the step's box has too: clear() leaves every
    // node outside the box inactive).
    ++solves_;
    int unknown_nodes = 0;
    bool rebuild = pattern_nodes_.empty();
    g.for_each_node(box, [&](std::size_t i, const auto&) {
      if (role_[i] != unknown) return;
      ++unknown_nodes;
      last_unknown_[i] = solves_;
      rebuild = rebuild || !member_[i];
    });
    unknown_count_ = unknown_nodes;
    if (unknown_nodes == 0) return true;
    if (!rebuild)
      rebuild = std::any_of(pattern_nodes_.begin(), pattern_nodes_.end(),
                            [&](int I) { return role_[static_cast<std::size_t>(I)] == inactive; });
    if (rebuild) {
      for (const int I : pattern_nodes_) member_[static_cast<std::size_t>(I)] = 0;
      equations_.clear();
      g.for_each_node(box, [&](std::size_t i, const auto&) {
        const bool keep = role_[i] == unknown || (role_[i] == prescribed && solves_ - last_unknown_[i] <= kStickySteps);
        eq_[i] = keep ? static_cast<int>(equations_.size()) : -1;
        if (!keep) return;
        equations_.push_back(static_cast<int>(i));
        member_[i] = 1;
      });
      box_ = box;
      build_pattern();
    }
    const int n = static_cast<int>(equations_.size());
    double* values = A_.valuePtr();
    const std::size_t nnz = gather_.size();
    for (std::size_t e = 0; e < nnz; ++e) {
      const std::size_t I = entry_node_[e][0], J = entry_node_[e][1];
      values[e] = role_[I] == unknown && role_[J] == unknown ? stencil_[gather_[e]] : (I == J ? 1.0 : 0.0);
    }
    if (!analysed_) {
      cholesky_.analyse(A_);
      analysed_ = true;
      factored_ = false;
    }
    b_.resize(n);
    for (int j = 0; j < n; ++j) {
      const std::size_t I = static_cast<std::size_t>(equations_[j]);
      if (role_[I] != unknown) {
        b_[j] = 0.0;
        continue;
      }
      double r = rhs_[I];
      for (int k = 0; k < K; ++k) {  // move the prescribed neighbours' known increments to the right
        const long J = static_cast<long>(I) + step_[k];
        if (J < 0 || J >= static_cast<long>(role_.size())) continue;  // off the grid (L_IJ = 0)
        // L_IJ from the row holding it: I's own for J >= I, else J's slot of the offset -d.
        const double L_IJ = step_[k] >= 0 ? stencil_[I * K + k] : stencil_[static_cast<std::size_t>(J) * K + (K - 1 - k)];
        if (L_IJ == 0.0) continue;
        if (role_[J] == prescribed) r -= L_IJ * dp_[J];
      }
      b_[j] = r;
    }
    // The factor of an earlier step's L (same pattern: L changes only as the points move) is a
    // preconditioner for conjugate gradients on this step's L; refactorise when CG needs more than
    // kMaxIterations or the factor is kMaxAge steps old. Every decision depends on the numbers
    // only, so the result is the same for any thread count.
    if (factored_ && age_ < kMaxAge && preconditioned_cg()) {
      ++age_;
    } else {
      if (!cholesky_.factorise(A_)) return false;
      factor_values_.assign(values, values + nnz);  // what a restart factorises again
      factored_ = true;
      age_ = 0;
      ++factorisations_;
      if (!cholesky_.solve(b_, x_)) return false;
    }
    for (int j = 0; j < n; ++j)
      if (role_[equations_[j]] == unknown) dp_[equations_[j]] = x_[j];
    return true;
  }

  /// Restart: what a solve carries to the next — the equations and their pattern (kept while the
  /// nodes' roles allow), the sticky memory of formerly unknown nodes, and the factor reused as a
  /// preconditioner, stored as the matrix it was computed from and factorised again on restore
  /// (CHOLMOD's analysis and factorisation depend on the pattern and values only). The rows,
  /// right-hand sides and roles are rebuilt by every step (clear() zeroes what a step wrote).
  void save(Checkpoint& c, const std::string& k) const {
    c.header[k] = {{"solves", solves_},       {"analysed", analysed_},   {"factored", factored_},
                   {"age", age_},             {"pattern_builds", pattern_builds_},
                   {"factorisations", factorisations_}, {"cg_iterations", cg_iterations_},
                   {"rows", A_.rows()}};
    c.put(k + "/equations", equations_);
    c.put(k + "/pattern_nodes", pattern_nodes_);
    c.put(k + "/member", member_);
    c.put(k + "/last_unknown", last_unknown_);
    c.put(k + "/gather", gather_);
    c.put(k + "/entry_node", entry_node_);
    c.put(k + "/outer", std::vector<int>(A_.outerIndexPtr(), A_.outerIndexPtr() + A_.outerSize() + 1));
    c.put(k + "/inner", std::vector<int>(A_.innerIndexPtr(), A_.innerIndexPtr() + A_.nonZeros()));
    c.put(k + "/values", std::vector<double>(A_.valuePtr(), A_.valuePtr() + A_.nonZeros()));
    c.put(k + "/factor_values", factor_values_);
    std::vector<int> box(2 * Dim);
    for (int a = 0; a < Dim; ++a) box[a] = box_.lo[a], box[Dim + a] = box_.hi[a];
    c.put(k + "/box", box);
  }
  void restore(const Checkpoint& c, const std::string& k) {
    const auto& h = c.header.at(k);
    solves_ = h.at("solves");
    age_ = h.at("age");
    pattern_builds_ = h.at("pattern_builds");
    factorisations_ = h.at("factorisations");
    cg_iterations_ = h.at("cg_iterations");
    c.get(k + "/equations", equations_);
    c.get(k + "/pattern_nodes", pattern_nodes_);
    c.get(k + "/member", member_);
    c.get(k + "/last_unknown", last_unknown_);
    c.get(k + "/gather", gather_);
    c.get(k + "/entry_node", entry_node_);
    std::vector<int> outer, inner, box;
    std::vector<double> values;
    c.get(k + "/outer", outer);
    c.get(k + "/inner", inner);
    c.get(k + "/values", values);
    c.get(k + "/factor_values", factor_values_);
    c.get(k + "/box", box);
    for (int a = 0; a < Dim; ++a) box_.lo[a] = box[a], box_.hi[a] = box[Dim + a];
    const Eigen::Index n = h.at("rows");
    A_.resize(n, n);
    A_.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
    std::copy(outer.begin(), outer.end(), A_.outerIndexPtr());
    std::copy(inner.begin(), inner.end(), A_.innerIndexPtr());
    analysed_ = factored_ = false;
    if (h.at("analysed").get<bool>() && n > 0) {
      cholesky_.analyse(A_);
      analysed_ = true;
      if (h.at("factored").get<bool>()) {
        std::copy(factor_values_.begin(), factor_values_.end(), A_.valuePtr());
        factored_ = cholesky_.factorise(A_);
      }
    }
    std::copy(values.begin(), values.end(), A_.valuePtr());
  }

  /// Under mpirun: the same rows, right-hand sides, roles and prescribed increments solved over the
  /// ranks by `solver` (parallel::GridPoisson); the increments land in dp(). Collective.
  template <class RanksSolver>
  auto solve_on_ranks(RanksSolver& solver, const NodeBox<Dim>& box, double rtol) {
    return solver.solve(box, stencil_.data(), rhs_.data(), role_.data(), dp_.data(), 0, rtol);
  }
  NodeArray<double>& dp_nodes() { return dp_; }
  static constexpr double kTolerance = 1e-10;  // relative residual |b - L x| / |b|

  /// The increment at node i (after solve).
  double dp(std::size_t i) const { return dp_[i]; }
  const NodeArray<double>& dp() const { return dp_; }
  int unknown_count() const { return unknown_count_; }
  long factorisations() const { return factorisations_; }
  long cg_iterations() const { return cg_iterations_; }
  long pattern_builds() const { return pattern_builds_; }

 private:
  static constexpr int kMaxIterations = 10;
  static constexpr long kStickySteps = 100;   // solves a formerly unknown node keeps its equation
  static constexpr int kMaxAge = 50;          // steps

  /// x_ = L^-1 b_ by conjugate gradients preconditioned with the stored (older) factor, from
  /// x = 0. Returns false (x_ undefined) when it needs more than kMaxIterations.
  bool preconditioned_cg() {
    const Eigen::Index n = b_.size();
    const double b_norm = b_.norm();
    x_.setZero(n);
    if (b_norm == 0.0) return true;
    r_ = b_;
    cholesky_.solve(r_, z_);
    d_ = z_;
    double rz = r_.dot(z_);
    for (int it = 1; it <= kMaxIterations; ++it) {
      q_.noalias() = A_.selfadjointView<Eigen::Lower>() * d_;
      const double alpha = rz / d_.dot(q_);
      x_ += alpha * d_;
      r_ -= alpha * q_;
      ++cg_iterations_;
      if (r_.norm() <= kTolerance * b_norm) return true;
      cholesky_.solve(r_, z_);
      const double rz_new = r_.dot(z_);
      d_ = z_ + (rz_new / rz) * d_;
      rz = rz_new;
    }
    return false;
  }

  /// Lower-triangle CSC pattern of the equation nodes (linear::StencilPattern), with the stencil
  /// slot and the two nodes of every entry.
  void build_pattern() {
    pattern_.build(nodes_, box_, equations_, eq_, linear::Storage::lower, A_);
    const auto& entries = pattern_.entries();
    gather_.resize(entries.size());
    entry_node_.resize(entries.size());
    for (std::size_t e = 0; e < entries.size(); ++e) {
      gather_[e] = entries[e].J * K + static_cast<std::size_t>(entries[e].k);  // row J's slot of I: L_IJ = L_JI
      entry_node_[e] = {entries[e].I, entries[e].J};
    }
    pattern_nodes_ = equations_;
    analysed_ = false;
    ++pattern_builds_;
  }
  static NodeBox<Dim> empty_box() {
    NodeBox<Dim> b;
    b.lo.fill(std::numeric_limits<int>::max());
    b.hi.fill(std::numeric_limits<int>::min());
    return b;
  }

  std::array<int, Dim> nodes_;
  std::array<long, K> step_{};
  NodeArray<double> stencil_;  // per node: row of L over the stencil
  NodeArray<double> rhs_, dp_;
  NodeArray<std::uint8_t> role_;
  std::vector<int> eq_, equations_, pattern_nodes_;
  NodeArray<std::uint8_t> member_;  // per node: has an equation in the current pattern
  std::vector<long> last_unknown_;    // per node: the solve at which it was last unknown
  long solves_ = 0;
  NodeBox<Dim> cleared_ = empty_box();  // the box of the last clear()
  int unknown_count_ = 0;
  NodeBox<Dim> box_{};  // the box while the pattern is built (nodes outside it hold stale eq_)
  std::vector<std::size_t> gather_;                   // per CSC entry: its slot in stencil_
  std::vector<std::array<std::size_t, 2>> entry_node_;  // per CSC entry: its row and column nodes
  linear::StencilPattern<Dim, R> pattern_;
  linear::CscMatrix A_;
  Eigen::VectorXd b_, x_, r_, z_, d_, q_;  // right-hand side, solution, CG work vectors
  linear::Cholesky cholesky_;
  std::vector<double> factor_values_;  // A_'s values when it was last factorised
  bool analysed_ = false, factored_ = false;
  int age_ = 0;  // steps since the last factorisation
  long pattern_builds_ = 0, factorisations_ = 0, cg_iterations_ = 0;
};

}  // namespace swmpm
