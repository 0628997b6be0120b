#include "solver/linear/factorisation.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/UmfPackSupport>
#include <type_traits>

namespace swmpm::linear {

template <Method M>
struct Direct<M>::Impl {
  std::conditional_t<M == Method::cholesky, Eigen::CholmodSupernodalLLT<CscMatrix, Eigen::Lower>,
                     Eigen::UmfPackLU<CscMatrix>>
      solver;
};

template <Method M>
Direct<M>::Direct() : impl_(std::make_unique<Impl>()) {
  // UMFPACK refines each solve iteratively by default (up to 2 steps, each a product with A and
  // a solve): a caller that reuses a factor as a Krylov preconditioner refines already, so the
  // solve is the plain forward and back substitution.
  if constexpr (M == Method::lu) impl_->solver.umfpackControl()(UMFPACK_IRSTEP) = 0;
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
  return impl_->solver.info() == Eigen::Success;
}
template <Method M>
bool Direct<M>::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  x = impl_->solver.solve(b);
  return impl_->solver.info() == Eigen::Success;
}

template class Direct<Method::cholesky>;
template class Direct<Method::lu>;

}  // namespace swmpm::linear
