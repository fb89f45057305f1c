// The partition follows the graph: border poses move out of over-full blocks, as few as the
// bound needs, and an online run whose robots grow unevenly still ends at the batch optimum.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <tessera/generate/generator.hpp>
#include <tessera/online/block_rebalance.hpp>
#include <tessera/online/online_engine.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/solvers/centralized_solver.hpp>

#include "test_support.hpp"

namespace tessera {
namespace {

// A chain 0 - 1 - ... - n-1 (structure only: rebalancing reads endpoints).
PoseGraph chain(std::size_t n) {
  PoseGraph g;
  g.d = 2;
  g.num_poses = n;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    Measurement m;
    m.i = k;
    m.j = k + 1;
    g.measurements.push_back(m);
  }
  return g;
}

TEST(BlockRebalance, MovesBorderPosesOnlyUntilTheBoundHolds) {
  // Block 0 holds 0..39, block 1 holds 40..41 (a robot that just joined).
  const PoseGraph g = chain(42);
  std::vector<int> owner(42, 0);
  owner[40] = owner[41] = 1;
  RebalanceOptions o;
  o.slack = 0.0;
  o.min_excess = 0;
  const RebalanceResult r = rebalance_blocks(g, owner, 2, o);
  // Bound ceil(42/2) = 21: 19 poses move, the ones next to the border (39, 38, ...).
  EXPECT_EQ(r.largest_before, 40u);
  EXPECT_EQ(r.largest_after, 21u);
  EXPECT_EQ(r.moved, 19u);
  for (std::size_t k = 0; k < 42; ++k) EXPECT_EQ(owner[k], k < 21 ? 0 : 1) << k;
}

TEST(BlockRebalance, LeavesBlocksWithinSlackAlone) {
  const PoseGraph g = chain(42);
  std::vector<int> owner(42, 0);
  for (std::size_t k = 25; k < 42; ++k) owner[k] = 1;  // 25 / 17
  RebalanceOptions o;                                  // bound 1.2 * 21 + 10
  EXPECT_EQ(rebalance_blocks(g, owner, 2, o).moved, 0u);
  o.enabled = false;
  owner.assign(42, 0);
  owner[41] = 1;
  EXPECT_EQ(rebalance_blocks(g, owner, 2, o).moved, 0u);
}

// The definition of the moves, one scan of the graph per move: the lowest-id unmoved pose of
// the largest over-full block (that has one) with a measurement into the lightest block at
// least two poses lighter, to the first such block among its measurements.
std::size_t rebalance_by_definition(const PoseGraph& g, std::vector<int>& owner, int blocks,
                                    double bound) {
  std::vector<std::size_t> size(static_cast<std::size_t>(blocks), 0);
  for (int b : owner) ++size[static_cast<std::size_t>(b)];
  std::vector<std::vector<std::size_t>> adjacent(g.num_poses);
  for (const Measurement& m : g.measurements) {
    adjacent[m.i].push_back(m.j);
    adjacent[m.j].push_back(m.i);
  }
  std::vector<char> moved(g.num_poses, 0);
  std::size_t moves = 0;
  for (bool any = true; any;) {
    any = false;
    std::vector<int> order(static_cast<std::size_t>(blocks));
    for (int b = 0; b < blocks; ++b) order[static_cast<std::size_t>(b)] = b;
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return size[std::size_t(a)] > size[std::size_t(b)]; });
    for (int big : order) {
      const std::size_t big_size = size[static_cast<std::size_t>(big)];
      if (static_cast<double>(big_size) <= bound || big_size <= 1) break;
      std::size_t pose = g.num_poses;
      int to = -1;
      for (std::size_t k = 0; k < g.num_poses; ++k) {
        if (owner[k] != big || moved[k]) continue;
        for (std::size_t q : adjacent[k]) {
          const int c = owner[q];
          if (c == big || size[std::size_t(c)] + 2 > big_size) continue;
          if (to < 0 || size[std::size_t(c)] < size[std::size_t(to)]) {
            to = c;
            pose = k;
          }
        }
      }
      if (to < 0) continue;
      owner[pose] = to;
      moved[pose] = 1;
      --size[static_cast<std::size_t>(big)];
      ++size[static_cast<std::size_t>(to)];
      ++moves;
      any = true;
      break;
    }
  }
  return moves;
}

TEST(BlockRebalance, MakesTheMovesOfItsDefinitionOnRandomGraphs) {
  std::mt19937 rng(7);
  std::size_t total_moves = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t n = 20 + rng() % 200;
    const int blocks = 2 + static_cast<int>(rng() % 6);
    PoseGraph g = chain(n);  // odometry, and closures between random poses
    for (std::size_t k = 0, extra = rng() % (2 * n); k < extra; ++k) {
      Measurement m;
      m.i = rng() % n;
      m.j = (m.i + 1 + rng() % (n - 1)) % n;
      g.measurements.push_back(m);
    }
    // Uneven contiguous blocks (robots), some poses handed to random blocks (earlier moves).
    std::vector<int> owner(n);
    for (std::size_t k = 0; k < n; ++k)
      owner[k] = std::min(blocks - 1, static_cast<int>(blocks * (k * k) / (n * n)));
    for (std::size_t k = 0; k < n / 10; ++k) owner[rng() % n] = static_cast<int>(rng() % blocks);
    for (int b = 0; b < blocks; ++b) owner[static_cast<std::size_t>(b)] = b;  // none empty
    RebalanceOptions o;
    o.slack = 0.1 * static_cast<double>(rng() % 3);
    o.min_excess = rng() % 3;
    o.cut_fraction = 1.0;  // the balance moves alone
    std::vector<int> expected = owner;
    const double bound = (1.0 + o.slack) * std::ceil(static_cast<double>(n) / blocks) +
                         static_cast<double>(o.min_excess);
    const std::size_t moves = rebalance_by_definition(g, expected, blocks, bound);
    const RebalanceResult r = rebalance_blocks(g, owner, blocks, o);
    EXPECT_EQ(r.moved, moves) << "trial " << trial;
    EXPECT_EQ(owner, expected) << "trial " << trial;
    total_moves += moves;
  }
  EXPECT_GT(total_moves, 2000u) << "the trials move poses";
}

TEST(BlockRebalance, RejectsANegativeSlackNamingTheField) {
  RebalanceOptions o;
  o.slack = -0.1;
  EXPECT_TRUE(test::validation_names(o, "RebalanceOptions.slack"));
}

TEST(OnlineRebalance, ALateRobotGetsPosesAndTheFinalAnswerEqualsTheBatchOptimum) {
  GeneratorOptions gen_options;
  gen_options.kind = TrajectoryKind::kCity;
  gen_options.num_poses = 120;
  gen_options.num_robots = 3;
  gen_options.seed = 5;
  const auto gen = generate_pose_graph(gen_options);
  ReplayOptions ro;
  ro.start_s = {0.0, 0.0, 5.0};  // robot 2 starts when robots 0 and 1 are done
  const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, ro);
  OnlineOptions o;
  o.solver.grad_norm_tol = 1e-5;
  o.rebalance.slack = 0.1;
  o.rebalance.min_excess = 2;
  const OnlineResult res = run_online(gen.graph.d, plan.batches, o);
  // Robot 2's first poses arrive next to robot 1's block (their rendezvous measurement), so
  // robot 1's border poses move to the new, small block.
  EXPECT_GT(res.repartitions, 0);
  EXPECT_GT(res.poses_moved, 0u);
  const double f_star = solve_centralized(gen.graph).cost;
  EXPECT_NEAR(res.cost, f_star, 1e-6 * f_star);
  ASSERT_TRUE(res.certified.has_value());
  EXPECT_TRUE(*res.certified);
}

// The cut refinement: random graphs (a chain and closures, mostly between nearby ids, as a
// trajectory revisiting places) with blocks that cross each other (interleaved id ranges).
struct CrossedBlocks {
  PoseGraph graph;
  std::vector<int> owner;
  int blocks = 0;
};

CrossedBlocks crossed_blocks(std::mt19937& rng) {
  CrossedBlocks c;
  const std::size_t n = 30 + rng() % 300;
  c.blocks = 2 + static_cast<int>(rng() % 5);
  c.graph = chain(n);
  for (std::size_t k = 0, extra = rng() % (2 * n); k < extra; ++k) {
    Measurement m;
    m.i = rng() % n;
    m.j = std::min(n - 1, m.i + 1 + rng() % 8);
    if (m.j != m.i) c.graph.measurements.push_back(m);
  }
  // Runs of 1-12 poses handed to the blocks in turn: every block crosses every other.
  c.owner.resize(n);
  for (std::size_t k = 0, b = 0; k < n; b = (b + 1) % static_cast<std::size_t>(c.blocks)) {
    const std::size_t run = 1 + rng() % 12;
    for (std::size_t r = 0; r < run && k < n; ++r) c.owner[k++] = static_cast<int>(b);
  }
  for (int b = 0; b < c.blocks; ++b) c.owner[static_cast<std::size_t>(b)] = b;  // none empty
  return c;
}

std::vector<std::size_t> block_sizes(const std::vector<int>& owner, int blocks) {
  std::vector<std::size_t> size(static_cast<std::size_t>(blocks), 0);
  for (int b : owner) ++size[static_cast<std::size_t>(b)];
  return size;
}

TEST(CutRefinement, ReducesTheCutOfBlocksThatCrossEachOther) {
  std::mt19937 rng(11);
  std::size_t before = 0, after = 0;
  for (int trial = 0; trial < 100; ++trial) {
    CrossedBlocks c = crossed_blocks(rng);
    RebalanceOptions o;
    o.min_excess = 0;
    const RebalanceResult r = rebalance_blocks(c.graph, c.owner, c.blocks, o);
    EXPECT_TRUE(r.refined) << "trial " << trial;
    EXPECT_LE(r.cut_after, r.cut_before) << "trial " << trial;
    EXPECT_EQ(r.cut_after, cut_measurements(c.graph, c.owner)) << "trial " << trial;
    before += r.cut_before;
    after += r.cut_after;
  }
  // Crossed blocks cut most of the chain; the refinement gathers the runs.
  EXPECT_LT(static_cast<double>(after), 0.4 * static_cast<double>(before))
      << before << " -> " << after;
}

TEST(CutRefinement, KeepsEveryBlockWithinTheBalanceBounds) {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 200; ++trial) {
    CrossedBlocks c = crossed_blocks(rng);
    RebalanceOptions o;
    o.slack = 0.1 * static_cast<double>(rng() % 4);
    o.min_excess = rng() % 4;
    const double full = (1.0 + o.slack) * std::ceil(static_cast<double>(c.owner.size()) /
                                                    static_cast<double>(c.blocks)) +
                        static_cast<double>(o.min_excess);
    const double low = (1.0 - o.slack) * std::floor(static_cast<double>(c.owner.size()) /
                                                    static_cast<double>(c.blocks));
    const std::vector<std::size_t> start = block_sizes(c.owner, c.blocks);
    rebalance_blocks(c.graph, c.owner, c.blocks, o);
    const std::vector<std::size_t> end = block_sizes(c.owner, c.blocks);
    for (std::size_t b = 0; b < end.size(); ++b) {
      EXPECT_GE(end[b], 1u) << "trial " << trial << " block " << b;
      // Nor does one above the lower bound fall below it (the cut alone would be smallest with
      // blocks nearly empty).
      EXPECT_GE(static_cast<double>(end[b]),
                std::min(std::floor(low), static_cast<double>(start[b])))
          << "trial " << trial << " block " << b;
      // A block within the bound stays within it; one above it (the balance moves had no
      // lighter neighbour) does not grow.
      EXPECT_LE(static_cast<double>(end[b]),
                std::max(std::floor(full), static_cast<double>(start[b])))
          << "trial " << trial << " block " << b;
    }
  }
}

TEST(CutRefinement, EachPassMovesOnlyBorderPoses) {
  // One pass: a pose that moves was a border pose when the pass began (a measurement into
  // another block) or a neighbour of a pose that moved in the same pass (the border moving
  // pose by pose from where it is). k passes are k one-pass calls.
  std::mt19937 rng(13);
  std::size_t moved = 0;
  for (int trial = 0; trial < 100; ++trial) {
    CrossedBlocks c = crossed_blocks(rng);
    RebalanceOptions o;
    const std::size_t bound = c.owner.size() / static_cast<std::size_t>(c.blocks) + 5;
    std::vector<int> passes = c.owner;
    o.max_passes = 1;
    for (int pass = 0; pass < 8; ++pass) {
      const std::vector<int> start = passes;
      moved += refine_cut(c.graph, passes, c.blocks, bound, 1, o);
      std::vector<char> border_or_next(c.owner.size(), 0);
      for (const Measurement& m : c.graph.measurements) {
        if (start[m.i] != start[m.j]) border_or_next[m.i] = border_or_next[m.j] = 1;
        if (passes[m.i] != start[m.i]) border_or_next[m.j] = 1;  // next to a moved pose
        if (passes[m.j] != start[m.j]) border_or_next[m.i] = 1;
      }
      for (std::size_t k = 0; k < c.owner.size(); ++k) {
        if (passes[k] != start[k]) {
          EXPECT_TRUE(border_or_next[k]) << "trial " << trial << " pass " << pass << " pose " << k;
        }
      }
    }
    std::vector<int> at_once = c.owner;
    o.max_passes = 8;
    refine_cut(c.graph, at_once, c.blocks, bound, 1, o);
    EXPECT_EQ(at_once, passes) << "trial " << trial;
  }
  EXPECT_GT(moved, 1000u) << "the trials move poses";
}

TEST(CutRefinement, IsDeterministicAndLeavesALowCutAlone) {
  std::mt19937 rng(14);
  CrossedBlocks c = crossed_blocks(rng);
  RebalanceOptions o;
  std::vector<int> a = c.owner, b = c.owner;
  const RebalanceResult ra = rebalance_blocks(c.graph, a, c.blocks, o);
  const RebalanceResult rb = rebalance_blocks(c.graph, b, c.blocks, o);
  EXPECT_EQ(a, b);
  EXPECT_EQ(ra.moved, rb.moved);
  EXPECT_GT(ra.moved, 0u);
  // At or under cut_fraction nothing moves: the refinement is not even run.
  std::vector<int> low = c.owner;
  o.cut_fraction =
      static_cast<double>(ra.cut_before) / static_cast<double>(c.graph.measurements.size());
  const RebalanceResult r = rebalance_blocks(c.graph, low, c.blocks, o);
  EXPECT_FALSE(r.refined);
  EXPECT_EQ(r.moved, 0u);
  EXPECT_EQ(low, c.owner);
}

TEST(CutRefinement, NewPosesJoinTheBlockHoldingMostOfTheirMeasurements) {
  PoseGraph g = chain(6);  // 0-1-2-3-4-5, and 5-2, 5-3: pose 5 has 1 link to 4, 2 to {2, 3}
  for (std::size_t k : {2, 3}) {
    Measurement m;
    m.i = k;
    m.j = 5;
    g.measurements.push_back(m);
  }
  std::vector<int> owner = {0, 0, 1, 1};  // poses 4 and 5 are new, robot 0's
  RebalanceOptions o;
  assign_new_poses(g, owner, {0, 0}, o);
  // 4's one measurement to an older pose is into block 1 (pose 3); 5's three are all into
  // block 1 (4, 2, 3) once 4 joined it.
  EXPECT_EQ(owner, (std::vector<int>{0, 0, 1, 1, 1, 1}));
  o.cut_fraction = 1.0;  // refinement off: the robot's block
  owner = {0, 0, 1, 1};
  assign_new_poses(g, owner, {0, 0}, o);
  EXPECT_EQ(owner, (std::vector<int>{0, 0, 1, 1, 0, 0}));
}

TEST(CutRefinement, RejectsAnOutOfRangeCutFractionNamingTheField) {
  RebalanceOptions o;
  o.cut_fraction = 1.5;
  EXPECT_TRUE(test::validation_names(o, "RebalanceOptions.cut_fraction"));
  o.cut_fraction = 0.02;
  o.max_passes = 0;
  EXPECT_TRUE(test::validation_names(o, "RebalanceOptions.max_passes"));
}

TEST(CutRefinement, ARobotThatJoinsOpensItsOwnBlockWhateverItsFirstPoseLinksTo) {
  // Robot 1's first pose (2) has odometry from robot 0's last (1): it still opens block 1,
  // and its next pose (3), linked to it alone, follows it there.
  const PoseGraph g = chain(4);
  std::vector<int> owner = {0, 0};
  assign_new_poses(g, owner, {1, 1}, RebalanceOptions{});
  EXPECT_EQ(owner, (std::vector<int>{0, 0, 1, 1}));
}

std::size_t floor_of(std::size_t n, int blocks, const RebalanceOptions& o) {
  const double low = (1.0 - o.slack) * std::floor(static_cast<double>(n) / blocks);
  return low > 1.0 ? static_cast<std::size_t>(std::floor(low)) : 1;
}

TEST(BlockBounds, ABlockUnderTheFloorTakesPosesPassedAlongTheChainOfBlocks) {
  // Chain 0..59: A = 0..33, B = 34..49, C = 50..59. The floor is floor(0.8 * 20) = 16: C (10)
  // is under it, its only neighbour B is at it, so A gives 6 poses to B and B 6 to C.
  const PoseGraph g = chain(60);
  std::vector<int> owner(60, 0);
  for (std::size_t k = 34; k < 60; ++k) owner[k] = k < 50 ? 1 : 2;
  RebalanceOptions o;
  o.cut_fraction = 0.5;  // the refinement is on; the cut (2 of 59) is under its threshold
  const RebalanceResult r = rebalance_blocks(g, owner, 3, o);
  EXPECT_FALSE(r.refined);
  EXPECT_EQ(r.chain_moves, 12u);
  EXPECT_EQ(r.moved, 12u);
  EXPECT_EQ(r.smallest_after, 16u);
  for (std::size_t k = 0; k < 60; ++k) EXPECT_EQ(owner[k], k < 28 ? 0 : k < 44 ? 1 : 2) << k;
  EXPECT_EQ(r.cut_after, 2u);
}

TEST(BlockBounds, ABlockThatNoBlockAboveTheFloorReachesStaysUnderIt) {
  // Two pieces: 0..39 (blocks 0 and 1) and 40..44 (block 2, a robot that has met no other).
  PoseGraph g = chain(45);
  g.measurements.erase(g.measurements.begin() + 39);  // no 39 - 40
  std::vector<int> owner(45, 0);
  for (std::size_t k = 20; k < 45; ++k) owner[k] = k < 40 ? 1 : 2;
  const std::vector<int> start = owner;
  const RebalanceResult r = rebalance_blocks(g, owner, 3, RebalanceOptions{});
  EXPECT_EQ(r.moved, 0u);
  EXPECT_EQ(r.smallest_after, 5u);  // under the floor, 12
  EXPECT_EQ(owner, start);
}

TEST(BlockBounds, BothBoundsHoldAfterEveryCallOfAGrowingGraphWhoseNewPosesJoinOtherBlocks) {
  // Robots whose trajectories cross (crossed_blocks' closures between nearby ids): new poses
  // join the block of their measurements, which leaves robots' blocks light and fills others
  // past their neighbours; after every call every block holds the floor and at most the upper
  // bound (the graph is connected).
  std::mt19937 rng(21);
  std::size_t chain_moves = 0, checks = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const CrossedBlocks c = crossed_blocks(rng);
    const std::size_t n = c.owner.size();
    RebalanceOptions o;
    o.slack = 0.1 * static_cast<double>(1 + rng() % 3);
    o.min_excess = rng() % 4;
    std::vector<int> owner;
    const std::size_t step = 1 + rng() % 12;
    for (std::size_t have = std::min<std::size_t>(n, static_cast<std::size_t>(c.blocks));;) {
      PoseGraph g = c.graph;  // its first `have` poses
      g.num_poses = have;
      g.measurements.erase(
          std::remove_if(g.measurements.begin(), g.measurements.end(),
                         [&](const Measurement& m) { return std::max(m.i, m.j) >= have; }),
          g.measurements.end());
      const std::vector<int> robot(c.owner.begin() + static_cast<long>(owner.size()),
                                   c.owner.begin() + static_cast<long>(have));
      assign_new_poses(g, owner, robot, o);
      const RebalanceResult r = rebalance_blocks(g, owner, c.blocks, o);
      chain_moves += r.chain_moves;
      const std::vector<std::size_t> size = block_sizes(owner, c.blocks);
      const double full = (1.0 + o.slack) * std::ceil(static_cast<double>(have) / c.blocks) +
                          static_cast<double>(o.min_excess);
      for (std::size_t b = 0; b < size.size(); ++b) {
        EXPECT_GE(size[b], floor_of(have, c.blocks, o))
            << "trial " << trial << " poses " << have << " block " << b;
        EXPECT_LE(static_cast<double>(size[b]), std::floor(full))
            << "trial " << trial << " poses " << have << " block " << b;
      }
      EXPECT_EQ(r.smallest_after, *std::min_element(size.begin(), size.end()));
      ++checks;
      if (have == n) break;
      have = std::min(n, have + step);
    }
  }
  EXPECT_GT(chain_moves, 100u) << "the placements leave blocks out of the bounds";
  EXPECT_GT(checks, 500u);
}

}  // namespace
}  // namespace tessera
