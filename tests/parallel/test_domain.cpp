// solver/parallel/ on its own, under `mpirun -n 2` (and more): the exchange of shared node columns
// gives every node the one-rank sum bit for bit, migration moves whole particles and keeps the
// one-rank order, gather_set gives rank 0 the whole set in that order. Each rank builds the
// whole set itself (a fixed pseudo-random cloud), so the one-rank answer is known on every rank.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>

#include "solver/grid/grid.hpp"
#include "solver/parallel/comm.hpp"
#include "solver/parallel/domain.hpp"
#include "solver/parallel/particles.hpp"
#include "solver/shape/shape.hpp"
#include "solver/transfer/schedule.hpp"
#include "solver/transfer/transfer.hpp"

namespace swmpm::parallel {
namespace {

using Shape = shape::BSpline<2>;
constexpr int S = Shape::support;

Grid<2> grid() { return Grid<2>(Vec<2>(0.0, 0.0), Vec<2>(3.0, 1.0), 0.05, Shape::degree, Shape::bspline); }

/// n points scattered over [0.2, 2.8] x [0.1, 0.9] with masses of many magnitudes (so that the
/// order of a sum shows in its last bits).
ParticleSet<2> cloud(std::size_t n) {
  ParticleSet<2> ps;
  ps.resize(n);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(0.2, 2.8), uy(0.1, 0.9), um(-3.0, 3.0);
  for (std::size_t p = 0; p < n; ++p) {
    ps.id[p] = static_cast<std::int64_t>(p);
    ps.x[p] = Vec<2>(ux(rng), uy(rng));
    ps.x0[p] = ps.x[p];
    ps.l[p] = Vec<2>(0.0125, 0.0125);
    ps.m[p] = std::pow(10.0, um(rng));
    ps.V[p] = ps.V0[p] = 1e-3 * static_cast<double>(p + 1);
  }
  return ps;
}

/// sum_p N_ip m_p through the stripe schedule, into a node array cleared over `box`.
NodeArray<double> scatter(const Grid<2>& g, const ParticleSet<2>& ps, StripeSchedule& schedule, NodeBox<2>& box) {
  std::vector<shape::ShapeData<2, S>> sd;
  long bad = -1;
  box = transfer::evaluate_shapes<Shape>(g, ps, sd, bad);
  transfer::build_schedule(g, sd, schedule);
  NodeArray<double> m(g.num_nodes());
  schedule.run([&](int p) {
    shape::for_each_node(g, sd[p], [&](std::size_t i, double w, const auto&) { m[i] += w * ps.m[p]; });
  }, m);
  return m;
}

TEST(Domain, SharedColumnsGetTheOneRankSumBitForBit) {
  const Grid<2> g = grid();
  const ParticleSet<2> all = cloud(4000);
  StripeSchedule one;
  NodeBox<2> all_box;
  const NodeArray<double> reference = scatter(g, all, one, all_box);

  ParticleSet<2> mine = all;
  Domain<2> d;
  const int axis = transfer::stripe_axis(g);
  d.distribute(g, S, axis, {&mine}, [&](std::size_t, std::size_t p) { return first_node<Shape>(g, mine.x[p], mine.l[p], axis); });
  EXPECT_EQ(sum(static_cast<long>(mine.size())), 4000);
  EXPECT_TRUE(std::is_sorted(mine.key.begin(), mine.key.end()));
  StripeSchedule schedule;
  schedule.set_exchange(d.exchange());
  NodeBox<2> box;
  const NodeArray<double> got = scatter(g, mine, schedule, box);
  box = d.node_box(box);
  // Every node this rank's particles touch (its columns and the shared ones above) holds the
  // one-rank sum; and at least one shared column had contributions from both ranks.
  long compared = 0, differ = 0;
  g.for_each_node(box, [&](std::size_t i, const auto&) {
    ++compared;
    differ += got[i] != reference[i];
  });
  EXPECT_GT(compared, 0);
  EXPECT_EQ(differ, 0) << "of " << compared << " nodes on rank " << rank();
  // Without the exchange the shared columns would be partial: the test can fail.
  StripeSchedule alone;
  NodeBox<2> box_alone;
  const NodeArray<double> partial = scatter(g, mine, alone, box_alone);
  long partial_differ = 0;
  g.for_each_node(box, [&](std::size_t i, const auto&) { partial_differ += partial[i] != reference[i]; });
  const long partial_total = sum(partial_differ);
  if (ranks() > 1) {
    EXPECT_GT(partial_total, 0);
  }
}

TEST(Domain, MigrationMovesWholeParticlesToTheirStripesInKeyOrder) {
  const Grid<2> g = grid();
  ParticleSet<2> mine = cloud(3000);
  Domain<2> d;
  const int axis = transfer::stripe_axis(g);
  auto first = [&](std::size_t p) { return first_node<Shape>(g, mine.x[p], mine.l[p], axis); };
  d.distribute(g, S, axis, {&mine}, [&](std::size_t, std::size_t p) { return first(p); });
  // Everything slides 0.9 m to the right: most points change rank.
  for (auto& x : mine.x) x[0] = std::min(x[0] + 0.9, 2.95);
  const long before = sum(static_cast<long>(mine.size()));
  d.migrate(0, mine, first);
  EXPECT_EQ(sum(static_cast<long>(mine.size())), before);
  EXPECT_TRUE(std::is_sorted(mine.key.begin(), mine.key.end()));
  for (std::size_t p = 0; p < mine.size(); ++p) {
    ASSERT_EQ(d.owner(first(p) / d.width()), rank()) << "particle " << mine.id[p];
    // The fields travelled together: the id is the key (distribute) and the mass is the cloud's.
    EXPECT_EQ(mine.key[p], mine.id[p]);
    EXPECT_EQ(mine.V[p], 1e-3 * static_cast<double>(mine.id[p] + 1));
  }
  // Re-cut for the new distribution: the counts even out within the tolerance.
  std::vector<long> per_stripe(static_cast<std::size_t>(d.stripes()), 0);
  for (std::size_t p = 0; p < mine.size(); ++p) ++per_stripe[static_cast<std::size_t>(first(p) / d.width())];
  const bool moved = d.rebalance(per_stripe, 0.05);
  d.migrate(0, mine, first);
  const auto counts = all_gather(static_cast<long>(mine.size()));
  const long most = *std::max_element(counts.begin(), counts.end());
  if (moved) {
    EXPECT_LE(static_cast<double>(most), 1.1 * static_cast<double>(before) / ranks() + 60.0);
  }
}

TEST(Domain, GatherSetGivesRankZeroTheWholeSetInTheOneRankOrder) {
  const Grid<2> g = grid();
  ParticleSet<2> mine = cloud(2000);
  Domain<2> d;
  const int axis = transfer::stripe_axis(g);
  d.distribute(g, S, axis, {&mine}, [&](std::size_t, std::size_t p) { return first_node<Shape>(g, mine.x[p], mine.l[p], axis); });
  const ParticleSet<2> whole = gather_set(mine);
  if (rank() != 0) {
    EXPECT_EQ(whole.size(), 0u);
    return;
  }
  const ParticleSet<2> all = cloud(2000);
  ASSERT_EQ(whole.size(), all.size());
  for (std::size_t p = 0; p < all.size(); ++p) {
    EXPECT_EQ(whole.id[p], all.id[p]);
    EXPECT_EQ(whole.x[p], all.x[p]);
    EXPECT_EQ(whole.m[p], all.m[p]);
  }
}

}  // namespace
}  // namespace swmpm::parallel

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  swmpm::parallel::start(argc, argv);
  if (swmpm::parallel::rank() != 0) {  // one report, rank 0's; every rank's failures count
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
  }
  const int failed = RUN_ALL_TESTS();
  const long any_failed = swmpm::parallel::max(static_cast<long>(failed));
  swmpm::parallel::stop();
  return static_cast<int>(any_failed);
}
