#include "solver/parallel/poisson.hpp"

#include <petscksp.h>

#include <stdexcept>
#include <utility>
#include <string>

namespace swmpm::parallel {

namespace {
void petsc(PetscErrorCode code) {
  if (code != 0) throw std::runtime_error("PETSc error " + std::to_string(static_cast<int>(code)) + " (see above)");
}
}  // namespace

struct KspSolve::Impl {
  ::Mat A = nullptr;
  ::Vec x = nullptr, b = nullptr;
  KSP ksp = nullptr;
  void reset() {
    KSPDestroy(&ksp);
    MatDestroy(&A);
    VecDestroy(&x);
    VecDestroy(&b);
  }
  ~Impl() { reset(); }
};

KspSolve::KspSolve() : impl_(std::make_unique<Impl>()) {}
KspSolve::~KspSolve() = default;

KspSolve::Stats KspSolve::solve(long n, long N, const std::vector<long>& rows, const std::vector<long>& cols,
                                const std::vector<double>& values, const std::vector<long>& b_rows,
                                const std::vector<double>& b_values, const std::vector<long>& wanted,
                                std::vector<double>& x_wanted, double rtol) {
  Impl& m = *impl_;
  m.reset();
  // The matrix from coordinates (MatSetPreallocationCOO: entries of other ranks' rows are sent
  // there, duplicates added). Built anew each solve: the water's extent changes the rows that
  // couple, and hypre's setup is redone anyway.
  petsc(MatCreate(PETSC_COMM_WORLD, &m.A));
  petsc(MatSetSizes(m.A, static_cast<PetscInt>(n), static_cast<PetscInt>(n), static_cast<PetscInt>(N), static_cast<PetscInt>(N)));
  petsc(MatSetType(m.A, MATAIJ));
  std::vector<PetscInt> ri(rows.begin(), rows.end()), ci(cols.begin(), cols.end());
  petsc(MatSetPreallocationCOO(m.A, static_cast<PetscCount>(ri.size()), ri.data(), ci.data()));
  petsc(MatSetValuesCOO(m.A, values.data(), ADD_VALUES));
  petsc(MatCreateVecs(m.A, &m.x, &m.b));
  petsc(VecZeroEntries(m.b));
  std::vector<PetscInt> bi(b_rows.begin(), b_rows.end());
  petsc(VecSetValues(m.b, static_cast<PetscInt>(bi.size()), bi.data(), b_values.data(), ADD_VALUES));
  petsc(VecAssemblyBegin(m.b));
  petsc(VecAssemblyEnd(m.b));

  petsc(KSPCreate(PETSC_COMM_WORLD, &m.ksp));
  petsc(KSPSetOperators(m.ksp, m.A, m.A));
  petsc(KSPSetType(m.ksp, KSPCG));
  PC pc;
  petsc(KSPGetPC(m.ksp, &pc));
  petsc(PCSetType(pc, PCHYPRE));
  petsc(PCHYPRESetType(pc, "boomeramg"));
  petsc(KSPSetNormType(m.ksp, KSP_NORM_UNPRECONDITIONED));
  petsc(KSPSetTolerances(m.ksp, rtol, 0.0, PETSC_DEFAULT, 1000));
  // BoomerAMG's settings for 3D operators with wide stencils (a quadratic B-spline's row couples
  // 125 nodes): HMIS coarsening, extended+i interpolation with at most 4 entries per row, one level
  // of aggressive coarsening, strength threshold 0.5. Measured 2026-12-06 (Poisson.* tests, one
  // rank): 3D 8,400 unknowns 1.34 -> 0.26 s per solve (24 -> 25 iterations), 2D 49,408 unknowns
  // 1.02 -> 0.41 s (11 -> 18 iterations), against hypre's defaults. PETSC_OPTIONS overrides any.
  for (const auto& [name, value] : {std::pair{"-pc_hypre_boomeramg_coarsen_type", "HMIS"},
                                    std::pair{"-pc_hypre_boomeramg_interp_type", "ext+i"},
                                    std::pair{"-pc_hypre_boomeramg_P_max", "4"},
                                    std::pair{"-pc_hypre_boomeramg_agg_nl", "1"},
                                    std::pair{"-pc_hypre_boomeramg_strong_threshold", "0.5"}}) {
    PetscBool set = PETSC_FALSE;
    petsc(PetscOptionsHasName(nullptr, nullptr, name, &set));
    if (!set) petsc(PetscOptionsSetValue(nullptr, name, value));
  }
  petsc(KSPSetFromOptions(m.ksp));  // PETSC_OPTIONS may tune it (-ksp_*, -pc_hypre_*)
  petsc(VecZeroEntries(m.x));
  petsc(KSPSolve(m.ksp, m.b, m.x));

  Stats s;
  PetscInt its = 0;
  KSPConvergedReason reason;
  petsc(KSPGetIterationNumber(m.ksp, &its));
  petsc(KSPGetConvergedReason(m.ksp, &reason));
  s.iterations = static_cast<int>(its);
  s.converged = reason > 0;
  PetscReal bnorm = 0.0, rnorm = 0.0;
  petsc(VecNorm(m.b, NORM_2, &bnorm));
  petsc(KSPGetResidualNorm(m.ksp, &rnorm));
  s.relative_residual = bnorm > 0.0 ? rnorm / bnorm : 0.0;

  // The solution at the rows this rank wants (its columns and their neighbours').
  IS is;
  std::vector<PetscInt> wi(wanted.begin(), wanted.end());
  petsc(ISCreateGeneral(PETSC_COMM_SELF, static_cast<PetscInt>(wi.size()), wi.data(), PETSC_COPY_VALUES, &is));
  ::Vec local;
  petsc(VecCreateSeq(PETSC_COMM_SELF, static_cast<PetscInt>(wi.size()), &local));
  VecScatter scatter;
  petsc(VecScatterCreate(m.x, is, local, nullptr, &scatter));
  petsc(VecScatterBegin(scatter, m.x, local, INSERT_VALUES, SCATTER_FORWARD));
  petsc(VecScatterEnd(scatter, m.x, local, INSERT_VALUES, SCATTER_FORWARD));
  x_wanted.resize(wi.size());
  const PetscScalar* a = nullptr;
  petsc(VecGetArrayRead(local, &a));
  for (std::size_t k = 0; k < wi.size(); ++k) x_wanted[k] = a[k];
  petsc(VecRestoreArrayRead(local, &a));
  VecScatterDestroy(&scatter);
  VecDestroy(&local);
  ISDestroy(&is);
  return s;
}

}  // namespace swmpm::parallel
