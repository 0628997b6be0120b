#include "solver/parallel/sparse_solve.hpp"

#include <petscksp.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "solver/parallel/comm.hpp"
#include "solver/parallel/petsc_check.hpp"

namespace swmpm::parallel {

// BiCGSTAB and its preconditioner; for an LU, the preconditioner alone is a direct solve right
// after a factorisation.
struct SparseSolve::Impl {
  ::Mat A = nullptr;
  ::Vec x = nullptr, b = nullptr, x_all = nullptr;
  VecScatter to_all = nullptr;
  PC pc = nullptr;
  KSP krylov = nullptr;
  void reset() {  // (one rank never sets anything up, and never starts PETSc: nothing to call)
    if (krylov) KSPDestroy(&krylov);
    if (pc) PCDestroy(&pc);
    if (to_all) VecScatterDestroy(&to_all);
    if (x_all) VecDestroy(&x_all);
    if (x) VecDestroy(&x);
    if (b) VecDestroy(&b);
    if (A) MatDestroy(&A);
  }
  ~Impl() { reset(); }
};

SparseSolve::SparseSolve(Preconditioner p) : impl_(std::make_unique<Impl>()), kind_(p) {}
SparseSolve::~SparseSolve() = default;

void SparseSolve::set_pattern(long first, long n, long N, const std::vector<long>& rows, const std::vector<long>& cols,
                              const std::vector<long>& b_rows) {
  Impl& m = *impl_;
  m.reset();
  first_ = first, n_ = n, n_total_ = N;
  petsc(MatCreate(PETSC_COMM_WORLD, &m.A));
  petsc(MatSetSizes(m.A, static_cast<PetscInt>(n), static_cast<PetscInt>(n), static_cast<PetscInt>(N), static_cast<PetscInt>(N)));
  petsc(MatSetType(m.A, MATAIJ));
  // PETSc may rewrite the coordinates it is given: copies.
  std::vector<PetscInt> ri(rows.begin(), rows.end()), ci(cols.begin(), cols.end()), bi(b_rows.begin(), b_rows.end());
  petsc(MatSetPreallocationCOO(m.A, static_cast<PetscCount>(ri.size()), ri.data(), ci.data()));
  petsc(MatCreateVecs(m.A, &m.x, &m.b));
  petsc(VecZeroEntries(m.x));
  petsc(VecSetPreallocationCOO(m.b, static_cast<PetscCount>(bi.size()), bi.data()));
  petsc(VecScatterCreateToAll(m.x, &m.to_all, &m.x_all));

  petsc(PCCreate(PETSC_COMM_WORLD, &m.pc));
  petsc(PCSetOperators(m.pc, m.A, m.A));
  if (kind_ == Preconditioner::lu) {
    petsc(PCSetType(m.pc, PCLU));
    petsc(PCFactorSetMatSolverType(m.pc, MATSOLVERMUMPS));
    petsc(PCSetOptionsPrefix(m.pc, "fluid_"));  // PETSC_OPTIONS may tune MUMPS: -fluid_mat_mumps_icntl_14 50
  } else {
    petsc(PCSetType(m.pc, PCJACOBI));
    petsc(PCSetOptionsPrefix(m.pc, "phase_"));
  }
  petsc(PCSetFromOptions(m.pc));

  petsc(KSPCreate(PETSC_COMM_WORLD, &m.krylov));
  petsc(KSPSetPC(m.krylov, m.pc));
  petsc(KSPSetOperators(m.krylov, m.A, m.A));
  petsc(KSPSetType(m.krylov, KSPBCGS));
  // As Eigen's BiCGSTAB at one rank: the preconditioner on the right, the test on the true
  // residual, the last solution (or the caller's guess) as the start. An LU is reused until the
  // caller factorises; the diagonal is taken again each solve.
  petsc(KSPSetPCSide(m.krylov, PC_RIGHT));
  petsc(KSPSetNormType(m.krylov, KSP_NORM_UNPRECONDITIONED));
  petsc(KSPSetInitialGuessNonzero(m.krylov, PETSC_TRUE));
  petsc(KSPSetReusePreconditioner(m.krylov, kind_ == Preconditioner::lu ? PETSC_TRUE : PETSC_FALSE));
}

SparseSolve::Stats SparseSolve::solve(const std::vector<double>& values, const std::vector<double>& b_values,
                                      bool factorise, double rtol, int max_iterations, std::vector<double>& x,
                                      const double* guess) {
  Impl& m = *impl_;
  Stats s;
  factorise = factorise && kind_ == Preconditioner::lu;
  petsc(MatSetValuesCOO(m.A, values.data(), INSERT_VALUES));
  petsc(VecSetValuesCOO(m.b, b_values.data(), INSERT_VALUES));
  double t0 = wall_time();
  if (factorise) {
    // A fresh numeric factorisation of the new values (the symbolic one is the pattern's), then
    // x = A^-1 b by the factor alone.
    ++factorisations_;
    petsc(PCSetReusePreconditioner(m.pc, PETSC_FALSE));
    petsc(PCSetUp(m.pc));
    PCFailedReason failed = PC_NOERROR;
    petsc(PCGetFailedReason(m.pc, &failed));
    petsc(PCSetReusePreconditioner(m.pc, PETSC_TRUE));
    const double t1 = wall_time();
    s.seconds_factorise = t1 - t0;
    t0 = t1;
    failure_.clear();
    if (const long worst = max(static_cast<long>(failed)); worst != PC_NOERROR) {  // the same words on every rank
      const auto reason = static_cast<PCFailedReason>(worst);
      failure_ = reason == PC_FACTOR_OUTMEMORY ? "MUMPS ran out of memory factorising " + std::to_string(n_total_) + " unknowns"
                 : reason == PC_FACTOR_NUMERIC_ZEROPIVOT || reason == PC_FACTOR_STRUCT_ZEROPIVOT
                     ? std::string("the matrix is singular (MUMPS: a zero pivot)")
                     : "MUMPS's factorisation failed (PETSc's reason " + std::to_string(worst) + ")";
      s.seconds_solve = wall_time() - t0;
      return s;
    }
    petsc(PCApply(m.pc, m.b, m.x));
    s.ok = true;
  } else {
    if (guess) {
      PetscScalar* a = nullptr;
      petsc(VecGetArray(m.x, &a));
      for (long k = 0; k < n_; ++k) a[k] = guess[first_ + k];
      petsc(VecRestoreArray(m.x, &a));
    }
    petsc(KSPSetTolerances(m.krylov, rtol, 0.0, PETSC_DEFAULT, max_iterations));
    petsc(KSPSolve(m.krylov, m.b, m.x));
    PetscInt its = 0;
    KSPConvergedReason reason;
    petsc(KSPGetIterationNumber(m.krylov, &its));
    petsc(KSPGetConvergedReason(m.krylov, &reason));
    s.iterations = static_cast<int>(its);
    s.ok = reason > 0;
  }
  // Every rank takes the whole solution (the fluid's state is whole on every rank).
  const double t2 = wall_time();
  petsc(VecScatterBegin(m.to_all, m.x, m.x_all, INSERT_VALUES, SCATTER_FORWARD));
  petsc(VecScatterEnd(m.to_all, m.x, m.x_all, INSERT_VALUES, SCATTER_FORWARD));
  PetscInt size = 0;
  petsc(VecGetSize(m.x_all, &size));
  x.resize(static_cast<std::size_t>(size));
  const PetscScalar* a = nullptr;
  petsc(VecGetArrayRead(m.x_all, &a));
  bool finite = true;
  for (PetscInt k = 0; k < size; ++k) {
    x[static_cast<std::size_t>(k)] = a[k];
    finite = finite && std::isfinite(a[k]);
  }
  petsc(VecRestoreArrayRead(m.x_all, &a));
  add_communication_seconds(wall_time() - t2, Traffic::exchange);
  s.ok = s.ok && finite;
  s.seconds_solve = wall_time() - t0;
  if (!s.ok && !factorise) petsc(VecZeroEntries(m.x));  // a failed Krylov solve's x is no start for the next
  return s;
}

}  // namespace swmpm::parallel
