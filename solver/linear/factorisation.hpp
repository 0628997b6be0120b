// Sparse direct solvers of SuiteSparse behind one small interface (the library's headers stay in
// factorisation.cpp):
//   Cholesky  CHOLMOD's supernodal LL^T of a symmetric positive definite matrix, lower triangle
//             stored (the semi-implicit pressure Poisson, seed 001 eq. 60);
//   LU        UMFPACK's LU of a general (non-symmetric) matrix, every entry stored (the mpm-fem
//             velocity-pressure system, seed 004).
// Both split the symbolic analysis (pattern only: fill-reducing ordering, elimination tree) from
// the numeric factorisation, so a caller whose pattern is fixed (linear/stencil.hpp) analyses
// once and factorises each time the values change.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "solver/linear/stencil.hpp"

namespace swmpm::linear {

enum class Method { cholesky, lu };

template <Method M>
class Direct {
 public:
  Direct();
  ~Direct();
  Direct(const Direct&) = delete;
  Direct& operator=(const Direct&) = delete;

  /// Symbolic analysis of A's pattern (Cholesky: the lower triangle; LU: every entry).
  void analyse(const CscMatrix& A);
  /// Numeric factorisation of A (the pattern analysed last); false if A is singular (Cholesky:
  /// not positive definite).
  bool factorise(const CscMatrix& A);
  /// x = A^-1 b with the last factor; false if the solve failed.
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;

  /// Why the last factorisation failed, in words ("" after a success): LU says whether the
  /// matrix was singular or the factor did not fit in memory (with UMFPACK's estimate of it).
  const std::string& failure() const { return failure_; }

  long analyses() const { return analyses_; }
  long factorisations() const { return factorisations_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  long analyses_ = 0, factorisations_ = 0;
  std::string failure_;
};

using Cholesky = Direct<Method::cholesky>;
using LU = Direct<Method::lu>;

extern template class Direct<Method::cholesky>;
extern template class Direct<Method::lu>;

}  // namespace swmpm::linear
