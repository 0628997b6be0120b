#include "solver/parallel/domain.hpp"

#include <petscdmda.h>
#include <petscsf.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <map>
#include <stdexcept>
#include <string>
#include <cstddef>
#include <new>
#include <type_traits>

#include "solver/parallel/petsc_check.hpp"

namespace swmpm::parallel {

namespace {
/// The nodes of node columns [first, last) along `axis` (all across): leaves here, the same
/// nodes on rank `owner_of(column)` as roots, for a star forest.
template <class OwnerOf>
void add_columns(const std::array<int, 3>& nodes, int axis, int first, int last, OwnerOf&& owner_of,
                 std::vector<PetscInt>& leaves, std::vector<PetscSFNode>& roots) {
  for (int c = first; c < last; ++c) {
    std::array<int, 3> ijk{0, 0, 0}, from{0, 0, 0}, to{nodes[0], nodes[1], nodes[2]};
    from[axis] = c, to[axis] = c + 1;
    const int r = owner_of(c);
    for (ijk[2] = from[2]; ijk[2] < to[2]; ++ijk[2])
      for (ijk[1] = from[1]; ijk[1] < to[1]; ++ijk[1])
        for (ijk[0] = from[0]; ijk[0] < to[0]; ++ijk[0]) {
          leaves.push_back(ijk[0] + nodes[0] * (ijk[1] + static_cast<PetscInt>(nodes[1]) * ijk[2]));
          roots.push_back({r, leaves.back()});
        }
  }
}
}  // namespace

// ---- the exchange of shared columns ------------------------------------------------------------

struct StripeExchange::Impl {
  // Cuts at odd stripes (the lower rank's stripe is colour 0): the lower rank (leaf) finishes its
  // colour first. Cuts at even stripes: the upper rank (root) does.
  // Per Reach (support, moved_cell): its shared columns.
  std::array<PetscSF, 2> leaf_first{nullptr, nullptr}, root_first{nullptr, nullptr};
  // The grid's nodes over the ranks as PETSc holds them (DMDA): rank r owns the node columns of its
  // stripes along the stripe axis and every node across it. The distributed solves build their
  // vectors and matrices on it.
  DM da = nullptr;
  mutable std::map<std::size_t, MPI_Datatype> types;  // a node's bytes as doubles
  mutable std::map<int, PetscSF> ghosts;               // per ghost width: owners' nodes -> my ghosts
  /// add_ghosts_to_owners: the other ranks' ghost nodes in my columns -> slots here, per width.
  struct GhostSums {
    PetscSF sf = nullptr;
    std::vector<PetscInt> node;   // per slot: my node it adds to
    std::vector<double> values;   // per slot: the ghost's value (scratch)
  };
  mutable std::map<int, GhostSums> ghost_sums;
  std::array<int, 3> nodes{1, 1, 1};
  int axis = 0;
  std::vector<int> column_cuts;  // per rank its first node column, then the node count

  MPI_Datatype type(std::size_t bytes) const {
    auto it = types.find(bytes);
    if (it != types.end()) return it->second;
    MPI_Datatype t;
    MPI_Type_contiguous(static_cast<int>(bytes / sizeof(double)), MPI_DOUBLE, &t);
    MPI_Type_commit(&t);
    return types.emplace(bytes, t).first->second;
  }
  ~Impl() {
    DMDestroy(&da);
    for (auto* sf : {&leaf_first[0], &leaf_first[1], &root_first[0], &root_first[1]}) PetscSFDestroy(sf);
    for (auto& [w, sf] : ghosts) PetscSFDestroy(&sf);
    for (auto& [w, g] : ghost_sums) PetscSFDestroy(&g.sf);
    for (auto& [b, t] : types) MPI_Type_free(&t);
  }
};

StripeExchange::StripeExchange(const std::array<int, 3>& nodes, int axis, int width, int support,
                               const std::vector<int>& cuts)
    : impl_(std::make_unique<Impl>()) {
  const int me = rank(), R = ranks();
  const PetscInt n_all = static_cast<PetscInt>(static_cast<std::size_t>(nodes[0]) * nodes[1] * nodes[2]);
  impl_->nodes = nodes;
  impl_->axis = axis;
  for (int r = 0; r < R; ++r) impl_->column_cuts.push_back(cuts[static_cast<std::size_t>(r)] * width);
  impl_->column_cuts.push_back(nodes[axis]);
  for (const Reach reach : {Reach::support, Reach::moved_cell}) {
    std::vector<PetscInt> leaves;
    std::vector<PetscSFNode> roots;
    bool odd = false;
    if (me + 1 < R) {
      // The shared columns at my upper cut: my ghosts (leaves), the next rank's nodes (roots).
      const int s = cuts[static_cast<std::size_t>(me) + 1];
      odd = s % 2 == 1;
      const int first = s * width - (reach == Reach::moved_cell ? 1 : 0);
      const int last = std::min(nodes[axis] - 1, s * width + support - 2);
      add_columns(nodes, axis, first, last + 1, [&](int) { return me + 1; }, leaves, roots);
    }
    auto make = [&](PetscSF& sf, bool mine) {
      petsc(PetscSFCreate(PETSC_COMM_WORLD, &sf));
      const PetscInt n = mine ? static_cast<PetscInt>(leaves.size()) : 0;
      petsc(PetscSFSetGraph(sf, n_all, n, mine ? leaves.data() : nullptr, PETSC_COPY_VALUES,
                            mine ? roots.data() : nullptr, PETSC_COPY_VALUES));
      petsc(PetscSFSetUp(sf));
    };
    const auto k = static_cast<std::size_t>(reach);
    make(impl_->leaf_first[k], odd);
    make(impl_->root_first[k], !odd && me + 1 < R);
  }

  // The DMDA of the same partition: ownership ranges along the axis from the cuts, one rank
  // across the other axes, ghost width S - 1 (the shared columns).
  std::vector<PetscInt> along(static_cast<std::size_t>(R));
  for (int r = 0; r < R; ++r)
    along[static_cast<std::size_t>(r)] =
        (r + 1 < R ? cuts[static_cast<std::size_t>(r) + 1] * width : nodes[axis]) - cuts[static_cast<std::size_t>(r)] * width;
  std::array<PetscInt, 3> procs{1, 1, 1};
  procs[static_cast<std::size_t>(axis)] = R;
  std::array<const PetscInt*, 3> ranges{nullptr, nullptr, nullptr};
  ranges[static_cast<std::size_t>(axis)] = along.data();
  const std::array<PetscInt, 3> whole{nodes[0], nodes[1], nodes[2]};
  for (int a = 0; a < 3; ++a)
    if (a != axis) ranges[static_cast<std::size_t>(a)] = &whole[static_cast<std::size_t>(a)];
  const PetscInt ghost = std::max(1, support - 1);
  if (nodes[2] > 1)
    petsc(DMDACreate3d(PETSC_COMM_WORLD, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DMDA_STENCIL_BOX, nodes[0],
                 nodes[1], nodes[2], procs[0], procs[1], procs[2], 1, ghost, ranges[0], ranges[1], ranges[2], &impl_->da));
  else
    petsc(DMDACreate2d(PETSC_COMM_WORLD, DM_BOUNDARY_NONE, DM_BOUNDARY_NONE, DMDA_STENCIL_BOX, nodes[0], nodes[1], procs[0],
                 procs[1], 1, ghost, ranges[0], ranges[1], &impl_->da));
  petsc(DMSetUp(impl_->da));
  PetscInt start[3] = {0, 0, 0}, count[3] = {1, 1, 1};
  DMDAGetCorners(impl_->da, &start[0], &start[1], &start[2], &count[0], &count[1], &count[2]);
  if (start[axis] != cuts[static_cast<std::size_t>(me)] * width || count[axis] != along[static_cast<std::size_t>(me)])
    throw std::logic_error("the DMDA's ownership does not follow the stripes");
  owned_.first = static_cast<int>(start[axis]);
  owned_.second = static_cast<int>(start[axis] + count[axis]);
}

StripeExchange::~StripeExchange() = default;

void StripeExchange::after_colour(int colour, void* nodes, std::size_t bytes, Reach reach) const {
  const double t0 = MPI_Wtime();
  const MPI_Datatype t = impl_->type(bytes);
  PetscSF leaf_first = impl_->leaf_first[static_cast<std::size_t>(reach)];
  PetscSF root_first = impl_->root_first[static_cast<std::size_t>(reach)];
  if (colour == 0) {
    // Partial sums to the rank that adds the second colour: leaf -> root, root -> leaf.
    PetscSFReduceBegin(leaf_first, t, nodes, nodes, MPI_REPLACE);
    PetscSFBcastBegin(root_first, t, nodes, nodes, MPI_REPLACE);
    PetscSFReduceEnd(leaf_first, t, nodes, nodes, MPI_REPLACE);
    PetscSFBcastEnd(root_first, t, nodes, nodes, MPI_REPLACE);
  } else {
    // Finished sums back to the rank that ran the first colour.
    PetscSFBcastBegin(leaf_first, t, nodes, nodes, MPI_REPLACE);
    PetscSFReduceBegin(root_first, t, nodes, nodes, MPI_REPLACE);
    PetscSFBcastEnd(leaf_first, t, nodes, nodes, MPI_REPLACE);
    PetscSFReduceEnd(root_first, t, nodes, nodes, MPI_REPLACE);
  }
  add_communication_seconds(MPI_Wtime() - t0, Traffic::exchange);
}

PetscSF_ptr StripeExchange::ghost_forest(int width) const {
  const Impl& m = *impl_;
  auto it = m.ghosts.find(width);
  if (it == m.ghosts.end()) {
    // Leaves: my ghost nodes (the columns within `width` of my own, either side); roots: the same
    // nodes on the ranks that own their columns.
    const int me = rank();
    const int lo = m.column_cuts[static_cast<std::size_t>(me)], hi = m.column_cuts[static_cast<std::size_t>(me) + 1];
    std::vector<PetscInt> leaves;
    std::vector<PetscSFNode> roots;
    auto owner = [&](int c) {
      int r = 0;
      while (m.column_cuts[static_cast<std::size_t>(r) + 1] <= c) ++r;
      return r;
    };
    add_columns(m.nodes, m.axis, std::max(0, lo - width), lo, owner, leaves, roots);
    add_columns(m.nodes, m.axis, hi, std::min(m.nodes[m.axis], hi + width), owner, leaves, roots);
    const PetscInt n_all = static_cast<PetscInt>(static_cast<std::size_t>(m.nodes[0]) * m.nodes[1] * m.nodes[2]);
    PetscSF sf;
    petsc(PetscSFCreate(PETSC_COMM_WORLD, &sf));
    petsc(PetscSFSetGraph(sf, n_all, static_cast<PetscInt>(leaves.size()), leaves.data(), PETSC_COPY_VALUES, roots.data(),
                          PETSC_COPY_VALUES));
    petsc(PetscSFSetUp(sf));
    it = m.ghosts.emplace(width, sf).first;
  }
  return it->second;
}

void StripeExchange::fill_ghosts(void* nodes, std::size_t bytes, int width) const {
  const double t0 = MPI_Wtime();
  const PetscSF sf = ghost_forest(width);
  const MPI_Datatype t = impl_->type(bytes);
  petsc(PetscSFBcastBegin(sf, t, nodes, nodes, MPI_REPLACE));
  petsc(PetscSFBcastEnd(sf, t, nodes, nodes, MPI_REPLACE));
  add_communication_seconds(MPI_Wtime() - t0, Traffic::exchange);
}

void StripeExchange::add_ghosts_to_owners(double* nodes, int width) const {
  const double t0 = MPI_Wtime();
  const Impl& m = *impl_;
  auto it = m.ghost_sums.find(width);
  if (it == m.ghost_sums.end()) {
    // Roots: every other rank's ghost nodes in my own columns (in its node array); leaves: one slot
    // each here, rank by rank, column by column, in flat order inside a column. One root per
    // slot, so a broadcast fills the slots, which are then added in that order.
    const int me = rank();
    const int lo = m.column_cuts[static_cast<std::size_t>(me)], hi = m.column_cuts[static_cast<std::size_t>(me) + 1];
    Impl::GhostSums g;
    std::vector<PetscSFNode> roots;
    for (int q = 0; q < ranks(); ++q) {
      if (q == me) continue;
      const int qlo = m.column_cuts[static_cast<std::size_t>(q)], qhi = m.column_cuts[static_cast<std::size_t>(q) + 1];
      std::vector<PetscInt> slots;
      std::vector<PetscSFNode> from;
      auto owned_by_q = [&](int) { return q; };
      for (const auto& [c0, c1] : {std::pair{std::max(0, qlo - width), qlo}, std::pair{qhi, std::min(m.nodes[m.axis], qhi + width)}})
        add_columns(m.nodes, m.axis, std::max(c0, lo), std::min(c1, hi), owned_by_q, slots, from);
      g.node.insert(g.node.end(), slots.begin(), slots.end());
      roots.insert(roots.end(), from.begin(), from.end());
    }
    const PetscInt n_all = static_cast<PetscInt>(static_cast<std::size_t>(m.nodes[0]) * m.nodes[1] * m.nodes[2]);
    petsc(PetscSFCreate(PETSC_COMM_WORLD, &g.sf));
    petsc(PetscSFSetGraph(g.sf, n_all, static_cast<PetscInt>(roots.size()), nullptr, PETSC_COPY_VALUES, roots.data(),
                          PETSC_COPY_VALUES));
    petsc(PetscSFSetUp(g.sf));
    it = m.ghost_sums.emplace(width, std::move(g)).first;
  }
  Impl::GhostSums& g = it->second;
  g.values.resize(g.node.size());
  const MPI_Datatype t = m.type(sizeof(double));
  petsc(PetscSFBcastBegin(g.sf, t, nodes, g.values.data(), MPI_REPLACE));
  petsc(PetscSFBcastEnd(g.sf, t, nodes, g.values.data(), MPI_REPLACE));
  for (std::size_t k = 0; k < g.node.size(); ++k) nodes[g.node[k]] += g.values[k];
  add_communication_seconds(MPI_Wtime() - t0, Traffic::exchange);
}

// ---- particle migration --------------------------------------------------------------------------

template <int Dim>
bool move_particles(ParticleSet<Dim>& ps, const std::vector<int>& dest, const FieldBytes& layout,
                    std::vector<std::max_align_t>& scratch) {
  const double t0 = MPI_Wtime();
  const int R = ranks(), me = rank();
  const std::size_t n = ps.size();
  std::vector<int> send_n(static_cast<std::size_t>(R), 0), recv_n(static_cast<std::size_t>(R), 0);
  for (std::size_t p = 0; p < n; ++p)
    if (dest[p] != me) ++send_n[static_cast<std::size_t>(dest[p])];
  MPI_Alltoall(send_n.data(), 1, MPI_INT, recv_n.data(), 1, MPI_INT, PETSC_COMM_WORLD);
  const long sent = std::accumulate(send_n.begin(), send_n.end(), 0L);
  const long received = std::accumulate(recv_n.begin(), recv_n.end(), 0L);

  // Bytes of one particle: the fields the set carries.
  std::size_t record = 0;
  {
    std::size_t k = 0;
    ps.for_each_field([&](auto& f) {
      if (layout.active[k++]) record += sizeof(f[0]);
    });
  }
  // Leaving particles grouped by destination (increasing index inside a group), field by field.
  std::vector<int> send_at(static_cast<std::size_t>(R) + 1, 0);
  for (int r = 0; r < R; ++r) send_at[static_cast<std::size_t>(r) + 1] = send_at[static_cast<std::size_t>(r)] + send_n[static_cast<std::size_t>(r)];
  // Most steps nobody leaves: then nothing here walks the particles.
  std::vector<int> leaving(static_cast<std::size_t>(sent)), keep;
  if (sent > 0) {
    std::vector<int> fill(send_at.begin(), send_at.end() - 1);
    keep.reserve(n - static_cast<std::size_t>(sent));
    for (std::size_t p = 0; p < n; ++p) {
      if (dest[p] == me) keep.push_back(static_cast<int>(p));
      else leaving[static_cast<std::size_t>(fill[static_cast<std::size_t>(dest[p])]++)] = static_cast<int>(p);
    }
  }
  std::vector<int> send_bytes(static_cast<std::size_t>(R)), send_displ(static_cast<std::size_t>(R)),
      recv_bytes(static_cast<std::size_t>(R)), recv_displ(static_cast<std::size_t>(R));
  int total_send = 0, total_recv = 0;
  for (int r = 0; r < R; ++r) {
    send_displ[static_cast<std::size_t>(r)] = total_send;
    send_bytes[static_cast<std::size_t>(r)] = send_n[static_cast<std::size_t>(r)] * static_cast<int>(record);
    total_send += send_bytes[static_cast<std::size_t>(r)];
    recv_displ[static_cast<std::size_t>(r)] = total_recv;
    recv_bytes[static_cast<std::size_t>(r)] = recv_n[static_cast<std::size_t>(r)] * static_cast<int>(record);
    total_recv += recv_bytes[static_cast<std::size_t>(r)];
  }
  std::vector<char> out(static_cast<std::size_t>(total_send)), in(static_cast<std::size_t>(total_recv));
  {
    std::size_t k = 0;
    std::vector<std::size_t> at(send_displ.begin(), send_displ.end());
    ps.for_each_field([&](auto& f) {
      if (!layout.active[k++]) return;
      using T = typename std::decay_t<decltype(f)>::value_type;
      for (int r = 0; r < R; ++r)
        for (int j = send_at[static_cast<std::size_t>(r)]; j < send_at[static_cast<std::size_t>(r) + 1]; ++j) {
          std::memcpy(out.data() + at[static_cast<std::size_t>(r)], &f[static_cast<std::size_t>(leaving[static_cast<std::size_t>(j)])], sizeof(T));
          at[static_cast<std::size_t>(r)] += sizeof(T);
        }
    });
  }
  MPI_Alltoallv(out.data(), send_bytes.data(), send_displ.data(), MPI_BYTE, in.data(), recv_bytes.data(),
                  recv_displ.data(), MPI_BYTE, PETSC_COMM_WORLD);
  if (sent == 0 && received == 0) {
    add_communication_seconds(MPI_Wtime() - t0, Traffic::migration);
    return false;
  }
  // The new set in key order (the one-rank run's storage order), in one pass per field: the kept
  // particles are in key order already, each rank's arrivals too; their keys merge.
  if (sent == 0) {
    keep.resize(n);
    std::iota(keep.begin(), keep.end(), 0);
  }
  // Where each field of an arrival starts in `in` (field-major per source rank).
  std::vector<std::size_t> field_at;  // per active field: bytes of the active fields before it
  std::size_t key_at = 0;
  {
    std::size_t k = 0, before = 0;
    ps.for_each_field([&](auto& f) {
      if (!layout.active[k++]) return;
      field_at.push_back(before);
      if (static_cast<const void*>(&f) == static_cast<const void*>(&ps.key)) key_at = before;
      before += sizeof(f[0]);
    });
  }
  struct Arrival {
    std::int64_t key;
    int source, index;
  };
  std::vector<Arrival> arrivals;
  arrivals.reserve(static_cast<std::size_t>(received));
  for (int r = 0; r < R; ++r)
    for (int i = 0; i < recv_n[static_cast<std::size_t>(r)]; ++i) {
      std::int64_t key;
      std::memcpy(&key, in.data() + recv_displ[static_cast<std::size_t>(r)] +
                            static_cast<std::size_t>(recv_n[static_cast<std::size_t>(r)]) * key_at + static_cast<std::size_t>(i) * sizeof(key),
                  sizeof(key));
      arrivals.push_back({key, r, i});
    }
  std::sort(arrivals.begin(), arrivals.end(), [](const Arrival& a, const Arrival& b) { return a.key < b.key; });
  // order[j] >= 0: the kept particle of that index; < 0: arrival -order[j] - 1.
  const std::size_t n_new = keep.size() + arrivals.size();
  std::vector<int> order(n_new);
  {
    std::size_t a = 0, b = 0;
    for (std::size_t j = 0; j < n_new; ++j) {
      const bool take_kept = b == arrivals.size() ||
                             (a < keep.size() && ps.key[static_cast<std::size_t>(keep[a])] < arrivals[b].key);
      order[j] = take_kept ? keep[a++] : -static_cast<int>(b++) - 1;
    }
  }
  {
    std::size_t k = 0, f_index = 0;
    ps.for_each_field([&](auto& f) {
      if (!layout.active[k++]) return;
      using T = typename std::decay_t<decltype(f)>::value_type;
      const std::size_t offset = field_at[f_index++];
      const std::size_t words = (n_new * sizeof(T) + sizeof(std::max_align_t) - 1) / sizeof(std::max_align_t);
      if (scratch.size() < words) scratch.resize(words);
      T* tmp = reinterpret_cast<T*>(scratch.data());
      for (std::size_t j = 0; j < n_new; ++j) {
        if (order[j] >= 0) {
          new (tmp + j) T(f[static_cast<std::size_t>(order[j])]);
        } else {
          const Arrival& a = arrivals[static_cast<std::size_t>(-order[j] - 1)];
          const std::size_t r = static_cast<std::size_t>(a.source);
          std::memcpy(static_cast<void*>(tmp + j),
                      in.data() + recv_displ[r] + static_cast<std::size_t>(recv_n[r]) * offset + static_cast<std::size_t>(a.index) * sizeof(T),
                      sizeof(T));
        }
      }
      f.resize(n_new);
      std::copy(tmp, tmp + n_new, f.begin());
    });
  }
  add_communication_seconds(MPI_Wtime() - t0, Traffic::migration);
  return true;
}

template <int Dim>
ParticleSet<Dim> gather_set(const ParticleSet<Dim>& ps) {
  ParticleSet<Dim> all = ps;
  if (ranks() == 1) return all;
  const FieldBytes layout = layout_over_ranks(all);
  const std::size_t n = all.size();
  std::vector<std::max_align_t> scratch;
  move_particles(all, std::vector<int>(n, 0), layout, scratch);
  return all;
}

std::vector<std::int64_t> carry_values(const std::vector<std::int64_t>& keys, const std::vector<std::int64_t>& values,
                                       const std::vector<int>& dest, const std::vector<std::int64_t>& keys_after) {
  using Pair = std::array<std::int64_t, 2>;  // key, value
  std::vector<std::vector<char>> to(static_cast<std::size_t>(ranks()));
  for (std::size_t p = 0; p < keys.size(); ++p) {
    const Pair kv{keys[p], values[p]};
    auto& bytes = to[static_cast<std::size_t>(dest[p])];
    bytes.insert(bytes.end(), reinterpret_cast<const char*>(kv.data()), reinterpret_cast<const char*>(kv.data()) + sizeof kv);
  }
  std::vector<Pair> got;
  for (const auto& part : all_to_all(to))
    for (std::size_t k = 0; k < part.size() / sizeof(Pair); ++k) {
      Pair kv;
      std::memcpy(kv.data(), part.data() + k * sizeof kv, sizeof kv);
      got.push_back(kv);
    }
  std::sort(got.begin(), got.end());
  if (got.size() != keys_after.size()) throw std::logic_error("carry_values: not one value per particle");
  std::vector<std::int64_t> out(got.size());
  for (std::size_t p = 0; p < got.size(); ++p) {
    if (got[p][0] != keys_after[p]) throw std::logic_error("carry_values: a value without its particle");
    out[p] = got[p][1];
  }
  return out;
}

template bool move_particles<2>(ParticleSet<2>&, const std::vector<int>&, const FieldBytes&, std::vector<std::max_align_t>&);
template bool move_particles<3>(ParticleSet<3>&, const std::vector<int>&, const FieldBytes&, std::vector<std::max_align_t>&);
std::vector<long> start_slices(long n) {
  const long R = ranks();
  std::vector<long> counts(static_cast<std::size_t>(R), 0);
  const char* how = std::getenv("SWMPM_START_SLICES");
  if (how && std::string(how) == "last") {
    counts.back() = n;
    return counts;
  }
  for (long r = 0; r < R; ++r) counts[static_cast<std::size_t>(r)] = n / R + (r < n % R ? 1 : 0);
  return counts;
}

template <int Dim>
void scatter_slices(ParticleSet<Dim>& ps, const std::vector<long>& counts, std::size_t round_bytes) {
  if (ranks() == 1) return;
  // Rank 0's set kind and size; the others make an empty set of that kind.
  const std::vector<std::int64_t> head =
      broadcast(rank() == 0 ? std::vector<std::int64_t>{static_cast<std::int64_t>(ps.size()), ps.kind()}
                            : std::vector<std::int64_t>{});
  const std::size_t n = static_cast<std::size_t>(head.at(0));
  if (rank() != 0) ps = ParticleSet<Dim>::of_kind(static_cast<int>(head.at(1)));
  ps.key.resize(ps.size());
  std::iota(ps.key.begin(), ps.key.end(), std::int64_t{0});
  const FieldBytes layout = layout_over_ranks(ps);
  std::size_t record = 0;
  {
    std::size_t k = 0;
    ps.for_each_field([&](auto& f) {
      if (layout.active[k++]) record += sizeof(f[0]);
    });
  }
  std::vector<long> first(counts.size() + 1, 0);
  for (std::size_t r = 0; r < counts.size(); ++r) first[r + 1] = first[r] + counts[r];
  if (first.back() != static_cast<long>(n)) throw std::logic_error("scatter_slices: the slices do not add up to the set");
  // Rank 0 sends the particles after its own slice, a round at a time (each round a copy and a
  // send buffer of at most 64 MB), then keeps its slice: its peak is the whole set and two rounds.
  const std::size_t round = std::max<std::size_t>(1, round_bytes / std::max<std::size_t>(record, 1));
  const std::size_t own = static_cast<std::size_t>(first[1]);
  ParticleSet<Dim> mine = ps.empty_like();
  std::vector<std::max_align_t> scratch;
  for (std::size_t a = own; a < n; a += round) {
    const std::size_t b = std::min(n, a + round);
    ParticleSet<Dim> part = ps.empty_like();
    std::vector<int> dest;
    if (rank() == 0) {
      std::size_t k = 0;
      part.for_each_field_with(ps, [&](auto& to, auto& from) {
        if (!layout.active[k++]) return;
        to.assign(from.begin() + static_cast<std::ptrdiff_t>(a), from.begin() + static_cast<std::ptrdiff_t>(b));
      });
      for (std::size_t p = a; p < b; ++p)
        dest.push_back(static_cast<int>(std::upper_bound(first.begin(), first.end(), static_cast<long>(p)) - first.begin() - 1));
    }
    move_particles(part, dest, layout, scratch);
    std::size_t k = 0;
    mine.for_each_field_with(part, [&](auto& to, auto& from) {
      if (layout.active[k++]) to.insert(to.end(), from.begin(), from.end());
    });
  }
  if (rank() == 0) {  // its own slice, field by field (each shrunk to its slice at once)
    std::size_t k = 0;
    ps.for_each_field([&](auto& f) {
      if (!layout.active[k++]) return;
      f.resize(own);
      f.shrink_to_fit();
    });
    return;
  }
  ps = std::move(mine);
}

template <int Dim>
ParticleSet<Dim> all_gather_set(const ParticleSet<Dim>& ps) {
  if (ranks() == 1) return ps;
  ParticleSet<Dim> mine = ps;
  const FieldBytes layout = layout_over_ranks(mine);
  std::vector<char> bytes;
  std::size_t k = 0;
  mine.for_each_field([&](auto& f) {
    if (!layout.active[k++]) return;
    const char* b = reinterpret_cast<const char*>(f.data());
    bytes.insert(bytes.end(), b, b + f.size() * sizeof(f[0]));
  });
  const std::vector<long> counts = all_gather(static_cast<long>(mine.size()));
  const std::vector<std::vector<char>> parts = all_gather(bytes);
  ParticleSet<Dim> all = mine.empty_like();
  std::vector<std::size_t> at(parts.size(), 0);  // each part's next field
  k = 0;
  all.for_each_field([&](auto& f) {
    if (!layout.active[k++]) return;
    using T = typename std::decay_t<decltype(f)>::value_type;
    for (std::size_t r = 0; r < parts.size(); ++r) {
      const std::size_t n = static_cast<std::size_t>(counts[r]);
      if (n == 0) continue;  // (memcpy from an empty part's null data is not allowed even for 0 bytes)
      const std::size_t before = f.size();
      f.resize(before + n);
      std::memcpy(static_cast<void*>(f.data() + before), parts[r].data() + at[r], n * sizeof(T));
      at[r] += n * sizeof(T);
    }
  });
  std::vector<int> order(all.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return all.key[static_cast<std::size_t>(a)] < all.key[static_cast<std::size_t>(b)]; });
  Reorder<Dim>().apply(all, order);
  return all;
}

template ParticleSet<2> all_gather_set<2>(const ParticleSet<2>&);
template ParticleSet<3> all_gather_set<3>(const ParticleSet<3>&);
template void scatter_slices<2>(ParticleSet<2>&, const std::vector<long>&, std::size_t);
template void scatter_slices<3>(ParticleSet<3>&, const std::vector<long>&, std::size_t);
template ParticleSet<2> gather_set<2>(const ParticleSet<2>&);
template ParticleSet<3> gather_set<3>(const ParticleSet<3>&);

}  // namespace swmpm::parallel
