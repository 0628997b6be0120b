#include "solver/parallel/comm.hpp"

#include <petscsys.h>
#include <vtkMPIController.h>
#include <vtkSmartPointer.h>

#include <algorithm>
#include <cstdlib>

namespace swmpm::parallel {
namespace {

bool g_started = false;
// VTK's parallel writers take this (the global controller) to list every rank's piece in a .pvtu.
vtkSmartPointer<vtkMPIController> g_vtk;
int g_rank = 0, g_ranks = 1;
double g_comm_seconds = 0.0;
double g_traffic[3] = {0.0, 0.0, 0.0};  // by Traffic

MPI_Comm world() { return PETSC_COMM_WORLD; }

/// Times one collective into communication_seconds.
struct Timed {
  double t0 = MPI_Wtime();
  ~Timed() { add_communication_seconds(MPI_Wtime() - t0, Traffic::collective); }
};

template <class T>
MPI_Datatype type_of();
template <>
MPI_Datatype type_of<double>() { return MPI_DOUBLE; }
template <>
MPI_Datatype type_of<long>() { return MPI_LONG; }

template <class T>
void reduce(std::span<T> v, MPI_Op op) {
  if (!g_started || v.empty()) return;
  Timed t;
  MPI_Allreduce(MPI_IN_PLACE, v.data(), static_cast<int>(v.size()), type_of<T>(), op, world());
}
template <class T>
T reduce1(T v, MPI_Op op) {
  reduce(std::span<T>(&v, 1), op);
  return v;
}

}  // namespace

bool launched_by_mpirun() {
  // OpenMPI's mpirun sets OMPI_COMM_WORLD_SIZE; PMI/PMIx launchers (srun, hydra) set PMI_SIZE / PMIX_RANK.
  for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(var)) return true;
  return false;
}

void start(int& argc, char**& argv) {
  if (g_started || !launched_by_mpirun()) return;
  // PETSc's own options come from PETSC_OPTIONS only: swmpm's command line is CLI11's.
  int no_argc = argc > 0 ? 1 : 0;
  char** no_argv = argv;
  if (PetscInitialize(&no_argc, &no_argv, nullptr, nullptr) != 0) throw std::runtime_error("PETSc failed to start");
  g_started = true;
  MPI_Comm_rank(world(), &g_rank);
  MPI_Comm_size(world(), &g_ranks);
  g_vtk = vtkSmartPointer<vtkMPIController>::New();
  g_vtk->Initialize(nullptr, nullptr, /*initializedExternally=*/1);
  vtkMultiProcessController::SetGlobalController(g_vtk);
}

void stop() {
  if (!g_started) return;
  vtkMultiProcessController::SetGlobalController(nullptr);
  g_vtk = nullptr;
  PetscFinalize();
  g_started = false;
}

void abort(int code) {
  if (g_started) MPI_Abort(world(), code);
  std::exit(code);
}

int rank() { return g_rank; }
int ranks() { return g_ranks; }

double max(double v) { return reduce1(v, MPI_MAX); }
double min(double v) { return reduce1(v, MPI_MIN); }
double sum(double v) { return reduce1(v, MPI_SUM); }
long sum(long v) { return reduce1(v, MPI_SUM); }
long max(long v) { return reduce1(v, MPI_MAX); }
long min(long v) { return reduce1(v, MPI_MIN); }
bool any(bool v) { return reduce1(static_cast<long>(v), MPI_MAX) != 0; }
void max(std::span<double> v) { reduce(v, MPI_MAX); }
void min(std::span<double> v) { reduce(v, MPI_MIN); }
void sum(std::span<double> v) { reduce(v, MPI_SUM); }
void sum(std::span<long> v) { reduce(v, MPI_SUM); }
void min(std::span<long> v) { reduce(v, MPI_MIN); }
void max(std::span<long> v) { reduce(v, MPI_MAX); }

std::vector<long> all_gather(long v) {
  std::vector<long> all(static_cast<std::size_t>(g_ranks), v);
  if (!g_started) return all;
  Timed t;
  MPI_Allgather(&v, 1, MPI_LONG, all.data(), 1, MPI_LONG, world());
  return all;
}

std::string broadcast(const std::string& s) {
  if (!g_started) return s;
  Timed t;
  long n = static_cast<long>(s.size());
  MPI_Bcast(&n, 1, MPI_LONG, 0, world());
  std::string out = g_rank == 0 ? s : std::string(static_cast<std::size_t>(n), '\0');
  MPI_Bcast(out.data(), static_cast<int>(n), MPI_CHAR, 0, world());
  return out;
}

std::vector<std::int64_t> broadcast(const std::vector<std::int64_t>& v) {
  if (!g_started) return v;
  Timed t;
  long n = static_cast<long>(v.size());
  MPI_Bcast(&n, 1, MPI_LONG, 0, world());
  std::vector<std::int64_t> out = g_rank == 0 ? v : std::vector<std::int64_t>(static_cast<std::size_t>(n));
  MPI_Bcast(out.data(), static_cast<int>(n), MPI_INT64_T, 0, world());
  return out;
}

std::vector<std::vector<char>> gather_to_root(const std::vector<char>& bytes) {
  if (!g_started) return {bytes};
  Timed t;
  int n = static_cast<int>(bytes.size());
  std::vector<int> counts(static_cast<std::size_t>(g_ranks)), displs(counts.size() + 1, 0);
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, world());
  std::vector<char> all;
  if (g_rank == 0) {
    for (std::size_t r = 0; r < counts.size(); ++r) displs[r + 1] = displs[r] + counts[r];
    all.resize(static_cast<std::size_t>(displs.back()));
  }
  MPI_Gatherv(bytes.data(), n, MPI_CHAR, all.data(), counts.data(), displs.data(), MPI_CHAR, 0, world());
  std::vector<std::vector<char>> out;
  if (g_rank == 0)
    for (std::size_t r = 0; r < counts.size(); ++r) out.emplace_back(all.begin() + displs[r], all.begin() + displs[r + 1]);
  return out;
}

std::vector<std::vector<char>> all_gather(const std::vector<char>& bytes) {
  if (!g_started) return {bytes};
  Timed t;
  int n = static_cast<int>(bytes.size());
  std::vector<int> counts(static_cast<std::size_t>(g_ranks)), displs(counts.size() + 1, 0);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, world());
  for (std::size_t r = 0; r < counts.size(); ++r) displs[r + 1] = displs[r] + counts[r];
  std::vector<char> all(static_cast<std::size_t>(displs.back()));
  MPI_Allgatherv(bytes.data(), n, MPI_CHAR, all.data(), counts.data(), displs.data(), MPI_CHAR, world());
  std::vector<std::vector<char>> out;
  for (std::size_t r = 0; r < counts.size(); ++r) out.emplace_back(all.begin() + displs[r], all.begin() + displs[r + 1]);
  return out;
}

std::vector<std::vector<char>> all_to_all(const std::vector<std::vector<char>>& to) {
  if (to.size() != static_cast<std::size_t>(g_ranks)) throw std::logic_error("all_to_all: one list per rank expected");
  if (!g_started) return to;
  Timed t;
  const std::size_t R = to.size();
  std::vector<int> send_n(R), recv_n(R), send_at(R + 1, 0), recv_at(R + 1, 0);
  for (std::size_t r = 0; r < R; ++r) send_n[r] = static_cast<int>(to[r].size());
  MPI_Alltoall(send_n.data(), 1, MPI_INT, recv_n.data(), 1, MPI_INT, world());
  for (std::size_t r = 0; r < R; ++r) send_at[r + 1] = send_at[r] + send_n[r], recv_at[r + 1] = recv_at[r] + recv_n[r];
  std::vector<char> out(static_cast<std::size_t>(send_at[R])), in(static_cast<std::size_t>(recv_at[R]));
  for (std::size_t r = 0; r < R; ++r) std::copy(to[r].begin(), to[r].end(), out.begin() + send_at[r]);
  MPI_Alltoallv(out.data(), send_n.data(), send_at.data(), MPI_CHAR, in.data(), recv_n.data(), recv_at.data(), MPI_CHAR,
                world());
  std::vector<std::vector<char>> from(R);
  for (std::size_t r = 0; r < R; ++r) from[r].assign(in.begin() + recv_at[r], in.begin() + recv_at[r + 1]);
  return from;
}

void barrier() {
  if (!g_started) return;
  Timed t;
  MPI_Barrier(world());
}

double communication_seconds() { return g_comm_seconds; }
double communication_seconds(Traffic kind) { return g_traffic[static_cast<int>(kind)]; }
void add_communication_seconds(double s, Traffic kind) {
  g_comm_seconds += s;
  g_traffic[static_cast<int>(kind)] += s;
}
double wall_time() { return g_started ? MPI_Wtime() : 0.0; }

}  // namespace swmpm::parallel
