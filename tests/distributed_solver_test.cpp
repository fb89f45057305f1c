// The distributed engine: N agents in one process reach the centralized optimum, the agents'
// cost shares sum to the global cost, and iterates do not depend on message delivery order.

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <tessera/distributed/agent_state.hpp>
#include <tessera/distributed/block_layout.hpp>
#include <tessera/distributed/block_selection.hpp>
#include <tessera/distributed/distributed_solver.hpp>
#include <tessera/partition/sequential_partition.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/block_preconditioner.hpp>
#include <tessera/solvers/centralized_solver.hpp>
#include <tessera/util/input_error.hpp>

#include "random_graph.hpp"
#include "test_support.hpp"

namespace tessera {
namespace {

PoseGraph small_graph(int d, std::size_t poses, std::uint64_t seed) {
  test::RandomGraphSpec spec;
  spec.d = d;
  spec.poses = poses;
  spec.loop_closures = poses / 2;
  spec.seed = seed;
  return test::random_pose_graph(spec);
}

// f* to round-off: the default stop ends ~1e-8 above it, and the tests compare to 1e-9.
double optimum(const PoseGraph& g) {
  CentralizedOptions o;
  o.stop = CentralizedStop::kGradient;
  return solve_centralized(g, o).cost;
}

TEST(DistributedSolver, TwoBlocksConvergeToCentralizedOptimum) {
  const PoseGraph g = small_graph(2, 40, 3);
  DistributedOptions opt;
  opt.algorithm = DistributedAlgorithm::kRbcd;
  // 1e-4: far below the solvers' 0.01, yet above the level where one block step's decrease
  // is lost in the cost's round-off (then the trust region rejects every step).
  opt.grad_norm_tol = 1e-4;
  opt.max_rounds = 2000;
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 2), opt);
  EXPECT_EQ(r.stop_reason, "grad_norm") << r.grad_norm << " " << r.rounds;
  EXPECT_EQ(r.agents, 2);
  const double fstar = optimum(g);
  EXPECT_NEAR(r.cost, fstar, 1e-7 * fstar);
}

// Below that level no block step is accepted any more and the iterate stops moving: the run
// stops as "stalled" after a few rounds per block instead of spinning to max_rounds (seen as
// 10000 rounds, ~100 s, after a re-partition for survivors over DDS).
TEST(DistributedSolver, AnUnreachableToleranceStopsWhenTheIterateStallsNotAtMaxRounds) {
  const PoseGraph g = small_graph(2, 40, 3);
  const double fstar = optimum(g);
  for (auto alg : {DistributedAlgorithm::kRbcd, DistributedAlgorithm::kIrbcd}) {
    DistributedOptions opt;
    opt.algorithm = alg;
    opt.grad_norm_tol = 1e-15;
    opt.max_rounds = 20000;
    opt.refine.auto_interface_grad_tol = 0;  // the rounds themselves (no hand-over)
    const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 2), opt);
    EXPECT_EQ(r.stop_reason, "stalled")
        << algorithm_name(alg) << ": " << r.grad_norm << " after " << r.rounds << " rounds";
    EXPECT_LT(r.rounds, 20000) << algorithm_name(alg);
    EXPECT_NEAR(r.cost, fstar, 1e-9 * fstar) << algorithm_name(alg);
    // The rounds that decided it repeat the final cost and gradient norm exactly.
    ASSERT_GE(r.trace.size(), 21u) << algorithm_name(alg);
    for (std::size_t i = r.trace.size() - 21; i < r.trace.size(); ++i) {
      EXPECT_EQ(r.trace[i].cost, r.trace.back().cost) << algorithm_name(alg) << " round " << i;
      EXPECT_EQ(r.trace[i].grad_norm, r.trace.back().grad_norm) << algorithm_name(alg);
    }
  }
}

TEST(DistributedSolver, AgentCostSharesSumToGlobalCost) {
  const PoseGraph g = small_graph(3, 50, 5);
  const std::vector<int> assignment = {0, 1, 2, 0, 1, 2};  // interleaved: many cut edges
  std::vector<int> a(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) a[i] = assignment[i % assignment.size()];
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, a);
  const Eigen::MatrixXd X = lift_poses(g.initial, 5) + 0.0 * Eigen::MatrixXd::Zero(5, 4 * 50);
  const BlockProblem whole = BlockProblem::whole_graph(3, g.num_poses, g.measurements);
  double sum = 0.0, gsq = 0.0;
  for (int b = 0; b < 3; ++b) {
    const auto& ids = layout.poses[static_cast<std::size_t>(b)];
    BlockProblem p(3, ids, g.measurements);
    p.set_neighbor_poses(gather_pose_columns(X, p.neighbors(), 3));
    const Eigen::MatrixXd Xb = gather_pose_columns(X, ids, 3);
    sum += p.cost_share(Xb);
    gsq += p.riemannian_gradient(Xb, p.euclidean_gradient(Xb)).squaredNorm();
  }
  EXPECT_NEAR(sum, whole.cost(X), 1e-10 * whole.cost(X));
  const double g_whole = whole.riemannian_gradient(X, whole.euclidean_gradient(X)).squaredNorm();
  EXPECT_NEAR(gsq, g_whole, 1e-9 * g_whole);
}

// The status after a block update reuses the update's gradient only while the point and the
// neighbours are those of the update; either way it must equal a fresh computation.
TEST(DistributedSolver, StatusAfterUpdateMatchesFreshGradient) {
  const PoseGraph g = small_graph(3, 40, 7);
  const std::vector<int> a = [&] {
    std::vector<int> out(g.num_poses);
    for (std::size_t i = 0; i < g.num_poses; ++i) out[i] = i < g.num_poses / 2 ? 0 : 1;
    return out;
  }();
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, a);
  const Eigen::MatrixXd X = lift_poses(g.initial, 5);
  const auto& ids = layout.poses[0];
  AgentState agent(0, 3, layout, g.measurements, gather_pose_columns(X, ids, 3));
  BlockProblem fresh(3, ids, g.measurements);
  agent.Yn = gather_pose_columns(X, fresh.neighbors(), 3);
  auto fresh_gsq = [&] {
    fresh.set_neighbor_poses(agent.Yn);
    return fresh.riemannian_gradient(agent.Y, fresh.euclidean_gradient(agent.Y)).squaredNorm();
  };
  const double before = agent.status().grad_norm_sq;
  EXPECT_NEAR(before, fresh_gsq(), 1e-12 * before);
  agent.Y = agent.update(agent.Y, agent.Yn, BlockUpdateOptions{});
  const double reused = agent.status().grad_norm_sq;
  EXPECT_LT(reused, before);  // the update made progress, and the status sees the new point
  EXPECT_NEAR(reused, fresh_gsq(), 1e-10 * reused);
  agent.Yn.col(0) *= 1.5;  // a neighbour moved: the stored gradient no longer applies
  const double moved = agent.status().grad_norm_sq;
  EXPECT_NEAR(moved, fresh_gsq(), 1e-12 * moved);
  EXPECT_GT(std::abs(moved - reused), 1e-6 * reused);
}

// The agents compute on the rows that are not identically zero (a lifted [I_d; 0] R start has
// r - d zero rows). The update must be the full-rank update: the same result as the block update
// on all r rows, zero rows exactly zero, and, for a lifting without zero rows (rotated in R^r),
// the rotated result.
TEST(DistributedSolver, ActiveRowUpdateEqualsTheFullRankUpdate) {
  const PoseGraph g = small_graph(3, 40, 17);
  std::vector<int> a(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) a[i] = i < g.num_poses / 2 ? 0 : 1;
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, a);
  const int r = 5;
  const Eigen::MatrixXd X = lift_poses(g.initial, r);
  const auto& ids = layout.poses[0];
  BlockProblem full(3, ids, g.measurements);
  BlockPreconditioner precon(full);
  const LiftedManifold M = full.manifold(r);
  // Start away from the optimum of the block so that the update moves.
  std::srand(4);
  const Eigen::MatrixXd Y0 = gather_pose_columns(X, ids, 3);
  const Eigen::MatrixXd tangent = M.tangent_project(Y0, Eigen::MatrixXd::Random(r, Y0.cols()));
  Eigen::MatrixXd start = M.retract(Y0, 0.2 * tangent);
  start.bottomRows(r - 3).setZero();  // keep the zero rows of the lifting
  start = M.project(start);
  const Eigen::MatrixXd Yn = gather_pose_columns(X, full.neighbors(), 3);

  // The Q_BB preconditioner on both sides (the tangent one exists at rank d only).
  BlockUpdateOptions euclidean;
  euclidean.tangent_preconditioner = false;
  AgentState agent(0, 3, layout, g.measurements, start, euclidean);
  const Eigen::MatrixXd got = agent.update(start, Yn, euclidean);
  full.set_neighbor_poses(Yn);
  const Eigen::MatrixXd want = block_update(full, start, euclidean, nullptr);
  const Eigen::MatrixXd want_pre = block_update(full, start, euclidean, &precon);
  EXPECT_GT((got - start).norm(), 1e-6);  // it moved
  EXPECT_EQ(got.bottomRows(r - 3).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT((got - want_pre).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_GT((want - want_pre).norm(),
            0.0);  // (the preconditioner matters: the check is not vacuous)

  // A random rotation of R^r: no zero rows left, every row active; the result rotates along.
  const Eigen::MatrixXd R =
      Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd::Random(r, r)).householderQ();
  AgentState rotated(0, 3, layout, g.measurements, R * start, euclidean);
  const Eigen::MatrixXd got_rot = rotated.update(R * start, R * Yn, euclidean);
  EXPECT_LT((got_rot - R * got).cwiseAbs().maxCoeff(), 1e-8);
}

// greedy_newton scores each block by its preconditioned gradient norm sqrt(<(2Q_BB)^-1 g, g>)
// (the decrease a block update predicts); the gradient norm of the status stays the plain one.
TEST(DistributedSolver, GreedyNewtonScoreIsThePreconditionedGradientNorm) {
  const PoseGraph g = small_graph(2, 40, 23);
  std::vector<int> a(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) a[i] = i < 15 ? 0 : 1;
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, a);
  const Eigen::MatrixXd X = lift_poses(g.initial, 5);
  AgentState agent(0, 2, layout, g.measurements, gather_pose_columns(X, layout.poses[0], 2));
  BlockProblem fresh(2, layout.poses[0], g.measurements);
  agent.Yn = gather_pose_columns(X, fresh.neighbors(), 2);
  fresh.set_neighbor_poses(agent.Yn);
  const Eigen::MatrixXd grad =
      fresh.riemannian_gradient(agent.Y, fresh.euclidean_gradient(agent.Y));
  const BlockPreconditioner precon(fresh);
  const Eigen::MatrixXd z = precon.apply(fresh.manifold(5), agent.Y, grad);
  const double expected = std::sqrt((z.array() * grad.array()).sum());
  const LocalStatus plain = agent.status();
  const LocalStatus newton = agent.status(true);
  EXPECT_NEAR(newton.block_grad_norm, expected, 1e-10 * expected);
  EXPECT_NEAR(plain.block_grad_norm, grad.norm(), 1e-10 * grad.norm());
  EXPECT_NEAR(newton.grad_norm_sq, plain.grad_norm_sq, 1e-12 * plain.grad_norm_sq);
  EXPECT_GT(std::abs(newton.block_grad_norm - plain.block_grad_norm), 1e-6 * expected);
  EXPECT_EQ(newton.cost_share, plain.cost_share);

  // The rule picks the largest score, whole colour classes with `parallel`.
  EXPECT_EQ(parse_selection("greedy_newton"), SelectionRule::kGreedyNewton);
  EXPECT_STREQ(selection_name(SelectionRule::kGreedyNewton), "greedy_newton");
  EXPECT_EQ(select_blocks(SelectionRule::kGreedyNewton, false, 1, 0, {0.5, 2.0}, layout),
            std::vector<int>{1});
  EXPECT_EQ(select_blocks(SelectionRule::kGreedyNewton, false, 1, 0, {3.0, 2.0}, layout),
            std::vector<int>{0});
}

TEST(DistributedSolver, ClassNormScoresAColourClassByItsOwnGradientNorm) {
  BlockLayout layout;
  layout.num_blocks = 5;
  layout.colour = {0, 1, 0, 1, 2};
  layout.colour_classes = {{0, 2}, {1, 3}, {4}};
  // Block 1 has the largest norm (class {1, 3}: 4 + 0.25 = 4.25 squared); class {0, 2} has
  // the largest class norm (1 + 3.61 = 4.61 squared).
  const std::vector<double> norms = {1.0, 2.0, 1.9, 0.5, 1.5};
  EXPECT_EQ(select_blocks(SelectionRule::kGreedy, true, 1, 0, norms, layout),
            (std::vector<int>{1, 3}));
  EXPECT_EQ(
      select_blocks(SelectionRule::kGreedy, true, 1, 0, norms, layout, ClassScore::kLargestBlock),
      (std::vector<int>{1, 3}));
  EXPECT_EQ(
      select_blocks(SelectionRule::kGreedy, true, 1, 0, norms, layout, ClassScore::kClassNorm),
      (std::vector<int>{0, 2}));
  EXPECT_EQ(select_blocks(SelectionRule::kGreedyNewton, true, 1, 0, norms, layout,
                          ClassScore::kClassNorm),
            (std::vector<int>{0, 2}));
  // The largest block (4: 1.96) loses to a class of two smaller ones (2).
  EXPECT_EQ(select_blocks(SelectionRule::kGreedy, true, 1, 0, {1.0, 0.1, 1.0, 0.1, 1.4}, layout,
                          ClassScore::kClassNorm),
            (std::vector<int>{0, 2}));
  EXPECT_EQ(select_blocks(SelectionRule::kGreedy, true, 1, 0, {1.0, 0.1, 1.0, 0.1, 1.4}, layout,
                          ClassScore::kLargestBlock),
            (std::vector<int>{4}));
  // One block per round, and the non-greedy rules: the class score plays no part.
  EXPECT_EQ(
      select_blocks(SelectionRule::kGreedy, false, 1, 0, norms, layout, ClassScore::kClassNorm),
      std::vector<int>{1});
  EXPECT_EQ(
      select_blocks(SelectionRule::kRoundRobin, true, 1, 4, norms, layout, ClassScore::kClassNorm),
      layout.colour_classes[1]);
  EXPECT_EQ(parse_class_score(class_score_name(ClassScore::kClassNorm)), ClassScore::kClassNorm);
  EXPECT_EQ(parse_class_score(class_score_name(ClassScore::kLargestBlock)),
            ClassScore::kLargestBlock);
  EXPECT_EQ(parse_class_score("norm"), ClassScore::kClassNorm);
  EXPECT_EQ(parse_class_score("max"), ClassScore::kLargestBlock);
  EXPECT_THROW(parse_class_score("sum"), InputError);
}

TEST(DistributedSolver, GreedyNewtonSelectionReachesTheOptimum) {
  const PoseGraph g = small_graph(3, 60, 29);
  DistributedOptions opt;
  opt.selection = SelectionRule::kGreedyNewton;
  opt.max_rounds = 5000;
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 4), opt);
  EXPECT_EQ(r.stop_reason, "grad_norm");
  EXPECT_NEAR(r.cost, optimum(g), 1e-5 * optimum(g));
  opt.parallel = true;
  const DistributedResult p = solve_distributed(g, sequential_partition(g.num_poses, 4), opt);
  EXPECT_EQ(p.stop_reason, "grad_norm");
  EXPECT_NEAR(p.cost, optimum(g), 1e-5 * optimum(g));
}

// The slowest-agent CPU estimate sums, per (stage, round), one agent's share of the work the
// process did in total: positive, and never more than the whole process's CPU time.
TEST(DistributedSolver, CriticalPathCpuIsPartOfTheProcessCpu) {
  const PoseGraph g = small_graph(3, 80, 31);
  DistributedOptions opt;
  opt.max_rounds = 40;
  opt.grad_norm_tol = 0;
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 4), opt);
  EXPECT_GT(r.critical_path_cpu_s, 0.0);
  EXPECT_LE(r.critical_path_cpu_s, r.solve_cpu_s + 0.01);  // + clock granularity
}

TEST(DistributedSolver, DeterministicAcrossDeliveryOrdersAndReruns) {
  const PoseGraph g = small_graph(3, 60, 7);
  for (auto alg : {DistributedAlgorithm::kRbcd, DistributedAlgorithm::kRbcdPlusPlus,
                   DistributedAlgorithm::kIrbcd}) {
    DistributedOptions opt;
    opt.algorithm = alg;
    opt.selection = SelectionRule::kUniform;
    opt.max_rounds = 60;
    opt.grad_norm_tol = 0;
    opt.irbcd.restart_c = 1e-3;  // make restarts part of the comparison
    const auto part = sequential_partition(g.num_poses, 4);
    const DistributedResult a = solve_distributed(g, part, opt);
    const DistributedResult again = solve_distributed(g, part, opt);
    opt.delivery = DeliveryOrder::kReversed;
    const DistributedResult b = solve_distributed(g, part, opt);
    opt.delivery = DeliveryOrder::kShuffled;
    opt.delivery_seed = 99;
    const DistributedResult c = solve_distributed(g, part, opt);
    ASSERT_EQ(a.trace.size(), b.trace.size());
    for (const auto* o : {&again, &b, &c}) {
      EXPECT_TRUE(a.X == o->X) << algorithm_name(alg);  // bit-identical
      EXPECT_EQ(a.rounds, o->rounds);
      EXPECT_EQ(a.restarts, o->restarts);
      EXPECT_EQ(a.bytes_exchanged, o->bytes_exchanged);
      for (std::size_t k = 0; k < a.trace.size(); ++k) {
        EXPECT_EQ(a.trace[k].cost, o->trace[k].cost);
        EXPECT_EQ(a.trace[k].selected, o->trace[k].selected);
      }
    }
  }
}

class EachAlgorithm : public ::testing::TestWithParam<DistributedAlgorithm> {};

TEST_P(EachAlgorithm, ReachesToleranceAndOptimum) {
  for (int d : {2, 3}) {
    const PoseGraph g = small_graph(d, 80, 11);
    const double fstar = optimum(g);
    for (bool parallel : {false, true}) {
      DistributedOptions opt;
      opt.algorithm = GetParam();
      opt.parallel = parallel;
      opt.grad_norm_tol = 0.01;
      opt.max_rounds = 5000;
      const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 5), opt);
      EXPECT_EQ(r.stop_reason, "grad_norm") << algorithm_name(GetParam()) << " d=" << d;
      EXPECT_LE(r.grad_norm, 0.01);
      EXPECT_NEAR(r.cost, fstar, 1e-5 * fstar) << algorithm_name(GetParam()) << " d=" << d;
      EXPECT_GT(r.bytes_exchanged, 0u);
      ASSERT_FALSE(r.trace.empty());
      EXPECT_EQ(r.trace.back().round, r.rounds);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Distributed, EachAlgorithm,
                         ::testing::Values(DistributedAlgorithm::kRbcd,
                                           DistributedAlgorithm::kRbcdPlusPlus,
                                           DistributedAlgorithm::kIrbcd));

TEST(DistributedSolver, RestartPathConvergesAndIsRecorded) {
  const PoseGraph g = small_graph(3, 60, 13);
  DistributedOptions opt;
  opt.algorithm = DistributedAlgorithm::kIrbcd;
  opt.irbcd.restart_c = 1e3;  // absurdly demanding: nearly every round restarts
  opt.max_rounds = 5000;
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 3), opt);
  EXPECT_GT(r.restarts, 0);
  int flagged = 0;
  for (const auto& row : r.trace) flagged += row.restart ? 1 : 0;
  EXPECT_EQ(flagged, r.restarts);
  EXPECT_EQ(r.stop_reason, "grad_norm");
  // After a restart the redo is a plain block update: the cost never goes up.
  for (std::size_t k = 1; k < r.trace.size(); ++k)
    EXPECT_LE(r.trace[k].cost, r.trace[k - 1].cost * (1 + 1e-12));
}

TEST(DistributedSolver, MaxRoundsStops) {
  const PoseGraph g = small_graph(2, 30, 2);
  DistributedOptions opt;
  opt.max_rounds = 3;
  opt.grad_norm_tol = 0;
  opt.refine.auto_interface_grad_tol = 0;  // the rounds themselves (no hand-over)
  const DistributedResult r = solve_distributed(g, sequential_partition(g.num_poses, 3), opt);
  EXPECT_EQ(r.rounds, 3);
  EXPECT_EQ(r.stop_reason, "max_rounds");
  EXPECT_EQ(r.trace.size(), 4u);
}

TEST(DistributedSolver, DistributedInitializationStartsCloseAndConverges) {
  test::RandomGraphSpec spec;
  spec.d = 3;
  spec.poses = 60;
  spec.loop_closures = 30;
  spec.rotation_noise = 0;
  spec.translation_noise = 0;
  const PoseGraph exact = test::random_pose_graph(spec);
  DistributedOptions opt;
  opt.initialization = DistributedInit::kDistributed;
  opt.max_rounds = 0;
  const DistributedResult r0 = solve_distributed(exact, sequential_partition(60, 4), opt);
  EXPECT_LT(r0.cost, 1e-8);  // noise-free: every robot's chordal solve and the alignment are exact
  const PoseGraph g = small_graph(3, 60, 17);
  opt.max_rounds = 5000;
  const DistributedResult r = solve_distributed(g, sequential_partition(60, 4), opt);
  EXPECT_EQ(r.stop_reason, "grad_norm");
  EXPECT_NEAR(r.cost, optimum(g), 1e-5 * optimum(g));
}

TEST(DistributedSolver, ColourClassesAreIndependentSets) {
  const PoseGraph g = small_graph(2, 60, 19);
  std::vector<int> a(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) a[i] = static_cast<int>(i % 6);
  const BlockLayout L = make_block_layout(g.num_poses, g.measurements, a);
  for (const auto& cls : L.colour_classes)
    for (int x : cls)
      for (int y : cls) EXPECT_LT(L.adjacency_index(x, y), 0);
}

// What an agent builds from the whole graph's endpoints alone (8 bytes a measurement) is the
// layout built from the measurements themselves.
TEST(DistributedSolver, LayoutFromEndpointsEqualsLayoutFromMeasurements) {
  const PoseGraph g = small_graph(3, 80, 23);
  std::vector<int> a(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) a[i] = static_cast<int>((i * 7) % 5);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ends;
  for (const Measurement& m : g.measurements)
    ends.emplace_back(static_cast<std::uint32_t>(m.i), static_cast<std::uint32_t>(m.j));
  const BlockLayout from_measurements = make_block_layout(g.num_poses, g.measurements, a);
  const BlockLayout from_endpoints = make_block_layout(g.num_poses, ends, a);
  EXPECT_EQ(from_endpoints.num_blocks, from_measurements.num_blocks);
  EXPECT_EQ(from_endpoints.owner, from_measurements.owner);
  EXPECT_EQ(from_endpoints.poses, from_measurements.poses);
  EXPECT_EQ(from_endpoints.adjacent, from_measurements.adjacent);
  EXPECT_EQ(from_endpoints.public_to, from_measurements.public_to);
  EXPECT_EQ(from_endpoints.colour, from_measurements.colour);
  ends.back().second = static_cast<std::uint32_t>(g.num_poses);  // out of range
  EXPECT_THROW(make_block_layout(g.num_poses, ends, a), InputError);
}

// An agent frees its Q_BB factor while it certifies; the next update computes it again and
// takes exactly the step it would have taken with the factor kept.
TEST(DistributedSolver, ReleasedBlockFactorGivesTheSameUpdate) {
  const PoseGraph g = small_graph(3, 60, 29);
  std::vector<int> a(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) a[i] = i < g.num_poses / 2 ? 0 : 1;
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, a);
  const Eigen::MatrixXd X = lift_poses(g.initial, 5);
  BlockUpdateOptions o;
  o.tangent_preconditioner = false;  // the Q_BB factor preconditions every update
  AgentState kept(0, 3, layout, g.measurements, gather_pose_columns(X, layout.poses[0], 3), o);
  AgentState released(0, 3, layout, g.measurements, gather_pose_columns(X, layout.poses[0], 3), o);
  kept.Yn = released.Yn = gather_pose_columns(X, kept.problem().neighbors(), 3);
  released.release_block_factor();
  const Eigen::MatrixXd a_step = kept.update(kept.Y, kept.Yn, o);
  const Eigen::MatrixXd b_step = released.update(released.Y, released.Yn, o);
  EXPECT_EQ(a_step, b_step);
  EXPECT_GT((a_step - kept.Y).norm(), 0.0);
}

// Above max_factor_entries the agent's preconditioner is the block diagonal of Q_BB (memory
// linear in the block), and the solve still reaches the optimum.
TEST(DistributedSolver, BlockDiagonalFallbackAboveTheFactorCap) {
  const PoseGraph g = small_graph(3, 60, 31);
  std::vector<int> a(g.num_poses);
  for (std::size_t i = 0; i < g.num_poses; ++i) a[i] = i < g.num_poses / 2 ? 0 : 1;
  const BlockLayout layout = make_block_layout(g.num_poses, g.measurements, a);
  const Eigen::MatrixXd X = lift_poses(g.initial, 5);
  BlockUpdateOptions capped;
  capped.max_factor_entries = 1;
  AgentState small(0, 3, layout, g.measurements, gather_pose_columns(X, layout.poses[0], 3),
                   capped);
  EXPECT_TRUE(small.block_factor_too_large());
  AgentState exact(0, 3, layout, g.measurements, gather_pose_columns(X, layout.poses[0], 3));
  EXPECT_FALSE(exact.block_factor_too_large());
  DistributedOptions opt;
  opt.block_update.max_factor_entries = 1;
  const DistributedResult r = solve_distributed(g, a, opt);
  EXPECT_LE(r.grad_norm, opt.grad_norm_tol);
  const double fstar = optimum(g);
  EXPECT_NEAR(r.cost, fstar, 1e-4 * fstar);
}

TEST(DistributedSolver, BadOptionsNameTheField) {
  using test::input_error_of;
  using test::validation_names;
  DistributedOptions o;
  o.grad_norm_tol = -1;
  EXPECT_TRUE(validation_names(o, "grad_norm_tol"));
  o = {};
  o.max_rounds = -2;
  EXPECT_TRUE(validation_names(o, "max_rounds"));
  o = {};
  o.block_update.trust_region_steps = 0;
  EXPECT_TRUE(validation_names(o, "trust_region_steps"));
  o = {};
  o.irbcd.b0 = 0;
  EXPECT_TRUE(validation_names(o, "b0"));
  o = {};
  o.irbcd.sigma = -1;
  EXPECT_TRUE(validation_names(o, "IrbcdOptions.sigma"));
  const PoseGraph g = small_graph(3, 20, 1);
  o = {};
  o.rank = 2;
  EXPECT_NE(
      input_error_of([&] { solve_distributed(g, sequential_partition(20, 2), o); }).find("rank"),
      std::string::npos);
  std::vector<int> bad(20, 0);
  bad[3] = 2;  // block 1 empty
  EXPECT_NE(input_error_of([&] { solve_distributed(g, bad, DistributedOptions{}); }).find("empty"),
            std::string::npos);
  EXPECT_NE(input_error_of([] { parse_algorithm("sgd"); }).find("rbcd"), std::string::npos);
}

}  // namespace
}  // namespace tessera
