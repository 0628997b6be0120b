#include "solver/linear/factorisation.hpp"

#include <Eigen/CholmodSupport>
#include <Eigen/UmfPackSupport>

namespace swmpm::linear {

struct Cholesky::Impl {
  Eigen::CholmodSupernodalLLT<CscMatrix, Eigen::Lower> llt;
};

Cholesky::Cholesky() : impl_(std::make_unique<Impl>()) {}
Cholesky::~Cholesky() = default;

void Cholesky::analyse(const CscMatrix& A) {
  impl_->llt.analyzePattern(A);
  ++analyses_;
}
bool Cholesky::factorise(const CscMatrix& A) {
  impl_->llt.factorize(A);
  ++factorisations_;
  return impl_->llt.info() == Eigen::Success;
}
bool Cholesky::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  x = impl_->llt.solve(b);
  return impl_->llt.info() == Eigen::Success;
}

struct LU::Impl {
  Eigen::UmfPackLU<CscMatrix> lu;
};

LU::LU() : impl_(std::make_unique<Impl>()) {}
LU::~LU() = default;

void LU::analyse(const CscMatrix& A) {
  impl_->lu.analyzePattern(A);
  ++analyses_;
}
bool LU::factorise(const CscMatrix& A) {
  impl_->lu.factorize(A);
  ++factorisations_;
  return impl_->lu.info() == Eigen::Success;
}
bool LU::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  x = impl_->lu.solve(b);
  return impl_->lu.info() == Eigen::Success;
}

}  // namespace swmpm::linear
