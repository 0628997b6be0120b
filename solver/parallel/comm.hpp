// The run's ranks: MPI (Debian's OpenMPI) and PETSc, started only when mpirun launched the process.
//
// Without mpirun the program runs as it always did: no MPI_Init, no PETSc, rank 0 of 1, and every
// collective below returns its argument. Under `mpirun -n N swmpm solve RUN_DIR`, start() calls
// PetscInitialize (which starts MPI) and the collectives go over PETSC_COMM_WORLD. No formulation
// calls MPI: they call these (the house's vocabulary, like transfer/), and the decomposition,
// ghost exchange and migration live in solver/parallel/domain.hpp.
#pragma once

#include <cstdint>
#include <exception>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace swmpm::parallel {

/// Whether this process was launched by an MPI launcher (mpirun/mpiexec set these variables).
bool launched_by_mpirun();
/// Starts MPI and PETSc when launched by mpirun; otherwise does nothing. Call once, first in main.
void start(int& argc, char**& argv);
/// Ends PETSc and MPI if start() began them.
void stop();
/// Leaves every rank with `code` now (a failure on some ranks only, inside the time loop).
[[noreturn]] void abort(int code);

int rank();
int ranks();
inline bool distributed() { return ranks() > 1; }

// Collectives over all ranks (each rank must call them in the same order). At one rank they return
// their argument. Their wall time adds to communication_seconds().
double max(double v);
double min(double v);
double sum(double v);
long sum(long v);
long max(long v);
long min(long v);
bool any(bool v);
void max(std::span<double> v);
void min(std::span<double> v);
void sum(std::span<double> v);
void sum(std::span<long> v);
void min(std::span<long> v);
void max(std::span<long> v);
/// Every rank's value, in rank order.
std::vector<long> all_gather(long v);
/// Rank 0's string on every rank.
std::string broadcast(const std::string& s);
std::vector<std::int64_t> broadcast(const std::vector<std::int64_t>& v);
/// Bytes from every rank to rank 0, in rank order (rank 0 gets them all; the others an empty list).
std::vector<std::vector<char>> gather_to_root(const std::vector<char>& bytes);
/// Bytes from every rank to every rank, in rank order.
std::vector<std::vector<char>> all_gather(const std::vector<char>& bytes);
/// Bytes to each rank (`to[r]` for rank r; this rank's own entry comes back as it is), in one
/// all-to-all: what each rank sent this one, in rank order.
std::vector<std::vector<char>> all_to_all(const std::vector<std::vector<char>>& to);
void barrier();

/// The value of the rank whose `place` is the lowest over the ranks (`none` when every rank's
/// place is `unplaced`): what one rank's search keeps when it takes the first in its order.
/// Collective.
template <class T>
T value_at_lowest(long place, T value, T none, long unplaced) {
  const long lowest = min(place);
  return max(place == lowest && place != unplaced ? value : none);
}

/// Seconds of wall time this rank spent in communication (collectives, ghost exchange, migration).
/// A collective's time includes the wait for the slowest rank (load imbalance shows here).
double communication_seconds();
/// The parts of communication_seconds.
enum class Traffic { collective, exchange, migration };
double communication_seconds(Traffic kind);
/// Adds to communication_seconds (the exchange and migration code times itself).
void add_communication_seconds(double s, Traffic kind = Traffic::collective);
double wall_time();

/// A failure of some ranks that the others share: thrown on the ranks that did not fail
/// themselves, so that every rank leaves the stage together and only the failing ones speak.
struct ElsewhereError : std::runtime_error {
  ElsewhereError() : std::runtime_error("another rank failed") {}
};

/// Runs fn() on every rank; if it throws on any rank, every rank throws: the lowest rank that
/// failed rethrows its own exception (its message is the one the user reads), the others
/// ElsewhereError (silent). For the stages before the time loop (loading the scene and the
/// particles, preparing the run directory), where a bad input stops every rank with one message
/// and nothing written.
template <class Fn>
void together(Fn&& fn) {
  std::exception_ptr error;
  try {
    fn();
  } catch (...) {
    error = std::current_exception();
  }
  if (!distributed()) {
    if (error) std::rethrow_exception(error);
    return;
  }
  const long first = min(error ? static_cast<long>(rank()) : static_cast<long>(ranks()));
  if (first == rank()) std::rethrow_exception(error);
  if (first < ranks()) throw ElsewhereError();
}

}  // namespace swmpm::parallel
