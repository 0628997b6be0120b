// fluid_ksp: which PETSc solver for mpm-fem's velocity-pressure system over ranks (issue 28).
//
//   mpirun -n R build/bench/fluid_ksp [2|3] [cells along x] [only the candidates whose name holds this]
//
// Builds mpm-fem's fluid (solver/fem/fluid.hpp) on a B-spline grid: a tank [0, L] x [0, L/2]
// (x [0, L/4] in 3D) of water to 0.6 of its height, air above, a saturated soil block (n = 0.4,
// k = 1e-9 m^2) on the floor at its middle third, walls on the sides and the floor, the top open.
// Takes five steps of 1 ms from rest (the one-rank path: UMFPACK and its reused factor), then
// hands the sixth step's system to PETSc, every rank a slab of rows, and times each candidate:
// its setup (the factorisation or the preconditioner) and two solves (the step's right-hand side
// and the next step's, with the setup reused, as the one-rank path reuses its factor). Prints
// one line per candidate: ranks, unknowns, setup s, first and second solve s, iterations, the
// relative residual |b - A x| / |b|.
#include <mpi.h>
#include <petscksp.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "solver/fem/fluid.hpp"
#include "solver/shape/shape.hpp"

namespace {

void check(PetscErrorCode e) {
  if (e) {
    std::fprintf(stderr, "PETSc error %d\n", static_cast<int>(e));
    std::exit(1);
  }
}

struct Candidate {
  const char* name;
  const char* options;  // with the prefix "c_"
};

// The one-rank path is UMFPACK's LU reused as BiCGSTAB's preconditioner; over ranks the
// candidates are a direct factorisation on every rank (redundant), two distributed direct
// solvers, and Krylov methods with domain-decomposition preconditioners.
const Candidate kCandidates[] = {
    {"redundant LU (UMFPACK on every rank)",
     "-c_ksp_type preonly -c_pc_type redundant -c_redundant_pc_type lu -c_redundant_pc_factor_mat_solver_type umfpack"},
    {"MUMPS LU (distributed)", "-c_ksp_type preonly -c_pc_type lu -c_pc_factor_mat_solver_type mumps"},
    {"SuperLU_dist LU (distributed)", "-c_ksp_type preonly -c_pc_type lu -c_pc_factor_mat_solver_type superlu_dist"},
    {"GMRES + block Jacobi (UMFPACK per rank)",
     "-c_ksp_type gmres -c_ksp_gmres_restart 100 -c_ksp_rtol 1e-8 -c_ksp_max_it 1000 -c_pc_type bjacobi "
     "-c_sub_pc_type lu -c_sub_pc_factor_mat_solver_type umfpack"},
    {"GMRES + ASM overlap 2 (UMFPACK per subdomain)",
     "-c_ksp_type gmres -c_ksp_gmres_restart 100 -c_ksp_rtol 1e-8 -c_ksp_max_it 1000 -c_pc_type asm -c_pc_asm_overlap 2 "
     "-c_sub_pc_type lu -c_sub_pc_factor_mat_solver_type umfpack"},
    {"GMRES + ASM overlap 1 (ILU(1) per subdomain)",
     "-c_ksp_type gmres -c_ksp_gmres_restart 100 -c_ksp_rtol 1e-8 -c_ksp_max_it 1000 -c_pc_type asm -c_pc_asm_overlap 1 "
     "-c_sub_pc_type ilu -c_sub_pc_factor_levels 1"},
    // Block preconditioners whose cost grows with N (velocity block and the pressure Schur
    // complement by BoomerAMG): the candidates for 3D systems a direct factor cannot hold.
    {"FGMRES + Schur fieldsplit (BoomerAMG on v and on selfp)",
     "-c_ksp_type fgmres -c_ksp_gmres_restart 200 -c_ksp_rtol 1e-8 -c_ksp_max_it 1000 -c_pc_type fieldsplit "
     "-c_pc_fieldsplit_block_size BLOCK -c_pc_fieldsplit_0_fields VFIELDS -c_pc_fieldsplit_1_fields PFIELD "
     "-c_pc_fieldsplit_type schur -c_pc_fieldsplit_schur_fact_type upper -c_pc_fieldsplit_schur_precondition selfp "
     "-c_fieldsplit_0_ksp_type preonly -c_fieldsplit_0_pc_type hypre -c_fieldsplit_1_ksp_type preonly -c_fieldsplit_1_pc_type hypre"},
    {"FGMRES + Schur fieldsplit (ILU(0) on v, BoomerAMG on selfp)",
     "-c_ksp_type fgmres -c_ksp_gmres_restart 200 -c_ksp_rtol 1e-8 -c_ksp_max_it 1000 -c_pc_type fieldsplit "
     "-c_pc_fieldsplit_block_size BLOCK -c_pc_fieldsplit_0_fields VFIELDS -c_pc_fieldsplit_1_fields PFIELD "
     "-c_pc_fieldsplit_type schur -c_pc_fieldsplit_schur_fact_type upper -c_pc_fieldsplit_schur_precondition selfp "
     "-c_fieldsplit_0_ksp_type preonly -c_fieldsplit_0_pc_type bjacobi -c_fieldsplit_0_sub_pc_type ilu "
     "-c_fieldsplit_1_ksp_type preonly -c_fieldsplit_1_pc_type hypre"},
    {"FGMRES + Schur fieldsplit (SOR on v, BoomerAMG on selfp)",
     "-c_ksp_type fgmres -c_ksp_gmres_restart 200 -c_ksp_rtol 1e-8 -c_ksp_max_it 1000 -c_pc_type fieldsplit "
     "-c_pc_fieldsplit_block_size BLOCK -c_pc_fieldsplit_0_fields VFIELDS -c_pc_fieldsplit_1_fields PFIELD "
     "-c_pc_fieldsplit_type schur -c_pc_fieldsplit_schur_fact_type upper -c_pc_fieldsplit_schur_precondition selfp "
     "-c_fieldsplit_0_ksp_type preonly -c_fieldsplit_0_pc_type sor -c_fieldsplit_1_ksp_type preonly -c_fieldsplit_1_pc_type hypre"},
};

template <int Dim>
int run(int cells_x, const char* only) {
  using Shape = swmpm::shape::BSpline<Dim>;
  using Fluid = swmpm::fem::Fluid<Dim, Shape>;
  const double L = 1.0, h = L / cells_x;
  swmpm::Vec<Dim> lo = swmpm::Vec<Dim>::Zero(), hi;
  hi[0] = L;
  hi[1] = 0.5 * L;
  if constexpr (Dim == 3) hi[2] = 0.25 * L;
  const swmpm::Grid<Dim> g(lo, hi, h, Shape::degree, true);
  const std::size_t nn = g.num_nodes();
  const auto& n_axis = g.nodes_per_axis();
  typename Fluid::Conditions bc;
  bc.fixed.assign(nn, 0);
  bc.p_value.assign(nn, 0.0);
  bc.face_load.assign(nn, swmpm::Vec<Dim>::Zero());
  g.for_each_node(g.all_nodes(), [&](std::size_t i, const std::array<int, Dim>& ijk) {
    for (int a = 0; a < Dim; ++a) {
      if (a == 1 && ijk[a] == n_axis[a] - 1) bc.fixed[i] |= 1u << Dim;  // the open top: p = 0
      else if (ijk[a] == 0 || ijk[a] == n_axis[a] - 1) bc.fixed[i] |= 1u << a;  // walls: no normal flow
    }
  });
  Fluid fluid;
  fluid.setup(g, swmpm::fem::FluidProperties{}, bc);
  swmpm::fem::SoilOnGrid<Dim> soil;
  soil.resize(nn);
  g.for_each_node(g.all_nodes(), [&](std::size_t i, const std::array<int, Dim>& ijk) {
    const swmpm::Vec<Dim> x = g.node_position(ijk);
    fluid.phi[i] = x[1] < 0.6 * hi[1] ? 1.0 : 0.0;
    if (x[0] > L / 3 && x[0] < 2 * L / 3 && x[1] < 0.2 * hi[1]) {
      soil.n[i] = 0.4, soil.theta[i] = 0.6, soil.k[i] = 1e-9, soil.rho_p[i] = 0.6 * 2650.0;
    }
  });
  swmpm::Vec<Dim> b = swmpm::Vec<Dim>::Zero();
  b[1] = -9.81;
  bool direct_failed = false;
  for (int s = 0; s < 5 && !direct_failed; ++s)
    if (!fluid.step(soil, b, 1e-3)) {
      // A system too large for one rank's direct factor (3D at 40 cells: UMFPACK out of memory):
      // the candidates get the step's assembled system, from rest.
      std::fprintf(stderr, "step %d: the one-rank direct solve failed (%s); the candidates get its system\n", s, fluid.failure().c_str());
      direct_failed = true;
    }
  // The sixth step's system and the seventh's right-hand side (the solution moved on).
  const swmpm::linear::CscMatrix A = fluid.system().A;
  const Eigen::VectorXd rhs1 = fluid.system().rhs;
  if (!direct_failed) fluid.step(soil, b, 1e-3);
  const Eigen::VectorXd rhs2 = fluid.system().rhs;
  const Eigen::SparseMatrix<double, Eigen::RowMajor, int> Ar = A;
  const PetscInt N = static_cast<PetscInt>(Ar.rows());

  int rank = 0, ranks = 1;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &ranks);
  // Rows in slabs of whole nodes along the last axis (node order x fastest): as the ranks'
  // columns would hold them.
  const PetscInt per_node = Dim + 1, nodes = N / per_node;
  const PetscInt first = nodes * rank / ranks * per_node, last = nodes * (rank + 1) / ranks * per_node;
  Mat M;
  check(MatCreate(PETSC_COMM_WORLD, &M));
  check(MatSetSizes(M, last - first, last - first, N, N));
  check(MatSetType(M, MATAIJ));
  std::vector<PetscInt> d_nnz(static_cast<std::size_t>(last - first)), o_nnz(d_nnz.size());
  for (PetscInt r = first; r < last; ++r)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor, int>::InnerIterator it(Ar, r); it; ++it)
      ++(it.col() >= first && it.col() < last ? d_nnz : o_nnz)[static_cast<std::size_t>(r - first)];
  check(MatSeqAIJSetPreallocation(M, 0, d_nnz.data()));
  check(MatMPIAIJSetPreallocation(M, 0, d_nnz.data(), 0, o_nnz.data()));
  for (PetscInt r = first; r < last; ++r)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor, int>::InnerIterator it(Ar, r); it; ++it) {
      const PetscInt c = static_cast<PetscInt>(it.col());
      const PetscScalar v = it.value();
      check(MatSetValues(M, 1, &r, 1, &c, &v, INSERT_VALUES));
    }
  check(MatAssemblyBegin(M, MAT_FINAL_ASSEMBLY));
  check(MatAssemblyEnd(M, MAT_FINAL_ASSEMBLY));
  Vec x, b1, b2, r;
  check(MatCreateVecs(M, &x, &b1));
  check(VecDuplicate(b1, &b2));
  check(VecDuplicate(b1, &r));
  for (PetscInt i = first; i < last; ++i) {
    check(VecSetValue(b1, i, rhs1[i], INSERT_VALUES));
    check(VecSetValue(b2, i, rhs2[i], INSERT_VALUES));
  }
  for (Vec v : {b1, b2}) check(VecAssemblyBegin(v)), check(VecAssemblyEnd(v));

  if (rank == 0)
    std::printf("%dD fluid, h = %g m, %ld unknowns, %d ranks\n%-48s %9s %9s %9s %6s %9s\n", Dim, h, static_cast<long>(N), ranks,
                "candidate", "setup s", "solve s", "again s", "its", "residual");
  for (const Candidate& c : kCandidates) {
    if (only && !std::strstr(c.name, only)) continue;
    // The block candidates name the fields: velocity components 0 .. Dim-1, pressure Dim.
    std::string options = c.options;
    auto put = [&](const std::string& key, const std::string& value) {
      for (std::size_t at = options.find(key); at != std::string::npos; at = options.find(key)) options.replace(at, key.size(), value);
    };
    put("BLOCK", std::to_string(Dim + 1));
    put("VFIELDS", Dim == 2 ? "0,1" : "0,1,2");
    put("PFIELD", std::to_string(Dim));
    check(PetscOptionsInsertString(nullptr, options.c_str()));
    KSP ksp;
    check(KSPCreate(PETSC_COMM_WORLD, &ksp));
    check(KSPSetOptionsPrefix(ksp, "c_"));
    check(KSPSetOperators(ksp, M, M));
    check(KSPSetFromOptions(ksp));
    double t0 = MPI_Wtime();
    PetscErrorCode e = KSPSetUp(ksp);
    double t1 = MPI_Wtime();
    PetscInt its = 0, its2 = 0;
    double t2 = t1, t3 = t1, res = -1.0;
    if (!e) e = KSPSolve(ksp, b1, x);
    t2 = MPI_Wtime();
    if (!e) {
      KSPGetIterationNumber(ksp, &its);
      e = KSPSolve(ksp, b2, x);
      t3 = MPI_Wtime();
      KSPGetIterationNumber(ksp, &its2);
      PetscReal rn = 0, bn = 0;
      MatMult(M, x, r);
      VecAYPX(r, -1.0, b2);
      VecNorm(r, NORM_2, &rn);
      VecNorm(b2, NORM_2, &bn);
      res = rn / bn;
    }
    // Each rank's wall time: the slowest.
    double t[3] = {t1 - t0, t2 - t1, t3 - t2}, tmax[3];
    MPI_Reduce(t, tmax, 3, MPI_DOUBLE, MPI_MAX, 0, PETSC_COMM_WORLD);
    if (rank == 0) {
      if (e) std::printf("%-48s failed (PETSc error %d)\n", c.name, static_cast<int>(e));
      else std::printf("%-48s %9.4f %9.4f %9.4f %3ld+%-3ld %9.1e\n", c.name, tmax[0], tmax[1], tmax[2], static_cast<long>(its), static_cast<long>(its2), res);
      std::fflush(stdout);
    }
    KSPDestroy(&ksp);
    check(PetscOptionsClear(nullptr));
  }
  for (Vec v : {x, b1, b2, r}) VecDestroy(&v);
  MatDestroy(&M);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const int dim = argc > 1 ? std::atoi(argv[1]) : 2;
  const int cells = argc > 2 ? std::atoi(argv[2]) : (dim == 2 ? 200 : 40);
  const char* only = argc > 3 ? argv[3] : nullptr;  // run only the candidates whose name holds this
  check(PetscInitialize(&argc, &argv, nullptr, nullptr));
  const int rc = dim == 3 ? run<3>(cells, only) : run<2>(cells, only);
  PetscFinalize();
  return rc;
}
