#include "solver/parallel/poisson.hpp"

#include <petscksp.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "solver/parallel/petsc_check.hpp"

namespace swmpm::parallel {

struct KspSolve::Impl {
  ::Mat A = nullptr;
  ::Vec x = nullptr, b = nullptr;
  KSP ksp = nullptr;
  std::vector<PetscInt> rows, cols;  // the matrix's coordinates (its pattern)
  long n = -1, N = -1;
  int age = 0;                // solves since hypre's last setup
  int setup_iterations = 0;   // CG iterations of the solve right after it
  bool fresh = true;          // the next solve sets the preconditioner up again
  long setups = 0;
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
long KspSolve::setups() const { return impl_->setups; }

namespace {
/// CG on A with the preconditioner `kind` (the solver's settings; PETSC_OPTIONS may override them).
void create_ksp(::Mat A, double rtol, KspSolve::Preconditioner kind, KSP& ksp) {
  petsc(KSPCreate(PETSC_COMM_WORLD, &ksp));
  petsc(KSPSetOperators(ksp, A, A));
  petsc(KSPSetType(ksp, KSPCG));
  PC pc;
  petsc(KSPGetPC(ksp, &pc));
  if (kind == KspSolve::Preconditioner::redundant_cholesky) {
    // Every rank factorises the whole system with CHOLMOD (PCREDUNDANT), reused as the one-rank
    // path reuses its factor.
    petsc(PCSetType(pc, PCREDUNDANT));
    KSP inner;
    PC inner_pc;
    petsc(PCRedundantGetKSP(pc, &inner));
    petsc(KSPGetPC(inner, &inner_pc));
    petsc(PCSetType(inner_pc, PCCHOLESKY));
    petsc(PCFactorSetMatSolverType(inner_pc, MATSOLVERCHOLMOD));
  } else {
    petsc(PCSetType(pc, PCHYPRE));
    petsc(PCHYPRESetType(pc, "boomeramg"));
  }
  petsc(KSPSetNormType(ksp, KSP_NORM_UNPRECONDITIONED));
  petsc(KSPSetTolerances(ksp, rtol, 0.0, PETSC_DEFAULT, 1000));
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
  petsc(KSPSetFromOptions(ksp));  // PETSC_OPTIONS may tune it (-ksp_*, -pc_hypre_*)
}
}  // namespace

KspSolve::Stats KspSolve::solve(long n, long N, const std::vector<long>& rows, const std::vector<long>& cols,
                                const std::vector<double>& values, const std::vector<long>& b_rows,
                                const std::vector<double>& b_values, const std::vector<long>& wanted,
                                std::vector<double>& x_wanted, double rtol) {
  Impl& m = *impl_;
  // The matrix from coordinates (MatSetPreallocationCOO: entries of other ranks' rows are sent
  // there, duplicates added), built again only when its pattern changed on some rank (GridPoisson:
  // the node box moved); otherwise only its values are set. Every rank decides alike (the
  // decisions are reduced), since the calls are collective.
  const bool same = n == m.n && N == m.N && m.A &&
                    std::equal(rows.begin(), rows.end(), m.rows.begin(), m.rows.end()) &&
                    std::equal(cols.begin(), cols.end(), m.cols.begin(), m.cols.end());
  const bool resized = any(n != m.n || N != m.N);
  if (any(!same)) {
    MatDestroy(&m.A);
    m.rows.assign(rows.begin(), rows.end());
    m.cols.assign(cols.begin(), cols.end());
    petsc(MatCreate(PETSC_COMM_WORLD, &m.A));
    petsc(MatSetSizes(m.A, static_cast<PetscInt>(n), static_cast<PetscInt>(n), static_cast<PetscInt>(N), static_cast<PetscInt>(N)));
    petsc(MatSetType(m.A, MATAIJ));
    // PETSc may rewrite the coordinates it is given: it gets a copy, m.rows and m.cols stay the pattern.
    std::vector<PetscInt> ri = m.rows, ci = m.cols;
    petsc(MatSetPreallocationCOO(m.A, static_cast<PetscCount>(ri.size()), ri.data(), ci.data()));
    if (resized) {  // a new size: new vectors and a new solver (a preconditioner of the old size is no use)
      VecDestroy(&m.x);
      VecDestroy(&m.b);
      petsc(MatCreateVecs(m.A, &m.x, &m.b));
      petsc(VecZeroEntries(m.x));
      KSPDestroy(&m.ksp);
      m.fresh = true;
    }
    m.n = n, m.N = N;
  }
  petsc(MatSetValuesCOO(m.A, values.data(), INSERT_VALUES));
  petsc(VecZeroEntries(m.b));
  std::vector<PetscInt> bi(b_rows.begin(), b_rows.end());
  petsc(VecSetValues(m.b, static_cast<PetscInt>(bi.size()), bi.data(), b_values.data(), ADD_VALUES));
  petsc(VecAssemblyBegin(m.b));
  petsc(VecAssemblyEnd(m.b));

  // A preconditioner's setup (hypre's hierarchy, a factorisation) costs several solves: that of
  // an earlier step's L preconditions this step's (L changes only as the points move), as one
  // rank reuses CHOLMOD's factor. Set up again
  // after kMaxAge solves, when CG needed more than twice the iterations (and 10 more) of the solve
  // right after the last setup, or did not converge with the old one.
  if (!m.ksp) create_ksp(m.A, rtol, preconditioner_, m.ksp);
  else petsc(KSPSetOperators(m.ksp, m.A, m.A));
  // CG starts from the last solve's solution (the rows number the same nodes while the size
  // stays): the increments of consecutive steps differ little. The test stays |b - A x| <= rtol |b|.
  petsc(KSPSetInitialGuessNonzero(m.ksp, PETSC_TRUE));
  auto run = [&](bool setup) {
    petsc(KSPSetReusePreconditioner(m.ksp, setup ? PETSC_FALSE : PETSC_TRUE));
    if (setup) {
      ++m.setups;
      m.age = 0;
    }
    petsc(KSPSolve(m.ksp, m.b, m.x));
    PetscInt its = 0;
    KSPConvergedReason reason;
    petsc(KSPGetIterationNumber(m.ksp, &its));
    petsc(KSPGetConvergedReason(m.ksp, &reason));
    return std::pair{static_cast<int>(its), reason > 0};
  };
  const bool setup = m.fresh || m.age >= kMaxAge;
  auto [its, converged] = run(setup);
  if (!converged && its == 0) {
    // A start far from this solution: KSP stops at once (DTOL, residual above 1e5 |b|) when |b|
    // is much smaller than the last right-hand side. Again from zero, with this preconditioner.
    petsc(VecZeroEntries(m.x));
    std::tie(its, converged) = run(false);
  }
  if (!converged) {  // an old preconditioner: again from zero with a fresh setup
    petsc(VecZeroEntries(m.x));
    std::tie(its, converged) = run(true);
  } else if (!setup) {
    ++m.age;
  }
  if (m.age == 0) m.setup_iterations = its;
  m.fresh = its > 2 * m.setup_iterations + 10;

  Stats s;
  s.iterations = its;
  s.converged = converged;
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
