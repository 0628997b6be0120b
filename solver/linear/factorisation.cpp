#include "solver/linear/factorisation.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/UmfPackSupport>
#include <cstdio>
#include <string>
#include <type_traits>

namespace swmpm::linear {

namespace {
/// Eigen's UMFPACK wrapper with the status and statistics it keeps (protected there): why a
/// factorisation failed, and the analysis' estimate of the factor's peak memory.
struct UmfPack : Eigen::UmfPackLU<CscMatrix> {
  int status() const { return m_fact_errorCode; }
  double peak_memory_bytes() const { return m_umfpackInfo(UMFPACK_PEAK_MEMORY_ESTIMATE) * m_umfpackInfo(UMFPACK_SIZE_OF_UNIT); }
};

std::string gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
  return text;
}
}  // namespace

template <Method M>
struct Direct<M>::Impl {
  std::conditional_t<M == Method::cholesky, Eigen::CholmodSupernodalLLT<CscMatrix, Eigen::Lower>, UmfPack> solver;
};

template <Method M>
Direct<M>::Direct() : impl_(std::make_unique<Impl>()) {
  // UMFPACK refines each solve iteratively by default (up to 2 steps, each a product with A and
  // a solve): a caller that reuses a factor as a Krylov preconditioner refines already, so the
  // solve is the plain forward and back substitution.
  //
  // The ordering: the v-p systems of mpm-fem are structurally symmetric, and UMFPACK's symmetric
  // strategy (AMD or METIS on A + A^T, diagonal pivots preferred) with its "best" ordering (it
  // tries several and keeps the one of least fill) leaves fewer entries in L + U than the default
  // unsymmetric COLAMD: on the 81 x 41-node grid of examples/column-in-water-and-air-mpm-fem
  // (9,963 unknowns) 4.04e6 against 5.49e6, and each substitution streams the whole factor, so
  // its solves took 33 % less time (3.61 s against 5.36 s over 100 steps, 1 thread). The ordering
  // is chosen once, in the symbolic analysis.
  if constexpr (M == Method::lu) {
    auto& control = impl_->solver.umfpackControl();
    control(UMFPACK_IRSTEP) = 0;
    control(UMFPACK_STRATEGY) = UMFPACK_STRATEGY_SYMMETRIC;
    control(UMFPACK_ORDERING) = UMFPACK_ORDERING_BEST;
  }
}
template <Method M>
Direct<M>::~Direct() = default;

template <Method M>
void Direct<M>::analyse(const CscMatrix& A) {
  impl_->solver.analyzePattern(A);
  ++analyses_;
}
template <Method M>
bool Direct<M>::factorise(const CscMatrix& A) {
  impl_->solver.factorize(A);
  ++factorisations_;
  const bool ok = impl_->solver.info() == Eigen::Success;
  failure_.clear();
  if (ok) return true;
  if constexpr (M == Method::lu) {
    const int status = impl_->solver.status();
    if (status == UMFPACK_ERROR_out_of_memory)
      failure_ = "UMFPACK ran out of memory factorising " + std::to_string(A.rows()) + " unknowns (its estimate of the peak: " +
                 gigabytes(impl_->solver.peak_memory_bytes()) + ")";
    else if (status == UMFPACK_WARNING_singular_matrix)
      failure_ = "the matrix is singular (UMFPACK)";
    else
      failure_ = "UMFPACK's factorisation failed (status " + std::to_string(status) + ")";
  } else {
    failure_ = "the matrix is not positive definite (CHOLMOD)";
  }
  return false;
}
template <Method M>
bool Direct<M>::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  x = impl_->solver.solve(b);
  return impl_->solver.info() == Eigen::Success;
}

template class Direct<Method::cholesky>;
template class Direct<Method::lu>;

}  // namespace swmpm::linear
