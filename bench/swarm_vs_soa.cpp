// swarm_vs_soa: PETSc's DMSwarm migration against swmpm's own (parallel::move_particles), side by
// side in one run under `mpirun -n 2` (issue 28: "choose by measurement and say why").
//
// Each rank holds N 3D particles with the fields of a dry ParticleSet<3> (id, x, x0, v, l, m, V,
// V0, F, L, sigma, eps_p, material, body, faces, key: 348 bytes). Each round a fraction of them
// (--moving, default 1 %: a slide crossing a cut) is sent to the other rank, then the same number
// comes back the next round; the time of a round is the migration alone, fastest and mean of
// --rounds. swmpm's sets end in key order (the one-rank order the bitwise match needs); the
// swarm's order after DMSwarmMigrate is reported (whether its keys stay sorted).
//
// Usage: mpirun -n 2 build/bench/swarm_vs_soa [--particles 200000] [--moving 0.01] [--rounds 50]
#include <petscdmswarm.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <string>
#include <vector>

#include "solver/parallel/comm.hpp"
#include "solver/parallel/domain.hpp"

namespace {

using swmpm::ParticleSet;
namespace parallel = swmpm::parallel;

struct Field {
  const char* name;
  PetscInt components;
  PetscDataType type;
};
// The fields of a dry 3D set, as the swarm registers them (doubles, 64-bit integers, and PetscInt: 32-bit in Debian's PETSc).
const Field kFields[] = {{"id", 1, PETSC_INT64}, {"x", 3, PETSC_REAL},  {"x0", 3, PETSC_REAL},   {"v", 3, PETSC_REAL},
                         {"l", 3, PETSC_REAL},   {"m", 1, PETSC_REAL},  {"V", 1, PETSC_REAL},    {"V0", 1, PETSC_REAL},
                         {"F", 9, PETSC_REAL},   {"L", 9, PETSC_REAL},  {"sigma", 6, PETSC_REAL}, {"eps_p", 1, PETSC_REAL},
                         {"material", 1, PETSC_INT}, {"body", 1, PETSC_INT}, {"faces", 1, PETSC_INT},
                         {"key", 1, PETSC_INT64}};

void check(PetscErrorCode e) {
  if (e) std::exit(1);
}

ParticleSet<3> make_set(std::size_t n, int rank) {
  ParticleSet<3> ps;
  ps.resize(n);
  ps.key.resize(n);
  for (std::size_t p = 0; p < n; ++p) {
    const auto global = static_cast<std::int64_t>(rank * n + p);
    ps.id[p] = ps.key[p] = global;
    ps.x[p] = swmpm::Vec<3>(static_cast<double>(p), 1.0, 2.0);
    ps.m[p] = 1.0 + static_cast<double>(global);
  }
  return ps;
}

struct Stats {
  double best = 1e300, sum = 0.0;
  int n = 0;
  void add(double t) {
    best = std::min(best, t);
    sum += t;
    ++n;
  }
};

}  // namespace

int main(int argc, char** argv) {
  parallel::start(argc, argv);
  if (parallel::ranks() != 2) {
    if (parallel::rank() == 0) std::fprintf(stderr, "run with mpirun -n 2\n");
    parallel::stop();
    return 2;
  }
  long N = 200000;
  double moving = 0.01;
  int rounds = 50;
  for (int k = 1; k + 1 < argc; k += 2) {
    const std::string a = argv[k];
    if (a == "--particles") N = std::atol(argv[k + 1]);
    else if (a == "--moving") moving = std::atof(argv[k + 1]);
    else if (a == "--rounds") rounds = std::atoi(argv[k + 1]);
  }
  const int me = parallel::rank(), other = 1 - me;
  const auto n = static_cast<std::size_t>(N);
  const auto k = static_cast<std::size_t>(moving * static_cast<double>(N));

  // ---- swmpm: ParticleSet + move_particles -------------------------------------------------
  ParticleSet<3> ps = make_set(n, me);
  swmpm::parallel::FieldBytes layout;
  ps.for_each_field([&](auto& f) { layout.active.push_back(f.size() == n); });
  std::vector<std::max_align_t> scratch;
  Stats ours;
  bool ours_sorted = true;
  for (int r = 0; r < rounds; ++r) {
    // Every other round the particles that arrived go back: the ones of the other rank's keys.
    std::vector<int> dest(ps.size(), me);
    std::size_t sent = 0;
    for (std::size_t p = 0; p < ps.size() && sent < k; ++p)
      if ((r % 2 == 0) == (ps.key[p] / N == me)) dest[p] = other, ++sent;
    parallel::barrier();
    const double t0 = MPI_Wtime();
    swmpm::parallel::move_particles(ps, dest, layout, scratch);
    ours.add(MPI_Wtime() - t0);
    ours_sorted = ours_sorted && std::is_sorted(ps.key.begin(), ps.key.end());
  }

  // ---- PETSc DMSwarm (basic: points go to the rank in DMSwarmField_rank) ---------------------
  DM sw;
  check(DMCreate(PETSC_COMM_WORLD, &sw));
  check(DMSetType(sw, DMSWARM));
  check(DMSetDimension(sw, 3));
  check(DMSwarmSetType(sw, DMSWARM_BASIC));
  for (const Field& f : kFields) check(DMSwarmRegisterPetscDatatypeField(sw, f.name, f.components, f.type));
  check(DMSwarmFinalizeFieldRegister(sw));
  check(DMSwarmSetLocalSizes(sw, static_cast<PetscInt>(n), static_cast<PetscInt>(k)));
  {
    PetscInt64* key;
    check(DMSwarmGetField(sw, "key", nullptr, nullptr, reinterpret_cast<void**>(&key)));
    for (std::size_t p = 0; p < n; ++p) key[p] = static_cast<PetscInt64>(me * n + p);
    check(DMSwarmRestoreField(sw, "key", nullptr, nullptr, reinterpret_cast<void**>(&key)));
  }
  Stats swarm;
  bool swarm_sorted = true;
  for (int r = 0; r < rounds; ++r) {
    PetscInt local;
    check(DMSwarmGetLocalSize(sw, &local));
    PetscInt64* key;
    PetscInt* rank;
    check(DMSwarmGetField(sw, "key", nullptr, nullptr, reinterpret_cast<void**>(&key)));
    check(DMSwarmGetField(sw, DMSwarmField_rank, nullptr, nullptr, reinterpret_cast<void**>(&rank)));
    std::size_t sent = 0;
    for (PetscInt p = 0; p < local; ++p) {
      rank[p] = me;
      if (sent < k && (r % 2 == 0) == (key[p] / N == me)) rank[p] = other, ++sent;
    }
    check(DMSwarmRestoreField(sw, DMSwarmField_rank, nullptr, nullptr, reinterpret_cast<void**>(&rank)));
    check(DMSwarmRestoreField(sw, "key", nullptr, nullptr, reinterpret_cast<void**>(&key)));
    parallel::barrier();
    const double t0 = MPI_Wtime();
    check(DMSwarmMigrate(sw, PETSC_TRUE));
    swarm.add(MPI_Wtime() - t0);
    check(DMSwarmGetLocalSize(sw, &local));
    check(DMSwarmGetField(sw, "key", nullptr, nullptr, reinterpret_cast<void**>(&key)));
    swarm_sorted = swarm_sorted && std::is_sorted(key, key + local);
    check(DMSwarmRestoreField(sw, "key", nullptr, nullptr, reinterpret_cast<void**>(&key)));
  }
  check(DMDestroy(&sw));

  const double ours_best = parallel::max(ours.best), ours_mean = parallel::max(ours.sum / ours.n);
  const double swarm_best = parallel::max(swarm.best), swarm_mean = parallel::max(swarm.sum / swarm.n);
  if (me == 0)
    std::printf("%ld particles per rank, %zu moving per round (%.2g %%), %d rounds, 348 B per particle\n"
                "swmpm move_particles: fastest %.3f ms, mean %.3f ms; key order kept: %s\n"
                "PETSc DMSwarmMigrate: fastest %.3f ms, mean %.3f ms; key order kept: %s\n",
                N, k, 100 * moving, rounds, 1e3 * ours_best, 1e3 * ours_mean, ours_sorted ? "yes" : "no",
                1e3 * swarm_best, 1e3 * swarm_mean, swarm_sorted ? "yes" : "no");
  parallel::stop();
  return 0;
}
