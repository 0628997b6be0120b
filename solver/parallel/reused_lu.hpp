// A sparse non-symmetric system over the ranks, solved as one rank solves mpm-fem's
// velocity-pressure system (seed 004 eqs. 67-68; fem/fluid.hpp): a sparse LU factor reused over
// steps as the preconditioner of BiCGSTAB, factorised afresh when the caller says so. Over the
// ranks the factor is MUMPS's (distributed LU; chosen by measurement, bench/fluid_ksp.cpp and
// bench/results/fluid-ksp-2026-12-06.md: on a 2D tank of 61,812 unknowns its factorisation took
// 0.91 -> 0.65 s and a solve with the kept factor 0.035 -> 0.022 s on 1 -> 2 ranks, where the
// whole system factorised by UMFPACK on every rank took 1.08 -> 1.13 s and 0.059 -> 0.060 s) and
// the Krylov method PETSc's BiCGSTAB, right-preconditioned and tested on the true residual
// |b - A x| <= rtol |b| as Eigen's BiCGSTAB does at one rank. The answers agree with one rank's to
// the Krylov tolerance, not bit for bit.
//
// The system is given in coordinates, as KspSolve's (poisson.hpp): n of the N rows live on this
// rank (the ranks' rows in rank order), and each rank names the entries and right-hand-side rows
// it contributes to (any rank's rows; duplicates are added). The pattern is set once (per fluid
// region); each solve sets only the values.
#pragma once

#include <memory>
#include <vector>

namespace swmpm::parallel {

class ReusedLU {
 public:
  ReusedLU();
  ~ReusedLU();
  ReusedLU(const ReusedLU&) = delete;
  ReusedLU& operator=(const ReusedLU&) = delete;

  /// The pattern: this rank's n rows of N, the coordinates of the entries it adds to, and the rows
  /// of its right-hand-side contributions. Collective. The factor and the last solution are
  /// dropped (the next solve must factorise).
  void set_pattern(long n, long N, const std::vector<long>& rows, const std::vector<long>& cols, const std::vector<long>& b_rows);

  struct Stats {
    int iterations = 0;       // BiCGSTAB's (0 for a direct solve with a fresh factor)
    bool ok = false;          // converged (Krylov) or factorised and solved (direct)
    double seconds_factorise = 0.0, seconds_solve = 0.0;
  };
  /// Solves A x = b, A's values in the pattern's order, b's in b_rows' order. `factorise`: a fresh
  /// LU of A and x = A^-1 b; otherwise BiCGSTAB from the last solution, preconditioned by the last
  /// factor, to |b - A x| <= rtol |b| in at most max_iterations. On return `x` holds all N rows on
  /// every rank. Collective.
  Stats solve(const std::vector<double>& values, const std::vector<double>& b_values, bool factorise, double rtol,
              int max_iterations, std::vector<double>& x);

  long factorisations() const { return factorisations_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  long factorisations_ = 0;
};

}  // namespace swmpm::parallel
