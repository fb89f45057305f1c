// The smoothed coarse space: its pieces and weights, its cost is f's model in the pieces'
// motions (exact for rigid pieces, to second order for blended ones, which stay on the
// manifold), it undoes a smooth bend of the map far better than one rigid motion per block,
// and two-level rounds over it are deterministic and need fewer rounds than one-level ones.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/coarse_correction.hpp>
#include <tessera/distributed/coarse_space.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/generate/generator.hpp>
#include <tessera/manifold/lifted_manifold.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/util/input_error.hpp>
#include <utility>
#include <vector>

#include "test_support.hpp"

namespace tessera {
namespace {

// f at a lifted iterate of the whole graph.
double f_of(const PoseGraph& g, const Eigen::MatrixXd& X) {
  return BlockProblem::whole_graph(g.d, g.num_poses, g.measurements).cost(X);
}

struct Grid {
  PoseGraph graph;
  std::vector<Pose> truth;
};

Grid grid(std::size_t poses, double noise) {
  GeneratorOptions o;
  o.kind = TrajectoryKind::kGrid3d;
  o.num_poses = poses;
  o.num_robots = 4;
  o.seed = 1;
  o.rotation_noise = noise;
  o.translation_noise = 5 * noise;
  GeneratorResult r = generate_pose_graph(o);
  return {std::move(r.graph), std::move(r.ground_truth)};
}

std::vector<std::vector<double>> smoothed_terms(const PoseGraph& g, const CoarseSpace& space,
                                                const Eigen::MatrixXd& X) {
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, space.owner);
  std::vector<std::vector<double>> out;
  for (int a = 0; a < layout.num_blocks; ++a) {
    const BlockProblem p(g.d, layout.poses[static_cast<std::size_t>(a)], g.measurements);
    const SmoothedCoarseTerms t(space, a, g.d, p.owned(), p.neighbors(), g.measurements);
    out.push_back(t.compute(gather_pose_columns(X, p.owned(), g.d),
                            gather_pose_columns(X, p.neighbors(), g.d)));
  }
  return out;
}

std::vector<const std::vector<double>*> pointers(const std::vector<std::vector<double>>& t) {
  std::vector<const std::vector<double>*> p;
  for (const auto& v : t) p.push_back(&v);
  return p;
}

// The f decrease of the block space's best correction at X.
double block_space_decrease(const PoseGraph& g, const std::vector<int>& part,
                            const Eigen::MatrixXd& X, const CoarseOptions& o) {
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, part);
  std::vector<std::vector<double>> terms;
  for (int a = 0; a < layout.num_blocks; ++a) {
    const BlockProblem p(g.d, layout.poses[static_cast<std::size_t>(a)], g.measurements);
    const CoarseTerms t(a, g.d, layout, p.owned(), p.neighbors(), g.measurements);
    terms.push_back(t.compute(gather_pose_columns(X, p.owned(), g.d),
                              gather_pose_columns(X, p.neighbors(), g.d)));
  }
  const CoarseResult c = solve_coarse(layout, static_cast<int>(X.rows()), pointers(terms), o);
  return c.cost_before - c.cost_after;
}

// The truth bent smoothly: pose i turned about the z axis by an angle growing with its x.
Eigen::MatrixXd bent(const std::vector<Pose>& truth, int r, double per_metre) {
  std::vector<Pose> b = truth;
  for (Pose& p : b) {
    const double a = per_metre * p.t(0);
    Eigen::Matrix3d Rz;
    Rz << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
    p.R = Rz * p.R;
    p.t = Rz * p.t;
  }
  return lift_poses(b, r);
}

std::vector<std::size_t> all_ids(std::size_t n) {
  std::vector<std::size_t> ids(n);
  std::iota(ids.begin(), ids.end(), std::size_t{0});
  return ids;
}

TEST(SmoothedCoarseSpace, OptionsNameTheBadField) {
  CoarseOptions o;
  o.aggregates = 0;
  EXPECT_TRUE(test::validation_names(o, "aggregates"));
  o = CoarseOptions();
  o.smoothing_steps = 9;
  EXPECT_THROW(o.validate(), InputError);
  o = CoarseOptions();
  o.smoothing_weight = 0;
  EXPECT_THROW(o.validate(), InputError);
  EXPECT_EQ(parse_coarse_space("smoothed"), CoarseSpaceKind::kSmoothed);
  EXPECT_THROW(parse_coarse_space("rigid"), InputError);
}

TEST(SmoothedCoarseSpace, PosesPerAggregateGivesEachBlockPiecesByItsSizeUpToAggregates) {
  CoarseOptions o;
  o.aggregates = 8;
  for (std::size_t n : {1u, 100u, 500u, 5000u}) EXPECT_EQ(block_aggregates(o, n), 8) << n;
  o.poses_per_aggregate = 250;
  // One piece per 250 poses, rounded, at least one and at most `aggregates`.
  const std::pair<std::size_t, int> expected[] = {
      {1, 1}, {124, 1}, {374, 1}, {375, 2}, {500, 2}, {1000, 4}, {1800, 7}, {2000, 8}, {40000, 8}};
  for (const auto& [n, pieces] : expected) EXPECT_EQ(block_aggregates(o, n), pieces) << n;
  o.poses_per_aggregate = -1;
  EXPECT_TRUE(test::validation_names(o, "poses_per_aggregate"));
}

TEST(SmoothedCoarseSpace, ABlockTwiceAsLargeGetsTwiceThePiecesUnderPosesPerAggregate) {
  // One chain of 180 poses: block 0 the first 60, block 1 the other 120.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::uint32_t i = 0; i + 1 < 180; ++i) edges.emplace_back(i, i + 1);
  std::vector<int> part(180, 0);
  for (std::size_t i = 60; i < 180; ++i) part[i] = 1;
  CoarseOptions o;
  o.space = CoarseSpaceKind::kSmoothed;
  o.aggregates = 8;
  o.poses_per_aggregate = 20;
  const CoarseSpace s = make_coarse_space(180, edges, part, o);
  EXPECT_EQ(std::count(s.aggregate_block.begin(), s.aggregate_block.end(), 0), 3);
  EXPECT_EQ(std::count(s.aggregate_block.begin(), s.aggregate_block.end(), 1), 6);
  o.poses_per_aggregate = 0;
  EXPECT_EQ(make_coarse_space(180, edges, part, o).num_aggregates, 16);
}

TEST(SmoothedCoarseSpace, PiecesStayInTheirBlockAndWeightsArePartitionsOfUnity) {
  const Grid G = grid(400, 0.01);
  const PoseGraph& g = G.graph;
  const std::vector<int> part = sequential_partition(g.num_poses, 5);
  CoarseOptions o;
  o.aggregates = 3;
  o.smoothing_steps = 0;
  const CoarseSpace rigid = make_coarse_space(g.num_poses, g.measurements, part, o);
  EXPECT_GE(rigid.num_aggregates, 15);
  for (std::size_t i = 0; i < g.num_poses; ++i) {
    EXPECT_EQ(rigid.aggregate_block[static_cast<std::size_t>(rigid.aggregate[i])], part[i]);
    ASSERT_EQ(rigid.weight_start[i + 1] - rigid.weight_start[i], 1u);  // no blend without steps
  }
  o.smoothing_steps = 2;
  const CoarseSpace s = make_coarse_space(g.num_poses, g.measurements, part, o);
  EXPECT_EQ(s.aggregate, rigid.aggregate);
  std::size_t blended = 0, across_blocks = 0;
  for (std::size_t i = 0; i < g.num_poses; ++i) {
    double sum = 0.0;
    for (std::size_t e = s.weight_start[i]; e < s.weight_start[i + 1]; ++e) {
      EXPECT_GT(s.weight[e], 0.0);
      sum += s.weight[e];
      if (s.aggregate_block[static_cast<std::size_t>(s.weight_aggregate[e])] != part[i])
        ++across_blocks;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    blended += s.weight_start[i + 1] - s.weight_start[i] > 1;
  }
  EXPECT_GT(blended, g.num_poses / 10);
  EXPECT_GT(across_blocks, 0u);  // the blend crosses block borders
}

// Every agent keeps the whole graph's weight lists through the run: they are sized once, not
// left with a doubling's spare capacity, and bytes() counts what the lists hold.
TEST(SmoothedCoarseSpace, WeightListsHoldNoSpareCapacityAndBytesCountThem) {
  const Grid G = grid(400, 0.01);
  const PoseGraph& g = G.graph;
  const std::vector<int> part = sequential_partition(g.num_poses, 5);
  CoarseOptions o;
  o.aggregates = 3;
  o.smoothing_steps = 2;
  const CoarseSpace s = make_coarse_space(g.num_poses, g.measurements, part, o);
  const std::size_t entries = s.weight_start.back();
  ASSERT_GT(entries, g.num_poses);  // some poses are blended
  EXPECT_EQ(s.weight.size(), entries);
  EXPECT_EQ(s.weight.capacity(), entries);
  EXPECT_EQ(s.weight_aggregate.capacity(), entries);
  // At least the per-pose lists (owner, aggregate, weight_start) and the weights themselves.
  EXPECT_GE(s.bytes(), g.num_poses * (2 * sizeof(int) + sizeof(std::size_t)) +
                           entries * (sizeof(int) + sizeof(double)));
  EXPECT_LT(s.bytes(), g.num_poses * 64 + entries * 16);
}

TEST(SmoothedCoarseSpace, CostIsTheModelOfFAndTheBlendStaysOnTheManifold) {
  const Grid G = grid(300, 0.01);
  const PoseGraph& g = G.graph;
  const int r = 5;
  const std::vector<int> part = sequential_partition(g.num_poses, 4);
  const Eigen::MatrixXd X = bent(G.truth, r, 0.05);
  const double f0 = f_of(g, X);
  for (int steps : {0, 1}) {
    CoarseOptions o;
    o.aggregates = 3;
    o.smoothing_steps = steps;
    o.max_iterations = 20;
    const CoarseSpace s = make_coarse_space(g.num_poses, g.measurements, part, o);
    const CoarseResult c = solve_smoothed_coarse(s, r, pointers(smoothed_terms(g, s, X)), o);
    ASSERT_TRUE(c.moved);
    Eigen::MatrixXd Xc = X;
    apply_blended_motions(s, c.motions, g.d, all_ids(g.num_poses), Xc);
    const double model = c.cost_before - c.cost_after, real = f0 - f_of(g, Xc);
    EXPECT_GT(model, 0.01 * f0) << steps;
    if (steps == 0)  // rigid pieces: exact
      EXPECT_NEAR(real, model, 1e-9 * f0);
    else  // blended and projected back: second order in the step
      EXPECT_NEAR(real, model, 0.05 * model);
    EXPECT_LT(LiftedManifold(r, g.d, g.num_poses).distance_from_manifold(Xc), 1e-12);
    EXPECT_TRUE((Xc.bottomRows(r - g.d).array() == 0.0).all());
  }
}

TEST(SmoothedCoarseSpace, UndoesASmoothBendFarBetterThanOneRigidMotionPerBlock) {
  // Noise-free measurements: f = 0 at the truth, so f at the bent truth is all error, and it
  // is the smooth bending that block updates remove slowest.
  const Grid G = grid(600, 0.0);
  const PoseGraph& g = G.graph;
  const int r = 5;
  const std::vector<int> part = sequential_partition(g.num_poses, 6);
  const Eigen::MatrixXd X = bent(G.truth, r, 0.03);
  const double f0 = f_of(g, X);
  CoarseOptions o;
  o.max_iterations = 20;
  const double blocks = block_space_decrease(g, part, X, o);
  o.aggregates = 4;
  o.smoothing_steps = 1;
  const CoarseSpace s = make_coarse_space(g.num_poses, g.measurements, part, o);
  const CoarseResult c = solve_smoothed_coarse(s, r, pointers(smoothed_terms(g, s, X)), o);
  const double smoothed = c.cost_before - c.cost_after;
  EXPECT_GT(smoothed, 100.0 * blocks) << "f " << f0 << ", blocks " << blocks;
  EXPECT_GT(smoothed, 0.15 * f0) << "f " << f0 << ", blocks " << blocks;
}

TEST(SmoothedCoarseSpace, WrongSizedTermsAreRejected) {
  const Grid G = grid(200, 0.01);
  const std::vector<int> part = sequential_partition(G.graph.num_poses, 3);
  const CoarseOptions o;
  const CoarseSpace s = make_coarse_space(G.graph.num_poses, G.graph.measurements, part, o);
  auto terms = smoothed_terms(G.graph, s, lift_poses(G.graph.initial, 5));
  terms[2].push_back(0.0);
  EXPECT_THROW(solve_smoothed_coarse(s, 5, pointers(terms), o), std::runtime_error);
}

TEST(SmoothedCoarseSpace, TwoLevelRoundsAreDeterministicAndNeedFewerRoundsThanOneLevel) {
  const Grid G = grid(800, 0.01);
  const PoseGraph& g = G.graph;
  const std::vector<int> part = sequential_partition(g.num_poses, 16);
  DistributedOptions opt;
  opt.grad_norm_tol = 0.01;
  const DistributedResult one = solve_distributed(g, part, opt);
  opt.coarse.enabled = true;
  opt.coarse.space = CoarseSpaceKind::kSmoothed;
  opt.coarse.aggregates = 2;
  const DistributedResult smoothed = solve_distributed(g, part, opt);
  opt.delivery = DeliveryOrder::kShuffled;
  opt.delivery_seed = 7;
  const DistributedResult shuffled = solve_distributed(g, part, opt);
  EXPECT_EQ(smoothed.stop_reason, "grad_norm");
  EXPECT_TRUE(smoothed.X == shuffled.X);  // every agent solved the same coarse problem
  EXPECT_EQ(smoothed.rounds, shuffled.rounds);
  EXPECT_NEAR(smoothed.cost, one.cost, 1e-5 * one.cost);
  EXPECT_LT(smoothed.rounds, one.rounds)
      << "one-level " << one.rounds << ", smoothed " << smoothed.rounds;
}

}  // namespace
}  // namespace tessera
