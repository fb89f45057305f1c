// Block problems grown in place as an online run's data arrives (LiveBlocks, AgentState::extend,
// BlockProblem::extend, TangentPreconditioner::grow) are the problems a rebuild on the final
// graph gives, and the grown preconditioner is still a symmetric positive definite map.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <tessera/generate/generator.hpp>
#include <tessera/online/estimate_extension.hpp>
#include <tessera/online/graph_stream.hpp>
#include <tessera/online/live_blocks.hpp>
#include <tessera/online/replay_schedule.hpp>
#include <tessera/problem/block_problem.hpp>
#include <tessera/problem/lifting.hpp>
#include <tessera/solvers/tangent_preconditioner.hpp>

namespace tessera {
namespace {

GeneratorResult small_graph(TrajectoryKind kind, std::size_t n, std::size_t robots) {
  GeneratorOptions o;
  o.kind = kind;
  o.num_poses = n;
  o.num_robots = robots;
  o.seed = 5;
  return generate_pose_graph(o);
}

double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(1.0, b.norm());
}

// Plays `gen` as its robots' front ends would and syncs a LiveBlocks (blocks = robots) every
// `every` batches, as the online engine does at its steps.
struct GrownRun {
  GraphStream stream;
  LiveBlocks live;
  Eigen::MatrixXd X;  // stream ids
  int extended = 0, built = 0, kept = 0;

  GrownRun(const GeneratorResult& gen, std::size_t every, double refactor_growth)
      : stream(gen.graph.d), live(gen.graph.d, BlockUpdateOptions{}, refactor_growth) {
    ReplayOptions opt;
    opt.rate = 10;
    const ReplayPlan plan = plan_replay(gen.graph, gen.robot_of, opt);
    X.resize(5, 0);
    std::size_t extended_over = 0;
    for (std::size_t b = 0; b < plan.batches.size(); ++b) {
      stream.absorb(plan.batches[b]);
      if ((b + 1) % every != 0 && b + 1 != plan.batches.size()) continue;
      const PoseGraph& g = stream.graph();
      X = extend_estimate(g, X, stream.guesses(), extended_over).X;
      extended_over = g.measurements.size();
      std::vector<int> owner;
      for (std::size_t k = 0; k < g.num_poses; ++k)
        owner.push_back(static_cast<int>(stream.robot_of_pose()[k]));
      const LiveSync s = live.sync(g, owner, X);
      extended += s.extended;
      built += s.built;
      kept += s.kept;
    }
  }
};

TEST(LiveBlocks, BlocksGrownInPlaceEqualBlocksBuiltOnTheFinalGraph) {
  // Small steps, and steps of many batches at once (a step that lagged behind the stream).
  for (auto [kind, every] :
       {std::pair{TrajectoryKind::kSphere, 7}, std::pair{TrajectoryKind::kCity, 7},
        std::pair{TrajectoryKind::kSphere, 97}}) {
    const auto gen = small_graph(kind, 240, 4);
    GrownRun run(gen, static_cast<std::size_t>(every), 0.25);
    const PoseGraph& g = run.live.graph();
    const int d = g.d;
    EXPECT_EQ(g.num_poses, gen.graph.num_poses);
    EXPECT_EQ(g.measurements.size(), gen.graph.measurements.size());
    // Most syncs grew blocks; only the robots' first appearances built one.
    EXPECT_EQ(run.built, 4);
    EXPECT_GT(run.extended, every == 7 ? 40 : 4);
    // The compact iterate of the linked graph, and a second point to evaluate at.
    Eigen::MatrixXd Xc = gather_pose_columns(run.X, run.live.full_id(), d);
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.1);
    Eigen::MatrixXd Xr = Xc.unaryExpr([&](double v) { return v + noise(rng); });
    const BlockLayout& layout = run.live.layout();
    ASSERT_EQ(layout.num_blocks, 4);
    for (int c = 0; c < layout.num_blocks; ++c) {
      const AgentState& state = *run.live.states()[static_cast<std::size_t>(c)];
      BlockProblem grown = state.problem();  // a copy, to set its neighbours here
      BlockProblem fresh(d, layout.poses[static_cast<std::size_t>(c)], g.measurements);
      EXPECT_EQ(grown.owned(), fresh.owned());
      EXPECT_EQ(grown.neighbors(), fresh.neighbors());
      EXPECT_EQ(grown.num_measurements(), fresh.num_measurements());
      EXPECT_LT(relative_difference(Eigen::MatrixXd(grown.data_matrix()),
                                    Eigen::MatrixXd(fresh.data_matrix())),
                1e-14);
      // The state starts from the iterate.
      EXPECT_EQ(state.Y, gather_pose_columns(Xc, layout.poses[static_cast<std::size_t>(c)], d));
      for (const Eigen::MatrixXd* P : {&Xc, &Xr}) {
        const Eigen::MatrixXd Xb = gather_pose_columns(*P, grown.owned(), d);
        const Eigen::MatrixXd Xn = gather_pose_columns(*P, grown.neighbors(), d);
        grown.set_neighbor_poses(Xn);
        fresh.set_neighbor_poses(Xn);
        const double f = fresh.cost(Xb);
        EXPECT_NEAR(grown.cost(Xb), f, 1e-12 * std::max(1.0, f));
        EXPECT_NEAR(grown.cost_share(Xb), fresh.cost_share(Xb), 1e-12 * std::max(1.0, f));
        EXPECT_LT(relative_difference(grown.euclidean_gradient(Xb), fresh.euclidean_gradient(Xb)),
                  1e-12);
      }
    }
  }
}

TEST(LiveBlocks, ABlockWithNoNewDataIsKeptAsItIs) {
  const auto gen = small_graph(TrajectoryKind::kSphere, 120, 3);
  GrownRun run(gen, 5, 0.25);
  const AgentState* before = run.live.states()[0].get();
  const std::vector<std::size_t> neighbours = before->problem().neighbors();
  std::vector<int> owner;
  for (std::size_t k = 0; k < run.stream.graph().num_poses; ++k)
    owner.push_back(static_cast<int>(run.stream.robot_of_pose()[k]));
  const LiveSync again = run.live.sync(run.stream.graph(), owner, run.X);
  EXPECT_EQ(again.new_measurements, 0u);
  EXPECT_EQ(again.kept, 3);
  EXPECT_EQ(again.extended + again.built, 0);
  EXPECT_EQ(run.live.states()[0].get(), before);
  EXPECT_EQ(before->problem().neighbors(), neighbours);
}

TEST(LiveBlocks, AMoveRebuildsOnlyTheBlocksThatGaveOrTookPoses) {
  const auto gen = small_graph(TrajectoryKind::kSphere, 120, 3);
  GrownRun run(gen, 5, 0.25);
  std::vector<int> owner;
  for (std::size_t k = 0; k < run.stream.graph().num_poses; ++k)
    owner.push_back(static_cast<int>(run.stream.robot_of_pose()[k]));
  // A pose that robot 0's block holds as a neighbour moves between robots 1 and 2: block 0
  // keeps its own and neighbour poses, but that neighbour's owner (and so the index of its
  // block among block 0's neighbour blocks, which the coarse terms read) changes.
  const std::vector<std::size_t>& full = run.live.full_id();
  const int c0 = run.live.compact_block(0);
  ASSERT_EQ(c0, 0);
  const AgentState* kept = run.live.states()[0].get();
  std::size_t moved = full.size();
  for (std::size_t nb : kept->problem().neighbors())
    if (moved == full.size()) moved = full[nb];
  ASSERT_LT(moved, owner.size());
  owner[moved] = 3 - owner[moved];
  const std::vector<double> terms_before = kept->coarse_terms();  // built on the old layout
  const long long factorizations = kept->tangent_factorizations_total();
  EXPECT_GT(factorizations, 0);
  const std::vector<std::size_t> neighbours = kept->problem().neighbors();
  const LiveSync s = run.live.sync(run.stream.graph(), owner, run.X);
  EXPECT_EQ(s.built, 2);
  EXPECT_EQ(s.kept, 1);
  EXPECT_EQ(s.extended, 0);
  const std::size_t compact =
      static_cast<std::size_t>(std::find(full.begin(), full.end(), moved) - full.begin());
  const BlockLayout& layout = run.live.layout();
  EXPECT_EQ(run.live.block_of()[static_cast<std::size_t>(layout.owner[compact])], owner[moved]);
  // The unchanged block kept its state and its factor, and starts from the iterate.
  const AgentState& state = *run.live.states()[0];
  EXPECT_EQ(&state, kept);
  EXPECT_EQ(state.tangent_factorizations_total(), factorizations);
  EXPECT_EQ(state.problem().neighbors(), neighbours);
  const PoseGraph& g = run.live.graph();
  const Eigen::MatrixXd Xc = gather_pose_columns(run.X, full, g.d);
  EXPECT_EQ(state.Y, gather_pose_columns(Xc, layout.poses[0], g.d));
  // Every block, kept or built again, is the one a build on the new layout gives: its coarse
  // terms (which read the neighbours' owners) included.
  for (int c = 0; c < layout.num_blocks; ++c) {
    const AgentState& live = *run.live.states()[static_cast<std::size_t>(c)];
    const auto& own = layout.poses[static_cast<std::size_t>(c)];
    AgentState fresh(c, g.d, layout, g.measurements, gather_pose_columns(Xc, own, g.d));
    EXPECT_EQ(live.problem().owned(), fresh.problem().owned());
    EXPECT_EQ(live.problem().neighbors(), fresh.problem().neighbors());
    fresh.reset_iterate(live.Y, live.Yn);
    EXPECT_EQ(live.coarse_terms(), fresh.coarse_terms());
  }
  EXPECT_NE(state.coarse_terms(), terms_before);
}

TEST(TangentPreconditionerGrow, TheGrownPreconditionerIsSymmetricPositiveDefinite) {
  const auto gen = small_graph(TrajectoryKind::kSphere, 91, 1);
  const PoseGraph& g = gen.graph;
  const int d = g.d;
  // Poses 1..90 (pose 0 a neighbour: a block held in place, as in a run where robots met).
  const Eigen::MatrixXd X = lift_poses(g.initial, d).rightCols((d + 1) * 90);
  std::vector<std::size_t> first, rest;
  for (std::size_t k = 1; k < g.num_poses; ++k) (k <= 60 ? first : rest).push_back(k);
  // The problem of the first 60 poses' measurements, then grown by the other 30.
  std::vector<Measurement> early;
  std::vector<Measurement> ordered;
  for (const Measurement& m : g.measurements)
    if (m.i <= 60 && m.j <= 60) early.push_back(m);
  ordered = early;
  for (const Measurement& m : g.measurements)
    if (m.i > 60 || m.j > 60) ordered.push_back(m);
  BlockProblem problem(d, first, early);
  TangentPreconditioner precon(problem);
  ASSERT_TRUE(precon.factorize(X.leftCols((d + 1) * 60)));
  problem.extend(rest, ordered, early.size());
  ASSERT_TRUE(precon.grow(problem, X));
  EXPECT_EQ(precon.grown_poses(), 30);
  EXPECT_FALSE(precon.factorize(X));  // a grown factor is replaced, not refreshed
  const LiftedManifold M = problem.manifold(d);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise;
  auto tangent = [&] {
    Eigen::MatrixXd V = Eigen::MatrixXd::NullaryExpr(d, X.cols(), [&] { return noise(rng); });
    return M.tangent_project(X, V);
  };
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::MatrixXd u = tangent(), v = tangent();
    const Eigen::MatrixXd Pu = precon.apply(M, X, u), Pv = precon.apply(M, X, v);
    EXPECT_GT((v.array() * Pv.array()).sum(), 0.0);
    const double uPv = (u.array() * Pv.array()).sum(), vPu = (v.array() * Pu.array()).sum();
    EXPECT_NEAR(uPv, vPu, 1e-9 * std::max(1.0, std::abs(uPv)));
    // A tangent vector at X.
    EXPECT_LT((M.tangent_project(X, Pv) - Pv).norm(), 1e-9 * std::max(1.0, Pv.norm()));
  }
}

// The grown poses are appended to the held factor (block LDL^T with their Schur complement; the
// new measurements' share of the factored poses by Woodbury), not approximated: at the factor's
// point the grown preconditioner is the exact inverse of A over all poses.
TEST(TangentPreconditionerGrow, AppendedPosesGiveTheExactInverseAtTheFactorsPoint) {
  for (TrajectoryKind kind : {TrajectoryKind::kCity, TrajectoryKind::kSphere}) {
    const auto gen = small_graph(kind, 80, 1);
    const PoseGraph& g = gen.graph;
    const int d = g.d;
    const Eigen::MatrixXd X = lift_poses(g.initial, d);
    // The block: poses 1..49, then 50..79 with every measurement that touches them (loop
    // closures to 1..49 included); pose 0 is a neighbour, so A is positive definite unshifted.
    std::vector<std::size_t> first, rest, all_owned;
    for (std::size_t k = 1; k < g.num_poses; ++k) {
      (k < 50 ? first : rest).push_back(k);
      all_owned.push_back(k);
    }
    std::vector<Measurement> early, late;
    for (const Measurement& m : g.measurements)
      (std::max(m.i, m.j) < 50 ? early : late).push_back(m);
    std::vector<Measurement> all = early;
    all.insert(all.end(), late.begin(), late.end());
    BlockProblem problem(d, first, early);
    TangentPreconditioner precon(problem, /*relative_shift=*/0.0, 0);
    const Eigen::MatrixXd Xb = X.rightCols((d + 1) * (g.num_poses - 1));
    ASSERT_TRUE(precon.factorize(Xb.leftCols((d + 1) * 49)));
    problem.extend(rest, all, early.size());
    ASSERT_TRUE(precon.grow(problem, Xb));
    EXPECT_EQ(precon.grown_poses(), 30);
    const BlockProblem whole(d, all_owned, all);
    TangentPreconditioner fresh(whole, /*relative_shift=*/0.0, 0);
    ASSERT_TRUE(fresh.factorize(Xb));
    const LiftedManifold M = problem.manifold(d);
    std::mt19937 rng(5);
    std::normal_distribution<double> noise;
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::MatrixXd V = M.tangent_project(
          Xb, Eigen::MatrixXd::NullaryExpr(d, Xb.cols(), [&] { return noise(rng); }));
      const Eigen::MatrixXd grown = precon.apply(M, Xb, V), exact = fresh.apply(M, Xb, V);
      EXPECT_LT((grown - exact).norm(), 1e-8 * exact.norm()) << "d = " << d;
    }
  }
}

}  // namespace
}  // namespace tessera
