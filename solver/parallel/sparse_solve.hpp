// A sparse non-symmetric system over the ranks, solved as one rank solves mpm-fem's systems
// (fem/fluid.hpp, fem/phase_field.hpp) with Eigen's BiCGSTAB: PETSc's BiCGSTAB, right-
// preconditioned and tested on the true residual |b - A x| <= rtol |b| as Eigen's is. Two
// preconditioners:
//   lu      the fluid's velocity-pressure system (seed 004 eqs. 67-68): a sparse LU factor reused
//           over steps, factorised afresh when the caller says so (and then applied alone, a
//           direct solve). One rank's factor is UMFPACK's; over the ranks it is MUMPS's
//           (distributed LU; chosen by measurement, bench/fluid_ksp.cpp and
//           bench/results/fluid-ksp-2026-12-06.md: on a 2D tank of 61,812 unknowns its
//           factorisation took 0.91 -> 0.65 s and a solve with the kept factor 0.035 -> 0.022 s on
//           1 -> 2 ranks, where the whole system factorised by UMFPACK on every rank took 1.08 ->
//           1.13 s and 0.059 -> 0.060 s);
//   jacobi  the phase field's advection-diffusion system (eq. 106): the diagonal, set up each solve.
// The answers agree with one rank's to the Krylov tolerance, not bit for bit.
//
// The system is given in coordinates, as KspSolve's (poisson.hpp): n of the N rows live on this
// rank (the ranks' rows in rank order), and each rank names the entries and right-hand-side rows
// it contributes to (any rank's rows; duplicates are added). The pattern is set once (per fluid
// region); each solve sets only the values.
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace swmpm::parallel {

class SparseSolve {
 public:
  enum class Preconditioner { lu, jacobi };
  explicit SparseSolve(Preconditioner p);
  ~SparseSolve();
  SparseSolve(const SparseSolve&) = delete;
  SparseSolve& operator=(const SparseSolve&) = delete;

  /// The pattern: this rank's n rows of N (the first at `first`), the coordinates of the entries
  /// it adds to, and the rows of its right-hand-side contributions. Collective. The factor and
  /// the last solution are dropped (an LU's next solve must factorise).
  void set_pattern(long first, long n, long N, const std::vector<long>& rows, const std::vector<long>& cols,
                   const std::vector<long>& b_rows);

  struct Stats {
    int iterations = 0;  // BiCGSTAB's (0 for a direct solve with a fresh factor)
    bool ok = false;     // converged (Krylov) or factorised and solved (direct)
    double seconds_factorise = 0.0, seconds_solve = 0.0;
  };
  /// Solves A x = b, A's values in the pattern's order, b's in b_rows' order. `factorise` (lu): a
  /// fresh LU of A and x = A^-1 b. Otherwise BiCGSTAB preconditioned by the last factor (lu) or
  /// by A's diagonal (jacobi), to |b - A x| <= rtol |b| in at most max_iterations, from `guess`
  /// (all N rows) if given, else from the last solution. On return `x` holds all N rows on every
  /// rank. Collective.
  Stats solve(const std::vector<double>& values, const std::vector<double>& b_values, bool factorise, double rtol,
              int max_iterations, std::vector<double>& x, const double* guess = nullptr);

  long factorisations() const { return factorisations_; }
  /// Why the last factorisation failed, in words ("" after a success; the same on every rank).
  const std::string& failure() const { return failure_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Preconditioner kind_;
  long first_ = 0, n_ = 0, n_total_ = 0;
  long factorisations_ = 0;
  std::string failure_;
};

}  // namespace swmpm::parallel
