// solver/linear/: the structured-grid fixed-pattern assembly (StencilPattern) against a dense
// assembly of the same operator, and the SuiteSparse solvers behind linear::Cholesky (CHOLMOD)
// and linear::LU (UMFPACK) against manufactured solutions, with the symbolic analysis reused
// across factorisations and singular or indefinite matrices reported.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "solver/linear/factorisation.hpp"
#include "solver/linear/stencil.hpp"

using namespace swmpm;
using namespace swmpm::linear;

namespace {

constexpr int R = 1;  // linear shape functions: rows reach one node per axis
using St2 = Stencil<2, R>;
const std::array<int, 2> kNodes = {6, 5};
constexpr int kN = 6 * 5;

NodeBox<2> whole() {
  NodeBox<2> b;
  b.lo = {0, 0};
  b.hi = {kNodes[0] - 1, kNodes[1] - 1};
  return b;
}

/// Every node an equation except those in `skip` (increasing order, as StencilPattern needs).
void equations_except(const std::vector<int>& skip, std::vector<int>& eqs, std::vector<int>& eq_of) {
  eqs.clear();
  eq_of.assign(kN, -1);
  for (int i = 0; i < kN; ++i) {
    if (std::find(skip.begin(), skip.end(), i) != skip.end()) continue;
    eq_of[i] = static_cast<int>(eqs.size());
    eqs.push_back(i);
  }
}

/// A(I a, J b) of a test operator on the 9-point stencil (unknowns a, b of nodes I, J); symmetric positive
/// definite when `symmetric` (a shifted graph Laplacian, coupling the unknowns), otherwise with
/// an upwind-like skew part and an off-diagonal block coupling. 0 beyond the stencil.
double op(int I, int a, int J, int b, bool symmetric) {
  const int ix = I % kNodes[0], iy = I / kNodes[0], jx = J % kNodes[0], jy = J / kNodes[0];
  const int dx = jx - ix, dy = jy - iy;
  if (std::abs(dx) > R || std::abs(dy) > R) return 0.0;
  if (I == J) return a == b ? 10.0 + 0.1 * I + a : (symmetric ? 0.5 : 0.5 + 0.3 * a);
  const double w = (dx != 0 && dy != 0) ? -0.25 : -1.0;
  if (symmetric) return a == b ? w * (1.0 + 0.01 * (I + J)) : 0.0;
  return a == b ? w + 0.4 * dx - 0.2 * dy : 0.1 * (a - b) * dx;
}

/// The system's matrix from the pattern: each entry's value read off the per-node rows, as an
/// assembler does (the row of node I, the slot of the offset J - I: K - 1 - k for entry slot k).
template <int B>
CscMatrix assemble(const StencilPattern<2, R, B>& pat, CscMatrix A, bool symmetric) {
  std::vector<double> rows(static_cast<std::size_t>(kN) * St2::K * B * B, 0.0);
  for (int I = 0; I < kN; ++I)
    for (int k = 0; k < St2::K; ++k) {
      const auto d = St2::offset(k);
      const int jx = I % kNodes[0] + d[0], jy = I / kNodes[0] + d[1];
      if (jx < 0 || jy < 0 || jx >= kNodes[0] || jy >= kNodes[1]) continue;
      for (int a = 0; a < B; ++a)
        for (int b = 0; b < B; ++b)
          rows[((static_cast<std::size_t>(I) * St2::K + k) * B + a) * B + b] = op(I, a, jx + jy * kNodes[0], b, symmetric);
    }
  const auto& entries = pat.entries();
  for (std::size_t e = 0; e < entries.size(); ++e) {
    const Entry& en = entries[e];
    A.valuePtr()[e] = rows[((en.I * St2::K + (St2::K - 1 - en.k)) * B + en.a) * B + en.b];
  }
  return A;
}

Eigen::VectorXd random_vector(Eigen::Index n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) x[i] = u(rng);
  return x;
}

}  // namespace

// The pattern against the dense operator: every nonzero of the dense lower triangle (B = 1) or
// of the whole matrix (B = 2) is stored, nothing else, columns sorted, and the gathered values
// are the operator's.
TEST(Linear, StencilPatternHoldsExactlyTheOperatorsEntries) {
  std::vector<int> eqs, eq_of;
  equations_except({0, 7, 29}, eqs, eq_of);  // three nodes without an equation (a corner, inner, corner)
  for (const bool lower : {true, false}) {
    constexpr int B = 2;
    StencilPattern<2, R, B> pat;
    CscMatrix A;
    pat.build(kNodes, whole(), eqs, eq_of, lower ? Storage::lower : Storage::full, A);
    A = assemble(pat, A, lower);
    const int n = static_cast<int>(eqs.size()) * B;
    ASSERT_EQ(A.rows(), n);
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
    long expected_nnz = 0;
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) {
        if (lower && r < c) continue;
        const double v = op(eqs[r / B], r % B, eqs[c / B], c % B, lower);
        dense(r, c) = v;
        const int dx = eqs[r / B] % kNodes[0] - eqs[c / B] % kNodes[0], dy = eqs[r / B] / kNodes[0] - eqs[c / B] / kNodes[0];
        expected_nnz += std::abs(dx) <= R && std::abs(dy) <= R;  // the stencil's reach, zero values included
      }
    EXPECT_EQ(A.nonZeros(), expected_nnz);
    EXPECT_EQ((Eigen::MatrixXd(A) - dense).cwiseAbs().maxCoeff(), 0.0);
    for (int c = 0; c < n; ++c)
      for (int e = A.outerIndexPtr()[c] + 1; e < A.outerIndexPtr()[c + 1]; ++e)
        EXPECT_LT(A.innerIndexPtr()[e - 1], A.innerIndexPtr()[e]);
  }
  // A node outside the box is no neighbour: with the box cut to x <= 2 the columns of x = 2 stop there.
  StencilPattern<2, R> pat;
  CscMatrix A;
  NodeBox<2> left = whole();
  left.hi[0] = 2;
  std::vector<int> eqs_left, eq_of_left(kN, -1);
  for (int i = 0; i < kN; ++i)
    if (i % kNodes[0] <= 2) eq_of_left[i] = static_cast<int>(eqs_left.size()), eqs_left.push_back(i);
  pat.build(kNodes, left, eqs_left, eq_of_left, Storage::lower, A);
  for (const Entry& e : pat.entries()) EXPECT_LE(static_cast<int>(e.I % kNodes[0]), 2);
}

// CHOLMOD: an SPD system on the grid solved to round-off; new values on the same pattern are
// factorised without a new analysis; an indefinite matrix is reported.
TEST(Linear, CholeskySolvesAndReusesItsAnalysis) {
  std::vector<int> eqs, eq_of;
  equations_except({}, eqs, eq_of);
  StencilPattern<2, R> pat;
  CscMatrix A;
  pat.build(kNodes, whole(), eqs, eq_of, Storage::lower, A);
  A = assemble(pat, A, true);
  const Eigen::VectorXd x_true = random_vector(A.rows(), 1);
  const Eigen::VectorXd b = A.selfadjointView<Eigen::Lower>() * x_true;
  Cholesky chol;
  chol.analyse(A);
  ASSERT_TRUE(chol.factorise(A));
  Eigen::VectorXd x;
  ASSERT_TRUE(chol.solve(b, x));
  EXPECT_LT((x - x_true).norm() / x_true.norm(), 1e-13);
  // Scaled values, same pattern: one analysis, two factorisations, x / 2.
  CscMatrix A2 = 2.0 * A;
  ASSERT_TRUE(chol.factorise(A2));
  ASSERT_TRUE(chol.solve(b, x));
  EXPECT_LT((2.0 * x - x_true).norm() / x_true.norm(), 1e-13);
  EXPECT_EQ(chol.analyses(), 1);
  EXPECT_EQ(chol.factorisations(), 2);
  // Indefinite: one diagonal entry negative.
  CscMatrix bad = A;
  bad.coeffRef(3, 3) = -50.0;
  EXPECT_FALSE(chol.factorise(bad));
}

// UMFPACK: a non-symmetric block system (two unknowns per node, coupled) solved to round-off,
// refactorised on new values without a new analysis; a singular matrix is reported.
TEST(Linear, LUSolvesNonSymmetricBlockSystems) {
  std::vector<int> eqs, eq_of;
  equations_except({12}, eqs, eq_of);
  StencilPattern<2, R, 2> pat;
  CscMatrix A;
  pat.build(kNodes, whole(), eqs, eq_of, Storage::full, A);
  A = assemble(pat, A, false);
  ASSERT_GT((Eigen::MatrixXd(A) - Eigen::MatrixXd(A).transpose()).cwiseAbs().maxCoeff(), 0.1);  // non-symmetric
  const Eigen::VectorXd x_true = random_vector(A.rows(), 2);
  const Eigen::VectorXd b = A * x_true;
  LU lu;
  lu.analyse(A);
  ASSERT_TRUE(lu.factorise(A));
  Eigen::VectorXd x;
  ASSERT_TRUE(lu.solve(b, x));
  EXPECT_LT((x - x_true).norm() / x_true.norm(), 1e-13);
  // The transpose's values in the same pattern would not fit; perturb the diagonal instead.
  CscMatrix A2 = A;
  for (int i = 0; i < A2.rows(); ++i) A2.coeffRef(i, i) += 1.0;
  ASSERT_TRUE(lu.factorise(A2));
  ASSERT_TRUE(lu.solve(A2 * x_true, x));
  EXPECT_LT((x - x_true).norm() / x_true.norm(), 1e-13);
  EXPECT_EQ(lu.analyses(), 1);
  EXPECT_EQ(lu.factorisations(), 2);
  EXPECT_EQ(lu.failure(), "");
  // Singular: a zero column, and the reason in words (mpm-fem reports it when its fluid fails).
  CscMatrix singular = A;
  for (int e = singular.outerIndexPtr()[5]; e < singular.outerIndexPtr()[6]; ++e) singular.valuePtr()[e] = 0.0;
  EXPECT_FALSE(lu.factorise(singular));
  EXPECT_EQ(lu.failure(), "the matrix is singular (UMFPACK)");
  ASSERT_TRUE(lu.factorise(A2));
  EXPECT_EQ(lu.failure(), "");
}
