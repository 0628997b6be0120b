// Domain decomposition over MPI ranks: who owns which particles and nodes, the exchange of node
// columns at the cuts, and the migration of particles. The one place that knows about ranks
// besides comm.hpp; formulations hold a Domain and call it at named points of their step.
//
// The cut follows the scatter schedule (transfer/schedule.hpp). Particles are binned into stripes
// of W = S node columns along the grid's longest axis by their first node; a rank owns a run of
// whole stripes [cut_r, cut_{r+1}) and every particle whose stripe is in it:
//
//      rank 0            | rank 1                          node columns along the stripe axis
//   ... s-2 | s-1 (c0)   | s (c1) | s+1 ...                 stripes, colour = stripe parity
//              [sW ... sW+S-2] shared columns: touched by stripe s-1 (rank 0) and stripe s (rank 1)
//
// One rank adds a node's contributions stripe by stripe, colour 0 first, particles in storage
// order inside a stripe. N ranks do the same: after colour 0 the rank that ran the colour-0
// stripe at a cut hands its partial sums of the shared columns to the other (who has none yet);
// after colour 1 the finished sums go back (StripeExchange, on PETSc's star forest). Inside a
// stripe, every rank keeps its particles in the one-rank run's storage order (ParticleSet::key,
// carried across migration and renumbered when the one-rank run would reorder). So each node, and
// hence every particle, gets the one-rank values bit for bit.
//
// Ownership of nodes (for the pressure solves, PETSc DMDA): rank r owns node columns
// [W cut_r, W cut_{r+1}); its particles also touch the S - 1 shared columns above, which it holds
// as ghosts with the finished values.
#pragma once

#include <algorithm>
#include <cmath>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "solver/grid/grid.hpp"
#include "solver/parallel/comm.hpp"
#include "solver/particles/particles.hpp"
#include "solver/transfer/schedule.hpp"

// PETSc's PetscSF, declared here as petscsf.h does, so that this header needs no PETSc.
typedef struct _p_PetscSF* PetscSF_ptr;

namespace swmpm::parallel {

/// The exchange of shared node columns between the scatter's two colours (PETSc star forests,
/// domain.cpp). Built from the cuts; rebuilt when they move.
class StripeExchange final : public NodeExchange {
 public:
  StripeExchange(const std::array<int, 3>& nodes, int axis, int width, int support, const std::vector<int>& cuts);
  ~StripeExchange() override;
  StripeExchange(const StripeExchange&) = delete;
  StripeExchange& operator=(const StripeExchange&) = delete;
  void after_colour(int colour, void* nodes, std::size_t bytes, Reach reach) const override;
  /// The node columns [first, second) this rank owns along the axis, as PETSc's DMDA holds them.
  std::pair<int, int> owned_columns() const { return owned_; }
  /// Copies into this rank's `width` node columns either side of its own (ghosts; clamped to the
  /// grid) their owners' values: after a per-node stage that each rank runs on its own nodes, the
  /// values its neighbour reads R nodes away (a stencil's reach). `nodes` as after_colour's; one
  /// PETSc star forest per width, built at its first use. Collective.
  void fill_ghosts(void* nodes, std::size_t bytes, int width) const;
  /// The reverse of fill_ghosts for sums (PETSc's local-to-global ADD_VALUES): each rank's values
  /// in its ghost columns (`width` either side) are added to their owners' nodes; the ghosts keep
  /// theirs. For a sum over particles that sit up to `width` columns outside their rank's own
  /// (after a step moved them). One double per node. Collective.
  void add_ghosts_to_owners(double* nodes, int width) const;

 private:
  PetscSF_ptr ghost_forest(int width) const;  // the star forest of fill_ghosts, built at its first use
  std::pair<int, int> owned_{0, 0};
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Particle migration: moves whole particles (every field the set carries) between ranks in one
/// all-to-all, then puts each rank's set back in key order (domain.cpp).
/// `dest[p]`: the rank particle p must live on. Returns whether this rank's set changed.
struct FieldBytes {
  std::vector<char> active;  // per field of ParticleSet::for_each_field: carried by this set
};

/// Keeps particles `keep` (increasing) of ps, in that order (the fields `layout` marks).
template <int Dim>
void compact(ParticleSet<Dim>& ps, const std::vector<int>& keep, const FieldBytes& layout) {
  std::size_t k = 0;
  ps.for_each_field([&](auto& f) {
    if (!layout.active[k++]) return;
    for (std::size_t j = 0; j < keep.size(); ++j) f[j] = f[static_cast<std::size_t>(keep[j])];
    f.resize(keep.size());
  });
}

/// The fields a set carries over the ranks' shares: those any rank's particles carry (a rank
/// without particles gets them sized to none), and always the key. Collective.
template <int Dim>
FieldBytes layout_over_ranks(ParticleSet<Dim>& ps) {
  std::vector<long> active;
  const std::size_t n = ps.size();
  ps.for_each_field([&](auto& f) { active.push_back(n > 0 && f.size() == n); });
  max(std::span<long>(active));
  FieldBytes l;
  for (long a : active) l.active.push_back(static_cast<char>(a));
  l.active.back() = 1;  // the key (the last field)
  ps.for_each_field([&, k = std::size_t{0}](auto& f) mutable {
    if (l.active[k++] && f.size() != n) f.resize(n);
  });
  return l;
}

/// Moves particle p of `ps` to rank dest[p] (the fields `layout` marks), in one all-to-all;
/// the set is then in key order (the kept particles and each rank's arrivals are; their keys are
/// merged, and each field is rebuilt in one pass through `scratch`, kept by the caller). Collective.
/// Returns whether this rank's set changed.
template <int Dim>
bool move_particles(ParticleSet<Dim>& ps, const std::vector<int>& dest, const FieldBytes& layout,
                    std::vector<std::max_align_t>& scratch);

/// A fresh start under mpirun: rank 0 read the whole set from its file (`ps`; the other ranks hold
/// an empty set). Afterwards rank r holds the particles [first_r, first_r + counts[r]) of the
/// file's order, each with its place there as its key (the one-rank run's storage order), and
/// every rank's set carries the fields rank 0's does. Rank 0 sends the other slices in rounds of
/// at most 64 MB (no message count near MPI's int), then shrinks the set to its own slice: its
/// peak is the whole set and two rounds, every other rank's its slice and a round. Collective.
template <int Dim>
void scatter_slices(ParticleSet<Dim>& ps, const std::vector<long>& counts, std::size_t round_bytes = std::size_t{64} << 20);
/// The particles per rank of a start's slices (scatter_slices) of a set of n: n / R each, the
/// remainder spread over the first ranks. With SWMPM_START_SLICES=last (for the tests) the last
/// rank gets them all: every setup step must then reduce over ranks that hold none.
std::vector<long> start_slices(long n);

/// Every rank's particles of a set, on rank 0, in key order: the one-rank run's set in its storage
/// order (the others get an empty set). Collective. It costs rank 0 the memory of the whole set:
/// for the tests and for what is built once from the whole set (the double-point tie table).
template <int Dim>
ParticleSet<Dim> gather_set(const ParticleSet<Dim>& ps);

/// Every rank's particles of a set, on every rank, in key order (for a small set: the loaded
/// particles of a start). Collective.
template <int Dim>
ParticleSet<Dim> all_gather_set(const ParticleSet<Dim>& ps);

/// Values that travel with particles: `values[p]` of this rank's particle p (key keys[p]) goes
/// to rank dest[p], as move_particles sends the particle; returns the values of the particles this
/// rank holds after the move, whose keys are `keys_after` (increasing). Collective.
std::vector<std::int64_t> carry_values(const std::vector<std::int64_t>& keys, const std::vector<std::int64_t>& values,
                                       const std::vector<int>& dest, const std::vector<std::int64_t>& keys_after);

/// On a resume from a whole checkpoint (one rank's): an order of the whole set (positions in it)
/// restricted to the particles this rank kept (`keys`: their positions in the whole set,
/// increasing), as indices into the rank's set.
inline std::vector<int> local_order(const std::vector<int>& whole_order, const std::vector<std::int64_t>& keys) {
  std::vector<int> local;
  local.reserve(keys.size());
  for (int g : whole_order) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), std::int64_t{g});
    if (it != keys.end() && *it == g) local.push_back(static_cast<int>(it - keys.begin()));
  }
  return local;
}

template <int Dim>
class Domain {
 public:
  /// One rank: an inactive domain (every call below is free).
  Domain() = default;

  bool active() const { return ranks() > 1; }
  int axis() const { return axis_; }
  int width() const { return width_; }
  const std::vector<int>& cuts() const { return cuts_; }
  const NodeExchange* exchange() const { return exchange_.get(); }

  /// The decomposition of grid `g` along the scatter schedule's stripe axis (transfer::stripe_axis)
  /// for shape functions of `support` nodes per axis, with the cuts balanced on `sets` (the whole
  /// run's particles, which every rank holds: a resume from a one-rank checkpoint). Each rank then
  /// keeps its own particles (keys: their index in the whole set).
  ///
  /// With `carried`, each rank holds a share of the particles instead (any slice of the whole
  /// sets, with their keys; a resume from a checkpoint's pieces): the cuts are balanced on the
  /// ranks' counts summed, and every particle moves to its owner (move_particles: each set then in
  /// key order). (*carried)[k] holds one value per particle of set k, which travels with it: on
  /// return, one per particle of the rank's new set.
  template <class FirstNode>
  void distribute(const Grid<Dim>& g, int support, int axis, std::vector<ParticleSet<Dim>*> sets,
                  FirstNode&& first_node, std::vector<std::vector<std::int64_t>>* carried = nullptr) {
    if (!active()) return;
    axis_ = axis;
    width_ = support;
    support_ = support;
    nodes_.fill(1);
    for (int a = 0; a < Dim; ++a) nodes_[a] = g.nodes_per_axis()[a];
    stripes_ = (nodes_[axis_] + width_ - 1) / width_;
    if (stripes_ < ranks())
      throw std::runtime_error("the grid has " + std::to_string(stripes_) + " stripes of " + std::to_string(width_) +
                               " node columns along axis " + std::to_string(axis_) + ", fewer than the " +
                               std::to_string(ranks()) + " ranks: run on at most " + std::to_string(stripes_) +
                               " ranks");
    layouts_.clear();
    std::vector<long> per_stripe(static_cast<std::size_t>(stripes_), 0);
    std::vector<std::vector<int>> stripe_of(sets.size());
    for (std::size_t k = 0; k < sets.size(); ++k) {
      ParticleSet<Dim>& ps = *sets[k];
      layouts_.push_back(carried ? parallel::layout_over_ranks(ps) : layout_of(ps));
      stripe_of[k].resize(ps.size());
      for (std::size_t p = 0; p < ps.size(); ++p) {
        const int s = std::clamp(first_node(k, p) / width_, 0, stripes_ - 1);
        stripe_of[k][p] = s;
        ++per_stripe[static_cast<std::size_t>(s)];
      }
    }
    if (carried) sum(std::span<long>(per_stripe));
    set_cuts(balanced_cuts(per_stripe));
    for (std::size_t k = 0; k < sets.size(); ++k) {
      ParticleSet<Dim>& ps = *sets[k];
      if (carried) {
        if (ps.key.size() != ps.size() || (*carried)[k].size() != ps.size())
          throw std::logic_error("Domain::distribute: a share without keys or carried values");
        std::vector<int> dest(ps.size());
        for (std::size_t p = 0; p < ps.size(); ++p) dest[p] = owner(stripe_of[k][p]);
        const std::vector<std::int64_t> keys = ps.key;
        move_particles(ps, dest, layouts_[k]);
        (*carried)[k] = carry_values(keys, (*carried)[k], dest, ps.key);
        continue;
      }
      ps.key.resize(ps.size());
      std::iota(ps.key.begin(), ps.key.end(), std::int64_t{0});
      std::vector<int> keep;
      for (std::size_t p = 0; p < ps.size(); ++p)
        if (owner(stripe_of[k][p]) == rank()) keep.push_back(static_cast<int>(p));
      compact(ps, keep, layouts_[k]);
    }
  }

  /// The rank that owns stripe s.
  int owner(int s) const { return owner_[static_cast<std::size_t>(std::clamp(s, 0, stripes_ - 1))]; }
  int stripe_of_node(int first_node) const { return first_node / width_; }

  /// Moves every particle of set k whose first node along the axis (first_node(p)) lies in
  /// another rank's stripes to that rank; the set stays in key order. Collective. Returns whether
  /// this rank's set changed.
  template <class FirstNode>
  bool migrate(std::size_t k, ParticleSet<Dim>& ps, FirstNode&& first_node) {
    if (!active()) return false;
    dest_.resize(ps.size());
    for (std::size_t p = 0; p < ps.size(); ++p) {
      dest_[p] = owner(first_node(p) / width_);
      migrated_ += dest_[p] != rank();
    }
    return move_particles(ps, dest_, layouts_.at(k));
  }

  /// The keys after the one-rank run's reordering (reorder_for_locality): a rank's particles, now
  /// in its schedule order, follow those of the ranks before it.
  void renumber(ParticleSet<Dim>& ps) const {
    if (!active()) return;
    const std::vector<long> counts = all_gather(static_cast<long>(ps.size()));
    std::int64_t first = 0;
    for (int r = 0; r < rank(); ++r) first += counts[static_cast<std::size_t>(r)];
    ps.key.resize(ps.size());
    std::iota(ps.key.begin(), ps.key.end(), first);
  }

  /// The node box a rank's per-node work covers: its own node columns and the shared ones above
  /// (so that every shared column is cleared before a scatter and finished on both sides), across
  /// the union of the ranks' boxes on the other axes.
  NodeBox<Dim> node_box(NodeBox<Dim> box) const {
    if (!active()) return box;
    box = union_box(box);
    std::tie(box.lo[axis_], box.hi[axis_]) = box_columns();
    return box;
  }

  /// The union of every rank's `box` (one rank: `box`). Collective.
  NodeBox<Dim> union_box(NodeBox<Dim> box) const {
    if (!active()) return box;
    std::array<long, 2 * Dim> lohi;
    for (int a = 0; a < Dim; ++a) lohi[a] = box.lo[a], lohi[Dim + a] = -static_cast<long>(box.hi[a]);
    min(std::span<long>(lohi));
    for (int a = 0; a < Dim; ++a) box.lo[a] = static_cast<int>(lohi[a]), box.hi[a] = static_cast<int>(-lohi[Dim + a]);
    return box;
  }

  /// The node columns along the axis that node_box gives this rank: its own and the shared ones
  /// above, [first, last].
  std::pair<int, int> box_columns() const {
    return {cuts_[rank()] * width_, std::min(nodes_[axis_] - 1, cuts_[rank() + 1] * width_ + support_ - 2)};
  }

  /// The node columns [first, second) this rank owns along the axis.
  std::pair<int, int> owned_columns() const { return exchange_->owned_columns(); }

  /// The first node column of every rank along the axis, then the node count (parallel::GridPoisson's
  /// cuts).
  std::vector<int> column_cuts() const {
    std::vector<int> c;
    for (int r = 0; r < ranks(); ++r) c.push_back(cuts_[static_cast<std::size_t>(r)] * width_);
    c.push_back(nodes_[axis_]);
    return c;
  }

  /// StripeExchange::fill_ghosts of a node array (nothing at one rank). Collective.
  template <class NodeArrayT>
  void fill_ghosts(NodeArrayT&& nodes, int width) const {
    if (active()) exchange_->fill_ghosts(nodes.data(), node_bytes(nodes), width);
  }
  /// StripeExchange::add_ghosts_to_owners of a node array of doubles (nothing at one rank). Collective.
  template <class NodeArrayT>
  void add_ghosts_to_owners(NodeArrayT&& nodes, int width) const {
    if (active()) exchange_->add_ghosts_to_owners(nodes.data(), width);
  }

  /// Every rank's own node columns of `arrays` copied to every other rank (fill_ghosts as wide as
  /// the grid): afterwards each rank holds the whole grid's values as their columns' owners
  /// computed them (a field that a grid-wide stage, such as mpm-fem's fluid solved on every rank,
  /// reads anywhere). Nothing at one rank. Collective.
  template <class... Arrays>
  void share_owned_columns(Arrays&... arrays) const {
    (fill_ghosts(arrays, nodes_[axis_]), ...);
  }

  /// Re-cuts for an equal particle count per rank when the counts differ by more than
  /// `tolerance` (0.1: the largest rank holds 10 % more than the mean). Collective; the caller
  /// migrates afterwards. Returns whether the cuts moved.
  bool rebalance(const std::vector<long>& local_per_stripe, double tolerance) {
    if (!active()) return false;
    std::vector<long> per_stripe = local_per_stripe;
    sum(std::span<long>(per_stripe));
    std::vector<long> load(static_cast<std::size_t>(ranks()), 0);
    for (int s = 0; s < stripes_; ++s) load[static_cast<std::size_t>(owner(s))] += per_stripe[static_cast<std::size_t>(s)];
    const long total = std::accumulate(load.begin(), load.end(), 0L);
    const long most = *std::max_element(load.begin(), load.end());
    if (total == 0 || static_cast<double>(most) <= (1.0 + tolerance) * static_cast<double>(total) / ranks()) return false;
    std::vector<int> cuts = balanced_cuts(per_stripe);
    if (cuts == cuts_) return false;
    set_cuts(std::move(cuts));
    ++rebalances_;
    return true;
  }
  int stripes() const { return stripes_; }
  int rebalances() const { return rebalances_; }
  /// The run's counters (mpirun): particles that moved between ranks (over all ranks) and re-cuts.
  /// Collective.
  template <class Counter>
  void add_counters(std::vector<Counter>& out) const {
    if (!active()) return;
    out.push_back({"particles migrated", static_cast<double>(sum(migrated_)), "particle moves between ranks"});
    out.push_back({"rebalances", static_cast<double>(rebalances_), "re-cuts for an even particle count"});
  }

 private:
  /// Stripe cuts with about total / ranks particles per rank (every rank at least one stripe): cut
  /// r at the stripe where the particles below come closest to r total / ranks.
  std::vector<int> balanced_cuts(const std::vector<long>& per_stripe) const {
    const int R = ranks();
    std::vector<long> below(static_cast<std::size_t>(stripes_) + 1, 0);  // particles in stripes < s
    for (int s = 0; s < stripes_; ++s) below[static_cast<std::size_t>(s) + 1] = below[static_cast<std::size_t>(s)] + per_stripe[static_cast<std::size_t>(s)];
    std::vector<int> cuts(static_cast<std::size_t>(R) + 1, 0);
    cuts[static_cast<std::size_t>(R)] = stripes_;
    for (int r = 1; r < R; ++r) {
      const double target = static_cast<double>(below.back()) * r / R;
      const int lo = cuts[static_cast<std::size_t>(r) - 1] + 1, hi = stripes_ - (R - r);
      int best = lo;
      for (int s = lo; s <= hi; ++s)
        if (std::abs(static_cast<double>(below[static_cast<std::size_t>(s)]) - target) <
            std::abs(static_cast<double>(below[static_cast<std::size_t>(best)]) - target))
          best = s;
      cuts[static_cast<std::size_t>(r)] = best;
    }
    return cuts;
  }

  void set_cuts(std::vector<int> cuts) {
    cuts_ = std::move(cuts);
    owner_.assign(static_cast<std::size_t>(stripes_), 0);
    for (int r = 0; r < ranks(); ++r)
      for (int s = cuts_[static_cast<std::size_t>(r)]; s < cuts_[static_cast<std::size_t>(r) + 1]; ++s) owner_[static_cast<std::size_t>(s)] = r;
    exchange_ = std::make_unique<StripeExchange>(nodes_, axis_, width_, support_, cuts_);
  }

  static FieldBytes layout_of(ParticleSet<Dim>& ps) {
    FieldBytes l;
    const std::size_t n = ps.size();
    ps.for_each_field([&](auto& f) { l.active.push_back(n > 0 && f.size() == n); });
    // The key is carried by every set under mpirun.
    l.active.back() = 1;
    return l;
  }

  bool move_particles(ParticleSet<Dim>& ps, const std::vector<int>& dest, const FieldBytes& layout) {
    return parallel::move_particles(ps, dest, layout, scratch_);
  }

  int axis_ = 0, width_ = 1, support_ = 1, stripes_ = 1;
  std::array<int, 3> nodes_{1, 1, 1};
  std::vector<int> cuts_;
  std::vector<int> owner_;  // per stripe: its rank
  std::unique_ptr<StripeExchange> exchange_;
  std::vector<FieldBytes> layouts_;
  std::vector<int> dest_;
  std::vector<std::max_align_t> scratch_;  // migration's rebuild of each field
  int rebalances_ = 0;
  long migrated_ = 0;  // this rank's particles sent away
};

}  // namespace swmpm::parallel
